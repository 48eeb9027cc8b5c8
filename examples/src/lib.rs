//! Runnable Yggdrasil writer/reader pairs, one folder per scenario (see `README.md`):
//! `minimal/` (a hand-built scene) and `office/` (the built-in office in mint layout).

/// The README's Rust examples, compiled (and the first one run) as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeExamples;
