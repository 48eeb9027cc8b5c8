//! Assembling consistent snapshots from the segments a reader receives (DESIGN.md §5).
//!
//! Segments arrive in publish order on the stream (a cut's segments, then its manifest),
//! interleaved with catch-up bursts (copies of the current snapshot's segments, then its
//! manifest). Each received sample is filed at once, in order: a segment is kept as the
//! newest of its id (or, if a catch-up copy, with its burst), a manifest is assembled from
//! the burst, what is kept and the current snapshot. A segment the current snapshot already holds is dropped on
//! arrival, so a burst meant for another reader costs a receive and a header check per
//! segment. A manifest that cannot be assembled stays pending: its missing segments were
//! overflowed away (the stream carries a manifest after its segments), so the reader asks for
//! a catch-up burst.

use std::collections::BTreeMap;
use std::sync::Arc;

use super::segment::HeldSegment;
use super::snapshot::{Snapshot, SnapshotLayer};
use crate::protocol::{self, FLAG_CATCH_UP, ManifestEntry, SegmentError, SegmentKind};

/// A manifest received and checked, not assembled yet.
pub(crate) struct PendingManifest {
    segment: Arc<HeldSegment>,
    entries: Vec<ManifestEntry>,
    offset: usize,
}

/// What a reader keeps between receives.
#[derive(Default)]
pub(crate) struct Assembly {
    /// Segments newer than the current snapshot's, the newest per id.
    held: BTreeMap<u64, Arc<HeldSegment>>,
    /// The segments of the catch-up burst being received, until its manifest.
    burst: BTreeMap<u64, Arc<HeldSegment>>,
    /// The newest manifest that could not be assembled yet.
    pending: Option<PendingManifest>,
    current: Option<Arc<Snapshot>>,
}

impl Assembly {
    /// The newest complete snapshot.
    pub(crate) fn current(&self) -> Option<&Arc<Snapshot>> {
        self.current.as_ref()
    }

    /// Whether a manifest waits for segments that will not come by themselves.
    pub(crate) fn is_stuck(&self) -> bool {
        self.pending.is_some()
    }

    /// Files one received segment. A manifest that breaks the protocol is reported and
    /// dropped.
    pub(crate) fn accept(&mut self, segment: HeldSegment) -> Result<(), SegmentError> {
        let catch_up = segment.header().flags & FLAG_CATCH_UP != 0;
        match segment.kind() {
            SegmentKind::Layer => {
                self.accept_layer(segment, catch_up);
                Ok(())
            }
            SegmentKind::Manifest => self.accept_manifest(segment),
        }
    }

    /// Tries the pending manifest again (its segments may have arrived after it).
    pub(crate) fn retry_pending(&mut self) {
        if let Some(pending) = self.pending.take() {
            self.pending = self.assemble(pending).err();
        }
    }

    /// Forgets everything a writer that is gone left half-published.
    pub(crate) fn drop_incomplete(&mut self) {
        self.held.clear();
        self.burst.clear();
        self.pending = None;
    }

    fn accept_layer(&mut self, segment: HeldSegment, catch_up: bool) {
        let id = segment.header().layer_id;
        let (session, generation) = segment.version();
        // Already held, or older than what the current snapshot holds: nothing to keep.
        if let Some(current) = &self.current
            && current.session == session
            && current
                .layer_generation(id)
                .is_some_and(|g| g >= generation)
        {
            return;
        }
        let segment = Arc::new(segment);
        if catch_up {
            // A burst is one writer's snapshot, one segment per id.
            if self
                .burst
                .values()
                .next()
                .is_some_and(|s| s.header().session != session)
            {
                self.burst.clear();
            }
            self.burst.insert(id, segment);
        } else {
            self.keep(id, segment);
        }
    }

    fn accept_manifest(&mut self, segment: HeldSegment) -> Result<(), SegmentError> {
        let (entries, offset) = protocol::decode_manifest_prefix(segment.bytes())?;
        let (session, generation) = segment.version();
        let newer = |(s, g): (u64, u64)| s == session && g > generation;
        let not_newer_than = |(s, g): (u64, u64)| s == session && g >= generation;
        if self
            .current
            .as_ref()
            .is_some_and(|c| not_newer_than(c.key()))
            || self
                .pending
                .as_ref()
                .is_some_and(|p| newer(p.segment.version()))
        {
            return Ok(());
        }
        let manifest = PendingManifest {
            segment: Arc::new(segment),
            entries,
            offset,
        };
        self.pending = self.assemble(manifest).err();
        Ok(())
    }

    /// Keeps `segment` as the newest of `id` unless a newer one of the same session is kept.
    fn keep(&mut self, id: u64, segment: Arc<HeldSegment>) {
        let (session, generation) = segment.version();
        match self.held.get(&id) {
            Some(old)
                if old.header().session == session && old.header().generation >= generation => {}
            _ => {
                self.held.insert(id, segment);
            }
        }
    }

    /// Makes `manifest` the current snapshot if every segment it names is at hand (kept, in
    /// the burst being received, or in the current snapshot); otherwise hands it back.
    fn assemble(&mut self, manifest: PendingManifest) -> Result<(), PendingManifest> {
        let session = manifest.segment.header().session;
        let previous = self
            .current
            .as_deref()
            .filter(|c| c.session == session)
            .map_or(&[][..], |c| &c.layers[..]);
        let mut at = 0;
        let mut layers = Vec::with_capacity(manifest.entries.len());
        for entry in &manifest.entries {
            let wanted = (session, entry.generation);
            let is_wanted = |s: &&Arc<HeldSegment>| s.version() == wanted;
            // Both lists are sorted by id: walk the previous snapshot's along.
            while previous
                .get(at)
                .is_some_and(|l| l.entry.layer_id < entry.layer_id)
            {
                at += 1;
            }
            // An entry unchanged since the current snapshot names the segment it holds:
            // `held` and `burst` keep only newer ones, so that is looked at first (most
            // entries of a cut are unchanged; this saves two map lookups each).
            let found = previous
                .get(at)
                .filter(|l| l.entry == *entry)
                .map(|l| &l.segment)
                .or_else(|| self.held.get(&entry.layer_id).filter(is_wanted))
                .or_else(|| self.burst.get(&entry.layer_id).filter(is_wanted));
            let Some(segment) = found else {
                return Err(manifest);
            };
            layers.push(SnapshotLayer {
                entry: *entry,
                segment: Arc::clone(segment),
            });
        }
        let snapshot = Snapshot {
            session,
            generation: manifest.segment.header().generation,
            manifest: manifest.segment,
            manifest_offset: manifest.offset,
            layers,
        };
        // Keep only segments newer than the new snapshot's.
        let is_newer = |id: &u64, s: &mut Arc<HeldSegment>| {
            s.header().session == session
                && snapshot
                    .layer_generation(*id)
                    .is_none_or(|g| s.header().generation > g)
        };
        self.held.retain(is_newer);
        self.burst.retain(is_newer);
        self.pending = None;
        self.current = Some(Arc::new(snapshot));
        Ok(())
    }
}
