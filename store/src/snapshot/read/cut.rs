//! [`ArchivedScene`]: a consistent cut of validated archived segments, joined and checked
//! (the manifest's structure, each layer's parts, point chunks and tree chunks against the
//! entry that names them). Its [`crate::SceneView`] is in `scene_view.rs`.

use super::chunk_check::{check_chunk_matches, check_tree_chunk_matches, chunk_points};
use super::rejoin::KnownParts;
use super::validate::{LayerPositions, check_dag};
use crate::snapshot::chunking::PART_ITEM_ROW_BITS;
use crate::snapshot::schema::{
    ArchivedLayerSegment, ArchivedManifest, ArchivedManifestLayer, ArchivedPointChunk,
    ArchivedStructure, ArchivedStructureLayer, ArchivedTreeChunk, ArchivedTreeChunkRef, u32s, u64s,
};
use crate::{LayerId, Point};
use rkyv::collections::swiss_table::ArchivedHashMap;
use rkyv::string::ArchivedString;
use rkyv::vec::ArchivedVec;

/// An archived inverted index: term -> `[start, end)` range of its posting column.
pub(super) type ArchivedTermIndex = ArchivedHashMap<ArchivedString, [rkyv::rend::u32_le; 2]>;

/// A consistent cut of archived layers: the [`crate::SceneView`] over validated bytes from a
/// `.ygg` file or from shared memory. Cloning copies its tables of references, not the
/// bytes.
#[derive(Clone)]
pub struct ArchivedScene<'a> {
    pub(super) manifest: &'a ArchivedManifest,
    /// The cut's structure (layer names, DAG, part lists, term indexes), whose layers are
    /// the manifest's at the same positions.
    pub(super) structure: &'a ArchivedStructure,
    /// Part segments in manifest order: each layer's parts in the order its entry lists
    /// them (ascending ids). A layer in one piece has one part.
    pub(super) parts: Vec<&'a ArchivedLayerSegment>,
    /// Per manifest position (and one past the last), where its parts start in `parts`.
    pub(super) part_start: Vec<u32>,
    /// The point chunks of every chunked part, by (layer id, part number), then in
    /// column order.
    pub(super) chunks: Vec<&'a ArchivedPointChunk>,
    /// The points of each of `chunks`.
    pub(super) chunk_points: Vec<&'a [Point]>,
    /// Per position in `parts`, the range of its chunks in `chunks`; empty when no part
    /// is chunked.
    pub(super) chunk_ranges: Vec<[u32; 2]>,
    /// The trees that travel as tree chunks, by (layer id, part number, slot),
    /// ascending: slot 0 is a part's layer index base tree, slot `1 + i` the tree of its
    /// node index `i`.
    pub(super) index_trees: Vec<&'a ArchivedTreeChunk>,
    /// Per position in `parts`, the range of its trees in `index_trees`; empty when no
    /// tree travels as a chunk.
    pub(super) tree_ranges: Vec<[u32; 2]>,
}

/// Checks what a structure's bytecheck does not: layer ids ascending, DAG edges and term
/// lists naming listed layers, the DAG itself, part lists not empty and without repeats.
fn check_structure(manifest: &ArchivedStructure) -> Result<(), String> {
    let ids = manifest.layers.iter().map(|m| m.id.to_native());
    if ids.clone().zip(ids.skip(1)).any(|(a, b)| a >= b) {
        return Err("structure layers are not ascending".into());
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
        let mut parts = u32s(&m.parts).to_vec();
        parts.sort_unstable();
        if parts.is_empty() || parts.windows(2).any(|w| w[0] == w[1]) {
            return Err(format!(
                "layer {} lists no part or a part twice ({:?})",
                m.id,
                u32s(&m.parts)
            ));
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

/// Checks that a manifest names the layers of `structure`, of its generation.
fn check_manifest_matches(
    manifest: &ArchivedManifest,
    structure: &ArchivedStructure,
) -> Result<(), String> {
    if manifest.structure != structure.generation {
        return Err(format!(
            "manifest names structure {}, structure {} given",
            manifest.structure, structure.generation
        ));
    }
    if manifest.layers.len() != structure.layers.len()
        || manifest
            .layers
            .iter()
            .zip(structure.layers.iter())
            .any(|(m, s)| m.id != s.id)
    {
        return Err(format!(
            "manifest lists {} layers, not the {} of its structure",
            manifest.layers.len(),
            structure.layers.len()
        ));
    }
    Ok(())
}

/// A node of an [`ArchivedScene`]: its part's position in the cut and its row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArchivedNodeRef {
    pub(super) part: u32,
    pub(super) row: u32,
}

/// The position in `given` (sorted by `key`) of the element with key `k`.
fn find<T>(given: &[T], k: (u32, u32), key: impl Fn(&T) -> (u32, u32)) -> Option<usize> {
    given.binary_search_by_key(&k, key).ok()
}

/// Why `given` (named `what`) does not ascend strictly by `key`, if it does not.
fn unordered<T, K: Ord + std::fmt::Debug>(
    what: &str,
    given: &[T],
    key: impl Fn(&T) -> K,
) -> Option<String> {
    let at = given.windows(2).position(|w| key(&w[0]) >= key(&w[1]))?;
    Some(format!(
        "{what} given out of order: {:?} at {} after {:?} (ascending by layer, part, place)",
        key(&given[at + 1]),
        at + 1,
        key(&given[at])
    ))
}

/// Per part of `parts`, the range of the items (keyed by layer, part and place,
/// ascending) that belong to it; empty when there are no items.
fn part_ranges(
    parts: &[&ArchivedLayerSegment],
    keys: impl Iterator<Item = (u32, u32, u32)>,
) -> Vec<[u32; 2]> {
    // The runs of items by (layer, part), then each part's run among them.
    let mut runs: Vec<((u32, u32), [u32; 2])> = Vec::new();
    for (i, (layer, part, _)) in keys.enumerate() {
        match runs.last_mut() {
            Some((k, range)) if *k == (layer, part) => range[1] = i as u32 + 1,
            _ => runs.push(((layer, part), [i as u32, i as u32 + 1])),
        }
    }
    if runs.is_empty() {
        return Vec::new();
    }
    parts
        .iter()
        .map(|p| {
            runs.binary_search_by_key(&(p.layer.to_native(), p.part.to_native()), |(k, _)| *k)
                .map_or([0, 0], |at| runs[at].1)
        })
        .collect()
}

impl<'a> ArchivedScene<'a> {
    /// Joins a validated manifest with its validated part segments (ascending by
    /// (layer id, part number), as segment ids sort them), the validated point chunks of
    /// its chunked parts (ascending by layer id, part number and place) and the
    /// validated tree chunks (ascending by layer id, part number and slot), checking that
    /// they form the cut the manifest names (same layers and parts, generations no newer
    /// than the cut's, the same node counts, parts disjoint and ascending by id, each
    /// chunk the one its part names).
    ///
    /// # Errors
    /// A description of the first mismatch.
    pub fn new(
        manifest: &'a ArchivedManifest,
        structure: &'a ArchivedStructure,
        parts: Vec<&'a ArchivedLayerSegment>,
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
    ) -> Result<Self, String> {
        Self::rejoin(manifest, structure, parts, chunks, trees, KnownParts::NONE)
    }

    /// [`ArchivedScene::new`] for a reader's next cut: checks what `known` does not say
    /// an earlier join of the same reader accepted (the manifest's structure; per layer,
    /// its entry against its parts and their chunks), so that a cut in which one layer
    /// changed costs O(segments) reads, not a check of every segment.
    ///
    /// # Errors
    /// A description of the first mismatch.
    pub fn rejoin(
        manifest: &'a ArchivedManifest,
        structure: &'a ArchivedStructure,
        parts: Vec<&'a ArchivedLayerSegment>,
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
        known: KnownParts<'_>,
    ) -> Result<Self, String> {
        if !known.structure {
            check_structure(structure)?;
        }
        check_manifest_matches(manifest, structure)?;
        let listed: usize = structure.layers.iter().map(|m| m.parts.len()).sum();
        if listed != parts.len() {
            return Err(format!(
                "manifest lists {listed} parts, {} segments given",
                parts.len()
            ));
        }
        let (scene, problem) = Self::assemble(manifest, structure, &parts, chunks, trees);
        if let Some(problem) = problem {
            return Err(problem);
        }
        for (i, m) in manifest.layers.iter().enumerate() {
            let range = scene.part_start[i] as usize..scene.part_start[i + 1] as usize;
            if known.layer(i) {
                // The same parts with the same chunks as in an accepted cut: only what a
                // chunk given beside them would change is looked at.
                for at in range {
                    scene.check_point_chunk_count(scene.parts[at], at)?;
                }
            } else {
                scene.check_layer_parts(m, &structure.layers[i], range)?;
            }
        }
        // Every given chunk lies in the range of some part (which checked it above).
        let assigned =
            |ranges: &[[u32; 2]]| -> usize { ranges.iter().map(|[a, b]| (b - a) as usize).sum() };
        if assigned(&scene.chunk_ranges) != scene.chunks.len() {
            return Err(format!(
                "{} point chunks given that no part names ({} given){}",
                scene.chunks.len() - assigned(&scene.chunk_ranges),
                scene.chunks.len(),
                scene.stray_point_chunk().unwrap_or_default()
            ));
        }
        if assigned(&scene.tree_ranges) != scene.index_trees.len() {
            return Err(format!(
                "{} tree chunks given that no part names ({} given)",
                scene.index_trees.len() - assigned(&scene.tree_ranges),
                scene.index_trees.len()
            ));
        }
        Ok(scene)
    }

    /// Checks a layer's parts (at `range` of the cut's parts) against its manifest entry
    /// `m`, and their chunks against them.
    fn check_layer_parts(
        &self,
        m: &ArchivedManifestLayer,
        s: &ArchivedStructureLayer,
        range: std::ops::Range<usize>,
    ) -> Result<(), String> {
        let layer = m.id.to_native();
        let mut rows = 0u64;
        let mut last_id: Option<u64> = None;
        let several = range.len() > 1;
        if several && range.len() >= 1 << (32 - PART_ITEM_ROW_BITS) {
            return Err(format!("layer {layer} has {} parts", range.len()));
        }
        for (k, &p) in self.parts[range.clone()].iter().enumerate() {
            let number = s.parts[k].to_native();
            if p.layer != layer || p.part != number || p.generation > m.generation {
                return Err(format!(
                    "manifest entry of layer {layer} (generation {}) names part {number}, segment is layer {} part {} generation {}",
                    m.generation, p.layer, p.part, p.generation
                ));
            }
            let ids = u64s(&p.ids);
            if several && ids.is_empty() {
                return Err(format!(
                    "part {number} of layer {layer} (of several) is empty"
                ));
            }
            if several && ids.len() >= 1 << PART_ITEM_ROW_BITS {
                return Err(format!(
                    "part {number} of layer {layer} has {} rows, a layer in parts at most {} per part",
                    ids.len(),
                    (1u64 << PART_ITEM_ROW_BITS) - 1
                ));
            }
            if let (Some(last), Some(&first)) = (last_id, ids.first())
                && last >= first
            {
                return Err(format!(
                    "part {number} of layer {layer} starts at id {first}, not above the part before it"
                ));
            }
            if let Some(&l) = ids.last() {
                last_id = Some(l);
            }
            rows += ids.len() as u64;
            self.check_part_chunks(p, range.start + k)?;
        }
        if rows != m.node_count.to_native() {
            return Err(format!(
                "manifest entry of layer {layer} counts {} nodes, its parts hold {rows}",
                m.node_count
            ));
        }
        Ok(())
    }

    /// Checks that part `p` (at `position` in the cut) is given as many point chunks as
    /// it names.
    fn check_point_chunk_count(
        &self,
        p: &ArchivedLayerSegment,
        position: usize,
    ) -> Result<(), String> {
        let [a, b] = self.chunk_ranges.get(position).copied().unwrap_or([0, 0]);
        if (b - a) as usize != p.point_chunks.len() {
            return Err(format!(
                "part {} of layer {} names {} point chunks, {} given",
                p.part,
                p.layer,
                p.point_chunks.len(),
                b - a
            ));
        }
        Ok(())
    }

    /// Checks the point and tree chunks of part `p` (at `position` in the cut) against
    /// the references it holds: every one it names given, and nothing else for it.
    fn check_part_chunks(&self, p: &ArchivedLayerSegment, position: usize) -> Result<(), String> {
        let (layer, part) = (p.layer.to_native(), p.part.to_native());
        self.check_point_chunk_count(p, position)?;
        let [a, _] = self.chunk_ranges.get(position).copied().unwrap_or([0, 0]);
        for (index, r) in p.point_chunks.iter().enumerate() {
            check_chunk_matches(self.chunks[a as usize + index], layer, part, index, r)?;
        }
        let [a, b] = self.tree_ranges.get(position).copied().unwrap_or([0, 0]);
        let trees = &self.index_trees[a as usize..b as usize];
        let mut named = 0;
        let mut check_tree = |slot: u32, items: u32, r: &ArchivedTreeChunkRef| {
            named += 1;
            let at = trees
                .binary_search_by_key(&slot, |t| t.slot.to_native())
                .map_err(|_| {
                    format!("part {part} of layer {layer} names tree chunk {slot}, not given")
                })?;
            check_tree_chunk_matches(trees[at], layer, part, slot, items, r)
        };
        if let Some(index) = p.layer_index.as_ref()
            && let Some(r) = index.tree_chunk.as_ref()
        {
            check_tree(0, index.base_rows.to_native(), r)?;
        }
        for (i, index) in p.node_indexes.iter().enumerate() {
            if let Some(r) = index.tree_chunk.as_ref() {
                // `check_layer` bounded the node indexes by the part's rows.
                check_tree(1 + i as u32, index.ids.len() as u32, r)?;
            }
        }
        if named != trees.len() {
            return Err(format!(
                "part {part} of layer {layer} names {named} tree chunks, {} given",
                trees.len()
            ));
        }
        Ok(())
    }
    /// Joins a manifest with its segments that [`ArchivedScene::new`] already accepted,
    /// without checking them again (a reader builds a view per query on a snapshot it
    /// checked once). Given a cut `new` would refuse, queries may panic or answer wrongly,
    /// but stay memory-safe.
    pub fn new_prechecked(
        manifest: &'a ArchivedManifest,
        structure: &'a ArchivedStructure,
        parts: Vec<&'a ArchivedLayerSegment>,
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
    ) -> Self {
        Self::assemble(manifest, structure, &parts, chunks, trees).0
    }

    /// The cut's parts put in manifest order (found by (layer, part number) in `given`,
    /// which ascends by it), each part's chunk range, the trees; and what a join must
    /// refuse, if anything: a listed part not given, a list not strictly ascending by its
    /// key.
    fn assemble(
        manifest: &'a ArchivedManifest,
        structure: &'a ArchivedStructure,
        given: &[&'a ArchivedLayerSegment],
        chunks: Vec<&'a ArchivedPointChunk>,
        trees: Vec<&'a ArchivedTreeChunk>,
    ) -> (Self, Option<String>) {
        let part_key = |p: &&ArchivedLayerSegment| (p.layer.to_native(), p.part.to_native());
        let chunk_key = |c: &&ArchivedPointChunk| {
            (c.layer.to_native(), c.part.to_native(), c.index.to_native())
        };
        let tree_key =
            |t: &&ArchivedTreeChunk| (t.layer.to_native(), t.part.to_native(), t.slot.to_native());
        let mut problem = unordered("part segments", given, part_key)
            .or_else(|| unordered("point chunks", &chunks, chunk_key))
            .or_else(|| unordered("tree chunks", &trees, tree_key));
        let mut parts = Vec::with_capacity(given.len());
        let mut part_start = Vec::with_capacity(structure.layers.len() + 1);
        // Both ascend by layer: each layer's given parts are one run of `given`, found by
        // walking along; within it a part is found by its number (the run ascends by
        // number), directly when the numbers come in id order.
        let mut run_start = 0;
        for m in structure.layers.iter() {
            part_start.push(parts.len() as u32);
            let layer = m.id.to_native();
            while given
                .get(run_start)
                .is_some_and(|p| p.layer.to_native() < layer)
            {
                run_start += 1;
            }
            let run_len = given[run_start..]
                .iter()
                .take_while(|p| p.layer == layer)
                .count();
            let layer_run = &given[run_start..run_start + run_len];
            for (k, number) in u32s(&m.parts).iter().enumerate() {
                let found = match layer_run.get(k) {
                    Some(p) if p.part == *number => Some(*p),
                    _ => find(layer_run, (layer, *number), part_key).map(|at| layer_run[at]),
                };
                match found {
                    Some(p) => parts.push(p),
                    None => {
                        problem.get_or_insert_with(|| {
                            format!("layer {layer} lists part {number}, not given")
                        });
                    }
                }
            }
            run_start += run_len;
        }
        part_start.push(parts.len() as u32);
        let chunk_ranges = part_ranges(&parts, chunks.iter().map(chunk_key));
        let tree_ranges = part_ranges(&parts, trees.iter().map(tree_key));
        let scene = ArchivedScene {
            manifest,
            structure,
            parts,
            part_start,
            chunk_points: chunks.iter().map(|c| chunk_points(c)).collect(),
            chunks,
            chunk_ranges,
            index_trees: trees,
            tree_ranges,
        };
        (scene, problem)
    }

    /// A description of a given point chunk that no part of the cut names, if any.
    fn stray_point_chunk(&self) -> Option<String> {
        let named = |c: &ArchivedPointChunk| {
            self.parts.iter().any(|p| {
                p.layer == c.layer
                    && p.part == c.part
                    && (c.index.to_native() as usize) < p.point_chunks.len()
            })
        };
        let c = self.chunks.iter().find(|c| !named(c))?;
        Some(format!(
            ": chunk {} of layer {} part {}",
            c.index, c.layer, c.part
        ))
    }

    /// Tree chunk `slot` of part `part` of layer `layer`, if given.
    pub(super) fn tree_chunk_segment(
        &self,
        layer: u32,
        part: u32,
        slot: u32,
    ) -> Option<&'a ArchivedTreeChunk> {
        let at = self
            .index_trees
            .binary_search_by_key(&(layer, part, slot), |t| {
                (t.layer.to_native(), t.part.to_native(), t.slot.to_native())
            })
            .ok()?;
        Some(self.index_trees[at])
    }

    /// The manifest position of the layer of the part at `part`.
    pub(super) fn layer_position(&self, part: u32) -> usize {
        self.part_start
            .partition_point(|&s| s <= part)
            .saturating_sub(1)
    }

    /// The cut's manifest (validated).
    pub fn manifest(&self) -> &'a ArchivedManifest {
        self.manifest
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
