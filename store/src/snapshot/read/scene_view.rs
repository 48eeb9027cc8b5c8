//! The [`SceneView`] of an [`ArchivedScene`]: every method reads the validated columns in
//! place (ids by binary search, children as runs of `by_parent`, labels and keys through
//! the archived inverted indexes, spatial indexes as [`ArchivedIndex`]).

use super::cut::{ArchivedNodeRef, ArchivedScene, ArchivedTermIndex};
use crate::feature::{FEATURE_FLOAT, FEATURE_INT, FEATURE_STR};
use crate::index::{ArchivedIndex, ArchivedKdTree, RowPatch, SpatialIndex};
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
    /// The segment of `node`'s layer and the position of the node index rooted at
    /// `node` in it, if there is one (its tree may be withheld).
    fn node_index_position(&self, node: NodeId) -> Option<(&'a ArchivedLayerSegment, usize)> {
        let seg = self.seg(self.node(node)?);
        let at = seg
            .node_indexes
            .binary_search_by_key(&node.0, |ni| ni.root.to_native())
            .ok()?;
        Some((seg, at))
    }

    /// Tree `slot` of layer `layer` (id), which travels as a tree chunk.
    fn tree_chunk(&self, layer: u32, slot: u32) -> Option<&'a ArchivedKdTree> {
        let at = self
            .index_trees
            .binary_search_by_key(&(layer, slot), |(key, _)| *key)
            .ok()?;
        Some(self.index_trees[at].1)
    }

    /// The point column of the layer at manifest position `layer`.
    fn point_column(&self, layer: u32) -> PointColumn<'_> {
        let l = layer as usize;
        match self.chunk_start.get(l..=l + 1) {
            Some(&[a, b]) if a < b => PointColumn::Chunked {
                chunks: self.chunks.get(a as usize..b as usize).unwrap_or(&[]),
                // At least 1 so that a position's chunk is defined even in a cut no
                // check accepted.
                chunk_len: (self.layers[l].point_chunk_len.to_native() as usize).max(1),
            },
            _ => PointColumn::Inline(bytemuck::cast_slice(self.layers[l].points.as_slice())),
        }
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

    fn points(&self, n: ArchivedNodeRef) -> Points<'_> {
        let seg = self.seg(n);
        self.point_column(n.layer)
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
        for &child_layer in u32s(&self.manifest.layers[n.layer as usize].children) {
            let Some((_, seg)) = self.segment(LayerId(child_layer)) else {
                continue;
            };
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
        let (position, seg) = self.segment(layer)?;
        let index = seg.layer_index.as_ref()?;
        let tree = match index.tree_chunk.as_ref() {
            Some(_) => self.tree_chunk(seg.layer.to_native(), 0)?,
            None => &index.tree,
        };
        let patch = RowPatch::new(
            index.base_rows.to_native(),
            u32s(&index.patched),
            u32s(&seg.point_offsets),
            self.point_column(position),
        );
        // `check_layer` (or, for a tree chunk, `validate_tree_chunk` and the join) bounded
        // the tree's items by its base rows, and the patched rows by the layer's rows.
        Some(ArchivedIndex::patched(tree, u64s(&seg.ids), patch))
    }

    fn node_index(&self, node: NodeId) -> Option<impl SpatialIndex + '_> {
        let (seg, at) = self.node_index_position(node)?;
        let ni = &seg.node_indexes[at];
        let tree = match ni.tree_chunk.as_ref() {
            Some(_) => self.tree_chunk(seg.layer.to_native(), 1 + at as u32)?,
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
