//! [`ArchivedScene`]: a consistent cut of validated archived segments, joined and checked
//! (the manifest's structure, each layer segment, point chunk and tree chunk against the
//! entry that names it). Its [`crate::SceneView`] is in `scene_view.rs`.

use super::chunk_check::{check_chunk_matches, check_tree_chunk_matches, chunk_points};
use super::rejoin::KnownParts;
use super::validate::{LayerPositions, check_dag};
use crate::index::ArchivedKdTree;
use crate::snapshot::schema::{
    ArchivedLayerSegment, ArchivedManifest, ArchivedPointChunk, ArchivedTreeChunk,
    ArchivedTreeChunkRef, u32s,
};
use crate::{LayerId, Point};
use rkyv::collections::swiss_table::ArchivedHashMap;
use rkyv::string::ArchivedString;
use rkyv::vec::ArchivedVec;

/// An archived inverted index: term -> `[start, end)` range of its posting column.
pub(super) type ArchivedTermIndex = ArchivedHashMap<ArchivedString, [rkyv::rend::u32_le; 2]>;

/// A consistent cut of archived layers: the [`crate::SceneView`] over validated bytes from a
/// `.ygg` file or from shared memory.
pub struct ArchivedScene<'a> {
    pub(super) manifest: &'a ArchivedManifest,
    /// Layer segments in manifest order (ascending layer id).
    pub(super) layers: Vec<&'a ArchivedLayerSegment>,
    /// The points of every chunk of every chunked layer, in layer and column order.
    pub(super) chunks: Vec<&'a [Point]>,
    /// Per layer position (and one past the last), where its chunks start in `chunks`;
    /// empty when no layer is chunked.
    pub(super) chunk_start: Vec<u32>,
    /// The trees that travel as tree chunks, by (layer id, slot), ascending: slot 0 is
    /// a layer index's base tree, slot `1 + i` the tree of the layer's node index `i`.
    pub(super) index_trees: Vec<((u32, u32), &'a ArchivedKdTree)>,
}

/// Checks what a manifest's bytecheck does not and depends on nothing but its structure:
/// layer ids ascending, DAG edges and term lists naming listed layers, the DAG itself.
fn check_structure(manifest: &ArchivedManifest) -> Result<(), String> {
    let ids = manifest.layers.iter().map(|m| m.id.to_native());
    if ids.clone().zip(ids.skip(1)).any(|(a, b)| a >= b) {
        return Err("manifest layers are not ascending".into());
    }
    // Ascending (checked above): each id is found in a table or by binary search.
    let positions = LayerPositions::new(manifest);
    let known = |ids: &ArchivedVec<rkyv::rend::u32_le>| {
        u32s(ids).iter().all(|&id| positions.get(id).is_some())
    };
    for m in manifest.layers.iter() {
        if !known(&m.parents) || !known(&m.children) {
            return Err(format!("layer {} has a DAG edge to an unknown layer", m.id));
        }
    }
    check_dag(manifest, &positions)?;
    for ls in manifest
        .label_layers
        .values()
        .chain(manifest.key_layers.values())
    {
        if !known(ls) {
            return Err("graph index names an unknown layer".into());
        }
    }
    Ok(())
}

/// A node of an [`ArchivedScene`]: its layer's position in the manifest and its row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArchivedNodeRef {
    pub(super) layer: u32,
    pub(super) row: u32,
}

impl<'a> ArchivedScene<'a> {
    /// Joins a validated manifest with its validated layer segments, the validated point
    /// chunks of its chunked layers (in layer order, then column order) and the validated
    /// tree chunks of its layer indexes (in layer order), checking that they form the
    /// cut the manifest names (same layers, same generations, same counts, each chunk the
    /// one its layer names).
    ///
    /// # Errors
    /// A description of the first mismatch.
    pub fn new(
        manifest: &'a ArchivedManifest,
        layers: Vec<&'a ArchivedLayerSegment>,
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
    ) -> Result<Self, String> {
        Self::rejoin(manifest, layers, chunks, trees, KnownParts::NONE)
    }

    /// [`ArchivedScene::new`] for a reader's next cut: checks what `known` does not say
    /// an earlier join of the same reader accepted (the manifest's structure; per layer,
    /// its entry against its segment and its chunks), so that a cut in which one layer
    /// changed costs O(layers) reads of the manifest, not of every segment.
    ///
    /// # Errors
    /// A description of the first mismatch.
    pub fn rejoin(
        manifest: &'a ArchivedManifest,
        layers: Vec<&'a ArchivedLayerSegment>,
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
        known: KnownParts<'_>,
    ) -> Result<Self, String> {
        if manifest.layers.len() != layers.len() {
            return Err(format!(
                "manifest lists {} layers, {} segments given",
                manifest.layers.len(),
                layers.len()
            ));
        }
        if !known.structure {
            check_structure(manifest)?;
        }
        for (i, (m, l)) in manifest.layers.iter().zip(&layers).enumerate() {
            if !known.layer(i)
                && (m.id != l.layer
                    || m.generation != l.generation
                    || m.node_count.to_native() != l.ids.len() as u64)
            {
                return Err(format!(
                    "manifest entry {i} (layer {}, generation {}) does not match segment (layer {}, generation {})",
                    m.id, m.generation, l.layer, l.generation
                ));
            }
        }
        // A known layer named no chunk: a chunk given for it is refused below, as the
        // chunk of another layer or as one that no layer names.
        let mut next = chunks.iter();
        for (i, l) in layers.iter().enumerate().filter(|(i, _)| !known.layer(*i)) {
            for (index, r) in l.point_chunks.iter().enumerate() {
                let chunk = next.next().ok_or_else(|| {
                    format!("layer {} names point chunk {index}, not given", l.layer)
                })?;
                check_chunk_matches(chunk, manifest.layers[i].id.to_native(), index, r)?;
            }
        }
        if next.next().is_some() {
            return Err(format!(
                "{} point chunks given that no layer names",
                next.len() + 1
            ));
        }
        let mut next = trees.iter();
        for (i, l) in layers.iter().enumerate().filter(|(i, _)| !known.layer(*i)) {
            let layer = manifest.layers[i].id.to_native();
            let mut expect = |slot: u32, items: u32, r: &ArchivedTreeChunkRef| {
                let tree = next
                    .next()
                    .ok_or_else(|| format!("layer {layer} names tree chunk {slot}, not given"))?;
                check_tree_chunk_matches(tree, layer, slot, items, r)
            };
            if let Some(index) = l.layer_index.as_ref()
                && let Some(r) = index.tree_chunk.as_ref()
            {
                expect(0, index.base_rows.to_native(), r)?;
            }
            for (i, index) in l.node_indexes.iter().enumerate() {
                if let Some(r) = index.tree_chunk.as_ref() {
                    // `check_layer` bounded the node indexes by the layer's rows.
                    expect(1 + i as u32, index.ids.len() as u32, r)?;
                }
            }
        }
        if next.next().is_some() {
            return Err(format!(
                "{} tree chunks given that no layer names",
                next.len() + 1
            ));
        }
        Ok(Self::new_prechecked(manifest, layers, chunks, trees))
    }

    /// Joins a manifest with its layer segments that [`ArchivedScene::new`] already
    /// accepted, without checking them again (a reader builds a view per query on a
    /// snapshot it checked once). Given a cut `new` would refuse, queries may panic or
    /// answer wrongly, but stay memory-safe.
    pub fn new_prechecked(
        manifest: &'a ArchivedManifest,
        layers: Vec<&'a ArchivedLayerSegment>,
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
    ) -> Self {
        // The join checked that the chunks come in layer order, each layer's own: where a
        // layer's chunks start follows from the chunks' layer ids, without reading every
        // layer segment.
        let mut chunk_start = Vec::new();
        if !chunks.is_empty() {
            chunk_start.reserve(layers.len() + 1);
            let mut at = 0;
            for m in manifest.layers.iter() {
                chunk_start.push(at as u32);
                while chunks.get(at).is_some_and(|c| c.layer == m.id) {
                    at += 1;
                }
            }
            chunk_start.push(at as u32);
        }
        // The join checked each tree chunk's layer and slot against the index naming it.
        let index_trees = trees
            .into_iter()
            .map(|t| ((t.layer.to_native(), t.slot.to_native()), &t.tree))
            .collect();
        ArchivedScene {
            manifest,
            layers,
            chunks: chunks.into_iter().map(chunk_points).collect(),
            chunk_start,
            index_trees,
        }
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
}
