//! Process limits the transport runs into.

/// Raises the soft limit of open file descriptors to the hard limit and returns the new soft
/// limit (`None`: unlimited).
///
/// Every iceoryx2 service costs a process several descriptors (about six per layer for a
/// reader or the writer: 64 layers took ~410), so scenes with many layers exceed the usual
/// soft limit of 1024. Binaries call this at start; libraries leave it to the application.
///
/// # Errors
///
/// The OS error if the limit cannot be changed.
pub fn raise_open_file_limit() -> std::io::Result<Option<u64>> {
    use rustix::process::{Resource, getrlimit, setrlimit};
    let mut limit = getrlimit(Resource::Nofile);
    if limit.current != limit.maximum {
        limit.current = limit.maximum;
        setrlimit(Resource::Nofile, limit)?;
    }
    Ok(limit.current)
}
