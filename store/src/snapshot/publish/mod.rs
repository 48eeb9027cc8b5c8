//! What only a publishing writer runs: archiving its live graph into segments, and
//! [`SegmentCache`], which re-archives only what changed since the last publish.

mod archive;
mod by_parent;
mod chunk_source;
mod chunk_state;
mod layer_index_update;
mod part_patch;
mod parts;
mod segment_cache;

pub use archive::ArchivedGraph;
pub use chunk_source::{PointChunkSource, TreeChunkSource};
pub use chunk_state::PublishedLayer;
pub use parts::PublishedParts;
pub use segment_cache::{CutBytes, SegmentCache};
