//! Yggdrasil scene graph store.
