//! The benchmark's error and result types.

/// Errors of the benchmark: a message for the user.
pub(crate) type BenchError = Box<dyn std::error::Error>;
/// Result of the benchmark's steps.
pub(crate) type Res<T> = Result<T, BenchError>;
