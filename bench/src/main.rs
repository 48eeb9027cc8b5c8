//! Yggdrasil benchmarks.
fn main() {}
