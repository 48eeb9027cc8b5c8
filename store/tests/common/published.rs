//! A publishing writer and a reader in one, for the property tests of published views:
//! [`Publisher`] publishes a live graph through a [`SegmentCache`] and keeps, as a reader
//! does, the segments whose generation did not change.

use std::collections::BTreeMap;
use ygg_store::snapshot::{
    ArchivedLayerSegment, ArchivedManifest, ArchivedPointChunk, ArchivedScene, ArchivedStructure,
    ArchivedTreeChunk, SegmentBytes, SegmentCache, archive, is_chunk_segment_id,
    is_part_segment_id, is_tree_chunk_segment_id, validate_chunk, validate_layer,
    validate_manifest, validate_structure, validate_tree_chunk,
};
use ygg_store::{LayerId, SceneGraph, SceneView};

/// A publishing writer and a reader in one: the writer's cache patches the layer indexes
/// it built before, splits every layer into parts of a few rows ([`PART_ROWS`], merged up
/// to [`MAX_PART_ROWS`], so that part boundaries fall everywhere), chunks every part of
/// more than [`CHUNK`] points and sends every tree (layer index base, node index) of
/// [`TREE_CHUNK`] points or more as a tree chunk; like the transport, only parts and
/// chunks whose generation changed are sent, and the reader keeps the others as it got
/// them. A part or chunk the cache failed to resend after it changed, or a tree after a
/// fold, would answer queries wrongly.
pub struct Publisher {
    pub segments: SegmentCache,
    /// Segments the reader holds: segment id -> (generation, bytes).
    pub held: BTreeMap<u64, (u64, SegmentBytes)>,
}

/// Points per chunk in [`Publisher`].
const CHUNK: usize = 4;

/// Fewest points of a tree that [`Publisher`] sends as a tree chunk.
pub const TREE_CHUNK: usize = 8;

/// Rows of the newest part of a layer in [`Publisher`].
const PART_ROWS: usize = 2;

/// Most rows of a part in [`Publisher`].
const MAX_PART_ROWS: usize = 6;

impl Publisher {
    pub fn new() -> Self {
        Publisher {
            segments: SegmentCache::with_point_chunk_len(CHUNK)
                .with_tree_chunk_min_points(TREE_CHUNK)
                .with_part_rows(PART_ROWS, MAX_PART_ROWS),
            held: BTreeMap::new(),
        }
    }

    /// [`Publisher::new`] keeping every layer in one piece.
    pub fn one_piece() -> Self {
        Publisher {
            segments: SegmentCache::with_point_chunk_len(CHUNK)
                .with_tree_chunk_min_points(TREE_CHUNK),
            held: BTreeMap::new(),
        }
    }

    /// Publishes `g` now: the archived manifest and structure, and the ids of the
    /// segments of the cut, ascending (their bytes in `held`).
    pub fn publish(&mut self, g: &mut SceneGraph) -> (SegmentBytes, SegmentBytes, Vec<u64>) {
        let layers: Vec<LayerId> = g.layers().collect();
        let mut ids = Vec::new();
        for l in layers {
            let published = self.segments.published_layer(g, l);
            // As a publishing writer does after a publish that went out: only the parts
            // that changed are looked at; a changed part the cache did not flag would
            // leave the reader its old bytes.
            for p in published.changed_parts() {
                let id = p.segment_id();
                if self.held.get(&id).map(|h| h.0) != Some(p.segment.generation) {
                    self.held
                        .insert(id, (p.segment.generation, archive(p.segment)));
                }
                for (i, (id, generation)) in p.chunks().enumerate() {
                    if self.held.get(&id).map(|h| h.0) != Some(generation) {
                        self.held.insert(id, (generation, archive(&p.chunk(i))));
                    }
                }
                for (id, generation, tree) in p.tree_chunks() {
                    if self.held.get(&id).map(|h| h.0) != Some(generation) {
                        self.held.insert(id, (generation, archive(&tree)));
                    }
                }
            }
            ids.extend(published.segments().into_iter().map(|(id, _)| id));
        }
        ids.sort_unstable();
        self.held.retain(|id, _| ids.binary_search(id).is_ok());
        let manifest = archive(self.segments.manifest(g, 1));
        let (structure, _) = self.segments.structure().expect("built with the manifest");
        (manifest, archive(structure), ids)
    }
}

impl Publisher {
    /// The held segments of a cut (`ids`, ascending), its `manifest` and `structure`,
    /// validated.
    pub fn validated<'a>(
        &'a self,
        manifest: &'a [u8],
        structure: &'a [u8],
        ids: &[u64],
    ) -> Validated<'a> {
        let held = |id: &u64| &self.held[id].1;
        Validated {
            manifest: validate_manifest(manifest, "manifest").unwrap(),
            structure: validate_structure(structure, "structure").unwrap(),
            parts: ids
                .iter()
                .filter(|id| is_part_segment_id(**id))
                .map(|id| validate_layer(held(id), "part").unwrap())
                .collect(),
            chunks: ids
                .iter()
                .filter(|id| is_chunk_segment_id(**id) && !is_tree_chunk_segment_id(**id))
                .map(|id| validate_chunk(held(id), "chunk").unwrap())
                .collect(),
            trees: ids
                .iter()
                .filter(|id| is_tree_chunk_segment_id(**id))
                .map(|id| validate_tree_chunk(held(id), "tree chunk").unwrap())
                .collect(),
        }
    }
}

/// The validated segments of one published cut.
pub struct Validated<'a> {
    manifest: &'a ArchivedManifest,
    structure: &'a ArchivedStructure,
    parts: Vec<&'a ArchivedLayerSegment>,
    chunks: Vec<&'a ArchivedPointChunk>,
    trees: Vec<&'a ArchivedTreeChunk>,
}

impl<'a> Validated<'a> {
    /// The cut joined, as a reader joins it.
    pub fn join(&self) -> Result<ArchivedScene<'a>, String> {
        ArchivedScene::new(
            self.manifest,
            self.structure,
            self.parts.clone(),
            self.chunks.clone(),
            self.trees.clone(),
        )
    }
}
