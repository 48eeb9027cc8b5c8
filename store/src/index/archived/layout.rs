//! kiddo 6.3's archived kd-tree layout, mirrored field for field, and [`check_tree`],
//! the checks that make an archived tree from untrusted bytes safe to query.
//!
//! # Safety of archived trees
//! rkyv's bytecheck validates an archived kiddo tree's *structure*: every relative
//! pointer and length stays inside the buffer, buffers are 128-byte aligned, the
//! stem/leaf resolution enum has a known tag. kiddo's queries also rely on facts that
//! bytecheck cannot see: the stem array covers every level the traversal descends, each
//! leaf extent lies inside the leaf arena (leaves are read through raw pointers), the
//! arithmetic leaf index stays below the leaf count (kiddo panics otherwise), and no
//! distance is NaN (kiddo sorts results with a comparator that treats NaN as equal,
//! which a sort may reject with a panic). [`check_tree`] reads those fields through
//! `TreeLayout`, a `#[repr(C)]` mirror of kiddo 6.3's archived layout (pinned by a size
//! assertion and by `layout_mirror_reads_what_kiddo_reads`), and checks them once per
//! segment; it also checks that every item is in range. The pass reads the leaf arena
//! once (16 bytes per point). The nearest walk indexes only with bounds-checked slices.

#![allow(
    unsafe_code,
    reason = "reading the fields of a validated archived kiddo tree through a layout mirror"
)]

use kiddo::leaf_strategy::VecOfArenas;
use kiddo::{Eytzinger, ImmutableKdTree};
use rkyv::boxed::ArchivedBox;
use rkyv::primitive::{ArchivedI32, ArchivedUsize};
use rkyv::rend::f32_le;
use rkyv::tuple::ArchivedTuple2;
use rkyv::vec::ArchivedVec;

/// The kd-tree of archived and reader-built indexes: kiddo's `ImmutableKdTree` over
/// `f32` points in 3-D with `u32` items.
pub type KdTree = ImmutableKdTree<f32, 3>;

/// kiddo's archived form of [`KdTree`], queried in place.
pub type ArchivedKdTree =
    kiddo::kd_tree::ArchivedKdTree<f32, u32, Eytzinger, VecOfArenas<f32, u32, 3, 32>, 3, 32>;

/// kiddo 6.3's archived `VecOfArenas<f32, u32, 3, 32>`, field for field.
#[repr(C)]
pub(super) struct ArenasLayout {
    pub(super) leaf_extents: ArchivedVec<ArchivedTuple2<ArchivedUsize, ArchivedUsize>>,
    pub(super) leaf_bytes: ArchivedBox<[u8]>,
    pub(super) size: ArchivedUsize,
}

/// kiddo 6.3's archived `OwnedStemLeafResolution`: a `repr(u8)` enum, laid out as a tag
/// followed by the variant's fields. Tag 0 is `Arithmetic { stems_depth, leaf_count }`;
/// the largest variant, `Mapped { usize, Vec<usize> }`, sets the size.
#[repr(C)]
pub(super) struct ResolutionLayout {
    pub(super) tag: u8,
    pub(super) stems_depth: ArchivedUsize,
    pub(super) leaf_count: ArchivedUsize,
    pub(super) _mapped_tail: ArchivedUsize,
}

/// kiddo 6.3's archived `KdTree<f32, u32, Eytzinger, VecOfArenas<..>, 3, 32>`, field for
/// field (`AlignedArchiveSlice<[T]>` has the layout and metadata of `[T]`).
#[repr(C)]
pub(super) struct TreeLayout {
    pub(super) stems: ArchivedBox<[f32_le]>,
    pub(super) leaves: ArenasLayout,
    pub(super) resolution: ResolutionLayout,
    pub(super) size: ArchivedUsize,
    pub(super) max_stem_level: ArchivedI32,
    pub(super) max_leaf_len: ArchivedUsize,
}

const _: () = assert!(
    std::mem::size_of::<TreeLayout>() == std::mem::size_of::<ArchivedKdTree>()
        && std::mem::align_of::<TreeLayout>() == std::mem::align_of::<ArchivedKdTree>()
);

/// The archived tree's fields, read through the layout mirror.
pub(super) fn layout(tree: &ArchivedKdTree) -> &TreeLayout {
    // SAFETY: `TreeLayout` declares the fields of kiddo 6.3's archived tree in order,
    // with the same archived field types (rkyv derives `#[repr(C)]` archived structs,
    // and a `repr(u8)` enum is a tag followed by the variant's `repr(C)` fields); sizes
    // and alignments are asserted equal above, and `layout_mirror_reads_what_kiddo_reads`
    // checks the fields read here against kiddo's own accessors. Every `ArchivedKdTree`
    // reference we hold points into bytes that bytecheck validated, so each mirrored
    // field holds a valid value (relative pointers in bounds, initialised integers).
    unsafe { &*(tree as *const ArchivedKdTree).cast::<TreeLayout>() }
}

/// Leaf tiles, widest first, as kiddo's `VecOfArenas` encodes a leaf: each tile of width
/// `w` holds `w` x's, `w` y's, `w` z's, then `w` items (16 bytes per point).
const TILE_WIDTHS: [usize; 5] = [32, 8, 4, 2, 1];

/// The widths of the tiles of a leaf of `len` points, in order (see [`TILE_WIDTHS`]).
pub(super) fn tile_widths(len: usize) -> impl Iterator<Item = usize> {
    let mut remaining = len;
    std::iter::from_fn(move || {
        let w = TILE_WIDTHS.into_iter().find(|&w| remaining >= w)?;
        remaining -= w;
        Some(w)
    })
}

/// Checks what kiddo's queries rely on and bytecheck does not verify (see the module
/// docs), and that every item is below `items`. Linear in the number of points.
///
/// # Errors
/// A description of the first problem.
pub(crate) fn check_tree(tree: &ArchivedKdTree, items: usize) -> Result<(), String> {
    let l = layout(tree);
    let size = l.size.to_native() as usize;
    if size == 0 {
        return Ok(()); // never queried: every query returns at once on an empty tree
    }
    if l.resolution.tag != 0 {
        return Err("kd-tree leaf resolution is not arithmetic".into());
    }
    let depth = l.resolution.stems_depth.to_native() as usize;
    let leaf_count = l.resolution.leaf_count.to_native() as usize;
    let extents = l.leaves.leaf_extents.as_slice();
    if depth > 30
        || leaf_count != 1 << depth
        || extents.len() != leaf_count
        || !(-1..depth as i32).contains(&l.max_stem_level.to_native())
    {
        return Err(format!(
            "kd-tree shape: depth {depth}, {leaf_count} leaves, {} extents, max stem level {}",
            extents.len(),
            l.max_stem_level.to_native()
        ));
    }
    // Levels 0..=max_stem_level are read, at stem indices below 2^(max_stem_level + 1).
    let stem_levels = (l.max_stem_level.to_native() + 1) as u32;
    let stems = l.stems.get();
    let bytes = l.leaves.leaf_bytes.get();
    let misaligned = |len: usize, ptr: usize| len > 0 && !ptr.is_multiple_of(128);
    if stems.len() < (1usize << stem_levels) - usize::from(stem_levels == 0)
        || misaligned(stems.len(), stems.as_ptr() as usize)
        || misaligned(bytes.len(), bytes.as_ptr() as usize)
    {
        return Err("kd-tree stems too short or buffers misaligned".into());
    }
    if l.leaves.size.to_native() as usize != size {
        return Err("kd-tree leaf size differs from tree size".into());
    }
    let max_leaf = l.max_leaf_len.to_native() as usize;
    let mut total = 0usize;
    for e in extents {
        let (off, len) = (e.0.to_native() as usize, e.1.to_native() as usize);
        let end = len.checked_mul(16).and_then(|n| n.checked_add(off));
        if off % 4 != 0 || len > max_leaf || end.is_none_or(|end| end > bytes.len()) {
            return Err(format!("kd-tree leaf extent {off}+{len} out of bounds"));
        }
        total += len;
        check_leaf(&bytes[off..off + 16 * len], len, items)?;
    }
    if total != size {
        return Err(format!(
            "kd-tree leaves hold {total} points, size says {size}"
        ));
    }
    Ok(())
}

fn check_leaf(mut bytes: &[u8], len: usize, items: usize) -> Result<(), String> {
    for w in tile_widths(len) {
        let (coords, rest) = bytes.split_at(12 * w);
        let (item_bytes, rest) = rest.split_at(4 * w);
        if coords
            .chunks_exact(4)
            .any(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]).is_nan())
        {
            return Err("kd-tree leaf holds a NaN coordinate".into());
        }
        if item_bytes
            .chunks_exact(4)
            .any(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize >= items)
        {
            return Err(format!(
                "kd-tree leaf holds an item out of range (< {items})"
            ));
        }
        bytes = rest;
    }
    Ok(())
}
