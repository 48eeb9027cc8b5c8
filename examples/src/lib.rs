//! Minimal Yggdrasil examples: see `writer.rs` and `reader.rs`.
