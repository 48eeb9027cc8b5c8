//! Runnable Yggdrasil writer/reader pairs, one folder per scenario (see `README.md`):
//! `minimal/` (a hand-built scene) and `office/` (the built-in office in mint layout).
