//! Joining a reader's next cut without checking again what it checked in the last one:
//! [`CheckedManifest`] (a manifest whose structure passed the checks) and [`KnownParts`]
//! (what of a cut [`super::ArchivedScene::rejoin`] may take as checked).
//!
//! Between two structure changes a publishing writer changes only fixed-size fields of
//! its manifest: the cut's generation and each layer's generation, node count and id
//! bounds (`cut_field_offsets` in the schema; the writer patches them in place). Every bit pattern of
//! those `u64` fields is valid, so a manifest equal to a checked one everywhere else is as
//! valid as it, and its layer DAG, layer names and term lists are the ones checked.

#![allow(
    unsafe_code,
    reason = "re-deriving a manifest from bytes equal to validated ones but for integers"
)]

use crate::bytes::ARCHIVE_ALIGN;
use crate::snapshot::schema::{ArchivedManifest, cut_field_offsets};

/// A manifest that passed [`super::validate_manifest`] and the structure checks of a
/// join, kept (a private copy) so that the next cut's manifest is compared with it
/// rather than checked again.
#[derive(Debug, Clone)]
pub struct CheckedManifest {
    /// The checked bytes.
    bytes: Vec<u8>,
    /// Where the checked bytes lay, modulo [`ARCHIVE_ALIGN`]: rkyv's checks are of
    /// alignments up to that, so equal bytes at the same residue are equally valid.
    residue: usize,
    /// The byte ranges outside the per-cut fields, ascending and disjoint.
    fixed: Vec<std::ops::Range<usize>>,
}

impl CheckedManifest {
    /// Remembers `manifest`, read from `bytes` (its archived bytes), after
    /// [`super::validate_manifest`] accepted them and a join accepted its structure.
    ///
    /// # Panics
    /// If `manifest` does not lie inside `bytes` (a caller's bug, not bad input).
    pub fn new(bytes: &[u8], manifest: &ArchivedManifest) -> Self {
        let base = bytes.as_ptr().addr();
        assert!(
            (base..base + bytes.len()).contains(&std::ptr::from_ref(manifest).addr()),
            "the manifest is not read from these bytes"
        );
        let (generation, layers) = cut_field_offsets(manifest, base);
        let mut fields: Vec<usize> = layers.into_iter().flatten().collect();
        fields.push(generation);
        fields.sort_unstable();
        let mut fixed = Vec::with_capacity(fields.len() + 1);
        let mut from = 0;
        for f in fields {
            if f > from {
                fixed.push(from..f);
            }
            from = f + 8;
        }
        if from < bytes.len() {
            fixed.push(from..bytes.len());
        }
        CheckedManifest {
            bytes: bytes.to_vec(),
            residue: base % ARCHIVE_ALIGN,
            fixed,
        }
    }

    /// `bytes` as a manifest, without validating them again, if they are the checked
    /// manifest but for its per-cut fields (same length, same alignment residue, every
    /// other byte equal); `None` otherwise (the caller validates them in full).
    pub fn same_structure<'a>(&self, bytes: &'a [u8]) -> Option<&'a ArchivedManifest> {
        let same = bytes.len() == self.bytes.len()
            && bytes.as_ptr().addr() % ARCHIVE_ALIGN == self.residue
            && self
                .fixed
                .iter()
                .all(|r| bytes[r.clone()] == self.bytes[r.clone()]);
        // SAFETY: `self.bytes` passed `validate_manifest` (rkyv's bytecheck) at an address
        // with the same residue modulo ARCHIVE_ALIGN (the largest alignment any archived
        // type asks for), so every alignment check holds here too; `bytes` has the same
        // length and equal bytes everywhere but at the per-cut fields, which are plain
        // little-endian u64s (every bit pattern valid). rkyv's relative pointers are
        // position-independent, so `bytes` is a valid archived manifest.
        same.then(|| unsafe { rkyv::access_unchecked::<ArchivedManifest>(bytes) })
    }
}

/// What [`super::ArchivedScene::rejoin`] may take as checked, because the same reader
/// joined it in an earlier cut.
#[derive(Debug, Clone, Copy, Default)]
pub struct KnownParts<'k> {
    /// The manifest has the structure of one a join accepted (see
    /// [`CheckedManifest::same_structure`]): ascending layer ids, DAG, names and term
    /// lists need no check.
    pub structure: bool,
    /// Per layer position in the manifest: `true` if the layer's segment is the very
    /// bytes of an earlier accepted cut, its manifest entry has the generation and node
    /// count it had there, and it named no point or tree chunk there. Shorter than the
    /// layer count: the rest are unknown.
    pub layers: &'k [bool],
}

impl KnownParts<'_> {
    /// Nothing known: a join checks everything.
    pub const NONE: KnownParts<'static> = KnownParts {
        structure: false,
        layers: &[],
    };

    /// Whether the layer at manifest position `i` is known.
    pub(super) fn layer(&self, i: usize) -> bool {
        self.layers.get(i).copied().unwrap_or(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{SegmentBytes, archive, validate_manifest};
    use crate::{NodeId, SceneGraph};

    /// A manifest of two layers, archived, at generation `generation` with `nodes` nodes
    /// in its second layer.
    fn manifest_bytes(generation: u64, nodes: u64, name: &str) -> SegmentBytes {
        let mut g = SceneGraph::new();
        let rooms = g.add_layer("rooms").unwrap();
        let objects = g.add_layer(name).unwrap();
        g.add_layer_edge(rooms, objects).unwrap();
        for id in 0..nodes {
            g.add_node(NodeId(10 + id), objects).unwrap();
        }
        archive(&g.manifest(generation))
    }

    #[test]
    fn a_manifest_differing_only_in_cut_fields_has_the_checked_structure() {
        let first = manifest_bytes(1, 2, "objects");
        let checked = CheckedManifest::new(&first, validate_manifest(&first, "m").unwrap());
        let next = manifest_bytes(7, 5, "objects");
        let m = checked
            .same_structure(&next)
            .expect("only cut fields differ");
        assert_eq!(m.generation.to_native(), 7);
        assert_eq!(m.layers[1].node_count.to_native(), 5);
        assert_eq!(m.layers[1].max_id.to_native(), 14);

        // Another name of the same length, a byte flipped, another length.
        assert!(
            checked
                .same_structure(&manifest_bytes(1, 2, "objectz"))
                .is_none()
        );
        let mut flipped = first.clone();
        let at = flipped.len() / 3;
        flipped[at] ^= 1;
        assert!(checked.same_structure(&flipped).is_none());
        assert!(
            checked
                .same_structure(&manifest_bytes(1, 2, "things"))
                .is_none()
        );
        assert!(checked.same_structure(&first[..first.len() - 8]).is_none());
    }

    #[test]
    fn equal_bytes_at_another_alignment_are_not_taken_as_checked() {
        let first = manifest_bytes(1, 2, "objects");
        let checked = CheckedManifest::new(&first, validate_manifest(&first, "m").unwrap());
        let mut shifted = SegmentBytes::new();
        shifted.extend_from_slice(&[0; 16]);
        shifted.extend_from_slice(&first);
        assert!(checked.same_structure(&shifted[16..]).is_none());
        assert!(checked.same_structure(&first).is_some());
    }
}
