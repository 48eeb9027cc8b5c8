//! `yggdrasil.set_log_level`: how much the shared-memory transport (iceoryx2) prints on
//! stderr. The package sets it when it loads: from `YGG_LOG` if that names a level, else
//! errors only, so a `Reader` or `Writer` starts silently.

use pyo3::prelude::*;

use pyo3::exceptions::PyValueError;

/// Sets the transport's log level, process-wide: `"trace"`, `"debug"`, `"info"`,
/// `"warn"`, `"error"` (the default when the package loads, unless the environment
/// variable `YGG_LOG` names another) or `"fatal"`.
///
/// Raises `ValueError` for any other name.
#[pyfunction]
pub fn set_log_level(level: &str) -> PyResult<()> {
    ygg_transport::set_iceoryx_log_level(level).map_err(|e| PyValueError::new_err(e.to_string()))
}
