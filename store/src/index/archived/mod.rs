//! Indexes over kiddo's archived `ImmutableKdTree`: the trees a snapshot carries (a layer
//! index, plus the rows patched since its base was built) and the trees a reader builds.
//!
//! `layout` (kiddo's archived layout mirrored and checked, [`check_tree`]), `kdtree`
//! ([`ArchivedIndex`] in a snapshot, [`KdIndex`] built by a reader), `patched_rows`
//! (the rows of a layer index changed since its base tree), `parted` ([`PartedIndex`], the
//! layer index of a layer split into parts).

mod kdtree;
mod layout;
mod parted;
mod patched_rows;

pub(crate) use kdtree::build_tree;
pub use kdtree::{ArchivedIndex, KdIndex};
pub(crate) use layout::check_tree;
pub use layout::{ArchivedKdTree, KdTree};
pub use parted::PartedIndex;
pub(crate) use patched_rows::RowPatch;
