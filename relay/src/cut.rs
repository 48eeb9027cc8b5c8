//! [`Assembler`]: the importer's bookkeeping. It validates every segment and manifest that
//! arrives, keeps the valid ones, and hands out a [`Cut`] only when it holds every segment,
//! of exactly the named generation, that the newest manifest names: a cut never mixes
//! generations.

use std::collections::BTreeMap;
use std::sync::Arc;

use ygg_store::SnapshotError;
use ygg_store::snapshot::{
    SegmentBytes, is_chunk_segment_id, is_structure_segment_id, is_tree_chunk_segment_id,
    validate_chunk, validate_layer, validate_manifest, validate_structure, validate_tree_chunk,
};
use ygg_transport::ManifestEntry;
use ygg_transport::protocol::{SegmentError, decode_manifest_prefix};

/// A received segment or manifest that is not valid; the assembler keeps nothing of it.
#[derive(Debug, thiserror::Error)]
pub enum AssembleError {
    /// The store's validation refused the bytes.
    #[error(transparent)]
    Snapshot(#[from] SnapshotError),
    /// The manifest's transport prefix is malformed.
    #[error(transparent)]
    ManifestPrefix(#[from] SegmentError),
}

/// Generations kept per segment id beyond the ones the last cut named (segments of a cut
/// that is still arriving).
const KEPT_GENERATIONS: usize = 4;

/// A validated manifest: the transport entries and the whole payload.
#[derive(Debug)]
pub struct ManifestPayload {
    /// Writer session.
    pub session: u64,
    /// Snapshot generation.
    pub generation: u64,
    /// The segments the snapshot is made of, by increasing id.
    pub entries: Vec<ManifestEntry>,
    /// The payload as received: transport prefix, then the store's manifest bytes.
    pub bytes: SegmentBytes,
    /// Where the store's manifest bytes start in `bytes`.
    pub offset: usize,
}

impl ManifestPayload {
    /// The store's manifest bytes.
    pub fn store_bytes(&self) -> &[u8] {
        &self.bytes[self.offset..]
    }
}

/// A consistent snapshot ready to republish: the manifest and, in its entry order, the
/// bytes of each segment it names.
#[derive(Debug)]
pub struct Cut {
    /// The manifest.
    pub manifest: ManifestPayload,
    /// One validated payload per manifest entry, same order.
    pub segments: Vec<Arc<SegmentBytes>>,
}

/// Validated segments and the newest manifest, per writer session.
#[derive(Debug, Default)]
pub struct Assembler {
    /// Validated segments by (session, segment id, generation).
    segments: BTreeMap<(u64, u64, u64), Arc<SegmentBytes>>,
    /// The newest validated manifest not handed out yet.
    pending: Option<ManifestPayload>,
    /// (session, generation) of the last cut handed out.
    last: Option<(u64, u64)>,
}

impl Assembler {
    /// An empty assembler.
    pub fn new() -> Self {
        Self::default()
    }

    /// Validates a segment (the store's `validate_layer` for a part, `validate_chunk` /
    /// `validate_tree_chunk` for a point or tree chunk, `validate_structure` for the
    /// structure: what a local reader runs) and keeps it.
    ///
    /// # Errors
    /// Why the bytes are not a valid segment; nothing is kept then.
    pub fn add_segment(
        &mut self,
        session: u64,
        id: u64,
        generation: u64,
        bytes: SegmentBytes,
    ) -> Result<(), AssembleError> {
        if self.segments.contains_key(&(session, id, generation)) {
            return Ok(());
        }
        let what = format!("segment {id} generation {generation}");
        if is_structure_segment_id(id) {
            validate_structure(&bytes, &what)?;
        } else if is_tree_chunk_segment_id(id) {
            validate_tree_chunk(&bytes, &what)?;
        } else if is_chunk_segment_id(id) {
            validate_chunk(&bytes, &what)?;
        } else {
            validate_layer(&bytes, &what)?;
        }
        self.segments
            .insert((session, id, generation), Arc::new(bytes));
        // Bound what a stream of segments without manifests can hold.
        let held: Vec<u64> = self
            .segments
            .range((session, id, 0)..=(session, id, u64::MAX))
            .map(|(k, _)| k.2)
            .collect();
        for old in held
            .iter()
            .take(held.len().saturating_sub(KEPT_GENERATIONS))
        {
            self.segments.remove(&(session, id, *old));
        }
        Ok(())
    }

    /// Validates a manifest payload (the transport prefix, then the store's
    /// `validate_manifest`) and keeps it if it is newer than the last cut and the pending
    /// manifest of the same session. Returns whether it was kept.
    ///
    /// # Errors
    /// Why the bytes are not a valid manifest; nothing is kept then.
    pub fn add_manifest(
        &mut self,
        session: u64,
        generation: u64,
        bytes: SegmentBytes,
    ) -> Result<bool, AssembleError> {
        let newer =
            |known: Option<(u64, u64)>| known.is_none_or(|(s, g)| s != session || generation > g);
        let pending = self.pending.as_ref().map(|m| (m.session, m.generation));
        if !newer(self.last) || !newer(pending) {
            return Ok(false);
        }
        let (entries, offset) = decode_manifest_prefix(&bytes)?;
        validate_manifest(
            &bytes[offset..],
            &format!("manifest generation {generation}"),
        )?;
        self.pending = Some(ManifestPayload {
            session,
            generation,
            entries,
            bytes,
            offset,
        });
        Ok(true)
    }

    /// The segments (id, generation) the pending manifest names that have not arrived: a
    /// gap when the manifest came first.
    pub fn missing(&self) -> Vec<ManifestEntry> {
        let Some(m) = &self.pending else {
            return Vec::new();
        };
        m.entries
            .iter()
            .filter(|e| {
                !self
                    .segments
                    .contains_key(&(m.session, e.layer_id, e.generation))
            })
            .copied()
            .collect()
    }

    /// The pending manifest with all its segments, if every one has arrived; forgets
    /// segments no later cut can use.
    pub fn take_cut(&mut self) -> Option<Cut> {
        if self.pending.is_none() || !self.missing().is_empty() {
            return None;
        }
        let manifest = self.pending.take()?;
        let segments = manifest
            .entries
            .iter()
            .map(|e| Arc::clone(&self.segments[&(manifest.session, e.layer_id, e.generation)]))
            .collect();
        let named: BTreeMap<u64, u64> = manifest
            .entries
            .iter()
            .map(|e| (e.layer_id, e.generation))
            .collect();
        self.segments.retain(|&(session, id, generation), _| {
            session == manifest.session && named.get(&id).is_none_or(|&g| generation >= g)
        });
        self.last = Some((manifest.session, manifest.generation));
        Some(Cut { manifest, segments })
    }

    /// Forgets the last cut handed out, so that the next complete one is handed out even if
    /// it is the same generation (after the local publisher was dropped).
    pub fn forget_last(&mut self) {
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ygg_store::{NodeId, SceneGraph, SceneView};
    use ygg_transport::protocol::{encode_manifest_prefix, manifest_prefix_len};

    fn aligned(bytes: &[u8]) -> SegmentBytes {
        let mut out = SegmentBytes::with_capacity(bytes.len());
        out.extend_from_slice(bytes);
        out
    }

    /// Two generations of a two-layer graph: (manifest payload, its segments: the layers'
    /// parts and the structure) each.
    fn generations() -> Vec<(SegmentBytes, Vec<(ManifestEntry, SegmentBytes)>)> {
        let mut g = SceneGraph::new();
        let a = g.add_layer("a").expect("layer");
        let b = g.add_layer("b").expect("layer");
        g.add_node(NodeId(1), a).expect("node");
        g.add_node(NodeId(2), b).expect("node");
        let mut out = Vec::new();
        for step in 0..2 {
            g.set_geometry(NodeId(1), vec![[step as f32, 0.0, 0.0]])
                .expect("geometry");
            let archived = g.to_segments();
            let mut entries: Vec<ManifestEntry> = g
                .layers()
                .map(|l| ManifestEntry {
                    layer_id: ygg_store::snapshot::part_segment_id(l, 0).expect("fits"),
                    generation: g.layer_generation(l).expect("layer"),
                })
                .collect();
            // `to_segments` archives structure generation 1.
            entries.push(ManifestEntry {
                layer_id: ygg_store::snapshot::STRUCTURE_SEGMENT_ID,
                generation: 1,
            });
            let mut segments = archived.layers;
            segments.push(archived.structure);
            let mut payload = vec![0; manifest_prefix_len(entries.len())];
            encode_manifest_prefix(&entries, &mut payload);
            payload.extend_from_slice(&archived.manifest);
            out.push((
                aligned(&payload),
                entries.into_iter().zip(segments).collect(),
            ));
        }
        out
    }

    #[test]
    fn a_cut_is_handed_out_only_when_every_named_generation_arrived() {
        let gens = generations();
        let mut asm = Assembler::new();
        let (manifest0, layers0) = &gens[0];
        assert!(asm.add_manifest(1, 1, manifest0.clone()).expect("valid"));
        assert_eq!(asm.missing().len(), 3, "the manifest came first: a gap");
        assert!(asm.take_cut().is_none());
        for (e, bytes) in layers0 {
            asm.add_segment(1, e.layer_id, e.generation, bytes.clone())
                .expect("valid");
        }
        let cut = asm.take_cut().expect("complete");
        assert_eq!(cut.manifest.generation, 1);
        assert_eq!(&cut.segments[0][..], &layers0[0].1[..]);

        // Generation 2 changes layer a only; a manifest naming it waits for that segment,
        // never mixing in generation 1's.
        let (manifest1, layers1) = &gens[1];
        assert!(asm.add_manifest(1, 2, manifest1.clone()).expect("valid"));
        let changed = layers1
            .iter()
            .find(|(e, _)| !layers0.iter().any(|(e0, _)| e0 == e))
            .expect("a changed layer");
        assert_eq!(asm.missing(), vec![changed.0]);
        assert!(asm.take_cut().is_none());
        asm.add_segment(
            1,
            changed.0.layer_id,
            changed.0.generation,
            changed.1.clone(),
        )
        .expect("valid");
        let cut = asm.take_cut().expect("complete");
        assert_eq!(cut.manifest.generation, 2);
        // An older manifest of the same session is ignored.
        assert!(!asm.add_manifest(1, 1, manifest0.clone()).expect("valid"));
    }

    #[test]
    fn garbage_is_refused_and_kept_nowhere() {
        let gens = generations();
        let mut asm = Assembler::new();
        let garbage = aligned(&[0xAB; 300]);
        assert!(asm.add_segment(1, 0, 1, garbage.clone()).is_err());
        assert!(asm.add_manifest(1, 1, garbage).is_err());
        // A valid transport prefix followed by garbage store bytes is refused too.
        let (manifest, _) = &gens[0];
        let mut broken = manifest.clone();
        let len = broken.len();
        broken[len - 8..].fill(0xFF);
        broken[manifest_prefix_len(2)..manifest_prefix_len(2) + 16].fill(0xEE);
        assert!(asm.add_manifest(1, 1, broken).is_err());
        assert!(asm.missing().is_empty());
        assert!(asm.take_cut().is_none());
    }
}
