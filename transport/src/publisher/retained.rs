//! The writer's hold on the current snapshot: what a catch-up burst copies.
//!
//! iceoryx2 cannot send a sample twice, and a publisher forgets a sample once it is sent. So
//! the writer subscribes to its own segment stream and keeps, per segment id, the sample the
//! newest manifest names (`current`) and a newer one not named yet (`next`: published, its
//! manifest still to come). A catch-up burst copies `current` and the newest manifest, which
//! form a consistent cut whenever the burst runs, also in the middle of a cut.

use std::collections::BTreeMap;
use std::sync::Arc;

use iceoryx2::port::subscriber::Subscriber;

use crate::protocol::{Block128, FLAG_CATCH_UP, MANIFEST_LAYER_ID, ManifestEntry, SegmentHeader};
use crate::service::Ipc;
use crate::subscriber::HeldSegment;

/// A sample of the segment stream, as the writer's own subscriber holds it.
pub(crate) type RetainedSample = Arc<HeldSegment>;

/// The two samples kept per segment id.
#[derive(Default)]
struct Slots {
    current: Option<RetainedSample>,
    next: Option<RetainedSample>,
}

/// The writer's own subscription to its segment stream and the samples it keeps.
pub(crate) struct Retained {
    subscriber: Subscriber<Ipc, [Block128], SegmentHeader>,
    segments: BTreeMap<u64, Slots>,
    /// Segment ids published since the last manifest.
    touched: Vec<u64>,
    manifest: Option<RetainedSample>,
    /// What `manifest` names.
    entries: Vec<ManifestEntry>,
}

impl Retained {
    pub(crate) fn new(subscriber: Subscriber<Ipc, [Block128], SegmentHeader>) -> Self {
        Self {
            subscriber,
            segments: BTreeMap::new(),
            touched: Vec::new(),
            manifest: None,
            entries: Vec::new(),
        }
    }

    /// Receives what the writer just sent (called right after each send, so the subscriber's
    /// buffer never overflows) and files it; catch-up copies are dropped. `entries` are those
    /// of the manifest just sent, if one was.
    pub(crate) fn receive(&mut self, entries: Option<&[ManifestEntry]>) {
        while let Ok(Some(sample)) = self.subscriber.receive() {
            // The writer's own segments pass the check; one that did not could not be copied.
            let Ok(sample) = HeldSegment::new(sample) else {
                continue;
            };
            let header = *sample.header();
            if header.flags & FLAG_CATCH_UP != 0 {
                continue;
            }
            let sample = Arc::new(sample);
            if header.layer_id == MANIFEST_LAYER_ID {
                let entries = entries.unwrap_or_default();
                self.promote(entries);
                self.entries.clear();
                self.entries.extend_from_slice(entries);
                self.manifest = Some(sample);
            } else {
                self.segments.entry(header.layer_id).or_default().next = Some(sample);
                self.touched.push(header.layer_id);
            }
        }
    }

    /// A manifest naming `entries` was sent: the `next` samples it names become current.
    fn promote(&mut self, entries: &[ManifestEntry]) {
        for id in self.touched.drain(..) {
            let Some(slots) = self.segments.get_mut(&id) else {
                continue;
            };
            let named = entries
                .binary_search_by_key(&id, |e| e.layer_id)
                .ok()
                .map(|i| entries[i].generation);
            let next_generation = slots.next.as_ref().map(|s| s.header().generation);
            if named.is_some() && named == next_generation {
                slots.current = slots.next.take();
            }
        }
    }

    /// Forgets segment `id` (retired by the writer).
    pub(crate) fn forget(&mut self, id: u64) {
        self.segments.remove(&id);
    }

    /// The current snapshot's segments, then its manifest (empty before the first manifest).
    pub(crate) fn snapshot(&self) -> Vec<RetainedSample> {
        let Some(manifest) = &self.manifest else {
            return Vec::new();
        };
        let mut out: Vec<RetainedSample> = self
            .entries
            .iter()
            .filter_map(|e| self.segments.get(&e.layer_id)?.current.clone())
            .collect();
        out.push(Arc::clone(manifest));
        out
    }
}
