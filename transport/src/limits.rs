//! Process limits the transport runs into.

/// Raises the soft limit of open file descriptors to the hard limit and returns the new soft
/// limit (`None`: unlimited).
///
/// A scene costs a process about 40 descriptors whatever its number of layers, but an
/// application may attach to many scenes (and protocol 2 writers cost about six per layer).
/// Binaries call this at start; libraries leave it to the application.
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
