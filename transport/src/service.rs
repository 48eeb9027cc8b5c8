//! A scene's services: their names ([`SceneServices`]), the iceoryx2 configuration both
//! sides use ([`iceoryx_config`]: root, file-name prefix), the quality-of-service constants
//! the publisher creates them with (buffers, borrow limits, readers, event ids), and
//! setting up the node, services and ports, with the one error both sides report when that
//! fails.
//!
//! What travels on the services (headers, payload blocks, the manifest prefix, event ids)
//! is the wire format, [`crate::protocol`]. The quality of service is the publisher's (it
//! creates the services); the subscriber only opens them.

use core::time::Duration;

use iceoryx2::config::Config;
use iceoryx2::prelude::{FileName, Node, NodeBuilder, NodeName, Path, SemanticString, ServiceName};

/// The iceoryx2 service flavour used by writer and reader.
///
/// The thread-safe variant has the same shared-memory layout as `ipc::Service`; it makes ports
/// and samples `Send`, so a writer can answer readers from a helper thread and a reader's
/// snapshots can move between threads.
pub type Ipc = iceoryx2::service::ipc_threadsafe::Service;

/// First path component of every Yggdrasil service name.
pub const SERVICE_ROOT: &str = "ygg";

/// Longest accepted scene name, in bytes.
pub const MAX_SCENE_NAME_LEN: usize = 64;

/// Default for the most segments one snapshot may name (layers, or chunks of layers): sizes
/// the segment stream's pool (see [`stream_buffer_size`], [`stream_max_borrowed`]).
pub const DEFAULT_MAX_SEGMENTS: usize = 512;

/// Samples a reader's subscription to the segment stream buffers between two receives: one
/// whole snapshot and its manifest, so that neither a catch-up burst nor a cut that changes
/// every segment overflows a reader that keeps up. A reader that falls further behind loses
/// its oldest buffered samples (safe overflow), notices the hole and asks for a catch-up.
pub const fn stream_buffer_size(max_segments: usize) -> usize {
    max_segments + 2
}

/// Samples one subscriber may hold from the segment stream when snapshots name at most
/// `max_segments` segments: the current snapshot's, newer ones waiting for their manifest
/// (or a burst being received), and a few manifests and samples of older snapshots the
/// application still holds. Costs address space and a byte per sample and possible
/// reallocation in each connection: iceoryx2 reuses freed chunks last-in first-out, and the
/// writer gives back the pages a reused chunk no longer needs once the pool holds more than
/// about four snapshots (`publisher::loan`), so unused chunks cost address space, not memory.
pub const fn stream_max_borrowed(max_segments: usize) -> usize {
    2 * max_segments + 16
}

/// Segments per snapshot a stream created with this subscriber buffer size and borrow limit
/// supports: the inverse of [`stream_buffer_size`] and [`stream_max_borrowed`].
pub const fn stream_segments_supported(buffer_size: usize, max_borrowed: usize) -> usize {
    let by_buffer = buffer_size.saturating_sub(2);
    let by_borrowed = max_borrowed.saturating_sub(16) / 2;
    if by_buffer < by_borrowed {
        by_buffer
    } else {
        by_borrowed
    }
}

/// Samples the writer may hold on loan per service (it fills one at a time).
pub const PUBLISHER_MAX_LOANED: usize = 1;

/// Default number of readers a scene supports at once.
pub const DEFAULT_MAX_READERS: usize = 8;

/// Highest event id used on the event services.
pub const EVENT_ID_MAX: usize = 7;

/// Environment variable that overrides the iceoryx2 file-name prefix (default `iox2_`).
///
/// Every shared-memory object and node file the transport creates starts with this prefix, so a
/// distinct prefix isolates a group of processes (the integration tests use one per test).
/// Writer and readers of one scene must use the same prefix.
pub const ENV_IOX2_PREFIX: &str = "YGG_IOX2_PREFIX";

/// Default path of the POSIX shared-memory file system that iceoryx2 allocates from.
pub const DEFAULT_SHM_DIR: &str = "/dev/shm";

/// Where iceoryx2 keeps its node and service files for Yggdrasil (its own default is
/// `/tmp/iceoryx2/`): on the shared-memory tmpfs, because iceoryx2 fsyncs every node and
/// port file it writes, 7 fsyncs per attaching reader that cost 5-8 ms of a ~20 ms attach on
/// a disk-backed `/tmp`. Every Yggdrasil process uses it ([`iceoryx_config`]); iceoryx2's
/// own tools see these scenes when their config names the same root.
pub const ICEORYX2_ROOT: &str = "/dev/shm/iceoryx2/";

/// How often helper threads and waiting readers check peers for liveness.
pub const DEFAULT_LIVENESS_INTERVAL: Duration = Duration::from_millis(200);

/// A scene name that cannot name iceoryx2 services.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SceneNameError {
    /// The name is empty.
    #[error("the scene name is empty")]
    Empty,
    /// The name is longer than [`MAX_SCENE_NAME_LEN`].
    #[error("the scene name is {len} bytes long, at most {MAX_SCENE_NAME_LEN} are allowed")]
    TooLong {
        /// Its length.
        len: usize,
    },
    /// The name contains a character other than ASCII letters, digits, `-`, `_` and `.`.
    #[error("the scene name contains {found:?}; use ASCII letters, digits, '-', '_' or '.'")]
    InvalidCharacter {
        /// The first offending character.
        found: char,
    },
}

/// The names of the services of one scene.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneServices {
    scene: String,
}

impl SceneServices {
    /// Validates `scene` and returns its service names.
    ///
    /// # Errors
    ///
    /// [`SceneNameError`] if the name is empty, too long or has characters outside
    /// `[A-Za-z0-9._-]`.
    pub fn new(scene: &str) -> Result<Self, SceneNameError> {
        if scene.is_empty() {
            return Err(SceneNameError::Empty);
        }
        if scene.len() > MAX_SCENE_NAME_LEN {
            return Err(SceneNameError::TooLong { len: scene.len() });
        }
        if let Some(found) = scene
            .chars()
            .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.')))
        {
            return Err(SceneNameError::InvalidCharacter { found });
        }
        Ok(Self {
            scene: scene.to_owned(),
        })
    }

    /// The scene name.
    pub fn scene(&self) -> &str {
        &self.scene
    }

    /// `ygg/<scene>/segments`: every segment, in publish order, and catch-up bursts.
    pub fn segments(&self) -> String {
        format!("{SERVICE_ROOT}/{}/segments", self.scene)
    }

    /// `ygg/<scene>/events` (writer -> readers).
    pub fn events(&self) -> String {
        format!("{SERVICE_ROOT}/{}/events", self.scene)
    }

    /// `ygg/<scene>/readers` (readers -> writer).
    pub fn readers(&self) -> String {
        format!("{SERVICE_ROOT}/{}/readers", self.scene)
    }
}

/// An iceoryx2 file-name prefix that iceoryx2 does not accept.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid iceoryx2 prefix {prefix:?} (from {ENV_IOX2_PREFIX} or the builder): {reason}")]
pub struct PrefixError {
    /// The rejected prefix.
    pub prefix: String,
    /// Why iceoryx2 rejected it.
    pub reason: String,
}

/// The iceoryx2 configuration used by writer and readers: iceoryx2's global configuration,
/// with the file-name prefix replaced by `prefix` if given, else by [`ENV_IOX2_PREFIX`] if set.
///
/// # Errors
///
/// [`PrefixError`] if the prefix is not a valid file name.
pub fn iceoryx_config(prefix: Option<&str>) -> Result<Config, PrefixError> {
    let mut config = Config::global_config().clone();
    let root = Path::new(ICEORYX2_ROOT.as_bytes()).expect("ICEORYX2_ROOT is a valid path");
    config.global.set_root_path(&root);
    let from_env = std::env::var(ENV_IOX2_PREFIX).ok();
    if let Some(prefix) = prefix.or(from_env.as_deref()) {
        config.global.prefix = FileName::new(prefix.as_bytes()).map_err(|e| PrefixError {
            prefix: prefix.to_owned(),
            reason: format!("{e:?}"),
        })?;
    }
    Ok(config)
}

/// A scene's name or prefix is invalid, or its iceoryx2 node, a service or a port could not
/// be set up.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SetupError {
    /// The scene name cannot name services.
    #[error(transparent)]
    InvalidSceneName(#[from] SceneNameError),
    /// The iceoryx2 prefix is not a valid file name.
    #[error(transparent)]
    InvalidPrefix(#[from] PrefixError),
    /// The iceoryx2 node could not be created.
    #[error("cannot create the iceoryx2 node: {reason}")]
    Node {
        /// iceoryx2's description.
        reason: String,
    },
    /// A service of the scene could not be created or opened. If it exists with other
    /// settings (another protocol version, a smaller `max_readers`), the reason says so.
    #[error("cannot open or create service {service:?}: {reason}")]
    Service {
        /// The service name.
        service: String,
        /// iceoryx2's description.
        reason: String,
    },
    /// A port (publisher, subscriber, notifier, listener) could not be created, for example
    /// because the scene already has `max_readers` readers.
    #[error("cannot create a port on service {service:?}: {reason}")]
    Port {
        /// The service name.
        service: String,
        /// iceoryx2's description.
        reason: String,
    },
}

/// The service named `name` failed for `reason`.
pub(crate) fn service_failure(name: &str, reason: impl std::fmt::Debug) -> SetupError {
    SetupError::Service {
        service: name.to_owned(),
        reason: format!("{reason:?}"),
    }
}

/// A port of the service named `name` failed with `e`.
pub(crate) fn port_failure(name: &str, e: impl std::fmt::Display) -> SetupError {
    SetupError::Port {
        service: name.to_owned(),
        reason: e.to_string(),
    }
}

/// `name` as an iceoryx2 service name.
pub(crate) fn service_name(name: &str) -> Result<ServiceName, SetupError> {
    ServiceName::new(name).map_err(|e| SetupError::Service {
        service: name.to_owned(),
        reason: format!("invalid service name: {e:?}"),
    })
}

/// The iceoryx2 node of one side of a scene, named `<role>/<scene>` (for example
/// `ygg-writer/office`) so that `iox2 node list` tells the processes apart.
pub(crate) fn create_node(
    role: &str,
    scene: &str,
    config: &Config,
) -> Result<Node<Ipc>, SetupError> {
    let name = NodeName::new(&format!("{role}/{scene}")).map_err(|e| SetupError::Node {
        reason: format!("{e:?}"),
    })?;
    NodeBuilder::new()
        .name(&name)
        .config(config)
        .create::<Ipc>()
        .map_err(|e| SetupError::Node {
            reason: e.to_string(),
        })
}

/// Sets iceoryx2's log level from `IOX2_LOG_LEVEL`, or to errors only when it is unset:
/// iceoryx2 otherwise warns on stderr about routine things (a missing config file). For
/// command-line front ends; a library leaves logging to its application.
pub fn init_iceoryx_logging() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
}

/// The environment variable the bindings (C, Python) read for iceoryx2's log level when
/// they load: `YGG_LOG=warn` shows the warnings they hide by default.
pub const ENV_YGG_LOG: &str = "YGG_LOG";

/// A log level name that is none of `trace`, `debug`, `info`, `warn`, `error`, `fatal`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown log level {0:?} (expected trace, debug, info, warn, error or fatal)")]
pub struct UnknownLogLevelError(pub String);

/// Sets iceoryx2's log level by name (`trace`, `debug`, `info`, `warn`, `error`, `fatal`;
/// any case), process-wide. For bindings, whose users name levels as strings.
///
/// # Errors
/// [`UnknownLogLevelError`] for any other name; the level is then left as it was.
pub fn set_iceoryx_log_level(name: &str) -> Result<(), UnknownLogLevelError> {
    use iceoryx2::prelude::LogLevel;
    let level = match name.trim().to_ascii_lowercase().as_str() {
        "trace" => LogLevel::Trace,
        "debug" => LogLevel::Debug,
        "info" => LogLevel::Info,
        "warn" | "warning" => LogLevel::Warn,
        "error" => LogLevel::Error,
        "fatal" => LogLevel::Fatal,
        _ => return Err(UnknownLogLevelError(name.to_owned())),
    };
    iceoryx2::prelude::set_log_level(level);
    Ok(())
}

/// For bindings, when they load: iceoryx2's log level from [`ENV_YGG_LOG`] if it names a
/// level, else as [`init_iceoryx_logging`] (`IOX2_LOG_LEVEL`, else errors only), so the
/// routine warnings of a reader's or writer's start stay off a binding user's console
/// unless asked for.
pub fn init_binding_logging() {
    let from_env = std::env::var(ENV_YGG_LOG).ok();
    if from_env.is_none_or(|name| set_iceoryx_log_level(&name).is_err()) {
        init_iceoryx_logging();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::MAX_LAYERS;

    #[test]
    fn a_stream_supports_the_segments_it_was_sized_for() {
        for n in [1, 8, 42, 128, 512, MAX_LAYERS] {
            assert_eq!(
                stream_segments_supported(stream_buffer_size(n), stream_max_borrowed(n)),
                n
            );
        }
        // The smaller of the two limits wins.
        assert_eq!(
            stream_segments_supported(stream_buffer_size(64), stream_max_borrowed(8)),
            8
        );
        assert_eq!(stream_segments_supported(0, 0), 0);
    }

    #[test]
    fn scene_names_are_checked() {
        assert!(SceneServices::new("office-1.a_b").is_ok());
        assert_eq!(SceneServices::new(""), Err(SceneNameError::Empty));
        assert!(matches!(
            SceneServices::new("a/b"),
            Err(SceneNameError::InvalidCharacter { found: '/' })
        ));
        let s = SceneServices::new("s").expect("valid");
        assert_eq!(s.segments(), "ygg/s/segments");
    }
}
