//! Yggdrasil reader.
