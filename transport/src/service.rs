//! Setting up a scene's iceoryx2 services and ports: the failure both sides report.
//!
//! The service names themselves are part of the wire format
//! ([`SceneServices`](crate::protocol::SceneServices)); the quality of service is the
//! publisher's (it creates the services) and the subscriber only opens them.

use iceoryx2::prelude::ServiceName;

/// A service or port of a scene that could not be set up; converted into
/// [`WriterCreateError`](crate::WriterCreateError) or
/// [`ReaderOpenError`](crate::ReaderOpenError) by `?`.
#[derive(Debug)]
pub(crate) struct SetupFailure {
    /// The full service name (`ygg/<scene>/...`).
    pub(crate) service: String,
    /// What iceoryx2 reported.
    pub(crate) reason: String,
    /// Whether a port (publisher, subscriber, listener, notifier) failed rather than the
    /// service.
    pub(crate) port: bool,
}

/// The service named `name` failed for `reason`.
pub(crate) fn service_failure(name: &str, reason: impl std::fmt::Debug) -> SetupFailure {
    SetupFailure {
        service: name.to_owned(),
        reason: format!("{reason:?}"),
        port: false,
    }
}

/// A port of the service named `name` failed with `e`.
pub(crate) fn port_failure(name: &str, e: impl std::fmt::Display) -> SetupFailure {
    SetupFailure {
        service: name.to_owned(),
        reason: e.to_string(),
        port: true,
    }
}

/// `name` as an iceoryx2 service name.
pub(crate) fn service_name(name: &str) -> Result<ServiceName, SetupFailure> {
    ServiceName::new(name).map_err(|e| SetupFailure {
        service: name.to_owned(),
        reason: format!("invalid service name: {e:?}"),
        port: false,
    })
}

/// Sets iceoryx2's log level from `IOX2_LOG_LEVEL`, or to errors only when it is unset:
/// iceoryx2 otherwise warns on stderr about routine things (a missing config file). For
/// command-line front ends; a library leaves logging to its application.
pub fn init_iceoryx_logging() {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
}
