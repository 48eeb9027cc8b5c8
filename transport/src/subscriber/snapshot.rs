//! [`Snapshot`]: a consistent cut of a scene, held zero-copy in shared memory.

use std::sync::Arc;

use super::segment::HeldSegment;
use crate::protocol::ManifestEntry;

/// One layer of a [`Snapshot`].
#[derive(Debug, Clone)]
pub(crate) struct SnapshotLayer {
    pub(crate) entry: ManifestEntry,
    pub(crate) segment: Arc<HeldSegment>,
}

/// A consistent cut of a scene: one manifest and, for each layer it names, the layer segment of
/// exactly the generation it names (DESIGN.md §5).
///
/// The bytes stay in the writer's shared memory; the snapshot keeps the samples (and the
/// reader's iceoryx2 ports they came through) alive until it is dropped, so the writer cannot
/// reuse them meanwhile. A snapshot stays valid after its writer died and after its
/// [`SegmentSubscriber`](crate::SegmentSubscriber) was dropped.
///
/// Unchanged layers are shared, not re-received, between consecutive snapshots: a layer
/// segment is identified by `(`[`session`](Self::session)`, `[`layer_generation`](Self::layer_generation)`)`,
/// and two snapshots with the same identity for a layer hand out the very same bytes (same
/// address). Validate a layer once per identity and reuse the result (DESIGN.md §5).
///
/// Every byte slice starts 128-byte aligned. The bytes are not validated beyond the transport
/// header: validate archives before use (shared memory is untrusted input).
#[derive(Debug)]
pub struct Snapshot {
    pub(crate) session: u64,
    pub(crate) generation: u64,
    pub(crate) manifest: Arc<HeldSegment>,
    pub(crate) manifest_offset: usize,
    /// Sorted by layer id.
    pub(crate) layers: Vec<SnapshotLayer>,
}

impl Snapshot {
    /// The snapshot generation (the manifest's).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The session id of the writer instance that published it; a restarted writer has a
    /// new one and may start generations over.
    pub fn session(&self) -> u64 {
        self.session
    }

    /// When the writer began publishing this cut (nanoseconds since the Unix epoch, writer's
    /// clock; see [`SegmentHeader::published_unix_ns`](crate::protocol::SegmentHeader)).
    pub fn published_unix_ns(&self) -> u64 {
        self.manifest.header().published_unix_ns
    }

    /// The store's manifest bytes (after the transport prefix).
    pub fn manifest_bytes(&self) -> &[u8] {
        &self.manifest.bytes()[self.manifest_offset..]
    }

    /// The layers of the snapshot and their generations, by increasing layer id.
    pub fn entries(&self) -> impl ExactSizeIterator<Item = ManifestEntry> + '_ {
        self.layers.iter().map(|l| l.entry)
    }

    /// Number of layers.
    pub fn layer_count(&self) -> usize {
        self.layers.len()
    }

    /// The bytes of layer `layer_id`, if the snapshot has that layer.
    pub fn layer(&self, layer_id: u64) -> Option<&[u8]> {
        self.find(layer_id).map(|l| l.segment.bytes())
    }

    /// The generation of layer `layer_id` in this snapshot.
    pub fn layer_generation(&self, layer_id: u64) -> Option<u64> {
        self.find(layer_id).map(|l| l.entry.generation)
    }

    /// Every layer with its bytes, by increasing layer id.
    pub fn layers(&self) -> impl ExactSizeIterator<Item = (ManifestEntry, &[u8])> + '_ {
        self.layers.iter().map(|l| (l.entry, l.segment.bytes()))
    }

    fn find(&self, layer_id: u64) -> Option<&SnapshotLayer> {
        self.layers
            .binary_search_by_key(&layer_id, |l| l.entry.layer_id)
            .ok()
            .map(|i| &self.layers[i])
    }

    pub(crate) fn key(&self) -> (u64, u64) {
        (self.session, self.generation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_send_sync<T: Send + Sync>() {}

    #[test]
    fn snapshots_can_be_shared_across_threads() {
        assert_send_sync::<Snapshot>();
        assert_send_sync::<Arc<Snapshot>>();
    }
}
