//! Archived snapshots: the packed, column-oriented rkyv layout, `.ygg` files, and
//! [`ArchivedScene`], the [`SceneView`] over validated archived bytes.
//!
//! A snapshot is one **manifest** segment plus one **layer** segment per layer. A layer
//! segment is a struct of arrays: sorted node ids, points with CSR offsets, parent ids,
//! children in CSR form, out- and in-edges in CSR form (rows within the layer), labels,
//! features, sparse bounding boxes and the inverted label/key indexes, plus the layer's
//! spatial indexes: its layer index and the node indexes rooted at its nodes, as kiddo's
//! archived kd-trees (queried in place; their leaves are 128-byte aligned inside the
//! 128-byte aligned segment). The same segments travel through shared memory; a `.ygg`
//! file stores them back to back.
//!
//! # Validation
//! Bytes are untrusted. [`validate_layer`] and [`validate_manifest`] run rkyv's
//! bytecheck and then [`check_layer`]'s consistency pass (offsets monotonic and in
//! range, rows in range, ids sorted, string indexes in range, kd-tree shapes, extents and
//! items in range), so that every accessor of [`ArchivedScene`] is total: no index it
//! computes can be out of bounds. Only after that do we re-derive references with
//! `access_unchecked`.
//!
//! # Row indexes
//! Inside a layer segment nodes are addressed by a dense `u32` row (their rank by id).
//! A row is valid only within that layer generation.

#![allow(
    unsafe_code,
    reason = "re-deriving references to bytes validated at open"
)]

use crate::feature::{FEATURE_BOOL, FEATURE_FLOAT, FEATURE_INT, FEATURE_STR, StoredValue};
use crate::index::{ArchivedIndex, KdTree, SpatialIndex, check_tree};
use crate::view::{EdgeRef, SceneView};
use crate::{Aabb, FeatureRef, LayerId, Node, NodeId, Point, SceneGraph, SnapshotError};
use rkyv::collections::swiss_table::ArchivedHashMap;
use rkyv::string::ArchivedString;
use rkyv::vec::ArchivedVec;
use rkyv::{Archive, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// Version of the archived layout; bumped on every incompatible change.
pub const FORMAT_VERSION: u32 = 3;

/// Alignment an archived segment needs to be accessed in place (kd-tree leaves in archived
/// indexes need 128 bytes). Whatever carries segments (a `.ygg` file, the shared-memory
/// transport) must start each one at a multiple of it.
pub const ARCHIVE_ALIGN: usize = 128;

/// Bytes aligned for archived segments.
pub type SegmentBytes = rkyv::util::AlignedVec<ARCHIVE_ALIGN>;

/// Marks "no parent" in the parent column.
const NO_PARENT: u64 = u64::MAX;

/// One layer, as archived: columns indexed by row (rank of the node id in the layer).
#[derive(Archive, Serialize, Debug, Default)]
pub struct LayerSegment {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// The layer's id.
    pub layer: u32,
    /// The layer's generation.
    pub generation: u64,
    /// The layer's name.
    pub name: String,
    /// Strings used by this layer (labels, keys, string values, edge descriptions).
    pub strings: Vec<String>,
    /// Node ids, strictly ascending.
    pub ids: Vec<u64>,
    /// CSR offsets into `points` (rows + 1 entries).
    pub point_offsets: Vec<u32>,
    /// Every point of every node of the layer.
    pub points: Vec<[f32; 3]>,
    /// Parent id of each row (`u64::MAX` for none).
    pub parents: Vec<u64>,
    /// CSR offsets into `children`.
    pub child_offsets: Vec<u32>,
    /// Children ids (in other layers), ascending per row.
    pub children: Vec<u64>,
    /// CSR offsets into `out_targets` / `out_descriptions`.
    pub out_offsets: Vec<u32>,
    /// Target rows of out-edges, ascending by target id per row.
    pub out_targets: Vec<u32>,
    /// Description (string index) of each out-edge.
    pub out_descriptions: Vec<u32>,
    /// CSR offsets into `in_sources` / `in_descriptions`.
    pub in_offsets: Vec<u32>,
    /// Source rows of in-edges, ascending by source id per row.
    pub in_sources: Vec<u32>,
    /// Description (string index) of each in-edge.
    pub in_descriptions: Vec<u32>,
    /// CSR offsets into `labels`.
    pub label_offsets: Vec<u32>,
    /// Labels (string indexes).
    pub labels: Vec<u32>,
    /// CSR offsets into the feature columns.
    pub feature_offsets: Vec<u32>,
    /// Feature keys (string indexes).
    pub feature_keys: Vec<u32>,
    /// Feature kinds (string, int, float, bool).
    pub feature_kinds: Vec<u8>,
    /// Feature values: string index, i64 bits, f64 bits or 0/1.
    pub feature_bits: Vec<u64>,
    /// Rows whose bounding box is enabled and non-empty, ascending.
    pub aabb_rows: Vec<u32>,
    /// Their boxes, `[min, max]` flattened.
    pub aabbs: Vec<[f32; 6]>,
    /// Label -> `[start, end)` range of `label_postings`.
    pub label_index: HashMap<String, [u32; 2]>,
    /// Rows per label, ascending.
    pub label_postings: Vec<u32>,
    /// Feature key -> `[start, end)` range of `key_postings`.
    pub key_index: HashMap<String, [u32; 2]>,
    /// Rows per feature key, ascending.
    pub key_postings: Vec<u32>,
    /// The layer index, if enabled: a kd-tree over every point of the layer whose items
    /// are rows.
    pub layer_index: Option<KdTree>,
    /// The node indexes rooted at nodes of this layer, ascending by root.
    pub node_indexes: Vec<NodeIndexSegment>,
}

/// A node index as archived in its root's layer segment.
#[derive(Archive, Serialize, Debug)]
pub struct NodeIndexSegment {
    /// The root node.
    pub root: u64,
    /// Ids of the nodes with points in the root's sub-tree, ascending; an item is a
    /// position in this table.
    pub ids: Vec<u64>,
    /// A kd-tree over every point in the sub-tree.
    pub tree: KdTree,
}

/// A layer's entry in the manifest.
#[derive(Archive, Serialize, Debug, Default, Clone)]
pub struct ManifestLayer {
    /// The layer's id.
    pub id: u32,
    /// The layer's name.
    pub name: String,
    /// The generation of the layer segment that belongs to this cut.
    pub generation: u64,
    /// Number of nodes.
    pub node_count: u64,
    /// Smallest node id (`u64::MAX` when empty).
    pub min_id: u64,
    /// Largest node id (0 when empty).
    pub max_id: u64,
    /// DAG parents, ascending.
    pub parents: Vec<u32>,
    /// DAG children, ascending.
    pub children: Vec<u32>,
}

/// The manifest: which layers at which generations form one consistent cut, the layer
/// DAG, and the graph-level inverted indexes.
#[derive(Archive, Serialize, Debug, Default)]
pub struct Manifest {
    /// [`FORMAT_VERSION`] of the writer.
    pub version: u32,
    /// Generation of the whole cut (increases with every publish).
    pub generation: u64,
    /// Layers, ascending by id.
    pub layers: Vec<ManifestLayer>,
    /// Label -> layers holding it, ascending.
    pub label_layers: HashMap<String, Vec<u32>>,
    /// Feature key -> layers holding it, ascending.
    pub key_layers: HashMap<String, Vec<u32>>,
}

// ---- archiving the live graph ---------------------------------------------------------

/// Maps graph symbols to indexes in a layer segment's string table.
#[derive(Debug, Default)]
pub(crate) struct StringTable {
    index: rustc_hash::FxHashMap<u32, u32>,
}

impl StringTable {
    /// The index of `sym` in `strings`, appending the string on first use.
    fn get(&mut self, g: &SceneGraph, sym: u32, strings: &mut Vec<String>) -> u32 {
        *self.index.entry(sym).or_insert_with(|| {
            strings.push(g.strings.resolve(sym).to_owned());
            (strings.len() - 1) as u32
        })
    }
}

fn push_offset(offsets: &mut Vec<u32>, len: usize) {
    offsets.push(u32::try_from(len).expect("a layer column holds fewer than 2^32 entries"));
}

impl LayerSegment {
    /// A segment with no rows yet: header fields set, every offset column at `[0]`.
    pub(crate) fn empty(layer: LayerId, generation: u64, name: &str, rows: usize) -> Self {
        let mut s = LayerSegment {
            version: FORMAT_VERSION,
            layer: layer.0,
            generation,
            name: name.to_owned(),
            ..Default::default()
        };
        for o in s.offset_columns_mut() {
            o.reserve(rows + 1);
            o.push(0);
        }
        s.parents.reserve(rows);
        s
    }

    /// The CSR offset columns.
    fn offset_columns_mut(&mut self) -> [&mut Vec<u32>; 6] {
        [
            &mut self.point_offsets,
            &mut self.child_offsets,
            &mut self.out_offsets,
            &mut self.in_offsets,
            &mut self.label_offsets,
            &mut self.feature_offsets,
        ]
    }

    /// Rebuilds the label and key postings from the label and feature-key columns.
    pub(crate) fn rebuild_postings(&mut self) {
        let rows = self.ids.len();
        for (offsets, terms, index, postings) in [
            (
                &self.label_offsets,
                &self.labels,
                &mut self.label_index,
                &mut self.label_postings,
            ),
            (
                &self.feature_offsets,
                &self.feature_keys,
                &mut self.key_index,
                &mut self.key_postings,
            ),
        ] {
            let mut rows_by_term: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
            for row in 0..rows {
                for &term in &terms[offsets[row] as usize..offsets[row + 1] as usize] {
                    rows_by_term.entry(term).or_default().push(row as u32);
                }
            }
            index.clear();
            postings.clear();
            for (term, rows) in rows_by_term {
                let start = postings.len() as u32;
                postings.extend(rows);
                index.insert(
                    self.strings[term as usize].clone(),
                    [start, postings.len() as u32],
                );
            }
        }
    }
}

impl SceneGraph {
    /// Builds the archived columns of one layer.
    ///
    /// # Panics
    /// If `layer` does not exist.
    pub fn layer_segment(&self, layer: LayerId) -> LayerSegment {
        self.build_layer_segment(layer).0
    }

    /// [`SceneGraph::layer_segment`], also returning the symbol map of its string table.
    pub(crate) fn build_layer_segment(&self, layer: LayerId) -> (LayerSegment, StringTable) {
        let l = &self.layers[&layer];
        let mut ids: Vec<u64> = l.nodes.iter().map(|n| n.0).collect();
        ids.sort_unstable();
        let mut st = StringTable::default();
        let mut s = LayerSegment::empty(layer, l.generation, &l.name, ids.len());
        for (row, &id) in ids.iter().enumerate() {
            self.push_row(&mut s, &mut st, &self.nodes[&NodeId(id)], row as u32, &ids);
        }
        s.ids = ids;
        s.rebuild_postings();
        s.layer_index = self.archived_layer_index(layer, &s);
        s.node_indexes = self.archived_node_indexes(layer);
        (s, st)
    }

    /// Appends node `n` as row `row` to every per-row column of `s` (not `ids`, the
    /// postings or the spatial indexes). `ids` are the segment's sorted node ids, for
    /// edge rows.
    pub(crate) fn push_row(
        &self,
        s: &mut LayerSegment,
        st: &mut StringTable,
        n: &Node,
        row: u32,
        ids: &[u64],
    ) {
        let row_of = |id: NodeId| ids.binary_search(&id.0).expect("edge within layer") as u32;
        s.points.extend_from_slice(&n.points);
        push_offset(&mut s.point_offsets, s.points.len());
        s.parents.push(n.parent.map_or(NO_PARENT, |p| p.0));
        s.children.extend(n.children.iter().map(|c| c.0));
        push_offset(&mut s.child_offsets, s.children.len());
        for &(t, d) in &n.out_edges {
            s.out_targets.push(row_of(t));
            s.out_descriptions.push(st.get(self, d, &mut s.strings));
        }
        push_offset(&mut s.out_offsets, s.out_targets.len());
        for &(src, d) in &n.in_edges {
            s.in_sources.push(row_of(src));
            s.in_descriptions.push(st.get(self, d, &mut s.strings));
        }
        push_offset(&mut s.in_offsets, s.in_sources.len());
        for &lab in &n.labels {
            s.labels.push(st.get(self, lab, &mut s.strings));
        }
        push_offset(&mut s.label_offsets, s.labels.len());
        for &(k, v) in &n.features {
            s.feature_keys.push(st.get(self, k, &mut s.strings));
            let (kind, bits) = match v {
                StoredValue::Str(sym) => {
                    (FEATURE_STR, u64::from(st.get(self, sym, &mut s.strings)))
                }
                StoredValue::Int(v) => (FEATURE_INT, v as u64),
                StoredValue::Float(v) => (FEATURE_FLOAT, v.to_bits()),
                StoredValue::Bool(v) => (FEATURE_BOOL, u64::from(v)),
            };
            s.feature_kinds.push(kind);
            s.feature_bits.push(bits);
        }
        push_offset(&mut s.feature_offsets, s.feature_keys.len());
        if let (true, Some(b)) = (n.bbox_enabled, n.aabb) {
            s.aabb_rows.push(row);
            s.aabbs.push(b.to_array());
        }
    }

    /// Builds the manifest of the current graph (every layer at its current generation).
    pub fn manifest(&self, generation: u64) -> Manifest {
        let layers = self
            .layers
            .iter()
            .map(|(&id, l)| {
                let mut parents: Vec<u32> = l.parents.iter().map(|p| p.0).collect();
                let mut children: Vec<u32> = l.children.iter().map(|c| c.0).collect();
                parents.sort_unstable();
                children.sort_unstable();
                let (min_id, max_id) = l.id_bounds();
                ManifestLayer {
                    id: id.0,
                    name: l.name.clone(),
                    generation: l.generation,
                    node_count: l.nodes.len() as u64,
                    min_id,
                    max_id,
                    parents,
                    children,
                }
            })
            .collect();
        let graph_index = |m: &rustc_hash::FxHashMap<u32, Vec<LayerId>>| {
            m.iter()
                .map(|(&term, ls)| {
                    let mut v: Vec<u32> = ls.iter().map(|l| l.0).collect();
                    v.sort_unstable();
                    (self.strings.resolve(term).to_owned(), v)
                })
                .collect()
        };
        Manifest {
            version: FORMAT_VERSION,
            generation,
            layers,
            label_layers: graph_index(&self.label_layers),
            key_layers: graph_index(&self.key_layers),
        }
    }

    /// Archives the whole graph: the manifest and every layer segment.
    pub fn to_segments(&self) -> (SegmentBytes, Vec<SegmentBytes>) {
        let manifest = archive(&self.manifest(self.structure_generation));
        let layers = self
            .layers
            .keys()
            .map(|&l| archive(&self.layer_segment(l)))
            .collect();
        (manifest, layers)
    }

    /// Archives the graph into an in-memory, validated snapshot (the bytes a `.ygg` file
    /// would hold). Handy for tests and examples.
    pub fn to_snapshot(&self) -> SnapshotFile {
        let (manifest, layers) = self.to_segments();
        let mut segments: Vec<&[u8]> = vec![&manifest];
        segments.extend(layers.iter().map(|l| l.as_slice()));
        SnapshotFile::from_bytes(&pack_file(&segments), "in-memory snapshot")
            .expect("a freshly archived graph validates")
    }

    /// Writes the graph to a `.ygg` snapshot file.
    ///
    /// # Errors
    /// [`SnapshotError::Io`] when the file cannot be written.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), SnapshotError> {
        let path = path.as_ref();
        let (manifest, layers) = self.to_segments();
        let mut segments: Vec<&[u8]> = vec![&manifest];
        segments.extend(layers.iter().map(|l| l.as_slice()));
        let bytes = pack_file(&segments);
        std::fs::write(path, bytes).map_err(|source| SnapshotError::Io {
            path: path.display().to_string(),
            source,
        })
    }
}

/// Archives any serializable value into 128-aligned bytes.
pub fn archive<T>(value: &T) -> SegmentBytes
where
    T: for<'a> Serialize<
        rkyv::api::high::HighSerializer<
            SegmentBytes,
            rkyv::ser::allocator::ArenaHandle<'a>,
            rkyv::rancor::Error,
        >,
    >,
{
    rkyv::api::high::to_bytes_in::<_, rkyv::rancor::Error>(value, SegmentBytes::new())
        .expect("serializing plain columns into memory cannot fail")
}

/// A writer that only counts bytes: the first pass of archiving into a buffer of exact
/// size (a loaned shared-memory sample), so the archive is written once, in place.
#[derive(Default)]
struct ByteCounter {
    pos: usize,
}

impl rkyv::ser::Positional for ByteCounter {
    fn pos(&self) -> usize {
        self.pos
    }
}

impl<E> rkyv::ser::Writer<E> for ByteCounter {
    fn write(&mut self, bytes: &[u8]) -> Result<(), E> {
        self.pos += bytes.len();
        Ok(())
    }
}

type Serializer<'a, W> =
    rkyv::api::high::HighSerializer<W, rkyv::ser::allocator::ArenaHandle<'a>, rkyv::rancor::Error>;

fn archived_len_of<T>(value: &T) -> usize
where
    T: for<'a> Serialize<Serializer<'a, ByteCounter>>,
{
    rkyv::api::high::to_bytes_in::<_, rkyv::rancor::Error>(value, ByteCounter::default())
        .expect("counting bytes cannot fail")
        .pos
}

fn archive_into_slice<T>(value: &T, out: &mut [u8]) -> Result<usize, SnapshotError>
where
    T: for<'a, 'b> Serialize<Serializer<'a, rkyv::ser::writer::Buffer<'b>>>,
{
    use rkyv::ser::Positional;
    let len = out.len();
    let written = rkyv::api::high::to_bytes_in::<_, rkyv::rancor::Error>(
        value,
        rkyv::ser::writer::Buffer::from(out),
    )
    .map_err(|e| SnapshotError::Layout {
        what: "archive".into(),
        reason: format!("{len}-byte buffer: {e}"),
    })?
    .pos();
    Ok(written)
}

macro_rules! in_place_archiving {
    ($t:ty) => {
        impl $t {
            /// Exact size of this value's archive, for loaning a buffer of that size.
            pub fn archived_len(&self) -> usize {
                archived_len_of(self)
            }

            /// Archives straight into `out` (which must be 16-byte aligned and at least
            /// [`Self::archived_len`] bytes) and returns the bytes written.
            ///
            /// # Errors
            /// [`SnapshotError::Layout`] when `out` is too small.
            pub fn archive_into(&self, out: &mut [u8]) -> Result<usize, SnapshotError> {
                archive_into_slice(self, out)
            }
        }
    };
}

in_place_archiving!(LayerSegment);
in_place_archiving!(Manifest);

// ---- the .ygg file ------------------------------------------------------------------

/// First eight bytes of every `.ygg` file.
pub const FILE_MAGIC: &[u8; 8] = b"YGGSNAP\0";

fn align_up(n: usize) -> usize {
    n.div_ceil(ARCHIVE_ALIGN) * ARCHIVE_ALIGN
}

/// Lays segments out as a `.ygg` file: magic, version, count, `(offset, len)` table,
/// then each segment at a 128-aligned offset. The first segment is the manifest.
fn pack_file(segments: &[&[u8]]) -> Vec<u8> {
    let header = 16 + 16 * segments.len();
    let mut out = Vec::with_capacity(
        align_up(header) + segments.iter().map(|s| align_up(s.len())).sum::<usize>(),
    );
    out.extend_from_slice(FILE_MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(segments.len() as u32).to_le_bytes());
    let mut offset = align_up(header);
    for s in segments {
        out.extend_from_slice(&(offset as u64).to_le_bytes());
        out.extend_from_slice(&(s.len() as u64).to_le_bytes());
        offset = align_up(offset + s.len());
    }
    for s in segments {
        out.resize(align_up(out.len()), 0);
        out.extend_from_slice(s);
    }
    out
}

/// Reads the segment table of a `.ygg` file; every range is checked against `bytes`.
fn unpack_file(bytes: &[u8], what: &str) -> Result<Vec<std::ops::Range<usize>>, SnapshotError> {
    let layout = |reason: String| SnapshotError::Layout {
        what: what.to_owned(),
        reason,
    };
    if bytes.len() < 16 || &bytes[..8] != FILE_MAGIC {
        return Err(SnapshotError::BadMagic(what.to_owned()));
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let version = word(8);
    if version != FORMAT_VERSION {
        return Err(SnapshotError::SchemaVersion {
            what: what.to_owned(),
            found: version,
            expected: FORMAT_VERSION,
        });
    }
    let count = word(12) as usize;
    let table_end = count
        .checked_mul(16)
        .and_then(|t| t.checked_add(16))
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| {
            layout(format!(
                "segment table of {count} entries runs past the end of the file"
            ))
        })?;
    if count == 0 {
        return Err(layout("no manifest segment".into()));
    }
    let mut ranges = Vec::with_capacity(count);
    for i in 0..count {
        let at = 16 + 16 * i;
        let off = u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
        let len = u64::from_le_bytes(bytes[at + 8..at + 16].try_into().expect("8 bytes"));
        let end = off.checked_add(len).filter(|&e| e <= bytes.len() as u64);
        let (Some(end), true) = (end, off as usize >= table_end) else {
            return Err(layout(format!(
                "segment {i} ({off}+{len}) lies outside the file"
            )));
        };
        if !(off as usize).is_multiple_of(ARCHIVE_ALIGN) {
            return Err(layout(format!(
                "segment {i} at offset {off} is not {ARCHIVE_ALIGN}-byte aligned"
            )));
        }
        ranges.push(off as usize..end as usize);
    }
    Ok(ranges)
}

/// A `.ygg` snapshot file, memory-mapped and validated once at [`SnapshotFile::open`].
///
/// ```
/// # use ygg_store::{SceneGraph, SnapshotFile, SceneView, NodeId};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let rooms = g.add_layer("rooms")?;
/// g.add_node(NodeId(1), rooms)?;
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("scene.ygg");
/// g.save(&path)?;
/// let file = SnapshotFile::open(&path)?;
/// assert_eq!(file.view().node_count(), 1);
/// # Ok(()) }
/// ```
pub struct SnapshotFile {
    bytes: Backing,
    manifest: std::ops::Range<usize>,
    layers: Vec<std::ops::Range<usize>>,
}

enum Backing {
    Mapped(memmap2::Mmap),
    Owned(SegmentBytes),
}

impl Backing {
    fn as_slice(&self) -> &[u8] {
        match self {
            Backing::Mapped(m) => m,
            Backing::Owned(v) => v,
        }
    }
}

impl SnapshotFile {
    /// Memory-maps a `.ygg` file and validates every segment.
    ///
    /// # Errors
    /// I/O errors, a foreign or truncated file, or bytes that fail validation.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, SnapshotError> {
        let path = path.as_ref();
        let what = path.display().to_string();
        let io = |source| SnapshotError::Io {
            path: what.clone(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        if len == 0 {
            return Err(SnapshotError::BadMagic(what));
        }
        // SAFETY: the map is read-only and private to this process. Snapshot files are
        // written once and never modified in place (`save` writes a whole new file); a
        // concurrent truncation by another process is outside this contract (as for any
        // mmap-based reader) and documented on `SnapshotFile`.
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        Self::from_backing(Backing::Mapped(map), &what)
    }

    /// Validates snapshot-file bytes held in memory (copied into aligned storage).
    ///
    /// # Errors
    /// As [`SnapshotFile::open`].
    pub fn from_bytes(bytes: &[u8], what: &str) -> Result<Self, SnapshotError> {
        let mut v = SegmentBytes::with_capacity(bytes.len());
        v.extend_from_slice(bytes);
        Self::from_backing(Backing::Owned(v), what)
    }

    fn from_backing(bytes: Backing, what: &str) -> Result<Self, SnapshotError> {
        let data = bytes.as_slice();
        let mut ranges = unpack_file(data, what)?;
        let manifest_range = ranges.remove(0);
        let manifest = validate_manifest(&data[manifest_range.clone()], what)?;
        let mut layers = Vec::with_capacity(ranges.len());
        for (i, r) in ranges.iter().enumerate() {
            layers.push(validate_layer(
                &data[r.clone()],
                &format!("{what}: layer segment {i}"),
            )?);
        }
        ArchivedScene::new(manifest, layers).map_err(|reason| SnapshotError::Inconsistent {
            what: what.to_owned(),
            reason,
        })?;
        Ok(SnapshotFile {
            bytes,
            manifest: manifest_range,
            layers: ranges,
        })
    }

    /// The scene, queried in place.
    pub fn view(&self) -> ArchivedScene<'_> {
        let data = self.bytes.as_slice();
        // SAFETY: `from_backing` validated these exact ranges of these exact bytes with
        // `validate_manifest` / `validate_layer` (bytecheck + `check_layer`), and the
        // backing bytes are immutable for the life of `self`.
        let manifest =
            unsafe { rkyv::access_unchecked::<ArchivedManifest>(&data[self.manifest.clone()]) };
        let layers = self
            .layers
            .iter()
            // SAFETY: as above, each range was validated as an `ArchivedLayerSegment`.
            .map(|r| unsafe { rkyv::access_unchecked::<ArchivedLayerSegment>(&data[r.clone()]) })
            .collect();
        // `from_backing` ran `ArchivedScene::new` on this cut.
        ArchivedScene::new_prechecked(manifest, layers)
    }

    /// Size of the file in bytes.
    pub fn len(&self) -> usize {
        self.bytes.as_slice().len()
    }

    /// Whether the file is empty (never true for an opened snapshot).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes of each segment: the manifest's, then every layer segment's in manifest
    /// order (ascending layer id, as [`SceneView::layers`] lists them).
    pub fn segment_sizes(&self) -> (usize, Vec<usize>) {
        (
            self.manifest.len(),
            self.layers.iter().map(|r| r.len()).collect(),
        )
    }
}

/// Re-derives a layer segment from bytes that [`validate_layer`] accepted before.
///
/// # Safety
/// `bytes` must be exactly the bytes (same address, same length, unchanged since) that
/// an earlier call of [`validate_layer`] accepted.
pub unsafe fn layer_unchecked(bytes: &[u8]) -> &ArchivedLayerSegment {
    // SAFETY: the caller guarantees that `validate_layer` (bytecheck + `check_layer`)
    // accepted these very bytes and that they have not changed since.
    unsafe { rkyv::access_unchecked::<ArchivedLayerSegment>(bytes) }
}

/// Re-derives a manifest from bytes that [`validate_manifest`] accepted before.
///
/// # Safety
/// `bytes` must be exactly the bytes (same address, same length, unchanged since) that
/// an earlier call of [`validate_manifest`] accepted.
pub unsafe fn manifest_unchecked(bytes: &[u8]) -> &ArchivedManifest {
    // SAFETY: the caller guarantees that `validate_manifest` accepted these very bytes
    // and that they have not changed since.
    unsafe { rkyv::access_unchecked::<ArchivedManifest>(bytes) }
}

// ---- validation ---------------------------------------------------------------------

fn validation(what: &str, e: impl std::fmt::Display) -> SnapshotError {
    SnapshotError::Validation {
        what: what.to_owned(),
        reason: e.to_string(),
    }
}

/// Validates manifest bytes (bytecheck, version) and returns the archived manifest.
///
/// # Errors
/// Misaligned bytes, bytecheck failure, or a foreign version.
pub fn validate_manifest<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedManifest, SnapshotError> {
    check_alignment(bytes, what)?;
    let m = rkyv::access::<ArchivedManifest, rkyv::rancor::Error>(bytes)
        .map_err(|e| validation(what, e))?;
    if m.version.to_native() != FORMAT_VERSION {
        return Err(SnapshotError::SchemaVersion {
            what: what.to_owned(),
            found: m.version.to_native(),
            expected: FORMAT_VERSION,
        });
    }
    Ok(m)
}

/// Validates layer-segment bytes (bytecheck, version, [`check_layer`]).
///
/// # Errors
/// Misaligned bytes, bytecheck failure, a foreign version, or inconsistent columns.
pub fn validate_layer<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedLayerSegment, SnapshotError> {
    check_alignment(bytes, what)?;
    let l = rkyv::access::<ArchivedLayerSegment, rkyv::rancor::Error>(bytes)
        .map_err(|e| validation(what, e))?;
    if l.version.to_native() != FORMAT_VERSION {
        return Err(SnapshotError::SchemaVersion {
            what: what.to_owned(),
            found: l.version.to_native(),
            expected: FORMAT_VERSION,
        });
    }
    check_layer(l).map_err(|reason| SnapshotError::Inconsistent {
        what: what.to_owned(),
        reason,
    })?;
    Ok(l)
}

fn check_alignment(bytes: &[u8], what: &str) -> Result<(), SnapshotError> {
    if !(bytes.as_ptr() as usize).is_multiple_of(16) {
        return Err(SnapshotError::Layout {
            what: what.to_owned(),
            reason: "bytes are not 16-byte aligned".into(),
        });
    }
    Ok(())
}

fn u32s(v: &ArchivedVec<rkyv::rend::u32_le>) -> &[u32] {
    bytemuck::cast_slice(v.as_slice())
}

fn u64s(v: &ArchivedVec<rkyv::rend::u64_le>) -> &[u64] {
    bytemuck::cast_slice(v.as_slice())
}

/// Checks a CSR offsets column: `rows + 1` entries, starting at 0, non-decreasing,
/// ending at `len`.
fn check_offsets(name: &str, offsets: &[u32], rows: usize, len: usize) -> Result<(), String> {
    if offsets.len() != rows + 1 || offsets[0] != 0 || offsets[rows] as usize != len {
        return Err(format!(
            "{name}: {} offsets for {rows} rows and {len} entries",
            offsets.len()
        ));
    }
    if !offsets.is_sorted() {
        return Err(format!("{name}: offsets decrease"));
    }
    Ok(())
}

fn check_below(name: &str, values: &[u32], bound: usize) -> Result<(), String> {
    match values.iter().position(|&v| v as usize >= bound) {
        Some(i) => Err(format!(
            "{name}[{i}] = {} is out of range (< {bound})",
            values[i]
        )),
        None => Ok(()),
    }
}

/// The consistency pass run once per validated layer segment: everything an accessor
/// indexes is in range. Linear in the number of rows, edges, labels and features; the
/// point column itself is not scanned.
pub fn check_layer(l: &ArchivedLayerSegment) -> Result<(), String> {
    let ids = u64s(&l.ids);
    let rows = ids.len();
    if rows > u32::MAX as usize {
        return Err("too many rows".into());
    }
    if !ids.windows(2).all(|w| w[0] < w[1]) {
        return Err("node ids are not strictly ascending".into());
    }
    if ids.last() == Some(&u64::MAX) {
        return Err("reserved node id u64::MAX".into());
    }
    let nstr = l.strings.len();
    check_offsets(
        "point_offsets",
        u32s(&l.point_offsets),
        rows,
        l.points.len(),
    )?;
    if l.parents.len() != rows {
        return Err("parents column length differs from ids".into());
    }
    check_offsets(
        "child_offsets",
        u32s(&l.child_offsets),
        rows,
        l.children.len(),
    )?;
    check_offsets(
        "out_offsets",
        u32s(&l.out_offsets),
        rows,
        l.out_targets.len(),
    )?;
    check_offsets("in_offsets", u32s(&l.in_offsets), rows, l.in_sources.len())?;
    if l.out_descriptions.len() != l.out_targets.len()
        || l.in_descriptions.len() != l.in_sources.len()
    {
        return Err("edge description columns differ in length from edge columns".into());
    }
    check_below("out_targets", u32s(&l.out_targets), rows)?;
    check_below("in_sources", u32s(&l.in_sources), rows)?;
    check_below("out_descriptions", u32s(&l.out_descriptions), nstr)?;
    check_below("in_descriptions", u32s(&l.in_descriptions), nstr)?;
    check_offsets(
        "label_offsets",
        u32s(&l.label_offsets),
        rows,
        l.labels.len(),
    )?;
    check_below("labels", u32s(&l.labels), nstr)?;
    check_offsets(
        "feature_offsets",
        u32s(&l.feature_offsets),
        rows,
        l.feature_keys.len(),
    )?;
    let nfeat = l.feature_keys.len();
    if l.feature_kinds.len() != nfeat || l.feature_bits.len() != nfeat {
        return Err("feature columns differ in length".into());
    }
    check_below("feature_keys", u32s(&l.feature_keys), nstr)?;
    for (i, (&kind, bits)) in l
        .feature_kinds
        .iter()
        .zip(u64s(&l.feature_bits))
        .enumerate()
    {
        match kind {
            FEATURE_STR if *bits as usize >= nstr => {
                return Err(format!("feature {i}: string index {bits} out of range"));
            }
            FEATURE_STR | FEATURE_INT | FEATURE_FLOAT | FEATURE_BOOL => {}
            k => return Err(format!("feature {i}: unknown kind {k}")),
        }
    }
    let aabb_rows = u32s(&l.aabb_rows);
    if aabb_rows.len() != l.aabbs.len() || !aabb_rows.windows(2).all(|w| w[0] < w[1]) {
        return Err("aabb rows not strictly ascending or differ in length from boxes".into());
    }
    check_below("aabb_rows", aabb_rows, rows)?;
    for (name, index, postings) in [
        ("label", &l.label_index, &l.label_postings),
        ("key", &l.key_index, &l.key_postings),
    ] {
        let postings = u32s(postings);
        check_below(&format!("{name}_postings"), postings, rows)?;
        for (term, range) in index.iter() {
            let [s, e] = [range[0].to_native() as usize, range[1].to_native() as usize];
            if s > e || e > postings.len() {
                return Err(format!(
                    "{name} index entry {:?} has range {s}..{e} out of bounds",
                    term.as_str()
                ));
            }
        }
    }
    check_spatial_indexes(l, ids)
}

/// The spatial part of [`check_layer`]: every kd-tree passes [`check_tree`] with items
/// bounded by its id table, and node indexes are rooted at this layer's nodes.
fn check_spatial_indexes(l: &ArchivedLayerSegment, ids: &[u64]) -> Result<(), String> {
    if let Some(tree) = l.layer_index.as_ref() {
        check_tree(tree, ids.len()).map_err(|e| format!("layer index: {e}"))?;
    }
    let mut previous = None;
    for ni in l.node_indexes.iter() {
        let root = ni.root.to_native();
        if previous.is_some_and(|p| p >= root) || ids.binary_search(&root).is_err() {
            return Err(format!(
                "node index root {root} unsorted or not in this layer"
            ));
        }
        previous = Some(root);
        check_tree(&ni.tree, ni.ids.len()).map_err(|e| format!("node index {root}: {e}"))?;
    }
    Ok(())
}

/// Checks the manifest's layer DAG: unique names, mirrored edges, no cycle. Edges are
/// known to name listed layers.
fn check_dag(manifest: &ArchivedManifest) -> Result<(), String> {
    let mut names: Vec<&str> = manifest.layers.iter().map(|m| m.name.as_str()).collect();
    names.sort_unstable();
    if names.windows(2).any(|w| w[0] == w[1]) {
        return Err("two layers share a name".into());
    }
    let position = |id: u32| manifest.layers.iter().position(|m| m.id == id);
    for m in manifest.layers.iter() {
        for &c in u32s(&m.children) {
            let child = &manifest.layers[position(c).ok_or("unknown DAG child")?];
            if !u32s(&child.parents).contains(&m.id.to_native()) {
                return Err(format!("DAG edge {} -> {c} is not mirrored", m.id));
            }
        }
        for &p in u32s(&m.parents) {
            let parent = &manifest.layers[position(p).ok_or("unknown DAG parent")?];
            if !u32s(&parent.children).contains(&m.id.to_native()) {
                return Err(format!("DAG edge {p} -> {} is not mirrored", m.id));
            }
        }
    }
    // Kahn's algorithm: every layer must be removable, or the DAG has a cycle.
    let mut indegree: Vec<usize> = manifest.layers.iter().map(|m| m.parents.len()).collect();
    let mut ready: Vec<usize> = (0..indegree.len()).filter(|&i| indegree[i] == 0).collect();
    let mut removed = 0;
    while let Some(i) = ready.pop() {
        removed += 1;
        for &c in u32s(&manifest.layers[i].children) {
            let ci = position(c).ok_or("unknown DAG child")?;
            indegree[ci] = indegree[ci].saturating_sub(1);
            if indegree[ci] == 0 {
                ready.push(ci);
            }
        }
    }
    if removed != manifest.layers.len() {
        return Err("the layer DAG has a cycle".into());
    }
    Ok(())
}

// ---- the archived view ----------------------------------------------------------------

/// An archived inverted index: term -> `[start, end)` range of its posting column.
type ArchivedTermIndex = ArchivedHashMap<ArchivedString, [rkyv::rend::u32_le; 2]>;

/// A consistent cut of archived layers: the [`SceneView`] over validated bytes from a
/// `.ygg` file or from shared memory.
pub struct ArchivedScene<'a> {
    manifest: &'a ArchivedManifest,
    /// Layer segments in manifest order (ascending layer id).
    layers: Vec<&'a ArchivedLayerSegment>,
}

/// A node of an [`ArchivedScene`]: its layer's position in the manifest and its row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArchivedNodeRef {
    layer: u32,
    row: u32,
}

impl<'a> ArchivedScene<'a> {
    /// Joins a validated manifest with its validated layer segments, checking that they
    /// form the cut the manifest names (same layers, same generations, same counts).
    ///
    /// # Errors
    /// A description of the first mismatch.
    pub fn new(
        manifest: &'a ArchivedManifest,
        layers: Vec<&'a ArchivedLayerSegment>,
    ) -> Result<Self, String> {
        if manifest.layers.len() != layers.len() {
            return Err(format!(
                "manifest lists {} layers, {} segments given",
                manifest.layers.len(),
                layers.len()
            ));
        }
        for (i, (m, l)) in manifest.layers.iter().zip(&layers).enumerate() {
            if m.id != l.layer
                || m.generation != l.generation
                || m.node_count.to_native() != l.ids.len() as u64
            {
                return Err(format!(
                    "manifest entry {i} (layer {}, generation {}) does not match segment (layer {}, generation {})",
                    m.id, m.generation, l.layer, l.generation
                ));
            }
            if i > 0 && manifest.layers[i - 1].id >= m.id {
                return Err("manifest layers are not ascending".into());
            }
        }
        let known = |ids: &ArchivedVec<rkyv::rend::u32_le>| {
            u32s(ids)
                .iter()
                .all(|id| manifest.layers.iter().any(|m| m.id == *id))
        };
        for m in manifest.layers.iter() {
            if !known(&m.parents) || !known(&m.children) {
                return Err(format!("layer {} has a DAG edge to an unknown layer", m.id));
            }
        }
        check_dag(manifest)?;
        for ls in manifest
            .label_layers
            .values()
            .chain(manifest.key_layers.values())
        {
            if !known(ls) {
                return Err("graph index names an unknown layer".into());
            }
        }
        Ok(ArchivedScene { manifest, layers })
    }

    /// Joins a manifest with its layer segments that [`ArchivedScene::new`] already
    /// accepted, without checking them again (a reader builds a view per query on a
    /// snapshot it checked once). Given a cut `new` would refuse, queries may panic or
    /// answer wrongly, but stay memory-safe.
    pub fn new_prechecked(
        manifest: &'a ArchivedManifest,
        layers: Vec<&'a ArchivedLayerSegment>,
    ) -> Self {
        ArchivedScene { manifest, layers }
    }

    /// The manifest's generation.
    pub fn generation(&self) -> u64 {
        self.manifest.generation.to_native()
    }

    /// The generation of each layer in this cut, ascending by layer id.
    pub fn layer_generations(&self) -> impl Iterator<Item = (LayerId, u64)> + '_ {
        self.manifest
            .layers
            .iter()
            .map(|m| (LayerId(m.id.to_native()), m.generation.to_native()))
    }

    /// The segment of a layer.
    fn segment(&self, layer: LayerId) -> Option<(u32, &'a ArchivedLayerSegment)> {
        let i = self
            .manifest
            .layers
            .binary_search_by_key(&layer.0, |m| m.id.to_native())
            .ok()?;
        Some((i as u32, self.layers[i]))
    }

    fn seg(&self, n: ArchivedNodeRef) -> &'a ArchivedLayerSegment {
        self.layers[n.layer as usize]
    }

    fn string(seg: &'a ArchivedLayerSegment, i: u32) -> &'a str {
        seg.strings[i as usize].as_str()
    }

    fn range(offsets: &ArchivedVec<rkyv::rend::u32_le>, row: u32) -> std::ops::Range<usize> {
        let o = u32s(offsets);
        o[row as usize] as usize..o[row as usize + 1] as usize
    }

    fn postings(
        &self,
        layer: LayerId,
        term: &str,
        pick: fn(
            &'a ArchivedLayerSegment,
        ) -> (&'a ArchivedTermIndex, &'a ArchivedVec<rkyv::rend::u32_le>),
    ) -> impl Iterator<Item = ArchivedNodeRef> + 'a {
        let found = self.segment(layer).and_then(|(li, seg)| {
            let (index, postings) = pick(seg);
            let r = index.get(term)?;
            Some((
                li,
                &u32s(postings)[r[0].to_native() as usize..r[1].to_native() as usize],
            ))
        });
        found.into_iter().flat_map(|(li, rows)| {
            rows.iter()
                .map(move |&row| ArchivedNodeRef { layer: li, row })
        })
    }

    fn graph_layers(
        map: &'a ArchivedHashMap<ArchivedString, ArchivedVec<rkyv::rend::u32_le>>,
        term: &str,
    ) -> impl Iterator<Item = LayerId> + 'a {
        map.get(term)
            .into_iter()
            .flat_map(|v| u32s(v).iter().map(|&l| LayerId(l)))
    }
}

impl SceneView for ArchivedScene<'_> {
    type NodeRef<'b>
        = ArchivedNodeRef
    where
        Self: 'b;

    fn layers(&self) -> impl Iterator<Item = LayerId> + '_ {
        self.manifest
            .layers
            .iter()
            .map(|m| LayerId(m.id.to_native()))
    }

    fn layer_name(&self, layer: LayerId) -> Option<&str> {
        self.segment(layer).map(|(_, s)| s.name.as_str())
    }

    fn layer_by_name(&self, name: &str) -> Option<LayerId> {
        self.manifest
            .layers
            .iter()
            .find(|m| m.name == name)
            .map(|m| LayerId(m.id.to_native()))
    }

    fn layer_children(&self, layer: LayerId) -> Vec<LayerId> {
        self.segment(layer)
            .map(|(i, _)| {
                u32s(&self.manifest.layers[i as usize].children)
                    .iter()
                    .map(|&l| LayerId(l))
                    .collect()
            })
            .unwrap_or_default()
    }

    fn layer_parents(&self, layer: LayerId) -> Vec<LayerId> {
        self.segment(layer)
            .map(|(i, _)| {
                u32s(&self.manifest.layers[i as usize].parents)
                    .iter()
                    .map(|&l| LayerId(l))
                    .collect()
            })
            .unwrap_or_default()
    }

    fn layer_len(&self, layer: LayerId) -> usize {
        self.segment(layer).map_or(0, |(_, s)| s.ids.len())
    }

    fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = ArchivedNodeRef> + '_ {
        self.segment(layer).into_iter().flat_map(|(li, s)| {
            (0..s.ids.len() as u32).map(move |row| ArchivedNodeRef { layer: li, row })
        })
    }

    fn node(&self, id: NodeId) -> Option<ArchivedNodeRef> {
        for (li, m) in self.manifest.layers.iter().enumerate() {
            if !(m.min_id.to_native()..=m.max_id.to_native()).contains(&id.0) {
                continue;
            }
            if let Ok(row) = u64s(&self.layers[li].ids).binary_search(&id.0) {
                return Some(ArchivedNodeRef {
                    layer: li as u32,
                    row: row as u32,
                });
            }
        }
        None
    }

    fn node_id(&self, n: ArchivedNodeRef) -> NodeId {
        NodeId(u64s(&self.seg(n).ids)[n.row as usize])
    }

    fn node_layer(&self, n: ArchivedNodeRef) -> LayerId {
        LayerId(self.seg(n).layer.to_native())
    }

    fn points(&self, n: ArchivedNodeRef) -> &[Point] {
        let seg = self.seg(n);
        let points: &[Point] = bytemuck::cast_slice(seg.points.as_slice());
        &points[Self::range(&seg.point_offsets, n.row)]
    }

    fn parent(&self, n: ArchivedNodeRef) -> Option<NodeId> {
        let p = u64s(&self.seg(n).parents)[n.row as usize];
        (p != NO_PARENT).then_some(NodeId(p))
    }

    fn children(&self, n: ArchivedNodeRef) -> &[NodeId] {
        let seg = self.seg(n);
        let children: &[NodeId] = bytemuck::cast_slice(seg.children.as_slice());
        &children[Self::range(&seg.child_offsets, n.row)]
    }

    fn aabb(&self, n: ArchivedNodeRef) -> Option<Aabb> {
        let seg = self.seg(n);
        let i = u32s(&seg.aabb_rows).binary_search(&n.row).ok()?;
        let b: &[[f32; 6]] = bytemuck::cast_slice(seg.aabbs.as_slice());
        Some(Aabb::from_array(b[i]))
    }

    fn out_edges<'b>(&'b self, n: ArchivedNodeRef) -> impl Iterator<Item = EdgeRef<'b>> + 'b {
        let seg = self.seg(n);
        let ids = u64s(&seg.ids);
        let source = NodeId(ids[n.row as usize]);
        let r = Self::range(&seg.out_offsets, n.row);
        let targets = &u32s(&seg.out_targets)[r.clone()];
        let descs = &u32s(&seg.out_descriptions)[r];
        targets.iter().zip(descs).map(move |(&t, &d)| EdgeRef {
            source,
            target: NodeId(ids[t as usize]),
            description: Self::string(seg, d),
        })
    }

    fn in_edges<'b>(&'b self, n: ArchivedNodeRef) -> impl Iterator<Item = EdgeRef<'b>> + 'b {
        let seg = self.seg(n);
        let ids = u64s(&seg.ids);
        let target = NodeId(ids[n.row as usize]);
        let r = Self::range(&seg.in_offsets, n.row);
        let sources = &u32s(&seg.in_sources)[r.clone()];
        let descs = &u32s(&seg.in_descriptions)[r];
        sources.iter().zip(descs).map(move |(&s, &d)| EdgeRef {
            source: NodeId(ids[s as usize]),
            target,
            description: Self::string(seg, d),
        })
    }

    fn labels<'b>(&'b self, n: ArchivedNodeRef) -> impl Iterator<Item = &'b str> + 'b {
        let seg = self.seg(n);
        u32s(&seg.labels)[Self::range(&seg.label_offsets, n.row)]
            .iter()
            .map(move |&s| Self::string(seg, s))
    }

    fn features<'b>(
        &'b self,
        n: ArchivedNodeRef,
    ) -> impl Iterator<Item = (&'b str, FeatureRef<'b>)> + 'b {
        let seg = self.seg(n);
        let r = Self::range(&seg.feature_offsets, n.row);
        let keys = &u32s(&seg.feature_keys)[r.clone()];
        let kinds = &seg.feature_kinds[r.clone()];
        let bits = &u64s(&seg.feature_bits)[r];
        keys.iter()
            .zip(kinds)
            .zip(bits)
            .map(move |((&k, &kind), &b)| {
                let v = match kind {
                    FEATURE_STR => FeatureRef::Str(Self::string(seg, b as u32)),
                    FEATURE_INT => FeatureRef::Int(b as i64),
                    FEATURE_FLOAT => FeatureRef::Float(f64::from_bits(b)),
                    _ => FeatureRef::Bool(b != 0),
                };
                (Self::string(seg, k), v)
            })
    }

    fn layers_with_label(&self, label: &str) -> impl Iterator<Item = LayerId> {
        Self::graph_layers(&self.manifest.label_layers, label)
    }

    fn layers_with_key(&self, key: &str) -> impl Iterator<Item = LayerId> {
        Self::graph_layers(&self.manifest.key_layers, key)
    }

    fn nodes_with_label(
        &self,
        layer: LayerId,
        label: &str,
    ) -> impl Iterator<Item = ArchivedNodeRef> {
        self.postings(layer, label, |s| (&s.label_index, &s.label_postings))
    }

    fn nodes_with_key(&self, layer: LayerId, key: &str) -> impl Iterator<Item = ArchivedNodeRef> {
        self.postings(layer, key, |s| (&s.key_index, &s.key_postings))
    }

    fn layer_generation(&self, layer: LayerId) -> Option<u64> {
        self.segment(layer).map(|(_, s)| s.generation.to_native())
    }

    fn layer_index(&self, layer: LayerId) -> Option<impl SpatialIndex + '_> {
        let (_, seg) = self.segment(layer)?;
        // `check_layer` bounded the tree's items by the layer's rows.
        Some(ArchivedIndex::new(
            seg.layer_index.as_ref()?,
            u64s(&seg.ids),
        ))
    }

    fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
        let n = self.node(node)?;
        let seg = self.seg(n);
        let at = seg
            .node_indexes
            .binary_search_by_key(&node.0, |ni| ni.root.to_native())
            .ok()?;
        let ni = &seg.node_indexes[at];
        // `check_layer` bounded the tree's items by the index's id table.
        Some(ArchivedIndex::new(&ni.tree, u64s(&ni.ids)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn archiving_in_place_gives_the_same_bytes_as_archiving_to_a_vector() {
        let mut g = SceneGraph::new();
        let l = g.add_layer("objects").unwrap();
        for i in 0..50 {
            g.add_node(NodeId(i), l).unwrap();
            g.set_geometry(NodeId(i), vec![[i as f32, 1.0, 2.0]])
                .unwrap();
            g.add_label(NodeId(i), if i % 2 == 0 { "even" } else { "odd" })
                .unwrap();
        }
        let seg = g.layer_segment(l);
        let expected = archive(&seg);
        let len = seg.archived_len();
        assert_eq!(len, expected.len());
        let mut out = SegmentBytes::with_capacity(len);
        out.resize(len, 0);
        assert_eq!(seg.archive_into(&mut out).unwrap(), len);
        assert_eq!(out.as_slice(), expected.as_slice());
        validate_layer(&out, "in place").unwrap();
        let mut short = SegmentBytes::with_capacity(len);
        short.resize(len - 1, 0);
        assert!(seg.archive_into(&mut short).is_err());
    }
}
