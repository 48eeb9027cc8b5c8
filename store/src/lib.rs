//! Yggdrasil scene graph store.

pub mod dsg;
