//! Validating untrusted segment bytes: rkyv's bytecheck, then [`check_layer`]'s
//! consistency pass, so that every accessor of [`super::ArchivedScene`] is total; and
//! re-deriving references to bytes validated before.

#![allow(
    unsafe_code,
    reason = "re-deriving references to bytes validated before"
)]

use super::chunk_check::{check_chunk_refs, check_tree_chunk, chunk_error};
use crate::SnapshotError;
use crate::feature::{FEATURE_BOOL, FEATURE_FLOAT, FEATURE_INT, FEATURE_STR};
use crate::index::check_tree;
use crate::snapshot::chunking::MAX_POINT_CHUNK_LEN;
use crate::snapshot::schema::{
    ArchivedLayerSegment, ArchivedManifest, ArchivedPointChunk, ArchivedStructure,
    ArchivedTreeChunk, FORMAT_VERSION, NO_PARENT, u32s, u64s,
};

fn validation(what: &str, e: impl std::fmt::Display) -> SnapshotError {
    SnapshotError::Validation {
        what: what.to_owned(),
        reason: e.to_string(),
    }
}

/// Checks alignment and rkyv's bytecheck of `bytes` as a `T`, then that the format
/// version `version` reads off it is [`FORMAT_VERSION`].
fn access_versioned<'a, T>(
    bytes: &'a [u8],
    what: &str,
    version: impl FnOnce(&T) -> u32,
) -> Result<&'a T, SnapshotError>
where
    T: rkyv::Portable
        + for<'v> rkyv::bytecheck::CheckBytes<rkyv::api::high::HighValidator<'v, rkyv::rancor::Error>>,
{
    check_alignment(bytes, what)?;
    let archived =
        rkyv::access::<T, rkyv::rancor::Error>(bytes).map_err(|e| validation(what, e))?;
    let found = version(archived);
    if found != FORMAT_VERSION {
        return Err(SnapshotError::SchemaVersion {
            what: what.to_owned(),
            found,
            expected: FORMAT_VERSION,
        });
    }
    Ok(archived)
}

/// Validates manifest bytes (bytecheck, version) and returns the archived manifest.
///
/// # Errors
/// Misaligned bytes, bytecheck failure, or a foreign version.
pub fn validate_manifest<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedManifest, SnapshotError> {
    let m = access_versioned(bytes, what, |m: &ArchivedManifest| m.version.to_native())?;
    Ok(m)
}

/// Validates structure bytes (bytecheck, version) and returns the archived structure;
/// its consistency (ascending ids, DAG, part lists) is checked when a cut is joined.
///
/// # Errors
/// Misaligned bytes, bytecheck failure, or a foreign version.
pub fn validate_structure<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedStructure, SnapshotError> {
    access_versioned(bytes, what, |m: &ArchivedStructure| m.version.to_native())
}

/// Validates layer-segment bytes (bytecheck, version, [`check_layer`]).
///
/// # Errors
/// Misaligned bytes, bytecheck failure, a foreign version, or inconsistent columns.
pub fn validate_layer<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedLayerSegment, SnapshotError> {
    let l = access_versioned(bytes, what, |l: &ArchivedLayerSegment| {
        l.version.to_native()
    })?;
    check_layer(l).map_err(|reason| SnapshotError::Inconsistent {
        what: what.to_owned(),
        reason,
    })?;
    Ok(l)
}

/// Validates point-chunk bytes (bytecheck, version, at most
/// [`MAX_POINT_CHUNK_LEN`] points, not empty). Whether the chunk is the one its layer segment
/// names is checked when the cut is joined ([`super::ArchivedScene::new`]).
///
/// # Errors
/// Misaligned bytes, bytecheck failure, a foreign version, or a wrong point count.
pub fn validate_chunk<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedPointChunk, SnapshotError> {
    let c = access_versioned(bytes, what, |c: &ArchivedPointChunk| c.version.to_native())?;
    if c.points.is_empty() || c.points.len() > MAX_POINT_CHUNK_LEN {
        return Err(chunk_error(
            what,
            format!(
                "a point chunk holds {} points (1 to {MAX_POINT_CHUNK_LEN})",
                c.points.len()
            ),
        ));
    }
    Ok(c)
}

/// Validates tree-chunk bytes (bytecheck, version, the tree's structure with items below
/// the chunk's bound). Whether the chunk is the tree its layer segment names is checked
/// when the cut is joined ([`super::ArchivedScene::new`]).
///
/// # Errors
/// Misaligned bytes, bytecheck failure, a foreign version, or a malformed tree.
pub fn validate_tree_chunk<'a>(
    bytes: &'a [u8],
    what: &str,
) -> Result<&'a ArchivedTreeChunk, SnapshotError> {
    let c = access_versioned(bytes, what, |c: &ArchivedTreeChunk| c.version.to_native())?;
    check_tree_chunk(c).map_err(|e| chunk_error(what, format!("tree chunk: {e}")))?;
    Ok(c)
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

/// Checks a CSR offsets column: `rows + 1` entries, starting at 0, non-decreasing,
/// ending at `len`.
fn check_offsets(name: &str, offsets: &[u32], rows: usize, len: usize) -> Result<(), String> {
    if offsets.len() != rows + 1 || offsets[0] != 0 || offsets[rows] as usize != len {
        return Err(format!(
            "{name}: {} offsets for {rows} rows and {len} entries",
            offsets.len()
        ));
    }
    if !ascending(offsets, false) {
        return Err(format!("{name}: offsets decrease"));
    }
    Ok(())
}

/// Whether `values` ascend (strictly if `strict`), in one branch-free pass that
/// vectorises (`is_sorted` stops at the first pair, so it does not).
fn ascending<T: PartialOrd + Copy>(values: &[T], strict: bool) -> bool {
    let pairs = values.iter().zip(values.get(1..).unwrap_or(&[]));
    if strict {
        pairs.fold(true, |ok, (a, b)| ok & (a < b))
    } else {
        pairs.fold(true, |ok, (a, b)| ok & (a <= b))
    }
}

/// Checks that every value is below `bound`. The scan is branch-free (a maximum, which
/// vectorises): it runs over every column of every new segment a reader receives.
fn check_below(name: &str, values: &[u32], bound: usize) -> Result<(), String> {
    let max = values.iter().fold(0, |m, &v| m.max(v));
    if values.is_empty() || (max as usize) < bound {
        return Ok(());
    }
    let i = values
        .iter()
        .position(|&v| v as usize >= bound)
        .unwrap_or(0);
    Err(format!(
        "{name}[{i}] = {} is out of range (< {bound})",
        values[i]
    ))
}

/// Checks that `by_parent` lists exactly the rows with a parent, ascending by (parent
/// id, row): each entry below the row count, each row's parent set, each key above the
/// one before (so no row twice), and as many entries as rows with a parent.
fn check_by_parent(parents: &[u64], by_parent: &[u32]) -> Result<(), String> {
    let nested = parents.iter().filter(|&&p| p != NO_PARENT).count();
    if by_parent.len() != nested {
        return Err(format!(
            "by_parent lists {} rows, {nested} rows have a parent",
            by_parent.len()
        ));
    }
    let mut previous = None;
    for (i, &row) in by_parent.iter().enumerate() {
        let parent = match parents.get(row as usize) {
            Some(&p) if p != NO_PARENT => p,
            Some(_) => {
                return Err(format!(
                    "by_parent[{i}] = {row} names a row without a parent"
                ));
            }
            None => {
                return Err(format!(
                    "by_parent[{i}] = {row} is out of range (< {})",
                    parents.len()
                ));
            }
        };
        if previous.is_some_and(|p| p >= (parent, row)) {
            return Err(format!(
                "by_parent[{i}] = {row} is not ascending by (parent, row)"
            ));
        }
        previous = Some((parent, row));
    }
    Ok(())
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
    if !ascending(ids, true) {
        return Err("node ids are not strictly ascending".into());
    }
    if ids.last() == Some(&u64::MAX) {
        return Err("reserved node id u64::MAX".into());
    }
    let nstr = l.strings.len();
    let points = if l.point_chunks.is_empty() {
        l.points.len()
    } else if !l.points.is_empty() {
        return Err("a chunked layer also holds points inline".into());
    } else {
        check_chunk_refs(&l.point_chunks, l.point_chunk_len.to_native())?
    };
    check_offsets("point_offsets", u32s(&l.point_offsets), rows, points)?;
    if l.parents.len() != rows {
        return Err("parents column length differs from ids".into());
    }
    check_by_parent(u64s(&l.parents), u32s(&l.by_parent))?;
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
    if aabb_rows.len() != l.aabbs.len() || !ascending(aabb_rows, true) {
        return Err("aabb rows not strictly ascending or differ in length from boxes".into());
    }
    check_below("aabb_rows", aabb_rows, rows)?;
    for (name, postings_name, index, postings) in [
        ("label", "label_postings", &l.label_index, &l.label_postings),
        ("key", "key_postings", &l.key_index, &l.key_postings),
    ] {
        let postings = u32s(postings);
        check_below(postings_name, postings, rows)?;
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
    if let Some(index) = l.layer_index.as_ref() {
        let base_rows = index.base_rows.to_native() as usize;
        check_tree(&index.tree, base_rows).map_err(|e| format!("layer index: {e}"))?;
        // A tree sent as a chunk is checked against this count when the cut is joined.
        let inline_points = match index.tree_chunk.as_ref() {
            Some(r) if r.points != index.base_points => {
                return Err("layer index: its tree chunk's point count differs".into());
            }
            Some(_) => 0,
            None => index.base_points.to_native() as usize,
        };
        if index.tree.size() != inline_points {
            return Err("layer index: base point count differs from its tree".into());
        }
        let patched = u32s(&index.patched);
        if !patched.windows(2).all(|w| w[0] < w[1])
            || patched.last().is_some_and(|&r| r as usize >= ids.len())
        {
            return Err("layer index: patched rows unsorted or out of range".into());
        }
        let offsets = u32s(&l.point_offsets);
        let unlisted = (base_rows..ids.len())
            .find(|&r| offsets[r] != offsets[r + 1] && patched.binary_search(&(r as u32)).is_err());
        if let Some(row) = unlisted {
            return Err(format!(
                "layer index: row {row}, added since its base, is not patched"
            ));
        }
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
        // A tree sent as a chunk is checked against its reference when the cut is joined.
        if ni.tree_chunk.is_some() && ni.tree.size() != 0 {
            return Err(format!(
                "node index {root}: its tree travels as a chunk, yet the segment holds one"
            ));
        }
    }
    Ok(())
}

/// Where each layer of a structure (ascending by id, as the caller checked) is, by id: a
/// table indexed by `id - first id` when the ids are dense enough (at most
/// [`DENSE_SPAN_PER_LAYER`] ids per layer), else a binary search. Checking a cut looks up
/// every DAG edge and graph-index entry, so a scene of hundreds of layers is checked in
/// O(edges) per snapshot, not O(layers²).
pub(super) struct LayerPositions<'a> {
    manifest: &'a ArchivedStructure,
    first: u32,
    /// Position of id `first + k` at `k`, `u32::MAX` for none; empty when ids are sparse.
    dense: Vec<u32>,
}

/// Largest id span per layer for which [`LayerPositions`] builds its table (a few bytes
/// per id).
const DENSE_SPAN_PER_LAYER: usize = 16;

impl<'a> LayerPositions<'a> {
    /// The positions of `manifest`'s layers, whose ids are ascending.
    pub(super) fn new(manifest: &'a ArchivedStructure) -> Self {
        let layers = &manifest.layers;
        let (first, dense) = match (layers.first(), layers.last()) {
            (Some(a), Some(b)) => {
                let (first, last) = (a.id.to_native(), b.id.to_native());
                let span = last.saturating_sub(first) as usize + 1;
                let dense = if span <= DENSE_SPAN_PER_LAYER * layers.len() {
                    let mut dense = vec![u32::MAX; span];
                    for (i, m) in layers.iter().enumerate() {
                        if let Some(slot) =
                            dense.get_mut(m.id.to_native().wrapping_sub(first) as usize)
                        {
                            *slot = i as u32;
                        }
                    }
                    dense
                } else {
                    Vec::new()
                };
                (first, dense)
            }
            _ => (0, Vec::new()),
        };
        LayerPositions {
            manifest,
            first,
            dense,
        }
    }

    /// Where layer `id` is in the manifest.
    pub(super) fn get(&self, id: u32) -> Option<usize> {
        if self.dense.is_empty() {
            return self
                .manifest
                .layers
                .binary_search_by_key(&id, |m| m.id.to_native())
                .ok();
        }
        let at = *self.dense.get(id.wrapping_sub(self.first) as usize)?;
        (at != u32::MAX).then_some(at as usize)
    }
}

/// Checks the structure's layer DAG: unique names, mirrored edges, no cycle. Edges are
/// known to name listed layers, and layers are known to be ascending by id.
pub(super) fn check_dag(
    manifest: &ArchivedStructure,
    positions: &LayerPositions<'_>,
) -> Result<(), String> {
    let mut names =
        rustc_hash::FxHashSet::with_capacity_and_hasher(manifest.layers.len(), Default::default());
    if !manifest
        .layers
        .iter()
        .all(|m| names.insert(m.name.as_str()))
    {
        return Err("two layers share a name".into());
    }
    let position = |id: u32| positions.get(id);
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

/// Re-derives a point chunk from bytes that [`validate_chunk`] accepted before.
///
/// # Safety
/// `bytes` must be exactly the bytes (same address, same length, unchanged since) that
/// an earlier call of [`validate_chunk`] accepted.
pub unsafe fn chunk_unchecked(bytes: &[u8]) -> &ArchivedPointChunk {
    // SAFETY: the caller guarantees that `validate_chunk` accepted these very bytes and
    // that they have not changed since.
    unsafe { rkyv::access_unchecked::<ArchivedPointChunk>(bytes) }
}

/// Re-derives a tree chunk from bytes that [`validate_tree_chunk`] accepted before.
///
/// # Safety
/// `bytes` must be exactly the bytes (same address, same length, unchanged since) that
/// an earlier call of [`validate_tree_chunk`] accepted.
pub unsafe fn tree_chunk_unchecked(bytes: &[u8]) -> &ArchivedTreeChunk {
    // SAFETY: the caller guarantees that `validate_tree_chunk` accepted these very bytes
    // and that they have not changed since.
    unsafe { rkyv::access_unchecked::<ArchivedTreeChunk>(bytes) }
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

/// Re-derives a structure from bytes that [`validate_structure`] accepted before.
///
/// # Safety
/// `bytes` must be exactly the bytes (same address, same length, unchanged since) that
/// an earlier call of [`validate_structure`] accepted.
pub unsafe fn structure_unchecked(bytes: &[u8]) -> &ArchivedStructure {
    // SAFETY: the caller guarantees that `validate_structure` accepted these very bytes
    // and that they have not changed since.
    unsafe { rkyv::access_unchecked::<ArchivedStructure>(bytes) }
}
