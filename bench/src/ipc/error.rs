//! The benchmark's error and result types.

/// Errors of the benchmark: a message for the user.
pub(crate) type BenchError = Box<dyn std::error::Error>;
/// Result of the benchmark's steps.
pub(crate) type Res<T> = Result<T, BenchError>;

/// Runs a benchmark's entry point `f` with iceoryx2 logging errors only (unless
/// `IOX2_LOG_LEVEL` says otherwise: it warns on stderr that it found no config file); an
/// error is printed as `<who>: error: ...` (by then every child was stopped and every
/// shared-memory file removed) and ends the process with status 1.
pub(crate) fn run_or_exit(who: &str, f: impl FnOnce() -> Res<()>) {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    if let Err(e) = f() {
        eprintln!("{who}: error: {e}");
        std::process::exit(1);
    }
}
