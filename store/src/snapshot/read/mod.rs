//! What a reader runs: validating untrusted segment bytes, joining them into a checked
//! cut ([`ArchivedScene`]) and querying it in place, and `.ygg` files.

mod chunk_check;
mod cut;
mod file;
mod rejoin;
mod scene_view;
mod validate;

pub use cut::{ArchivedNodeRef, ArchivedScene};
pub use file::{FILE_MAGIC, SnapshotFile};
pub use rejoin::KnownParts;
pub use validate::{
    check_layer, chunk_unchecked, layer_unchecked, manifest_unchecked, structure_unchecked,
    tree_chunk_unchecked, validate_chunk, validate_layer, validate_manifest, validate_structure,
    validate_tree_chunk,
};
