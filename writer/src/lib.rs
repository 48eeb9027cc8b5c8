//! Yggdrasil writer.
