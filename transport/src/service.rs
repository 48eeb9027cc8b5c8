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
