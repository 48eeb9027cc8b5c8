//! `ygg-relay import`: receives a scene from Zenoh, validates every segment and manifest,
//! and republishes complete cuts into this host's shared memory, where local readers
//! attach to it as to any writer.

use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use clap::Args;
use ygg_store::snapshot::SegmentBytes;
use ygg_transport::service::{DEFAULT_MAX_READERS, DEFAULT_MAX_SEGMENTS};
use ygg_transport::{PublishError, PublisherBuilder, SegmentPublisher, WriterCreateError};
use zenoh::Wait as _;
use zenoh::bytes::ZBytes;
use zenoh::query::ConsolidationMode;
use zenoh::sample::{Sample, SampleKind};

use crate::access::Role;
use crate::cut::{Assembler, Cut};
use crate::keys::{Item, SceneArgsError, SceneKeys, scene_keys};
use crate::network::{Access, NetworkArgs, PeerCount, SessionCloseError, SessionOpenError, close};

/// Why the importer stopped.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// `--scene` or `--key` is invalid.
    #[error(transparent)]
    Args(#[from] SceneArgsError),
    /// The Zenoh session could not be opened.
    #[error(transparent)]
    Session(#[from] SessionOpenError),
    /// The subscriber of the scene's data could not be declared.
    #[error("cannot subscribe to {key}: {source}")]
    Subscribe {
        /// Its key expression.
        key: String,
        /// Zenoh's reason.
        source: zenoh::Error,
    },
    /// The exporter's liveliness cannot be followed.
    #[error("cannot follow the liveliness of {key}: {source}")]
    Liveliness {
        /// The liveliness key.
        key: String,
        /// Zenoh's reason.
        source: zenoh::Error,
    },
    /// Zenoh dropped the callbacks that feed the importer.
    #[error("the zenoh callbacks stopped")]
    CallbacksStopped,
    /// The local scene cannot be published (another writer on this host serves it, say).
    #[error("cannot publish scene {scene:?}: {source}")]
    Publish {
        /// The local scene.
        scene: String,
        /// The transport's reason.
        source: WriterCreateError,
    },
    /// A segment could not be republished.
    #[error("publishing segment {id}: {source}")]
    Segment {
        /// Its id.
        id: u64,
        /// The transport's reason.
        source: PublishError,
    },
    /// A manifest could not be republished.
    #[error("publishing manifest {generation}: {source}")]
    Manifest {
        /// Its generation.
        generation: u64,
        /// The transport's reason.
        source: PublishError,
    },
    /// The session did not close cleanly.
    #[error(transparent)]
    Close(#[from] SessionCloseError),
}

/// Arguments of `ygg-relay import`.
#[derive(Args, Debug)]
pub struct ImportArgs {
    /// The Zenoh key the scene is exported under, e.g. `robots/r1/office`.
    #[arg(long)]
    pub key: String,
    /// The local scene name to republish it as.
    #[arg(long)]
    pub scene: String,
    /// The certificate identity (a `--host` name of `ygg-relay certs`) of the exporter this
    /// importer takes the scene from; puts and replies on the key from anyone else are
    /// dropped before they reach the importer. Repeatable (e.g. a spare exporter).
    #[arg(long = "allow", value_name = "NAME")]
    pub allow: Vec<String>,
    /// Readers the local scene supports at once.
    #[arg(long, default_value_t = DEFAULT_MAX_READERS)]
    pub max_readers: usize,
    /// Most layers the remote scene may grow to (the segment stream is sized for it; a
    /// lower bound makes local readers attach faster).
    #[arg(long, default_value_t = DEFAULT_MAX_SEGMENTS)]
    pub max_layers: usize,
    /// How Zenoh connects.
    #[command(flatten)]
    pub network: NetworkArgs,
}

/// How long one wait for Zenoh events lasts before checking for signals.
const POLL: Duration = Duration::from_millis(50);

/// Least time between two snapshot queries while a gap persists.
const QUERY_INTERVAL: Duration = Duration::from_millis(300);

/// How long a snapshot query may take.
const QUERY_TIMEOUT: Duration = Duration::from_secs(10);

/// What the Zenoh callbacks hand to the importer's thread.
enum Event {
    /// A put or a query reply on the scene's keys.
    Data(Sample),
    /// The exporter's liveliness token appeared (true) or went (false).
    Alive(bool),
}

/// Runs the importer until SIGINT/SIGTERM.
///
/// # Errors
/// Bad arguments, a Zenoh session that cannot open, or a local scene that cannot be
/// published (for example one another writer on this host publishes).
pub fn run(args: &ImportArgs, stop: &AtomicBool) -> Result<(), ImportError> {
    let keys = scene_keys(&args.scene, &args.key)?;
    let session = args.network.open(Some(Access {
        role: Role::Import,
        keys: &keys,
        identities: &args.allow,
    }))?;
    let (tx, rx) = mpsc::channel();
    let data_tx = tx.clone();
    let _subscriber = session
        .declare_subscriber(keys.all())
        .callback(move |sample| {
            let _ = data_tx.send(Event::Data(sample));
        })
        .wait()
        .map_err(|source| ImportError::Subscribe {
            key: keys.all(),
            source,
        })?;
    let alive_tx = tx.clone();
    let _alive = session
        .liveliness()
        .declare_subscriber(keys.alive())
        .history(true)
        .callback(move |sample| {
            let _ = alive_tx.send(Event::Alive(sample.kind() == SampleKind::Put));
        })
        .wait()
        .map_err(|source| ImportError::Liveliness {
            key: keys.alive(),
            source,
        })?;
    println!("importing key={} scene={}", keys.base(), args.scene);

    let mut importer = Importer {
        args,
        keys: &keys,
        session: &session,
        tx,
        assembler: Assembler::new(),
        local: None,
        last_query: None,
    };
    let mut peers = PeerCount::default();
    let result = loop {
        peers.update(&session);
        if stop.load(Ordering::Relaxed) {
            break Ok(());
        }
        let step = match rx.recv_timeout(POLL) {
            Ok(Event::Data(sample)) => importer.receive(&sample),
            Ok(Event::Alive(true)) => {
                println!("exporter alive");
                importer.request("exporter appeared");
                Ok(())
            }
            Ok(Event::Alive(false)) => {
                importer.remote_gone();
                Ok(())
            }
            Err(RecvTimeoutError::Timeout) => importer.retry_gap(),
            Err(RecvTimeoutError::Disconnected) => Err(ImportError::CallbacksStopped),
        };
        if let Err(e) = step {
            break Err(e);
        }
    };
    importer.remote_gone();
    drop(importer);
    close(&session)?;
    result
}

/// The local scene republished from one remote writer session.
struct Local {
    publisher: SegmentPublisher,
    /// The remote writer session whose cuts it carries.
    remote_session: u64,
    /// Segment ids it publishes.
    ids: BTreeSet<u64>,
    /// The last snapshot generation published.
    generation: u64,
}

/// The importer's state.
struct Importer<'a> {
    args: &'a ImportArgs,
    keys: &'a SceneKeys,
    session: &'a zenoh::Session,
    tx: Sender<Event>,
    assembler: Assembler,
    local: Option<Local>,
    last_query: Option<Instant>,
}

impl Importer<'_> {
    /// Validates and keeps one received payload, and republishes the cut it completes.
    /// Anything that is not a valid segment or manifest of this scene is logged and dropped.
    fn receive(&mut self, sample: &Sample) -> Result<(), ImportError> {
        let key = sample.key_expr().as_str();
        if sample.kind() != SampleKind::Put {
            return Ok(());
        }
        let parsed = match self.keys.parse(key) {
            Ok(parsed) => parsed,
            Err(reason) => {
                dropped(key, reason);
                return Ok(());
            }
        };
        let bytes = aligned(sample.payload());
        let kept = match parsed.item {
            Item::Segment { id, generation } => {
                self.assembler
                    .add_segment(parsed.session, id, generation, bytes)
            }
            Item::Manifest { generation } => self
                .assembler
                .add_manifest(parsed.session, generation, bytes)
                .map(|_| ()),
        };
        if let Err(reason) = kept {
            dropped(key, reason);
            return Ok(());
        }
        match self.assembler.take_cut() {
            Some(cut) => self.publish(&cut),
            // Segments are put before the manifest naming them: one missing now is lost.
            None => self.retry_gap(),
        }
    }

    /// Asks for the snapshot while the newest manifest lacks segments (at most every
    /// [`QUERY_INTERVAL`]).
    fn retry_gap(&mut self) -> Result<(), ImportError> {
        let missing = self.assembler.missing();
        if let Some(first) = missing.first() {
            self.request(&format!(
                "gap: {} segments missing, e.g. {} generation {}",
                missing.len(),
                first.layer_id,
                first.generation
            ));
        }
        Ok(())
    }

    /// Queries the exporter for its current snapshot (at most every [`QUERY_INTERVAL`]); the
    /// replies arrive as [`Event::Data`].
    fn request(&mut self, reason: &str) {
        if self
            .last_query
            .is_some_and(|at| at.elapsed() < QUERY_INTERVAL)
        {
            return;
        }
        self.last_query = Some(Instant::now());
        let tx = self.tx.clone();
        let sent = self
            .session
            .get(self.keys.all())
            .consolidation(ConsolidationMode::None)
            .timeout(QUERY_TIMEOUT)
            .callback(move |reply| {
                if let Ok(sample) = reply.result() {
                    let _ = tx.send(Event::Data(sample.clone()));
                }
            })
            .wait();
        match sent {
            Ok(()) => println!("resync requested ({reason})"),
            Err(e) => eprintln!("ygg-relay import: warning: snapshot query failed: {e}"),
        }
    }

    /// The exporter or its writer went away (or the link broke): stop publishing, so local
    /// readers report the writer gone and keep the last snapshot.
    fn remote_gone(&mut self) {
        if let Some(local) = self.local.take() {
            println!(
                "writer gone; local readers keep generation={}",
                local.generation
            );
        }
        self.assembler.forget_last();
    }

    /// Republishes a complete cut: the segments whose generation changed, segments no
    /// longer named retired, then the manifest.
    fn publish(&mut self, cut: &Cut) -> Result<(), ImportError> {
        let manifest = &cut.manifest;
        if self
            .local
            .as_ref()
            .is_some_and(|l| l.remote_session != manifest.session)
        {
            // A restarted remote writer: readers see this one go and a new one come.
            self.remote_gone();
        }
        let local = match &mut self.local {
            Some(local) => local,
            None => {
                let publisher = PublisherBuilder::new(&self.args.scene)
                    .max_readers(self.args.max_readers)
                    .max_segments(self.args.max_layers)
                    .create()
                    .map_err(|source| ImportError::Publish {
                        scene: self.args.scene.clone(),
                        source,
                    })?;
                self.local.insert(Local {
                    publisher,
                    remote_session: manifest.session,
                    ids: BTreeSet::new(),
                    generation: 0,
                })
            }
        };
        let mut sent = 0usize;
        for (entry, bytes) in manifest.entries.iter().zip(&cut.segments) {
            if local.publisher.layer_generation(entry.layer_id) == Some(entry.generation) {
                continue;
            }
            local
                .publisher
                .publish_layer(entry.layer_id, entry.generation, bytes.len(), |buf| {
                    buf.copy_from_slice(bytes)
                })
                .map_err(|source| ImportError::Segment {
                    id: entry.layer_id,
                    source,
                })?;
            sent += 1;
        }
        let store = manifest.store_bytes();
        local
            .publisher
            .publish_manifest(manifest.generation, &manifest.entries, store.len(), |buf| {
                buf.copy_from_slice(store)
            })
            .map_err(|source| ImportError::Manifest {
                generation: manifest.generation,
                source,
            })?;
        let named: BTreeSet<u64> = manifest.entries.iter().map(|e| e.layer_id).collect();
        for gone in local.ids.difference(&named) {
            local.publisher.retire_layer(*gone);
        }
        local.ids = named;
        local.generation = manifest.generation;
        println!(
            "published generation={} segments={sent} of {}",
            manifest.generation,
            manifest.entries.len()
        );
        Ok(())
    }
}

/// Logs a payload that is dropped and why.
fn dropped(key: &str, reason: impl std::fmt::Display) {
    eprintln!("ygg-relay import: dropped {key}: {reason}");
    println!("dropped key={key}");
}

/// The payload copied into memory aligned for archives (Zenoh's buffers are not).
fn aligned(payload: &ZBytes) -> SegmentBytes {
    let mut out = SegmentBytes::with_capacity(payload.len());
    for slice in payload.slices() {
        out.extend_from_slice(slice);
    }
    out
}
