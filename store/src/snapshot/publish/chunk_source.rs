//! Chunk segments archived straight from the live graph: [`PointChunkSource`] (a slice
//! of a layer's point column) and [`TreeChunkSource`] (a built kd-tree), and how many
//! segments a graph's snapshot takes ([`crate::SceneGraph::snapshot_segments`]).

use crate::index::KdTree;
use crate::snapshot::chunking::{TREE_CHUNK_MIN_POINTS, chunk_count, has_tree_chunk, is_chunked};
use crate::snapshot::schema::{ArchivedPointChunk, ArchivedTreeChunk, FORMAT_VERSION, PointChunk};
use crate::{LayerId, NodeId, Point};
use rkyv::munge::munge;
use rkyv::rancor::Fallible;
use rkyv::ser::{Allocator, Writer};
use rkyv::vec::{ArchivedVec, VecResolver};
use rkyv::{Archive, Place, Serialize};
use std::collections::HashMap;

impl PointChunk {
    /// Chunk `index` of the column `points` of part `part` of `layer`, at `generation`
    /// (an owned copy; a publishing writer archives [`PointChunkSource`] instead).
    pub fn new(layer: LayerId, part: u32, index: usize, generation: u64, points: &[Point]) -> Self {
        PointChunk {
            version: FORMAT_VERSION,
            layer: layer.0,
            part,
            index: index as u32,
            generation,
            points: points.to_vec(),
        }
    }
}

/// A point chunk archived straight from the column it is part of: the same archive as
/// [`PointChunk`], without first copying its points (up to 384 KiB per chunk).
#[derive(Debug, Clone, Copy)]
pub struct PointChunkSource<'a> {
    layer: u32,
    part: u32,
    index: u32,
    generation: u64,
    points: &'a [Point],
}

impl<'a> PointChunkSource<'a> {
    /// Chunk `index` of the column of part `part` of `layer`, holding `points`, at
    /// `generation`.
    pub fn new(
        layer: LayerId,
        part: u32,
        index: usize,
        generation: u64,
        points: &'a [Point],
    ) -> Self {
        PointChunkSource {
            layer: layer.0,
            part,
            index: index as u32,
            generation,
            points,
        }
    }
}

impl Archive for PointChunkSource<'_> {
    type Archived = ArchivedPointChunk;
    type Resolver = VecResolver;

    fn resolve(&self, resolver: VecResolver, out: Place<ArchivedPointChunk>) {
        munge!(let ArchivedPointChunk { version, layer, part, index, generation, points } = out);
        FORMAT_VERSION.resolve((), version);
        self.layer.resolve((), layer);
        self.part.resolve((), part);
        self.index.resolve((), index);
        self.generation.resolve((), generation);
        ArchivedVec::resolve_from_len(self.points.len(), resolver, points);
    }
}

impl<S: Fallible + Allocator + Writer + ?Sized> Serialize<S> for PointChunkSource<'_> {
    fn serialize(&self, serializer: &mut S) -> Result<VecResolver, S::Error> {
        ArchivedVec::serialize_from_slice(self.points, serializer)
    }
}

/// A layer's kd-tree archived as a [`TreeChunk`](crate::snapshot::TreeChunk) straight from the tree
/// it holds (no copy of the tree).
#[derive(Debug, Clone, Copy)]
pub struct TreeChunkSource<'a> {
    layer: u32,
    part: u32,
    slot: u32,
    generation: u64,
    items: u32,
    tree: &'a KdTree,
}

impl<'a> TreeChunkSource<'a> {
    /// Tree chunk `slot` of part `part` of `layer`, at `generation`, holding `tree`
    /// whose items are below `items`.
    pub fn new(
        layer: LayerId,
        part: u32,
        slot: usize,
        generation: u64,
        items: u32,
        tree: &'a KdTree,
    ) -> Self {
        TreeChunkSource {
            layer: layer.0,
            part,
            slot: slot as u32,
            generation,
            items,
            tree,
        }
    }
}

impl Archive for TreeChunkSource<'_> {
    type Archived = ArchivedTreeChunk;
    type Resolver = <KdTree as Archive>::Resolver;

    fn resolve(&self, resolver: Self::Resolver, out: Place<ArchivedTreeChunk>) {
        munge!(let ArchivedTreeChunk { version, layer, part, slot, generation, items, tree } = out);
        FORMAT_VERSION.resolve((), version);
        self.layer.resolve((), layer);
        self.part.resolve((), part);
        self.slot.resolve((), slot);
        self.generation.resolve((), generation);
        self.items.resolve((), items);
        self.tree.resolve(resolver, tree);
    }
}

impl<S> Serialize<S> for TreeChunkSource<'_>
where
    S: Fallible + Allocator + Writer + ?Sized,
    KdTree: Serialize<S>,
{
    fn serialize(&self, serializer: &mut S) -> Result<Self::Resolver, S::Error> {
        self.tree.serialize(serializer)
    }
}

impl crate::SceneGraph {
    /// Segments a snapshot of this graph takes when published in point chunks of
    /// `chunk_len` ([`crate::snapshot::POINT_CHUNK_LEN`] by default): one per layer, plus the point chunks
    /// of each chunked layer and the tree chunks of its large indexes (for sizing a
    /// publisher's bound on segments per cut).
    pub fn snapshot_segments(&self, chunk_len: usize) -> usize {
        let mut node_trees: HashMap<LayerId, Vec<(NodeId, usize)>> = HashMap::new();
        for (root, tree) in &self.indexes.nodes {
            node_trees
                .entry(self.nodes[root].layer)
                .or_default()
                .push((*root, tree.len()));
        }
        self.layers
            .iter()
            .map(|(&id, l)| {
                let points = l.nodes.iter().map(|n| self.nodes[n].points.len()).sum();
                let point_chunks = if is_chunked(points, chunk_len) {
                    chunk_count(points, chunk_len)
                } else {
                    0
                };
                let layer_tree = self.indexes.layers.contains_key(&id)
                    && has_tree_chunk(0, points, TREE_CHUNK_MIN_POINTS);
                let mut roots = node_trees.remove(&id).unwrap_or_default();
                roots.sort_unstable();
                let node_tree_chunks = roots
                    .iter()
                    .enumerate()
                    .filter(|(i, (_, points))| {
                        has_tree_chunk(1 + i, *points, TREE_CHUNK_MIN_POINTS)
                    })
                    .count();
                1 + point_chunks + usize::from(layer_tree) + node_tree_chunks
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{TreeChunk, archive};

    #[test]
    fn a_chunk_archived_from_its_column_is_the_owned_chunks_archive() {
        let points: Vec<Point> = (0..1000).map(|i| [i as f32, -(i as f32), 0.5]).collect();
        for range in [0..1, 0..1000, 17..513] {
            let owned = PointChunk::new(LayerId(7), 2, 3, 42, &points[range.clone()]);
            let source = PointChunkSource::new(LayerId(7), 2, 3, 42, &points[range]);
            assert_eq!(source.archived_len(), owned.archived_len());
            assert_eq!(&archive(&source)[..], &archive(&owned)[..]);
        }
    }

    #[test]
    fn a_tree_chunk_archived_from_its_tree_is_the_owned_chunks_archive() {
        let entries: Vec<(u32, Point)> = (0..3000u32)
            .map(|i| (i / 3, [i as f32, (i % 7) as f32, 0.5]))
            .collect();
        let tree = crate::index::build_tree(&entries);
        let source = TreeChunkSource::new(LayerId(7), 2, 0, 42, 1000, &tree);
        let owned = TreeChunk {
            version: FORMAT_VERSION,
            layer: 7,
            part: 2,
            slot: 0,
            generation: 42,
            items: 1000,
            tree: crate::index::build_tree(&entries),
        };
        assert_eq!(source.archived_len(), owned.archived_len());
        assert_eq!(&archive(&source)[..], &archive(&owned)[..]);
        let bytes = archive(&source);
        let chunk = crate::snapshot::validate_tree_chunk(&bytes, "tree").unwrap();
        assert_eq!(chunk.tree.size(), 3000);
    }
}
