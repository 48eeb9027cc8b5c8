//! `ygg view`: the browser viewer. The viewer is the Python module `yggdrasil.view`
//! (viser, the package extra `yggdrasil[view]`), so that no crate compiles a viewer
//! library; this command checks that the module can be imported and then becomes
//! `python3 -m yggdrasil.view ARGS...` (every argument passed on unchanged).

use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::process::Command;

/// The Python interpreter the viewer runs in, unless [`ENV_PYTHON`] names another.
pub const DEFAULT_PYTHON: &str = "python3";
/// Env var naming the Python interpreter to run the viewer with.
pub const ENV_PYTHON: &str = "YGG_PYTHON";

/// Options of `ygg view`: all passed to `python3 -m yggdrasil.view` (`ygg view --help`
/// prints its options).
#[derive(clap::Args, Debug)]
#[command(disable_help_flag = true)]
pub struct ViewArgs {
    /// The viewer's arguments: FILE... or --scene NAME, --query LINE, --port N, ...
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    pub args: Vec<OsString>,
}

/// Why the viewer cannot start.
#[derive(Debug, thiserror::Error)]
pub enum ViewStartError {
    /// The interpreter could not be run at all.
    #[error(
        "cannot run {python} (set {ENV_PYTHON} to a Python 3 with the yggdrasil package): {source}"
    )]
    NoPython {
        /// The interpreter tried.
        python: String,
        /// The spawn error.
        source: std::io::Error,
    },
    /// The interpreter runs but cannot import the viewer.
    #[error(
        "{python} cannot import the viewer (yggdrasil.view with viser): install the Python package with its `view` extra, \
         `pip install './python[view]'` (or `pip install viser pygltflib` beside an installed yggdrasil); {python} said: {said}"
    )]
    NotInstalled {
        /// The interpreter tried.
        python: String,
        /// The last line of its error.
        said: String,
    },
    /// `exec` failed after the check passed.
    #[error("cannot start {python} -m yggdrasil.view")]
    Exec {
        /// The interpreter tried.
        python: String,
        /// The exec error.
        source: std::io::Error,
    },
}

/// The interpreter to run the viewer with: [`ENV_PYTHON`] or [`DEFAULT_PYTHON`].
pub fn python() -> String {
    std::env::var(ENV_PYTHON).unwrap_or_else(|_| DEFAULT_PYTHON.to_owned())
}

/// Checks that `python` can import the viewer (the module and viser).
///
/// # Errors
/// [`ViewStartError::NoPython`] or [`ViewStartError::NotInstalled`].
pub fn check_installed(python: &str) -> Result<(), ViewStartError> {
    let out = Command::new(python)
        .args(["-c", "import yggdrasil.view.viewer"])
        .output()
        .map_err(|source| ViewStartError::NoPython {
            python: python.to_owned(),
            source,
        })?;
    if out.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    Err(ViewStartError::NotInstalled {
        python: python.to_owned(),
        said: stderr.lines().last().unwrap_or("nothing").to_owned(),
    })
}

/// The command that runs the viewer with `args`.
pub fn command(python: &str, args: impl IntoIterator<Item = impl Into<OsString>>) -> Command {
    let mut command = Command::new(python);
    command
        .args(["-m", "yggdrasil.view"])
        .args(args.into_iter().map(Into::into));
    command
}

/// Runs `ygg view`: replaces this process with the viewer (it returns only on error).
///
/// # Errors
/// When the viewer is not installed or cannot be started.
pub fn run(args: &ViewArgs) -> Result<(), ViewStartError> {
    let python = python();
    check_installed(&python)?;
    let source = command(&python, args.args.iter().cloned()).exec();
    Err(ViewStartError::Exec { python, source })
}
