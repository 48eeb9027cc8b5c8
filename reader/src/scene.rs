//! [`SceneReader`]: attach to a published scene and query validated snapshots in place.
//!
//! # Trust
//! Shared memory is untrusted input: every manifest and every new layer segment is
//! validated (rkyv bytecheck plus the store's consistency pass) before any query touches
//! it. A layer segment is validated once per identity `(session, layer, generation)`;
//! later snapshots reuse the result only when they hand out the very same bytes (same
//! address and length, which the transport guarantees for an unchanged layer). The manifest
//! (fixed-size per-cut values) is validated each cut; the structure segment (names, DAG,
//! parts, term indexes) once per generation, and the join of the cut re-checks only the
//! layers that changed ([`crate::join_memo`]).
//!
//! Validation is a check at one moment. The reader maps samples read-only, but the
//! writer keeps its read-write mapping, and any process of the same user can open the
//! segment files read-write: such a process can change bytes after they were validated.
//! With [`SceneReaderBuilder::copy_segments`] the reader copies each newly received
//! segment into private memory and validates and queries the copy, so nothing another
//! process does afterwards reaches it (see the crate docs for the whole trust model).

#![expect(
    unsafe_code,
    reason = "re-deriving archives from bytes validated by this module"
)]

use crate::join_memo::JoinMemo;
use std::collections::HashMap;
use std::sync::{Arc, Weak};
use std::time::Duration;
use ygg_store::SnapshotError;
use ygg_store::snapshot::{
    ArchivedScene, KnownParts, SegmentBytes, chunk_unchecked, is_chunk_segment_id,
    is_structure_segment_id, is_tree_chunk_segment_id, layer_unchecked, segment_layer_part,
    structure_unchecked, tree_chunk_unchecked, validate_chunk, validate_layer, validate_manifest,
    validate_structure, validate_tree_chunk,
};
use ygg_transport::{
    ReaderOpenError, ReceiveError, SegmentSubscriber, Snapshot, SubscriberBuilder, WriterStatus,
};

/// Why no snapshot could be delivered.
#[derive(Debug, thiserror::Error)]
pub enum SceneReceiveError {
    /// The transport failed (writer gone, corrupt segment header, ...).
    #[error(transparent)]
    Receive(#[from] ReceiveError),
    /// The snapshot's bytes failed validation; the previous snapshot stays current.
    #[error("scene {scene}: snapshot {generation} rejected: {source}")]
    Invalid {
        /// The scene.
        scene: String,
        /// The rejected snapshot generation.
        generation: u64,
        /// What validation found.
        source: SnapshotError,
    },
}

/// A validated, consistent cut of a published scene, held zero-copy (or, with
/// [`SceneReaderBuilder::copy_segments`], as private copies).
///
/// Cheap to clone (an `Arc`); the shared-memory samples stay alive until the last clone
/// is dropped. Query it through [`SceneSnapshot::view`].
#[derive(Clone)]
pub struct SceneSnapshot {
    cut: Arc<JoinedCut>,
}

/// The bytes of an accepted cut: the transport's samples and, in copy mode, the private
/// copies that were validated and are queried instead.
struct CutBytes {
    inner: Arc<Snapshot>,
    private: Option<Arc<PrivateCut>>,
}

/// Private copies of a snapshot's manifest and layers (layers in `Snapshot::layers`
/// order); a layer unchanged since the previous snapshot shares its copy.
struct PrivateCut {
    manifest: SegmentBytes,
    layers: Vec<Arc<SegmentBytes>>,
}

impl CutBytes {
    /// The bytes queried: the manifest's and each segment's (parts, point chunks, tree
    /// chunks, then the structure), in `Snapshot::layers` order.
    fn bytes(&self) -> (&[u8], Vec<&[u8]>) {
        match &self.private {
            Some(p) => (&p.manifest, p.layers.iter().map(|l| &l[..]).collect()),
            None => (
                self.inner.manifest_bytes(),
                self.inner.layers().map(|(_, b)| b).collect(),
            ),
        }
    }
}

self_cell::self_cell!(
    /// A cut's bytes and the view `SceneReader::accept` joined over them once, which
    /// every query of the cut reuses.
    struct JoinedCut {
        owner: CutBytes,
        #[covariant]
        dependent: ArchivedScene,
    }
);

impl SceneSnapshot {
    /// The scene as a [`ygg_store::SceneView`]: every query of the store runs on it. The
    /// view was joined once, when the reader accepted the cut; this call costs nothing.
    pub fn view(&self) -> &ArchivedScene<'_> {
        self.cut.borrow_dependent()
    }

    /// The snapshot generation.
    pub fn generation(&self) -> u64 {
        self.raw().generation()
    }

    /// The transport snapshot (raw bytes per layer).
    pub fn raw(&self) -> &Snapshot {
        &self.cut.borrow_owner().inner
    }
}

/// A layer's private copy and the `(session, generation)` whose bytes it holds.
type LayerCopy = ((u64, u64), Arc<SegmentBytes>);

/// Identity of a validated layer segment: session, generation, address and length.
type SegmentIdentity = (u64, u64, usize, usize);

/// A reader of one scene: receives snapshots and validates what is new in them.
pub struct SceneReader {
    subscriber: SegmentSubscriber,
    /// The identity of each segment of the current snapshot, ascending by segment id (as a
    /// cut lists them): what a newer cut need not validate again.
    validated: Vec<(u64, SegmentIdentity)>,
    /// In copy mode: each layer's private copy.
    copies: Option<HashMap<u64, LayerCopy>>,
    current: Option<SceneSnapshot>,
    /// What the current snapshot's join lets the next one skip.
    memo: JoinMemo,
    validations: u64,
    /// The last cut refused: reported once, not validated again while it is the newest.
    refused: Weak<Snapshot>,
}

/// Configures and opens a [`SceneReader`]; see [`SceneReader::builder`].
#[derive(Debug, Clone)]
pub struct SceneReaderBuilder {
    subscriber: SubscriberBuilder,
    copy_segments: bool,
}

impl SceneReaderBuilder {
    /// If true, each newly received segment is copied into private memory and the copy is
    /// validated and queried, so that a process that rewrites the shared segment after
    /// validation cannot affect this reader (default false: zero-copy). Costs one copy of
    /// every changed layer per snapshot (a memcpy of its archived size) and the memory of
    /// the copies; unchanged layers keep their copy.
    pub fn copy_segments(mut self, value: bool) -> Self {
        self.copy_segments = value;
        self
    }

    /// How long [`SceneReaderBuilder::open`] waits for a writer to create the scene (default
    /// zero: fail at once with [`ReaderOpenError::NoWriter`]).
    pub fn wait_for_writer(mut self, value: Duration) -> Self {
        self.subscriber = self.subscriber.wait_for_writer(value);
        self
    }

    /// The iceoryx2 file-name prefix; overrides
    /// [`ygg_transport::service::ENV_IOX2_PREFIX`]. Must match the writer's.
    pub fn iceoryx_prefix(mut self, prefix: &str) -> Self {
        self.subscriber = self.subscriber.iceoryx_prefix(prefix);
        self
    }

    /// How often a waiting reader checks that the writer process is alive (default 200 ms).
    pub fn liveness_interval(mut self, value: Duration) -> Self {
        self.subscriber = self.subscriber.liveness_interval(value);
        self
    }

    /// If true, SIGINT/SIGTERM make [`SceneReader::wait_next`] return
    /// [`ReceiveError::Terminated`] so the process can exit cleanly. Off by default: a
    /// library should not take over an application's signals.
    pub fn handle_termination_signals(mut self, value: bool) -> Self {
        self.subscriber = self.subscriber.handle_termination_signals(value);
        self
    }

    /// Attaches to the scene; the first [`SceneReader::wait_next`] returns the current
    /// snapshot within milliseconds.
    ///
    /// # Errors
    /// As [`SubscriberBuilder::open`]: an invalid name, or no writer serving the scene
    /// within the wait.
    pub fn open(self) -> Result<SceneReader, ReaderOpenError> {
        Ok(SceneReader {
            subscriber: self.subscriber.open()?,
            validated: Vec::new(),
            copies: self.copy_segments.then(HashMap::new),
            current: None,
            memo: JoinMemo::default(),
            validations: 0,
            refused: Weak::new(),
        })
    }
}

impl SceneReader {
    /// A builder for a reader of `scene`, with default settings.
    pub fn builder(scene: &str) -> SceneReaderBuilder {
        SceneReaderBuilder {
            subscriber: SubscriberBuilder::new(scene),
            copy_segments: false,
        }
    }

    /// The newest snapshot, without blocking (and without ever blocking the writer).
    /// `None` until a first snapshot arrived.
    ///
    /// # Errors
    /// Transport errors, or a snapshot whose bytes fail validation. A refused snapshot is
    /// reported once: until a newer one arrives, later calls return the last accepted
    /// snapshot without validating the refused one again.
    pub fn latest(&mut self) -> Result<Option<SceneSnapshot>, SceneReceiveError> {
        let snap = self.subscriber.latest()?;
        self.accept(snap)
    }

    /// Blocks on the writer's event until a snapshot newer than the current one arrives
    /// or `timeout` passes (`Ok(None)`). No polling loop.
    ///
    /// # Errors
    /// As [`SceneReader::latest`].
    pub fn wait_next(
        &mut self,
        timeout: Duration,
    ) -> Result<Option<SceneSnapshot>, SceneReceiveError> {
        let snap = self.subscriber.wait_next(timeout)?;
        match snap {
            None => Ok(None),
            some => self.accept(some),
        }
    }

    /// Whether the writer is alive, gone, or back.
    pub fn writer_status(&self) -> WriterStatus {
        self.subscriber.writer_status()
    }

    /// The scene name.
    pub fn scene(&self) -> &str {
        self.subscriber.scene()
    }

    /// How many segments (layers, point and tree chunks) this reader has validated so far
    /// (unchanged ones are not validated again).
    pub fn validations(&self) -> u64 {
        self.validations
    }

    /// Whether SIGINT/SIGTERM was received (when the builder handles signals).
    pub fn termination_requested(&self) -> bool {
        self.subscriber.termination_requested()
    }

    /// `snap` as the current snapshot, validated (only what changed since the current
    /// one); a cut already current or already refused gives the current snapshot.
    fn accept(
        &mut self,
        snap: Option<Arc<Snapshot>>,
    ) -> Result<Option<SceneSnapshot>, SceneReceiveError> {
        let Some(snap) = snap else {
            return Ok(self.current.clone());
        };
        let current = self
            .current
            .as_ref()
            .is_some_and(|c| Arc::ptr_eq(&c.cut.borrow_owner().inner, &snap));
        // The weak pointer keeps the refused cut's allocation, so its address names it.
        if current || Weak::ptr_eq(&self.refused, &Arc::downgrade(&snap)) {
            return Ok(self.current.clone());
        }
        let refused = Arc::downgrade(&snap);
        let result = self.accept_new(snap);
        if result.is_err() {
            self.refused = refused;
        }
        result
    }

    /// [`SceneReader::accept`] of a cut neither current nor refused.
    fn accept_new(
        &mut self,
        snap: Arc<Snapshot>,
    ) -> Result<Option<SceneSnapshot>, SceneReceiveError> {
        let bytes = CutBytes {
            private: self.private_cut(&snap),
            inner: snap,
        };
        let generation = bytes.inner.generation();
        let invalid = |source| SceneReceiveError::Invalid {
            scene: self.subscriber.scene().to_owned(),
            generation,
            source,
        };
        let mut joined = Joined::default();
        let cut = JoinedCut::try_new(bytes, |bytes| {
            join(bytes, &self.validated, &self.memo, &mut joined)
        })
        .map_err(invalid)?;
        self.memo.remember(cut.borrow_dependent().manifest());
        self.validations += joined.newly as u64;
        self.validated = joined.identities;
        let accepted = SceneSnapshot { cut: Arc::new(cut) };
        self.current = Some(accepted.clone());
        Ok(Some(accepted))
    }

    /// In copy mode, private copies of `snap`'s manifest and layers: a layer whose
    /// `(session, generation)` this reader copied before keeps that copy, every other one
    /// is copied now. `None` in zero-copy mode.
    fn private_cut(&mut self, snap: &Snapshot) -> Option<Arc<PrivateCut>> {
        let copies = self.copies.as_mut()?;
        let mut layers = Vec::with_capacity(snap.layer_count());
        for (entry, bytes) in snap.layers() {
            let key = (snap.session(), entry.generation);
            let copy = match copies.get(&entry.layer_id) {
                Some((k, copy)) if *k == key => Arc::clone(copy),
                _ => {
                    let copy = Arc::new(private_copy(bytes));
                    copies.insert(entry.layer_id, (key, Arc::clone(&copy)));
                    copy
                }
            };
            layers.push(copy);
        }
        copies.retain(|id, _| snap.layer_generation(*id).is_some());
        Some(Arc::new(PrivateCut {
            manifest: private_copy(snap.manifest_bytes()),
            layers,
        }))
    }
}

/// What a join learnt beside the view: each segment's identity, ascending by segment id,
/// and how many segments it validated.
#[derive(Default)]
struct Joined {
    identities: Vec<(u64, SegmentIdentity)>,
    newly: usize,
}

/// Validates what is new in a cut (segments whose identity is not in `validated`, the
/// last accepted cut's) and joins it, taking as checked what `memo` and `validated` say
/// the last accepted cut had; `joined` learns the cut's identities.
fn join<'b>(
    bytes: &'b CutBytes,
    validated: &[(u64, SegmentIdentity)],
    memo: &JoinMemo,
    joined: &mut Joined,
) -> Result<ArchivedScene<'b>, SnapshotError> {
    let snap = &bytes.inner;
    let (manifest_bytes, segment_bytes) = bytes.bytes();
    let manifest = validate_manifest(manifest_bytes, "manifest")?;
    let mut structure = None;
    let mut same_structure = false;
    let mut layers = Vec::with_capacity(snap.layer_count());
    let mut chunks = Vec::new();
    let mut trees = Vec::new();
    // Per layer id with a segment this cut does not share with the last accepted one.
    let mut changed_layers = Vec::new();
    joined.identities.reserve(snap.layer_count());
    // Both lists ascend by segment id: one walk finds each segment's previous identity.
    let mut previous = validated.iter().peekable();
    for ((entry, _), bytes) in snap.layers().zip(segment_bytes) {
        let identity = (
            snap.session(),
            entry.generation,
            bytes.as_ptr() as usize,
            bytes.len(),
        );
        let known = loop {
            match previous.peek() {
                Some((id, _)) if *id < entry.layer_id => {
                    // A segment of the last cut that this one lacks: its layer changed.
                    changed_layers.extend(segment_layer_part(*id).map(|(l, _)| l.0));
                    previous.next();
                }
                Some((id, seen)) => break *id == entry.layer_id && *seen == identity,
                None => break false,
            }
        };
        let what = || format!("segment {} generation {}", entry.layer_id, entry.generation);
        let inconsistent = |reason: &str| SnapshotError::Inconsistent {
            what: what(),
            reason: reason.into(),
        };
        if !known && let Some((layer, _)) = segment_layer_part(entry.layer_id) {
            changed_layers.push(layer.0);
        }
        if structure.is_some() {
            // Entries are sorted by id, so the structure comes last: the writer broke that.
            return Err(inconsistent("a segment listed after the structure"));
        } else if is_structure_segment_id(entry.layer_id) {
            // A structure some accepted cut had was checked by its join.
            same_structure = known;
            structure = Some(if known {
                // SAFETY: these exact bytes (same address, length and identity) passed
                // `validate_structure` earlier, and the transport never changes a
                // published sample.
                unsafe { structure_unchecked(bytes) }
            } else {
                validate_structure(bytes, &what())?
            });
        } else if is_tree_chunk_segment_id(entry.layer_id) {
            trees.push(if known {
                // SAFETY: these exact bytes (same address, length and identity) passed
                // `validate_tree_chunk` earlier, and the transport never changes a
                // published sample.
                unsafe { tree_chunk_unchecked(bytes) }
            } else {
                validate_tree_chunk(bytes, &what())?
            });
        } else if !trees.is_empty() {
            // Entries are sorted by id, so tree chunks come last: the writer broke that.
            return Err(inconsistent(
                "a layer or point chunk listed after tree chunks",
            ));
        } else if is_chunk_segment_id(entry.layer_id) {
            chunks.push(if known {
                // SAFETY: these exact bytes (same address, length and identity) passed
                // `validate_chunk` earlier, and the transport never changes a published
                // sample.
                unsafe { chunk_unchecked(bytes) }
            } else {
                validate_chunk(bytes, &what())?
            });
        } else if !chunks.is_empty() {
            // Entries are sorted by id, so layers come first: the writer broke that.
            return Err(inconsistent("a layer segment listed after point chunks"));
        } else {
            layers.push(if known {
                // SAFETY: these exact bytes (same address, length and identity) passed
                // `validate_layer` earlier, and the transport never changes a published
                // sample.
                unsafe { layer_unchecked(bytes) }
            } else {
                validate_layer(bytes, &what())?
            });
        }
        joined.newly += usize::from(!known);
        joined.identities.push((entry.layer_id, identity));
    }
    changed_layers.extend(previous.filter_map(|(id, _)| segment_layer_part(*id).map(|(l, _)| l.0)));
    let Some(structure) = structure else {
        return Err(SnapshotError::Inconsistent {
            what: "snapshot".into(),
            reason: "the manifest names no structure segment".into(),
        });
    };
    // A layer is known when its segments are those of the last accepted cut (none new,
    // none gone) and its entry is as there.
    changed_layers.sort_unstable();
    changed_layers.dedup();
    let known_layers: Vec<bool> = manifest
        .layers
        .iter()
        .enumerate()
        .map(|(at, m)| {
            same_structure
                && changed_layers.binary_search(&m.id.to_native()).is_err()
                && memo.knows_layer(at, m)
        })
        .collect();
    let known = KnownParts {
        structure: same_structure,
        layers: &known_layers,
    };
    ArchivedScene::rejoin(manifest, structure, layers, chunks, trees, known).map_err(|reason| {
        SnapshotError::Inconsistent {
            what: "snapshot".into(),
            reason,
        }
    })
}

/// `bytes` copied into private memory aligned as archives need.
fn private_copy(bytes: &[u8]) -> SegmentBytes {
    let mut copy = SegmentBytes::with_capacity(bytes.len());
    copy.extend_from_slice(bytes);
    copy
}
