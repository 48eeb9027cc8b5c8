//! The [`SceneView`] of an [`ArchivedScene`]: every method reads the validated columns in
//! place (ids by binary search in the part that may hold them, children as runs of
//! `by_parent` in each part, labels and keys through each part's archived inverted
//! indexes, spatial indexes as [`ArchivedIndex`], merged over a layer's parts by
//! [`PartedIndex`]).

use super::cut::{ArchivedNodeRef, ArchivedScene, ArchivedTermIndex};
use crate::feature::{FEATURE_FLOAT, FEATURE_INT, FEATURE_STR};
use crate::index::{ArchivedIndex, ArchivedKdTree, PartedIndex, RowPatch, SpatialIndex};
use crate::points::PointColumn;
use crate::snapshot::schema::{ArchivedLayerSegment, NO_PARENT, u32s, u64s};
use crate::view::{EdgeRef, SceneView};
use crate::{Aabb, FeatureRef, LayerId, NodeId, Points};
use rkyv::collections::swiss_table::ArchivedHashMap;
use rkyv::string::ArchivedString;
use rkyv::vec::ArchivedVec;
/// A node's children in an [`ArchivedScene`], ascending by id.
enum ArchivedChildren<'a> {
    /// Children in one layer: a run of its `by_parent` (rows, hence ids, ascending).
    Run {
        ids: &'a [u64],
        rows: std::slice::Iter<'a, u32>,
    },
    /// Children in several layers, merged.
    Merged(std::vec::IntoIter<NodeId>),
}

impl Iterator for ArchivedChildren<'_> {
    type Item = NodeId;

    fn next(&mut self) -> Option<NodeId> {
        match self {
            ArchivedChildren::Run { ids, rows } => rows.next().map(|&r| NodeId(ids[r as usize])),
            ArchivedChildren::Merged(ids) => ids.next(),
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        match self {
            ArchivedChildren::Run { rows, .. } => rows.size_hint(),
            ArchivedChildren::Merged(ids) => ids.size_hint(),
        }
    }
}

impl DoubleEndedIterator for ArchivedChildren<'_> {
    fn next_back(&mut self) -> Option<NodeId> {
        match self {
            ArchivedChildren::Run { ids, rows } => {
                rows.next_back().map(|&r| NodeId(ids[r as usize]))
            }
            ArchivedChildren::Merged(ids) => ids.next_back(),
        }
    }
}

impl ExactSizeIterator for ArchivedChildren<'_> {}

/// The rows of `seg` nested under `parent`: one run of its `by_parent`, found by binary
/// search (the validated column is sorted by parent; a row out of range sorts last).
fn rows_under(seg: &ArchivedLayerSegment, parent: u64) -> &[u32] {
    let parents = u64s(&seg.parents);
    let by_parent = u32s(&seg.by_parent);
    let key = |r: &u32| parents.get(*r as usize).copied().unwrap_or(u64::MAX);
    // Most layers below a room hold none of its children: two reads rule them out.
    match (by_parent.first(), by_parent.last()) {
        (Some(first), Some(last)) if key(first) <= parent && parent <= key(last) => {}
        _ => return &[],
    }
    let start = by_parent.partition_point(|r| key(r) < parent);
    let len = by_parent[start..].partition_point(|r| key(r) <= parent);
    &by_parent[start..start + len]
}

impl<'a> ArchivedScene<'a> {
    /// The nodes of part number `part` of layer `layer`, if the cut has that part.
    pub fn part_nodes(&self, layer: LayerId, part: u32) -> impl Iterator<Item = ArchivedNodeRef> {
        let parts = self.segment(layer).map_or(0..0, |(_, r)| r);
        let found = parts
            .into_iter()
            .find(|&p| self.parts[p].part.to_native() == part);
        found.into_iter().flat_map(move |p| {
            (0..self.parts[p].ids.len() as u32).map(move |row| ArchivedNodeRef {
                part: p as u32,
                row,
            })
        })
    }

    /// The part holding `node` and the position of the node index rooted at `node` in
    /// it, if there is one (its tree may be withheld).
    fn node_index_position(&self, node: NodeId) -> Option<(&'a ArchivedLayerSegment, usize)> {
        let seg = self.seg(self.node(node)?);
        let at = seg
            .node_indexes
            .binary_search_by_key(&node.0, |ni| ni.root.to_native())
            .ok()?;
        Some((seg, at))
    }

    /// Tree `slot` of part `part` of layer `layer` (id), which travels as a tree chunk.
    fn tree_chunk(&self, layer: u32, part: u32, slot: u32) -> Option<&'a ArchivedKdTree> {
        self.tree_chunk_segment(layer, part, slot).map(|t| &t.tree)
    }

    /// The point column of the part at `part`.
    fn point_column(&self, part: u32) -> PointColumn<'_> {
        let p = part as usize;
        match self.chunk_ranges.get(p) {
            Some(&[a, b]) if a < b => PointColumn::Chunked {
                chunks: self.chunk_points.get(a as usize..b as usize).unwrap_or(&[]),
                // At least 1 so that a position's chunk is defined even in a cut no
                // check accepted.
                chunk_len: (self.parts[p].point_chunk_len.to_native() as usize).max(1),
            },
            _ => PointColumn::Inline(bytemuck::cast_slice(self.parts[p].points.as_slice())),
        }
    }

    /// The manifest position of a layer and the range of its parts in `parts`.
    fn segment(&self, layer: LayerId) -> Option<(usize, std::ops::Range<usize>)> {
        let i = self
            .manifest
            .layers
            .binary_search_by_key(&layer.0, |m| m.id.to_native())
            .ok()?;
        Some((i, self.part_range(i)))
    }

    /// The range in `parts` of the parts of the layer at manifest position `i`.
    fn part_range(&self, i: usize) -> std::ops::Range<usize> {
        match self.part_start.get(i..=i + 1) {
            Some(&[a, b]) => a as usize..b as usize,
            _ => 0..0,
        }
    }

    fn seg(&self, n: ArchivedNodeRef) -> &'a ArchivedLayerSegment {
        self.parts[n.part as usize]
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
    ) -> impl Iterator<Item = ArchivedNodeRef> {
        let parts = self.segment(layer).map_or(0..0, |(_, r)| r);
        let segs = &self.parts[parts.clone()];
        parts.zip(segs).flat_map(move |(part, &seg)| {
            let (index, postings) = pick(seg);
            let rows = index.get(term).map_or(&[][..], |r| {
                &u32s(postings)[r[0].to_native() as usize..r[1].to_native() as usize]
            });
            rows.iter().map(move |&row| ArchivedNodeRef {
                part: part as u32,
                row,
            })
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

    /// The index of the part at `part` of layer `layer` (id), if it has one.
    fn part_index(&self, layer: u32, part: usize) -> Option<ArchivedIndex<'_>> {
        let seg = self.parts[part];
        let index = seg.layer_index.as_ref()?;
        let tree = match index.tree_chunk.as_ref() {
            Some(_) => self.tree_chunk(layer, seg.part.to_native(), 0)?,
            None => &index.tree,
        };
        let patch = RowPatch::new(
            index.base_rows.to_native(),
            u32s(&index.patched),
            u32s(&seg.point_offsets),
            self.point_column(part as u32),
        );
        // `check_layer` (or, for a tree chunk, `validate_tree_chunk` and the join) bounded
        // the tree's items by its base rows, and the patched rows by the part's rows.
        Some(ArchivedIndex::patched(tree, u64s(&seg.ids), patch))
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
        self.segment(layer)
            .map(|(i, _)| self.structure.layers[i].name.as_str())
    }

    fn layer_by_name(&self, name: &str) -> Option<LayerId> {
        self.structure
            .layers
            .iter()
            .find(|m| m.name == name)
            .map(|m| LayerId(m.id.to_native()))
    }

    fn layer_children(&self, layer: LayerId) -> Vec<LayerId> {
        self.segment(layer)
            .map(|(i, _)| {
                u32s(&self.structure.layers[i].children)
                    .iter()
                    .map(|&l| LayerId(l))
                    .collect()
            })
            .unwrap_or_default()
    }

    fn layer_parents(&self, layer: LayerId) -> Vec<LayerId> {
        self.segment(layer)
            .map(|(i, _)| {
                u32s(&self.structure.layers[i].parents)
                    .iter()
                    .map(|&l| LayerId(l))
                    .collect()
            })
            .unwrap_or_default()
    }

    fn layer_len(&self, layer: LayerId) -> usize {
        self.segment(layer)
            .map_or(0, |(_, parts)| parts.map(|p| self.parts[p].ids.len()).sum())
    }

    fn layer_nodes(&self, layer: LayerId) -> impl Iterator<Item = ArchivedNodeRef> + '_ {
        let parts = self.segment(layer).map_or(0..0, |(_, r)| r);
        parts.flat_map(|part| {
            (0..self.parts[part].ids.len() as u32).map(move |row| ArchivedNodeRef {
                part: part as u32,
                row,
            })
        })
    }

    fn node(&self, id: NodeId) -> Option<ArchivedNodeRef> {
        for (li, m) in self.manifest.layers.iter().enumerate() {
            if !(m.min_id.to_native()..=m.max_id.to_native()).contains(&id.0) {
                continue;
            }
            let parts = self.part_range(li);
            // Parts ascend by id (the join checked it): the last one starting at or
            // below `id` is the only one that may hold it.
            let segs = &self.parts[parts.clone()];
            let k = segs
                .partition_point(|p| u64s(&p.ids).first().is_some_and(|&f| f <= id.0))
                .saturating_sub(1);
            let Some(seg) = segs.get(k) else {
                continue;
            };
            if let Ok(row) = u64s(&seg.ids).binary_search(&id.0) {
                return Some(ArchivedNodeRef {
                    part: (parts.start + k) as u32,
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

    fn points(&self, n: ArchivedNodeRef) -> Points<'_> {
        let seg = self.seg(n);
        self.point_column(n.part)
            .range(Self::range(&seg.point_offsets, n.row))
    }

    fn parent(&self, n: ArchivedNodeRef) -> Option<NodeId> {
        let p = u64s(&self.seg(n).parents)[n.row as usize];
        (p != NO_PARENT).then_some(NodeId(p))
    }

    fn children(
        &self,
        n: ArchivedNodeRef,
    ) -> impl DoubleEndedIterator<Item = NodeId> + ExactSizeIterator + '_ {
        let parent = u64s(&self.seg(n).ids)[n.row as usize];
        // Nesting follows the DAG, so the children lie in the layer's DAG children;
        // usually in one of them (no copy), else merged.
        let mut run: Option<(&[u64], &[u32])> = None;
        let mut merged = Vec::new();
        let layer = self.layer_position(n.part);
        for &child_layer in u32s(&self.structure.layers[layer].children) {
            let Some((_, parts)) = self.segment(LayerId(child_layer)) else {
                continue;
            };
            for &seg in &self.parts[parts] {
                let rows = rows_under(seg, parent);
                if rows.is_empty() {
                    continue;
                }
                let ids = u64s(&seg.ids);
                if run.is_none() && merged.is_empty() {
                    run = Some((ids, rows));
                    continue;
                }
                if let Some((first_ids, first_rows)) = run.take() {
                    merged.extend(first_rows.iter().map(|&r| NodeId(first_ids[r as usize])));
                }
                merged.extend(rows.iter().map(|&r| NodeId(ids[r as usize])));
            }
        }
        if merged.is_empty() {
            let (ids, rows) = run.unwrap_or((&[], &[]));
            ArchivedChildren::Run {
                ids,
                rows: rows.iter(),
            }
        } else {
            // Runs ascending each: the stable sort merges them in linear time.
            merged.sort();
            ArchivedChildren::Merged(merged.into_iter())
        }
    }

    fn aabb(&self, n: ArchivedNodeRef) -> Option<Aabb> {
        let seg = self.seg(n);
        let i = u32s(&seg.aabb_rows).binary_search(&n.row).ok()?;
        let b: &[[f32; 6]] = bytemuck::cast_slice(seg.aabbs.as_slice());
        Some(Aabb::from_array(b[i]))
    }

    fn out_edges<'b>(&'b self, n: ArchivedNodeRef) -> impl Iterator<Item = EdgeRef<'b>> + 'b {
        let seg = self.seg(n);
        let source = NodeId(u64s(&seg.ids)[n.row as usize]);
        let r = Self::range(&seg.out_offsets, n.row);
        let targets = &u64s(&seg.out_targets)[r.clone()];
        let descs = &u32s(&seg.out_descriptions)[r];
        targets.iter().zip(descs).map(move |(&t, &d)| EdgeRef {
            source,
            target: NodeId(t),
            description: Self::string(seg, d),
        })
    }

    fn in_edges<'b>(&'b self, n: ArchivedNodeRef) -> impl Iterator<Item = EdgeRef<'b>> + 'b {
        let seg = self.seg(n);
        let target = NodeId(u64s(&seg.ids)[n.row as usize]);
        let r = Self::range(&seg.in_offsets, n.row);
        let sources = &u64s(&seg.in_sources)[r.clone()];
        let descs = &u32s(&seg.in_descriptions)[r];
        sources.iter().zip(descs).map(move |(&s, &d)| EdgeRef {
            source: NodeId(s),
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
        Self::graph_layers(&self.structure.label_layers, label)
    }

    fn layers_with_key(&self, key: &str) -> impl Iterator<Item = LayerId> {
        Self::graph_layers(&self.structure.key_layers, key)
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
        self.segment(layer)
            .map(|(i, _)| self.manifest.layers[i].generation.to_native())
    }

    fn layer_index(&self, layer: LayerId) -> Option<impl SpatialIndex + '_> {
        let (_, parts) = self.segment(layer)?;
        let mut indexes = parts.map(|p| self.part_index(layer.0, p));
        // Every part of an indexed layer has an index (or the layer has none).
        let first = indexes.next()??;
        let rest: Option<Vec<_>> = indexes.collect();
        Some(PartedIndex::new(first, rest?))
    }

    fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
        let (seg, at) = self.node_index_position(node)?;
        let ni = &seg.node_indexes[at];
        let tree = match ni.tree_chunk.as_ref() {
            Some(_) => {
                self.tree_chunk(seg.layer.to_native(), seg.part.to_native(), 1 + at as u32)?
            }
            // A publishing writer withholds small trees: the sub-tree is walked instead.
            None if ni.tree.size() == 0 => return None,
            None => &ni.tree,
        };
        // `check_layer` (or, for a tree chunk, `validate_tree_chunk` and the join) bounded
        // the tree's items by the index's id table.
        Some(ArchivedIndex::new(tree, u64s(&ni.ids)))
    }

    fn has_node_index(&self, node: NodeId) -> bool {
        self.node_index_position(node).is_some()
    }
}
