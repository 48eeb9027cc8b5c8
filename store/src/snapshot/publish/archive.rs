//! Archiving the live graph: [`SceneGraph::layer_segment`], [`SceneGraph::manifest`],
//! [`SceneGraph::structure`], [`SceneGraph::to_segments`], the snapshot copies of its spatial indexes, and
//! archiving straight into a loaned buffer (`archived_len`, `archive_into`).

use super::chunk_source::{PointChunkSource, TreeChunkSource};
use crate::bytes::{SegmentBytes, archive};
use crate::feature::{FEATURE_BOOL, FEATURE_FLOAT, FEATURE_INT, FEATURE_STR, StoredValue};
use crate::index::{ArchivedKdTree, build_tree};
use crate::snapshot::schema::{
    FORMAT_VERSION, LayerIndexSegment, LayerSegment, Manifest, ManifestLayer, NO_PARENT,
    NodeIndexSegment, PointChunk, Structure, StructureLayer, TreeChunk,
};
use crate::{LayerId, Node, NodeId, Point, SceneGraph, SnapshotError};
use rkyv::Serialize;

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
    fn offset_columns_mut(&mut self) -> [&mut Vec<u32>; 5] {
        [
            &mut self.point_offsets,
            &mut self.out_offsets,
            &mut self.in_offsets,
            &mut self.label_offsets,
            &mut self.feature_offsets,
        ]
    }

    /// Rebuilds the label and key postings from the label and feature-key columns: a
    /// counting sort of the rows by term (string index), terms ascending, rows
    /// ascending within each.
    pub(crate) fn rebuild_postings(&mut self) {
        let terms = self.strings.len();
        for (offsets, column, index, postings) in [
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
            // starts[t + 1] counts term t's rows, then becomes where they start.
            let mut starts = vec![0u32; terms + 1];
            for &term in column.iter() {
                starts[term as usize + 1] += 1;
            }
            for t in 0..terms {
                starts[t + 1] += starts[t];
            }
            index.clear();
            for (t, w) in starts.windows(2).enumerate() {
                if w[0] < w[1] {
                    index.insert(self.strings[t].clone(), [w[0], w[1]]);
                }
            }
            postings.clear();
            postings.resize(column.len(), 0);
            let mut next = starts;
            for (row, w) in offsets.windows(2).enumerate() {
                for &term in &column[w[0] as usize..w[1] as usize] {
                    let at = &mut next[term as usize];
                    postings[*at as usize] = row as u32;
                    *at += 1;
                }
            }
        }
    }
}

impl LayerSegment {
    /// The layer index's live entries as `(row, point)`, sorted by row and then by the
    /// point's bits (`None` without a layer index): the base tree's entries that the
    /// patch leaves alive plus the patched rows' points. Equal for two segments whose
    /// indexes answer every query alike, however patched; for tests and tools (it
    /// archives the base tree to read it).
    pub fn layer_index_entries(&self) -> Option<Vec<(u32, Point)>> {
        let index = self.layer_index.as_ref()?;
        let rows = self.ids.len() as u32;
        let dead = |row: u32| row >= rows || index.patched.binary_search(&row).is_ok();
        let bytes = archive(&index.tree);
        let tree = rkyv::access::<ArchivedKdTree, rkyv::rancor::Error>(&bytes)
            .expect("a tree archived just now is valid");
        let mut entries: Vec<(u32, Point)> = tree.iter().filter(|(row, _)| !dead(*row)).collect();
        for &row in &index.patched {
            let r = self.point_offsets[row as usize] as usize
                ..self.point_offsets[row as usize + 1] as usize;
            entries.extend(self.points[r].iter().map(|p| (row, *p)));
        }
        entries.sort_unstable_by_key(|(row, p)| (*row, p.map(f32::to_bits)));
        Some(entries)
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
        let mut ids: Vec<u64> = self.layers[&layer].nodes.iter().map(|n| n.0).collect();
        ids.sort_unstable();
        self.build_part_segment(layer, 0, ids)
    }

    /// The segment of part `part` of `layer`: the rows of the nodes `ids` (ascending, all
    /// of the layer), at the layer's current generation, with the node indexes rooted at
    /// them.
    pub(crate) fn build_part_segment(
        &self,
        layer: LayerId,
        part: u32,
        ids: Vec<u64>,
    ) -> (LayerSegment, StringTable) {
        let l = &self.layers[&layer];
        let mut st = StringTable::default();
        let mut s = LayerSegment::empty(layer, l.generation, &l.name, ids.len());
        s.part = part;
        for (row, &id) in ids.iter().enumerate() {
            self.push_row(&mut s, &mut st, &self.nodes[&NodeId(id)], row as u32);
        }
        s.ids = ids;
        s.rebuild_postings();
        s.rebuild_by_parent();
        s.layer_index = self.archived_layer_index(layer, &s);
        s.node_indexes = self.archived_node_indexes(layer, &s.ids);
        (s, st)
    }

    /// Appends node `n` as row `row` to every per-row column of `s` (not `ids`, the
    /// postings or the spatial indexes).
    pub(crate) fn push_row(&self, s: &mut LayerSegment, st: &mut StringTable, n: &Node, row: u32) {
        s.points.extend_from_slice(&n.points);
        push_offset(&mut s.point_offsets, s.points.len());
        self.push_row_except_points(s, st, n, row);
    }

    /// [`SceneGraph::push_row`] for every column but the points and their offsets.
    pub(crate) fn push_row_except_points(
        &self,
        s: &mut LayerSegment,
        st: &mut StringTable,
        n: &Node,
        row: u32,
    ) {
        s.parents.push(n.parent.map_or(NO_PARENT, |p| p.0));
        for &(t, d) in &n.out_edges {
            s.out_targets.push(t.0);
            s.out_descriptions.push(st.get(self, d, &mut s.strings));
        }
        push_offset(&mut s.out_offsets, s.out_targets.len());
        for &(src, d) in &n.in_edges {
            s.in_sources.push(src.0);
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

    /// Builds the structure of the current graph at generation `generation` (each layer
    /// in one part).
    pub fn structure(&self, generation: u64) -> Structure {
        let layers = self
            .layers
            .iter()
            .map(|(&id, l)| {
                let mut parents: Vec<u32> = l.parents.iter().map(|p| p.0).collect();
                let mut children: Vec<u32> = l.children.iter().map(|c| c.0).collect();
                parents.sort_unstable();
                children.sort_unstable();
                StructureLayer {
                    id: id.0,
                    name: l.name.clone(),
                    parents,
                    children,
                    parts: vec![0],
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
        Structure {
            version: FORMAT_VERSION,
            generation,
            layers,
            label_layers: graph_index(&self.label_layers),
            key_layers: graph_index(&self.key_layers),
        }
    }

    /// Builds the manifest of the current graph (every layer at its current generation),
    /// of cut `generation` with the structure of generation `structure`.
    pub fn manifest(&self, generation: u64, structure: u64) -> Manifest {
        let layers = self
            .layers
            .iter()
            .map(|(&id, l)| {
                let (min_id, max_id) = l.id_bounds();
                ManifestLayer {
                    id: id.0,
                    generation: l.generation,
                    node_count: l.nodes.len() as u64,
                    min_id,
                    max_id,
                }
            })
            .collect();
        Manifest {
            version: FORMAT_VERSION,
            generation,
            structure,
            layers,
        }
    }

    /// Archives the whole graph, each layer in one part (structure and cut of generation
    /// 1).
    pub fn to_segments(&self) -> ArchivedGraph {
        ArchivedGraph {
            manifest: archive(&self.manifest(1, 1)),
            structure: archive(&self.structure(1)),
            layers: self
                .layers
                .keys()
                .map(|&l| archive(&self.layer_segment(l)))
                .collect(),
        }
    }
}

/// A whole graph archived ([`SceneGraph::to_segments`]).
#[derive(Debug)]
pub struct ArchivedGraph {
    /// The manifest.
    pub manifest: SegmentBytes,
    /// The structure.
    pub structure: SegmentBytes,
    /// Each layer's segment (one part each), ascending by layer id.
    pub layers: Vec<SegmentBytes>,
}

impl ArchivedGraph {
    /// Bytes of every segment together.
    pub fn len(&self) -> usize {
        self.manifest.len()
            + self.structure.len()
            + self.layers.iter().map(|l| l.len()).sum::<usize>()
    }

    /// Whether no segment holds a byte (never: a manifest always does).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
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
in_place_archiving!(Structure);
in_place_archiving!(PointChunk);
in_place_archiving!(PointChunkSource<'_>);
in_place_archiving!(TreeChunk);
in_place_archiving!(TreeChunkSource<'_>);

impl SceneGraph {
    /// The index of `layer` for a snapshot, if it has one: a kd-tree over the points of
    /// `segment` (the layer's columns) whose items are rows.
    ///
    /// The index is fresh: its base tree holds every point, nothing is patched.
    pub(crate) fn archived_layer_index(
        &self,
        layer: LayerId,
        segment: &LayerSegment,
    ) -> Option<LayerIndexSegment> {
        self.indexes.layers.get(&layer)?;
        let mut entries = Vec::with_capacity(segment.points.len());
        for (row, w) in segment.point_offsets.windows(2).enumerate() {
            entries.extend(
                segment.points[w[0] as usize..w[1] as usize]
                    .iter()
                    .map(|p| (row as u32, *p)),
            );
        }
        Some(LayerIndexSegment {
            base_rows: segment.ids.len() as u32,
            base_points: entries.len() as u32,
            tree: build_tree(&entries),
            tree_chunk: None,
            patched: Vec::new(),
        })
    }

    /// The node indexes rooted at nodes `ids` (ascending) of `layer` for a snapshot,
    /// ascending by root: items are positions in each index's sorted id table.
    pub(crate) fn archived_node_indexes(
        &self,
        layer: LayerId,
        ids: &[u64],
    ) -> Vec<NodeIndexSegment> {
        let mut roots: Vec<NodeId> = self
            .indexes
            .nodes
            .keys()
            .copied()
            .filter(|r| self.nodes[r].layer == layer && ids.binary_search(&r.0).is_ok())
            .collect();
        roots.sort_unstable();
        roots
            .into_iter()
            .map(|root| self.archived_node_index(root))
            .collect()
    }

    /// The node index rooted at `root` for a snapshot (`root` must have one): items are
    /// positions in its sorted id table.
    pub(crate) fn archived_node_index(&self, root: NodeId) -> NodeIndexSegment {
        let mut members = self.indexed_members(root);
        members.sort_unstable_by_key(|m| m.0);
        let mut entries = Vec::new();
        for (i, (_, points)) in members.iter().enumerate() {
            entries.extend(points.iter().map(|p| (i as u32, *p)));
        }
        NodeIndexSegment {
            root: root.0,
            ids: members.iter().map(|m| m.0.0).collect(),
            tree: build_tree(&entries),
            tree_chunk: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::validate_layer;

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
