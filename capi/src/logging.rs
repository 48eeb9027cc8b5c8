//! How much the shared-memory transport (iceoryx2) prints on stderr: errors only unless
//! the environment variable `YGG_LOG` or `ygg_set_log_level` asks for more. Set once,
//! before the library's first reader or writer (a C library has no load hook of its own).

use crate::args::str_arg;
use crate::errors::{FfiError, YggStatus, guard};
use std::ffi::c_char;
use std::sync::Once;

/// Sets the transport's log level from `YGG_LOG` (else errors only), once per process.
pub(crate) fn init() {
    static INIT: Once = Once::new();
    INIT.call_once(ygg_transport::init_binding_logging);
}

/// Sets the transport's log level, process-wide: `"trace"`, `"debug"`, `"info"`,
/// `"warn"`, `"error"` (the default, unless the environment variable `YGG_LOG` names
/// another level) or `"fatal"`; `YGG_STATUS_INVALID_ARGUMENT` for any other name.
///
/// # Safety
/// `level` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_set_log_level(level: *const c_char) -> YggStatus {
    guard("ygg_set_log_level", || {
        // SAFETY: the caller's contract for `level`.
        let level = unsafe { str_arg(level, "level") }?;
        init();
        ygg_transport::set_iceoryx_log_level(level).map_err(|e| FfiError::invalid(e.to_string()))
    })
}
