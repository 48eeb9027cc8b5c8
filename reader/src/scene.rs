//! [`SceneReader`]: attach to a published scene and query validated snapshots in place.
//!
//! # Trust
//! Shared memory is untrusted input: every manifest and every new layer segment is
//! validated (rkyv bytecheck plus the store's consistency pass) before any query touches
//! it. A layer segment is validated once per identity `(session, layer, generation)`;
//! later snapshots reuse the result only when they hand out the very same bytes (same
//! address and length, which the transport guarantees for an unchanged layer). The
//! transport maps samples read-only in the reader; a writer that rewrites a sample after
//! publishing it breaks the protocol, and is outside what validation can guard.

#![expect(
    unsafe_code,
    reason = "re-deriving archives from bytes validated by this module"
)]

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;
use ygg_store::SnapshotError;
use ygg_store::snapshot::{
    ArchivedScene, layer_unchecked, manifest_unchecked, validate_layer, validate_manifest,
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

/// A validated, consistent cut of a published scene, held zero-copy.
///
/// Cheap to clone (an `Arc`); the shared-memory samples stay alive until the last clone
/// is dropped. Query it through [`SceneSnapshot::view`].
#[derive(Clone)]
pub struct SceneSnapshot {
    inner: Arc<Snapshot>,
}

impl SceneSnapshot {
    /// The scene as a [`ygg_store::SceneView`]: every query of the store runs on it.
    pub fn view(&self) -> ArchivedScene<'_> {
        // SAFETY: a `SceneSnapshot` is only built by `SceneReader::accept`, after the
        // manifest bytes and every layer's bytes of `self.inner` passed
        // `validate_manifest` / `validate_layer` (cached per identical address, length and
        // identity). `self.inner` keeps those exact samples mapped and unchanged.
        let manifest = unsafe { manifest_unchecked(self.inner.manifest_bytes()) };
        let layers = self
            .inner
            .layers()
            // SAFETY: as above, each layer's bytes were validated before `accept` returned.
            .map(|(_, bytes)| unsafe { layer_unchecked(bytes) })
            .collect();
        // `accept` ran `ArchivedScene::new` on this cut.
        ArchivedScene::new_prechecked(manifest, layers)
    }

    /// The snapshot generation.
    pub fn generation(&self) -> u64 {
        self.inner.generation()
    }

    /// The transport snapshot (raw bytes per layer).
    pub fn raw(&self) -> &Snapshot {
        &self.inner
    }
}

/// Identity of a validated layer segment: session, generation, address and length.
type SegmentIdentity = (u64, u64, usize, usize);

/// A reader of one scene: receives snapshots and validates what is new in them.
pub struct SceneReader {
    subscriber: SegmentSubscriber,
    validated: HashMap<u32, SegmentIdentity>,
    current: Option<SceneSnapshot>,
    validations: u64,
}

/// Configures and opens a [`SceneReader`]; see [`SceneReader::builder`].
#[derive(Debug, Clone)]
pub struct SceneReaderBuilder {
    subscriber: SubscriberBuilder,
}

impl SceneReaderBuilder {
    /// How long [`SceneReaderBuilder::open`] waits for a writer to create the scene (default
    /// zero: fail at once with [`ReaderOpenError::NoWriter`]).
    pub fn wait_for_writer(mut self, value: Duration) -> Self {
        self.subscriber = self.subscriber.wait_for_writer(value);
        self
    }

    /// The iceoryx2 file-name prefix; overrides
    /// [`ygg_transport::protocol::ENV_IOX2_PREFIX`]. Must match the writer's.
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
            validated: HashMap::new(),
            current: None,
            validations: 0,
        })
    }
}

impl SceneReader {
    /// A builder for a reader of `scene`, with default settings.
    pub fn builder(scene: &str) -> SceneReaderBuilder {
        SceneReaderBuilder {
            subscriber: SubscriberBuilder::new(scene),
        }
    }

    /// The newest snapshot, without blocking (and without ever blocking the writer).
    /// `None` until a first snapshot arrived.
    ///
    /// # Errors
    /// Transport errors, or a snapshot whose bytes fail validation.
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

    /// How many layer segments this reader has validated so far (unchanged layers are
    /// not validated again).
    pub fn validations(&self) -> u64 {
        self.validations
    }

    /// Whether SIGINT/SIGTERM was received (when the builder handles signals).
    pub fn termination_requested(&self) -> bool {
        self.subscriber.termination_requested()
    }

    fn accept(
        &mut self,
        snap: Option<Arc<Snapshot>>,
    ) -> Result<Option<SceneSnapshot>, SceneReceiveError> {
        let Some(snap) = snap else {
            return Ok(self.current.clone());
        };
        if self
            .current
            .as_ref()
            .is_some_and(|c| Arc::ptr_eq(&c.inner, &snap))
        {
            return Ok(self.current.clone());
        }
        let invalid = |source| SceneReceiveError::Invalid {
            scene: self.subscriber.scene().to_owned(),
            generation: snap.generation(),
            source,
        };
        let manifest = validate_manifest(snap.manifest_bytes(), "manifest").map_err(invalid)?;
        let mut layers = Vec::with_capacity(snap.layer_count());
        let mut newly = Vec::new();
        for (entry, bytes) in snap.layers() {
            let identity = (
                snap.session(),
                entry.generation,
                bytes.as_ptr() as usize,
                bytes.len(),
            );
            if self.validated.get(&entry.layer_id) == Some(&identity) {
                // SAFETY: these exact bytes (same address, length and identity) passed
                // `validate_layer` earlier, and the transport never changes a published sample.
                layers.push(unsafe { layer_unchecked(bytes) });
            } else {
                let what = format!("layer {} generation {}", entry.layer_id, entry.generation);
                layers.push(validate_layer(bytes, &what).map_err(invalid)?);
                newly.push((entry.layer_id, identity));
            }
        }
        ArchivedScene::new(manifest, layers).map_err(|reason| {
            invalid(SnapshotError::Inconsistent {
                what: "snapshot".into(),
                reason,
            })
        })?;
        self.validations += newly.len() as u64;
        self.validated.extend(newly);
        let accepted = SceneSnapshot { inner: snap };
        self.current = Some(accepted.clone());
        Ok(Some(accepted))
    }
}
