//! [`SegmentCache`]: incremental layer segments and manifests for a publishing writer.
//!
//! The cache keeps, per layer, the parts it last built (`parts`; one part unless it
//! splits layers, [`SegmentCache::with_part_rows`]), each patched row by row from the
//! layer's change journal (`part_patch`), and the last manifest and structure, whose
//! per-cut fields it patches in place while the structure holds.
//!
//! Either way a part holds the same rows as a fresh build of its nodes, and a layer index
//! with the same entries (`LayerSegment::layer_index_entries`); only the order of its
//! string table and the split of the index into base tree and patch may differ.
//! `store/tests/graph_props.rs` and `dsg/tests/segment_cache_office.rs` check this
//! against fresh builds under random mutations, and the published parts against the
//! live graph's answers.

use super::parts::{LayerParts, PartRows, PublishedParts};
use crate::bytes::{SegmentBytes, archive};
use crate::graph::Layer;
use crate::snapshot::chunking::{MAX_POINT_CHUNK_LEN, POINT_CHUNK_LEN, TREE_CHUNK_MIN_POINTS};
use crate::snapshot::schema::{
    ArchivedManifest, LayerSegment, Manifest, ManifestLayer, Structure, cut_field_offsets,
};
use crate::{LayerId, SceneGraph};
use rustc_hash::FxHashMap;

/// Incremental segments and manifest of one live graph, owned by whoever publishes it:
/// after a small change to a large layer only the changed rows are rebuilt.
///
/// Use one cache per graph: it follows the graph through the graph's change journals,
/// which it consumes.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, snapshot::SegmentCache};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let poses = g.add_layer("poses")?;
/// g.add_node(NodeId(1), poses)?;
/// let mut cache = SegmentCache::new();
/// assert_eq!(cache.layer_segment(&mut g, poses).ids, [1]);
/// g.add_node(NodeId(2), poses)?; // appended: only the new row is built
/// assert_eq!(cache.layer_segment(&mut g, poses).ids, [1, 2]);
/// assert_eq!(cache.manifest(&g, 2).layers[0].node_count, 2);
/// # Ok(()) }
/// ```
pub struct SegmentCache {
    layers: FxHashMap<LayerId, Box<LayerParts>>,
    /// Points per chunk of a chunked part ([`SegmentCache::published_layer`]).
    point_chunk_len: usize,
    /// Fewest points of a layer index's base tree sent as a tree chunk.
    tree_chunk_min_points: usize,
    /// How layers are split into parts (`None`: each in one piece).
    part_rows: Option<PartRows>,
    /// The last manifest, the graph's structure and terms generations it was built at, and
    /// its archived length once asked for ([`SegmentCache::manifest_with_len`]).
    manifest: Option<CachedManifest>,
    /// Segments of every layer in published form beyond one per layer: further parts,
    /// point and tree chunks.
    extra_segments: usize,
    /// Bumped whenever a layer's list of parts changes (the structure lists them).
    parts_generation: u64,
    /// Structures built so far: the generation of the newest.
    structures: u64,
}

impl std::fmt::Debug for SegmentCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SegmentCache")
            .field("layers", &self.layers.len())
            .field("manifest", &self.manifest.is_some())
            .finish()
    }
}

/// What a publish sends besides its parts ([`SegmentCache::manifest_bytes`]): the
/// archived manifest, and the structure it names with its archive.
#[derive(Debug, Clone, Copy)]
pub struct CutBytes<'c> {
    /// The archived manifest.
    pub manifest: &'c [u8],
    /// The structure the manifest names (its generation in
    /// [`Structure::generation`](crate::snapshot::Structure::generation)).
    pub structure: &'c Structure,
    /// The structure archived: a segment of its own, sent when its generation is new.
    pub structure_bytes: &'c [u8],
}

/// The last manifest with what it was built from.
struct CachedManifest {
    structure_generation: u64,
    terms_generation: u64,
    /// [`SegmentCache::parts_generation`] when it was built.
    parts_generation: u64,
    manifest: Manifest,
    /// The manifest archived, once asked for ([`SegmentCache::manifest_bytes`]): only
    /// fixed-size fields change between structure or terms changes, so they are
    /// patched in place rather than archived again.
    archived: Option<ManifestBytes>,
    /// The structure the manifest names, and its archive.
    structure: Structure,
    structure_bytes: SegmentBytes,
}

/// An archived manifest and where its per-publish fields lie in its bytes.
struct ManifestBytes {
    bytes: SegmentBytes,
    /// Offset of the cut's generation.
    generation: usize,
    /// Per layer, in manifest order: offsets of its generation, node count and id bounds.
    layers: Vec<[usize; 4]>,
}

impl ManifestBytes {
    /// Archives `manifest` and finds its per-publish fields.
    fn new(manifest: &Manifest) -> Self {
        let bytes = archive(manifest);
        let archived = rkyv::access::<ArchivedManifest, rkyv::rancor::Error>(&bytes)
            .expect("a manifest archived just now is valid");
        let (generation, layers) = cut_field_offsets(archived, bytes.as_ptr().addr());
        ManifestBytes {
            bytes,
            generation,
            layers,
        }
    }

    /// Writes entry `i`'s generation, node count and id bounds from `entry`.
    fn patch(&mut self, i: usize, entry: &ManifestLayer) {
        let values = [
            entry.generation,
            entry.node_count,
            entry.min_id,
            entry.max_id,
        ];
        for (offset, value) in self.layers[i].into_iter().zip(values) {
            self.write_u64(offset, value);
        }
    }

    /// Writes the cut's generation.
    fn patch_generation(&mut self, generation: u64) {
        self.write_u64(self.generation, generation);
    }

    /// Writes an archived (little-endian) `u64` at `offset`.
    fn write_u64(&mut self, offset: usize, value: u64) {
        self.bytes[offset..offset + 8].copy_from_slice(&value.to_le_bytes());
    }
}

impl Default for SegmentCache {
    fn default() -> Self {
        SegmentCache {
            layers: FxHashMap::default(),
            point_chunk_len: POINT_CHUNK_LEN,
            tree_chunk_min_points: TREE_CHUNK_MIN_POINTS,
            part_rows: None,
            manifest: None,
            extra_segments: 0,
            parts_generation: 0,
            structures: 0,
        }
    }
}

impl SegmentCache {
    /// An empty cache that keeps each layer in one piece and chunks layers of more than
    /// [`POINT_CHUNK_LEN`] points.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty cache that chunks parts of more than `len` points into chunks of `len`
    /// (rounded up to a power of two, at most [`MAX_POINT_CHUNK_LEN`]): small chunks
    /// exercise chunk boundaries in tests.
    pub fn with_point_chunk_len(len: usize) -> Self {
        SegmentCache {
            point_chunk_len: len.next_power_of_two().min(MAX_POINT_CHUNK_LEN),
            ..Self::default()
        }
    }

    /// This cache, sending the base tree of every layer index of `min_points` or more
    /// points (default [`TREE_CHUNK_MIN_POINTS`]) as a tree chunk: small values exercise
    /// tree chunks in tests.
    pub fn with_tree_chunk_min_points(self, min_points: usize) -> Self {
        SegmentCache {
            tree_chunk_min_points: min_points,
            ..self
        }
    }

    /// This cache, splitting each layer into parts (see `parts`): the newest part grows
    /// to `tail` rows before another starts, sealed parts merge up to `max` rows, and a
    /// part past `max` rows is split ([`PART_ROWS`](crate::snapshot::PART_ROWS) and
    /// [`MAX_PART_ROWS`](crate::snapshot::MAX_PART_ROWS) for a publishing writer). Small values exercise part boundaries in tests.
    ///
    /// # Panics
    /// If `tail` is 0 or `max` is below `tail`.
    pub fn with_part_rows(self, tail: usize, max: usize) -> Self {
        assert!(0 < tail && tail <= max, "parts of {tail} to {max} rows");
        SegmentCache {
            part_rows: Some(PartRows { tail, max }),
            ..self
        }
    }

    /// The segment of `layer`, equal in content to [`SceneGraph::layer_segment`], built
    /// incrementally from the one this cache built last time (see the module docs):
    /// after a small change to a large layer only the changed rows are rebuilt. The
    /// columns stay allocated: about the layer's archived size, per layer. Consumes the
    /// layer's change journal.
    ///
    /// # Panics
    /// If `layer` does not exist, or this cache splits layers into parts
    /// ([`SegmentCache::with_part_rows`]): use [`SegmentCache::published_layer`].
    pub fn layer_segment(&mut self, graph: &mut SceneGraph, layer: LayerId) -> &LayerSegment {
        assert!(
            self.part_rows.is_none(),
            "a cache that splits layers into parts"
        );
        let cached = self.update(graph, layer).first_inline();
        cached
            .chunks
            .build_stale_node_trees(graph, &mut cached.segment, 0);
        &cached.segment
    }

    /// The layer as a publishing writer sends it: its parts (one unless this cache splits
    /// layers, [`SegmentCache::with_part_rows`]), each like [`SegmentCache::layer_segment`]
    /// but with a point column of more points than a chunk holds ([`POINT_CHUNK_LEN`] by
    /// default) split into chunks, each of which keeps the generation at which its points
    /// last changed, so that only changed parts and chunks need sending (see `chunk`).
    /// Consumes the layer's change journal.
    ///
    /// # Panics
    /// If `layer` does not exist.
    pub fn published_layer(
        &mut self,
        graph: &mut SceneGraph,
        layer: LayerId,
    ) -> PublishedParts<'_> {
        let (chunk_len, tree_min) = (self.point_chunk_len, self.tree_chunk_min_points);
        let parts = self.update(graph, layer);
        parts.publish_form(graph, chunk_len, tree_min);
        let extra = extra_segments(parts);
        self.extra_segments += extra;
        PublishedParts::new(&self.layers[&layer])
    }

    /// The segments the layers in published form send beyond one per layer (further
    /// parts, point and tree chunks), in O(1): with the layer count, the size of a cut.
    pub fn extra_segments(&self) -> usize {
        self.extra_segments
    }

    /// The layer as the last [`SegmentCache::published_layer`] left it (`None` if this
    /// cache never built it). A later [`SegmentCache::layer_segment`] puts its points
    /// back inline.
    pub fn published(&self, layer: LayerId) -> Option<PublishedParts<'_>> {
        self.layers.get(&layer).map(|p| PublishedParts::new(p))
    }

    /// The cached layer brought up to date with the graph, its points inline.
    fn update(&mut self, graph: &mut SceneGraph, layer: LayerId) -> &mut LayerParts {
        let l = &graph.layers[&layer];
        let (generation, incarnation) = (l.generation, l.incarnation);
        let removed = self.layers.remove(&layer);
        if let Some(p) = removed.as_deref() {
            self.extra_segments -= extra_segments(p);
        }
        let kept = removed.filter(|p| p.incarnation == incarnation);
        let parts = match kept {
            Some(p) if p.generation == generation => p,
            Some(p) => {
                let changes = graph.take_layer_changes(layer);
                let parts = p
                    .patched(graph, layer, changes, self.part_rows)
                    .unwrap_or_else(|| LayerParts::full(graph, layer, self.part_rows));
                if parts.reshaped {
                    self.parts_generation += 1;
                }
                parts
            }
            None => {
                graph.take_layer_changes(layer);
                self.parts_generation += 1;
                LayerParts::full(graph, layer, self.part_rows)
            }
        };
        self.layers.entry(layer).insert_entry(parts).into_mut()
    }

    /// The manifest [`SceneGraph::manifest`] builds, kept for next time: while no layer,
    /// layer edge, part or graph-level label/key entry was added or removed, only the
    /// per-layer generations, node counts and id bounds are brought up to date (the id
    /// bounds from this cache's segments where they are current).
    pub fn manifest(&mut self, graph: &SceneGraph, generation: u64) -> &Manifest {
        &self.update_manifest(graph, generation, None).manifest
    }

    /// [`SegmentCache::manifest`] archived: the bytes a publish copies into its sample.
    /// They are archived only when the structure, the parts or the terms changed;
    /// otherwise the changed entries' generations, node counts and id bounds and the
    /// cut's generation are written into the kept bytes (the other fields have fixed
    /// archived sizes).
    ///
    /// `changed`, if given, lists every layer whose generation changed since the last
    /// call: with the structure and terms unchanged, only their entries are brought up to
    /// date (O(changed), not O(layers)). Comes with the structure the manifest names.
    pub fn manifest_bytes(
        &mut self,
        graph: &SceneGraph,
        generation: u64,
        changed: Option<&[LayerId]>,
    ) -> CutBytes<'_> {
        let cached = self.update_manifest(graph, generation, changed);
        let archived = cached
            .archived
            .get_or_insert_with(|| ManifestBytes::new(&cached.manifest));
        CutBytes {
            manifest: &archived.bytes,
            structure: &cached.structure,
            structure_bytes: &cached.structure_bytes,
        }
    }

    /// The structure the last manifest ([`SegmentCache::manifest`],
    /// [`SegmentCache::manifest_bytes`]) names, and its archive: a segment of its own,
    /// built again (with a new generation) only when the graph's structure, its terms or
    /// a layer's parts changed.
    pub fn structure(&self) -> Option<(&Structure, &[u8])> {
        self.manifest
            .as_ref()
            .map(|c| (&c.structure, &c.structure_bytes[..]))
    }

    fn update_manifest(
        &mut self,
        graph: &SceneGraph,
        generation: u64,
        changed: Option<&[LayerId]>,
    ) -> &mut CachedManifest {
        let key = (
            graph.structure_generation,
            graph.terms_generation,
            self.parts_generation,
        );
        let cached = match self.manifest.take() {
            Some(mut c)
                if (
                    c.structure_generation,
                    c.terms_generation,
                    c.parts_generation,
                ) == key =>
            {
                match changed {
                    Some(changed) => {
                        for id in changed {
                            let found = c.manifest.layers.binary_search_by_key(&id.0, |e| e.id);
                            if let Ok(i) = found {
                                c.refresh(i, &self.layers, &graph.layers[id]);
                            }
                        }
                    }
                    // The same layers as when it was built, both ascending by id.
                    None => {
                        for (i, l) in graph.layers.values().enumerate() {
                            c.refresh(i, &self.layers, l);
                        }
                    }
                }
                c.manifest.generation = generation;
                if let Some(archived) = c.archived.as_mut() {
                    archived.patch_generation(generation);
                }
                c
            }
            _ => {
                let extra = &mut self.extra_segments;
                self.layers.retain(|id, p| {
                    let kept = graph.layers.contains_key(id);
                    if !kept {
                        *extra -= extra_segments(p);
                    }
                    kept
                });
                self.structures += 1;
                let mut structure = graph.structure(self.structures);
                for entry in &mut structure.layers {
                    if let Some(p) = self.layers.get(&LayerId(entry.id)) {
                        entry.parts = p.numbers();
                    }
                }
                let mut manifest = graph.manifest(generation, self.structures);
                for entry in &mut manifest.layers {
                    if let Some(p) = self.layers.get(&LayerId(entry.id))
                        && let Some(bounds) = p.current_id_bounds(&graph.layers[&LayerId(entry.id)])
                    {
                        (entry.min_id, entry.max_id) = bounds;
                    }
                }
                CachedManifest {
                    structure_generation: key.0,
                    terms_generation: key.1,
                    parts_generation: key.2,
                    manifest,
                    archived: None,
                    structure_bytes: archive(&structure),
                    structure,
                }
            }
        };
        self.manifest.insert(cached)
    }
}

impl CachedManifest {
    /// Brings entry `i` up to date with its live layer `l`, in the manifest and in its
    /// archived bytes if kept.
    fn refresh(&mut self, i: usize, cache: &FxHashMap<LayerId, Box<LayerParts>>, l: &Layer) {
        let entry = &mut self.manifest.layers[i];
        refresh_entry(entry, cache, l);
        if let Some(archived) = self.archived.as_mut() {
            archived.patch(i, entry);
        }
    }
}

/// Brings a manifest entry up to date with its live layer `l`: generation, node count and
/// id bounds (from the cached parts when they are current).
fn refresh_entry(
    entry: &mut ManifestLayer,
    cache: &FxHashMap<LayerId, Box<LayerParts>>,
    l: &Layer,
) {
    entry.generation = l.generation;
    entry.node_count = l.nodes.len() as u64;
    (entry.min_id, entry.max_id) = cache
        .get(&LayerId(entry.id))
        .and_then(|p| p.current_id_bounds(l))
        .unwrap_or_else(|| l.id_bounds());
}

/// The segments a cached layer publishes beyond one (none unless it is in published form
/// or split into parts).
fn extra_segments(p: &LayerParts) -> usize {
    p.segment_count() - 1
}
