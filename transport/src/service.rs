//! Setting up a scene's iceoryx2 node, services and ports, and the one error both sides
//! report when that fails.
//!
//! The service names themselves are part of the wire format
//! ([`SceneServices`](crate::protocol::SceneServices)); the quality of service is the
//! publisher's (it creates the services) and the subscriber only opens them.

use iceoryx2::config::Config;
use iceoryx2::prelude::{Node, NodeBuilder, NodeName, ServiceName};

use crate::protocol::{Ipc, PrefixError, SceneNameError};

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
