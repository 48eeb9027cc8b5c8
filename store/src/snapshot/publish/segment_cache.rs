//! [`SegmentCache`]: incremental layer segments and manifests for a publishing writer.
//!
//! The cache keeps the columns it last built for each layer; every mutation records
//! what it changed in the layer's change journal (`crate::graph::change_journal`). When the journal
//! starts at the generation of the cached segment and the rows kept their places since
//! — nodes removed only from the end (the largest ids), new nodes only with ids above
//! every remaining one, no index enabled or disabled — the next build looks up only the
//! changed nodes: each changed row is overwritten in place where it keeps the length of
//! a column (a node moved, a value changed) and spliced in where it does not (an edge or
//! a label added), and new rows are appended; when many rows change length, fresh
//! columns are built instead, copying each run of unchanged rows from the previous ones
//! in one go. Label and key postings are rebuilt (a counting sort of the rows by term)
//! only when labels or keys changed or rows were added or removed; the rows whose parent
//! changed are re-filed in `by_parent`. The layer index is patched with the rows whose points changed and folded
//! into a new tree past a budget (`index_patch`), a node index is rebuilt only when its
//! sub-tree changed. Otherwise (the journal overflowed, or starts elsewhere: another
//! consumer took it) it builds from scratch like [`SceneGraph::layer_segment`].
//!
//! Either way the segment holds the same rows as a fresh one, and a layer index with the
//! same entries (`LayerSegment::layer_index_entries`); only the order of its string
//! table and the split of the index into base tree and patch may differ, and strings no longer used stay until the next full build
//! (one is forced once the table doubled). `store/tests/graph_props.rs` and
//! `dsg/tests/segment_cache_office.rs` check this against fresh builds under random
//! mutations.

use super::archive::StringTable;
use super::chunk_state::ChunkState;
use super::layer_index_update::{PointChanges, update_layer_index};
use super::parts::{LayerParts, PartRows, PublishedParts};
use crate::bytes::{SegmentBytes, archive};
use crate::graph::Layer;
use crate::graph::LayerChanges;
use crate::snapshot::chunking::{MAX_POINT_CHUNK_LEN, POINT_CHUNK_LEN, TREE_CHUNK_MIN_POINTS};
use crate::snapshot::schema::{
    ArchivedManifest, LayerSegment, Manifest, ManifestLayer, NO_PARENT, Structure,
    cut_field_offsets,
};
use crate::{LayerId, NodeId, SceneGraph};
use rustc_hash::FxHashMap;
use std::ops::Range;

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

/// One part's cached segment.
pub(super) struct Cached {
    pub(super) segment: LayerSegment,
    strings: StringTable,
    /// The layer's incarnation (a removed layer's id may come back).
    incarnation: u64,
    /// Length of the string table after the last full build.
    strings_at_full_build: usize,
    /// Base entries of the layer index that its patch killed (`index_patch`).
    index_killed: usize,
    /// The point chunks last published, if the part is chunked (`chunk_state`).
    pub(super) chunks: ChunkState,
}

impl Cached {
    /// Part `part` of `layer` built afresh from the nodes `ids` (ascending).
    pub(super) fn build(
        graph: &SceneGraph,
        layer: LayerId,
        part: u32,
        ids: Vec<u64>,
    ) -> Box<Cached> {
        let (segment, strings) = graph.build_part_segment(layer, part, ids);
        Box::new(Cached {
            incarnation: graph.layers[&layer].incarnation,
            strings_at_full_build: segment.strings.len(),
            segment,
            strings,
            index_killed: 0,
            chunks: ChunkState::fresh(),
        })
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
        let parts = self.update(graph, layer);
        let cached = &mut parts.parts[0].cached;
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
        for part in &mut parts.parts {
            let cached = &mut part.cached;
            cached
                .chunks
                .build_stale_node_trees(graph, &mut cached.segment, tree_min);
            cached
                .chunks
                .publish_form(&mut cached.segment, chunk_len, tree_min);
        }
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
        let mut kept = removed.filter(|p| p.incarnation == incarnation);
        let numbers_before = kept.as_ref().map(|p| p.numbers());
        if let Some(p) = kept.as_mut() {
            for part in &mut p.parts {
                let Cached {
                    segment, chunks, ..
                } = &mut *part.cached;
                chunks.restore(segment);
            }
        }
        let parts = match kept {
            Some(p) if p.generation == generation => p,
            Some(p) => {
                let changes = graph.take_layer_changes(layer);
                p.patched(graph, layer, changes, self.part_rows)
                    .unwrap_or_else(|| LayerParts::full(graph, layer, self.part_rows))
            }
            None => {
                graph.take_layer_changes(layer);
                LayerParts::full(graph, layer, self.part_rows)
            }
        };
        if numbers_before.as_ref() != Some(&parts.numbers()) {
            self.parts_generation += 1;
        }
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
    /// date (O(changed), not O(layers)).
    pub fn manifest_bytes(
        &mut self,
        graph: &SceneGraph,
        generation: u64,
        changed: Option<&[LayerId]>,
    ) -> &[u8] {
        let cached = self.update_manifest(graph, generation, changed);
        let archived = cached
            .archived
            .get_or_insert_with(|| ManifestBytes::new(&cached.manifest));
        &archived.bytes
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
    PublishedParts::new(p).segment_count() - 1
}

/// The cached segment brought up to date row by row, or `None` when rows moved (a
/// full build is needed).
///
/// `expected_rows`, if given, is the row count the segment must have after the patch
/// (the layer's node count for a layer in one piece): a journal that disagrees means a
/// full build.
pub(super) fn patched(
    graph: &SceneGraph,
    layer: LayerId,
    cache: Cached,
    changes: LayerChanges,
    expected_rows: Option<usize>,
) -> Option<Box<Cached>> {
    let Cached {
        segment: mut old,
        strings: mut table,
        strings_at_full_build,
        incarnation,
        mut index_killed,
        mut chunks,
    } = cache;
    if changes.everything
        || changes.since != old.generation
        || old.strings.len() > 2 * strings_at_full_build + 64
    {
        return None;
    }
    let l = &graph.layers[&layer];
    let mut changed: Vec<NodeId> = changes.nodes;
    changed.sort_unstable();
    changed.dedup();
    let mut removed = changes.removed;
    removed.sort_unstable();
    removed.dedup();
    let mut cut_points = 0;
    if !removed.is_empty() {
        // Only the last rows, gone for good, keep the other rows in place.
        let kept = old.ids.len().checked_sub(removed.len())?;
        if !old.ids[kept..].iter().eq(removed.iter().map(|id| &id.0))
            || removed.iter().any(|id| graph.nodes.contains_key(id))
        {
            return None;
        }
        cut_points = PointChanges::points_from(&old, kept);
        old.truncate_rows(kept);
        changed.retain(|id| removed.binary_search(id).is_err());
    }
    let old_rows = old.ids.len();
    let mut dirty_rows = Vec::with_capacity(changed.len());
    let mut appended = Vec::new();
    for id in changed {
        if graph.nodes.get(&id).is_none_or(|n| n.layer != layer) {
            return None;
        }
        match old.ids.binary_search(&id.0) {
            Ok(row) => dirty_rows.push(row),
            Err(at) if at == old_rows => appended.push(id.0),
            Err(_) => return None,
        }
    }
    if expected_rows.is_some_and(|rows| old_rows + appended.len() != rows) {
        return None;
    }
    let mut ids = Vec::with_capacity(l.nodes.len());
    ids.extend_from_slice(&old.ids);
    ids.extend_from_slice(&appended);
    // Each rewritten or appended row with the parent it had, to re-file `by_parent`.
    let rewritten: Vec<(u32, u64)> = dirty_rows
        .iter()
        .map(|&row| (row as u32, old.parents[row]))
        .chain((old_rows..ids.len()).map(|row| (row as u32, NO_PARENT)))
        .collect();
    let point_changes = PointChanges::find(graph, &old, &dirty_rows, &ids, cut_points);
    let points_kept = chunks.changed.note_patch(graph, &old, &dirty_rows, &ids);

    let mut s = match rows_in_place(graph, &mut old, &mut table, &dirty_rows, &points_kept, &ids) {
        Some(terms_changed) => {
            for (row, &id) in ids.iter().enumerate().skip(old_rows) {
                graph.push_row(&mut old, &mut table, &graph.nodes[&NodeId(id)], row as u32);
            }
            old.ids = ids;
            old.generation = l.generation;
            if terms_changed || old_rows < old.ids.len() || !removed.is_empty() {
                old.rebuild_postings();
            }
            old
        }
        None => {
            let mut s = LayerSegment::empty(layer, l.generation, &l.name, ids.len());
            s.part = old.part;
            s.strings = std::mem::take(&mut old.strings);
            let mut aabb_cursor = 0;
            let mut clean_from = 0;
            for row in dirty_rows.into_iter().chain(old_rows..ids.len()) {
                copy_rows(
                    &old,
                    &mut s,
                    clean_from..row.min(old_rows),
                    &mut aabb_cursor,
                );
                let node = &graph.nodes[&NodeId(ids[row])];
                graph.push_row(&mut s, &mut table, node, row as u32);
                clean_from = row + 1;
            }
            copy_rows(&old, &mut s, clean_from..old_rows, &mut aabb_cursor);
            s.ids = ids;
            s.rebuild_postings();
            s.by_parent = std::mem::take(&mut old.by_parent);
            s.layer_index = old.layer_index.take();
            s.node_indexes = std::mem::take(&mut old.node_indexes);
            s
        }
    };

    s.refile_by_parent(&rewritten);
    if changes.geometry || s.layer_index.is_some() {
        chunks.tree_rebuilt |=
            update_layer_index(graph, layer, &mut s, point_changes, &mut index_killed);
    }
    let mut roots = changes.index_roots;
    roots.sort_unstable();
    roots.dedup();
    s.node_indexes
        .retain(|index| removed.binary_search(&NodeId(index.root)).is_err());
    for index in &mut s.node_indexes {
        if roots.binary_search(&NodeId(index.root)).is_ok() {
            // Built when the segment is next asked for, if it is sent at all.
            chunks.node_tree_stale(index);
        }
    }
    Some(Box::new(Cached {
        segment: s,
        strings: table,
        incarnation,
        strings_at_full_build,
        index_killed,
        chunks,
    }))
}

/// Most rows whose column lengths change (an edge or a label added) that one
/// build splices into the columns in place; each splice moves the tails of the columns
/// it changes and shifts the later offsets. Past it, fresh columns are built.
const MAX_SPLICED: usize = 32;

/// Rewrites the changed rows `dirty_rows` of `seg` in place: each row's entries are
/// overwritten where they keep their length (a node moved, a value changed) and
/// spliced in where they do not (an edge or label added: the odometry edge to the
/// previous pose). Returns whether the postings must be
/// rebuilt (labels or keys changed), or `None`, changing no row, when more than
/// [`MAX_SPLICED`] rows change length. `ids` are the new sorted ids; `points_kept`, per
/// dirty row, how many of its leading points are unchanged.
///
/// The new content of every dirty row is first built into one scratch segment (row `k`
/// of it is `dirty_rows[k]`), so a build allocates its columns once, not per row.
fn rows_in_place(
    graph: &SceneGraph,
    seg: &mut LayerSegment,
    table: &mut StringTable,
    dirty_rows: &[usize],
    points_kept: &[usize],
    ids: &[u64],
) -> Option<bool> {
    let mut fresh = LayerSegment::empty(LayerId(seg.layer), 0, "", dirty_rows.len());
    // New strings go to the segment's own table.
    fresh.strings = std::mem::take(&mut seg.strings);
    for &row in dirty_rows {
        let node = &graph.nodes[&NodeId(ids[row])];
        // The points go from the node to the column directly (a mesh node may hold many).
        graph.push_row_except_points(&mut fresh, table, node, row as u32);
        let end = fresh.point_offsets.last().copied().unwrap_or(0) + node.points.len() as u32;
        fresh.point_offsets.push(end);
    }
    seg.strings = std::mem::take(&mut fresh.strings);
    let reshaped = dirty_rows
        .iter()
        .enumerate()
        .filter(|&(k, &row)| {
            [
                (&seg.point_offsets, &fresh.point_offsets),
                (&seg.out_offsets, &fresh.out_offsets),
                (&seg.in_offsets, &fresh.in_offsets),
                (&seg.label_offsets, &fresh.label_offsets),
                (&seg.feature_offsets, &fresh.feature_offsets),
            ]
            .iter()
            .any(|(old, new)| row_range(old, row).len() != row_range(new, k).len())
        })
        .count();
    if reshaped > MAX_SPLICED {
        return None;
    }
    let mut terms_changed = false;
    for (k, (&row, &kept)) in dirty_rows.iter().zip(points_kept).enumerate() {
        let points = &graph.nodes[&NodeId(ids[row])].points;
        let new = row_range(&fresh.label_offsets, k);
        let r = row_range(&seg.label_offsets, row);
        terms_changed |= seg.labels[r.clone()] != fresh.labels[new.clone()];
        splice(&mut seg.labels, r.clone(), &fresh.labels[new.clone()]);
        shift_offsets(&mut seg.label_offsets, row, r.len(), new.len());
        let new = row_range(&fresh.feature_offsets, k);
        let r = row_range(&seg.feature_offsets, row);
        terms_changed |= seg.feature_keys[r.clone()] != fresh.feature_keys[new.clone()];
        splice(
            &mut seg.feature_keys,
            r.clone(),
            &fresh.feature_keys[new.clone()],
        );
        splice(
            &mut seg.feature_kinds,
            r.clone(),
            &fresh.feature_kinds[new.clone()],
        );
        splice(
            &mut seg.feature_bits,
            r.clone(),
            &fresh.feature_bits[new.clone()],
        );
        shift_offsets(&mut seg.feature_offsets, row, r.len(), new.len());
        // The leading points that stayed as they were are not rewritten (a mesh node
        // growing at its end).
        let r = row_range(&seg.point_offsets, row);
        splice(&mut seg.points, r.start + kept..r.end, &points[kept..]);
        shift_offsets(&mut seg.point_offsets, row, r.len(), points.len());
        let new = row_range(&fresh.out_offsets, k);
        let r = row_range(&seg.out_offsets, row);
        splice(
            &mut seg.out_targets,
            r.clone(),
            &fresh.out_targets[new.clone()],
        );
        splice(
            &mut seg.out_descriptions,
            r.clone(),
            &fresh.out_descriptions[new.clone()],
        );
        shift_offsets(&mut seg.out_offsets, row, r.len(), new.len());
        let new = row_range(&fresh.in_offsets, k);
        let r = row_range(&seg.in_offsets, row);
        splice(
            &mut seg.in_sources,
            r.clone(),
            &fresh.in_sources[new.clone()],
        );
        splice(
            &mut seg.in_descriptions,
            r.clone(),
            &fresh.in_descriptions[new.clone()],
        );
        shift_offsets(&mut seg.in_offsets, row, r.len(), new.len());
        seg.parents[row] = fresh.parents[k];
        // The scratch segment's boxes carry their real row numbers, ascending.
        let new_box = fresh
            .aabb_rows
            .binary_search(&(row as u32))
            .ok()
            .map(|i| fresh.aabbs[i]);
        match (seg.aabb_rows.binary_search(&(row as u32)), new_box) {
            (Ok(i), Some(b)) => seg.aabbs[i] = b,
            (Ok(i), None) => {
                seg.aabb_rows.remove(i);
                seg.aabbs.remove(i);
            }
            (Err(i), Some(b)) => {
                seg.aabb_rows.insert(i, row as u32);
                seg.aabbs.insert(i, b);
            }
            (Err(_), None) => {}
        }
    }
    Some(terms_changed)
}

/// The entries of row `row` of a CSR column with `offsets`.
fn row_range(offsets: &[u32], row: usize) -> Range<usize> {
    offsets[row] as usize..offsets[row + 1] as usize
}

/// Replaces `values[range]` by `new`: the common prefix is overwritten, and the rest
/// inserted or removed (moving the tail once).
fn splice<T: Copy>(values: &mut Vec<T>, range: Range<usize>, new: &[T]) {
    let common = range.len().min(new.len());
    values[range.start..range.start + common].copy_from_slice(&new[..common]);
    if new.len() > common {
        values.splice(range.end..range.end, new[common..].iter().copied());
    } else if range.len() > common {
        values.drain(range.start + common..range.end);
    }
}

/// Shifts the offsets after row `row` of a CSR column whose row went from `old_len` to
/// `new_len` entries.
fn shift_offsets(offsets: &mut [u32], row: usize, old_len: usize, new_len: usize) {
    if old_len != new_len {
        for o in &mut offsets[row + 1..] {
            *o = (*o as usize + new_len - old_len) as u32;
        }
    }
}

impl LayerSegment {
    /// Drops every row from `rows` on (not the postings or the spatial indexes).
    fn truncate_rows(&mut self, rows: usize) {
        fn cut<T>(offsets: &mut Vec<u32>, rows: usize, values: &mut Vec<T>) -> usize {
            let end = offsets[rows] as usize;
            offsets.truncate(rows + 1);
            values.truncate(end);
            end
        }
        cut(&mut self.point_offsets, rows, &mut self.points);
        let end = cut(&mut self.out_offsets, rows, &mut self.out_targets);
        self.out_descriptions.truncate(end);
        let end = cut(&mut self.in_offsets, rows, &mut self.in_sources);
        self.in_descriptions.truncate(end);
        cut(&mut self.label_offsets, rows, &mut self.labels);
        let end = cut(&mut self.feature_offsets, rows, &mut self.feature_keys);
        self.feature_kinds.truncate(end);
        self.feature_bits.truncate(end);
        self.parents.truncate(rows);
        self.by_parent.retain(|&row| (row as usize) < rows);
        self.ids.truncate(rows);
        let boxes = self.aabb_rows.partition_point(|&r| (r as usize) < rows);
        self.aabb_rows.truncate(boxes);
        self.aabbs.truncate(boxes);
    }
}

/// Appends rows `rows` of `old` to `new` unchanged (they keep their row numbers, so
/// edge rows stay valid), advancing `aabb_cursor` through `old`'s sparse boxes.
fn copy_rows(
    old: &LayerSegment,
    new: &mut LayerSegment,
    rows: Range<usize>,
    aabb_cursor: &mut usize,
) {
    let (a, b) = (rows.start, rows.end);
    if a < b {
        let r = copy_offsets(&mut new.point_offsets, &old.point_offsets, a, b);
        new.points.extend_from_slice(&old.points[r]);
        let r = copy_offsets(&mut new.out_offsets, &old.out_offsets, a, b);
        new.out_targets
            .extend_from_slice(&old.out_targets[r.clone()]);
        new.out_descriptions
            .extend_from_slice(&old.out_descriptions[r]);
        let r = copy_offsets(&mut new.in_offsets, &old.in_offsets, a, b);
        new.in_sources.extend_from_slice(&old.in_sources[r.clone()]);
        new.in_descriptions
            .extend_from_slice(&old.in_descriptions[r]);
        let r = copy_offsets(&mut new.label_offsets, &old.label_offsets, a, b);
        new.labels.extend_from_slice(&old.labels[r]);
        let r = copy_offsets(&mut new.feature_offsets, &old.feature_offsets, a, b);
        new.feature_keys
            .extend_from_slice(&old.feature_keys[r.clone()]);
        new.feature_kinds
            .extend_from_slice(&old.feature_kinds[r.clone()]);
        new.feature_bits.extend_from_slice(&old.feature_bits[r]);
        new.parents.extend_from_slice(&old.parents[a..b]);
    }
    // Boxes of rows before `b`: those in `a..b` are copied, the rest (rebuilt rows) are
    // skipped.
    while let Some(&row) = old.aabb_rows.get(*aabb_cursor) {
        if row as usize >= b {
            break;
        }
        if row as usize >= a {
            new.aabb_rows.push(row);
            new.aabbs.push(old.aabbs[*aabb_cursor]);
        }
        *aabb_cursor += 1;
    }
}

/// Appends `old`'s offsets of rows `a..b`, shifted to continue `new`; returns the range
/// of those rows' entries in `old`'s value columns.
fn copy_offsets(new: &mut Vec<u32>, old: &[u32], a: usize, b: usize) -> Range<usize> {
    let base = *new.last().expect("offset columns start with 0");
    let start = old[a];
    new.extend(old[a + 1..=b].iter().map(|&o| o - start + base));
    start as usize..old[b] as usize
}
