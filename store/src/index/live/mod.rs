//! The live graph's indexes: a dynamic kd-tree that every mutation updates in place.
//!
//! `kdtree` ([`LiveKdTree`]), `overlay` (nodes moved wholesale kept beside the tree),
//! `graph_indexes` ([`LiveIndexes`], the layer and node indexes of one graph, and
//! [`LiveIndex`], one of them as a [`crate::index::SpatialIndex`]).

mod graph_indexes;
mod kdtree;
mod overlay;

pub use graph_indexes::LiveIndex;
pub(crate) use graph_indexes::{LiveIndexes, NO_HANDLE};
pub use kdtree::LiveKdTree;
pub(crate) use kdtree::{Entry, Located};
pub(crate) use overlay::OverlaidTree;
