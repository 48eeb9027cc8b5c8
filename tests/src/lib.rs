//! Multi-process integration tests.
