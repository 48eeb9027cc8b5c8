//! [`PublisherBuilder`] and [`SegmentPublisher`]: one scene's publishing side.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime};

use crate::SetupError;
use crate::protocol::{
    self, BLOCK_SIZE, EVENT_SNAPSHOT_PUBLISHED, EVENT_WRITER_GONE, EVENT_WRITER_STOP,
    MANIFEST_LAYER_ID, ManifestEntry, SegmentHeader, SegmentKind,
};
use crate::service::{
    self, DEFAULT_LIVENESS_INTERVAL, DEFAULT_MAX_READERS, DEFAULT_MAX_SEGMENTS, Ipc, SceneServices,
};
use iceoryx2::node::NodeWaitFailure;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::Node;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;

use super::helper::Helper;
use super::ports::{PortSettings, open_event_service, open_segment_port, send_segment};
use super::retained::Retained;
use super::shared_state::{Inner, Stream, lock};
use super::{PublishError, WriterCreateError, WriterWaitError};

/// Default initial capacity of a segment before iceoryx2 grows it (power-of-two steps).
pub const DEFAULT_INITIAL_SEGMENT_BYTES: usize = 64 * 1024;

/// Configures and creates a [`SegmentPublisher`].
///
/// ```no_run
/// # fn main() -> Result<(), Box<dyn core::error::Error>> {
/// use ygg_transport::{ManifestEntry, PublisherBuilder};
/// let mut writer = PublisherBuilder::new("office").max_readers(4).create()?;
/// writer.publish_layer(1, 1, 5, |buf| buf.copy_from_slice(b"hello"))?;
/// writer.publish_manifest(1, &[ManifestEntry { layer_id: 1, generation: 1 }], 0, |_| {})?;
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone)]
pub struct PublisherBuilder {
    scene: String,
    max_readers: usize,
    max_segments: usize,
    initial_segment_bytes: usize,
    shm_dir: PathBuf,
    iceoryx_prefix: Option<String>,
    liveness_interval: Duration,
}

impl PublisherBuilder {
    /// A builder for the writer of `scene` with default settings.
    pub fn new(scene: &str) -> Self {
        Self {
            scene: scene.to_owned(),
            max_readers: DEFAULT_MAX_READERS,
            max_segments: DEFAULT_MAX_SEGMENTS,
            initial_segment_bytes: DEFAULT_INITIAL_SEGMENT_BYTES,
            shm_dir: PathBuf::from(service::DEFAULT_SHM_DIR),
            iceoryx_prefix: None,
            liveness_interval: DEFAULT_LIVENESS_INTERVAL,
        }
    }

    /// Readers the scene supports at once (default [`DEFAULT_MAX_READERS`]).
    ///
    /// On create this sizes the segment stream; each extra reader costs about
    /// `3 * max_segments` more chunks of address space (tmpfs pages are used only when
    /// written). A restarted writer that asks for more readers than the existing services
    /// support fails with [`SetupError::Service`](crate::SetupError::Service) while readers
    /// keep those services alive.
    pub fn max_readers(mut self, value: usize) -> Self {
        self.max_readers = value.max(1);
        self
    }

    /// Most segments one snapshot may name (default [`DEFAULT_MAX_SEGMENTS`]); a manifest
    /// naming more is refused with [`PublishError::TooManyLayers`]. Sizes the segment
    /// stream's pool: about `3 * max_segments` chunks per reader, each as large as the largest
    /// segment, and a reader's attach initialises bookkeeping for all of them, so a bound
    /// near the scene's real segment count makes attaching several times faster. A restarted
    /// writer whose readers kept the stream of an earlier writer alive gets that stream's
    /// bound if it is lower ([`SegmentPublisher::max_segments`]).
    pub fn max_segments(mut self, value: usize) -> Self {
        self.max_segments = value.clamp(1, protocol::MAX_LAYERS);
        self
    }

    /// Bytes a segment can hold before iceoryx2 allocates a larger shared-memory segment
    /// (growth is in powers of two). A good value is the expected size of the largest layer;
    /// too small costs a few reallocations early on, too large only address space.
    pub fn initial_segment_bytes(mut self, value: usize) -> Self {
        self.initial_segment_bytes = value.max(1);
        self
    }

    /// The shared-memory file system whose free space is checked before a publish writes
    /// pages the pool does not hold yet (default `/dev/shm`).
    pub fn shm_dir(mut self, path: impl Into<PathBuf>) -> Self {
        self.shm_dir = path.into();
        self
    }

    /// The iceoryx2 file-name prefix; overrides [`service::ENV_IOX2_PREFIX`]. Readers must use
    /// the same prefix.
    pub fn iceoryx_prefix(mut self, prefix: &str) -> Self {
        self.iceoryx_prefix = Some(prefix.to_owned());
        self
    }

    /// How often the helper thread asks iceoryx2 whether a reader whose process it cannot
    /// watch (another pid namespace) is alive (default 200 ms). Other readers are watched
    /// through a pidfd: their exit wakes the helper at once.
    pub fn liveness_interval(mut self, value: Duration) -> Self {
        self.liveness_interval = value.max(Duration::from_millis(1));
        self
    }

    /// Creates the writer: removes resources of dead processes (so a writer restarted after a
    /// crash can take over), creates or opens the scene's services, claims the single publisher
    /// slot and starts the helper thread that answers late-joining readers.
    ///
    /// # Errors
    ///
    /// [`WriterCreateError::AlreadyRunning`] if a live writer publishes the scene; otherwise
    /// the [`WriterCreateError`] variant naming the failing resource.
    pub fn create(self) -> Result<SegmentPublisher, WriterCreateError> {
        let services = SceneServices::new(&self.scene).map_err(SetupError::from)?;
        let config =
            service::iceoryx_config(self.iceoryx_prefix.as_deref()).map_err(SetupError::from)?;
        let node = crate::service::create_node("ygg-writer", services.scene(), &config)?;
        // Removes services and ports of a writer that was killed, so that its publisher slot is
        // free again. (Node creation does this as well under iceoryx2's default config.)
        node.try_cleanup_dead_nodes();

        let settings = PortSettings {
            max_readers: self.max_readers,
            max_segments: self.max_segments,
            initial_blocks: self.initial_segment_bytes.div_ceil(BLOCK_SIZE),
        };
        let stream_name = services.segments();
        let stream = open_segment_port(&node, &stream_name, settings)?;
        let max_segments = stream.max_segments;
        let own_subscriber = stream
            .service
            .subscriber_builder()
            .create()
            .map_err(|e| crate::service::port_failure(&stream_name, e))?;

        let events_name = services.events();
        let events = open_event_service(&node, &events_name, self.max_readers, true)?;
        let events_notifier = events
            .notifier_builder()
            .default_event_id(EVENT_SNAPSHOT_PUBLISHED)
            .create()
            .map_err(|e| crate::service::port_failure(&events_name, e))?;

        let readers_name = services.readers();
        let readers = open_event_service(&node, &readers_name, self.max_readers, false)?;
        let listener = readers
            .listener_builder()
            .create()
            .map_err(|e| crate::service::port_failure(&readers_name, e))?;
        let stop_notifier = readers
            .notifier_builder()
            .default_event_id(EVENT_WRITER_STOP)
            .create()
            .map_err(|e| crate::service::port_failure(&readers_name, e))?;

        let inner = Arc::new(Mutex::new(Inner {
            stream: Some(Stream {
                port: stream,
                retained: Retained::new(own_subscriber),
            }),
            events_notifier,
            _events: events,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let helper = Helper {
            listener,
            shm_dir: self.shm_dir.clone(),
            interval: self.liveness_interval,
            config: config.clone(),
        };
        let helper = std::thread::Builder::new()
            .name(format!("ygg-writer-{}", services.scene()))
            .spawn({
                let inner = Arc::clone(&inner);
                let stop = Arc::clone(&stop);
                move || helper.run(&inner, &stop)
            })
            .map_err(WriterCreateError::Thread)?;

        Ok(SegmentPublisher {
            session: new_session_id(),
            shm_dir: self.shm_dir,
            max_segments,
            services,
            published: BTreeMap::new(),
            cut_started_unix_ns: None,
            inner,
            stop,
            helper: Some(helper),
            stop_notifier,
            _readers: readers,
            node,
        })
    }
}

/// Publishes one scene's segments: byte segments (a layer, or a chunk of one: the id is
/// opaque here) and a manifest naming a consistent cut of them (DESIGN.md §5), all over one
/// stream service whatever the number of segments.
///
/// Call [`publish_layer`](Self::publish_layer) for every changed segment, then
/// [`publish_manifest`](Self::publish_manifest) naming the generation of every segment of the
/// snapshot. Publishing never blocks on readers: slow readers lose their oldest buffered
/// samples (safe overflow) and catch up from a burst of the current snapshot, and a reader
/// holding samples only holds its own share of the pool.
///
/// Dropping the writer tells readers it is gone and removes its shared memory.
pub struct SegmentPublisher {
    session: u64,
    shm_dir: PathBuf,
    max_segments: usize,
    services: SceneServices,
    /// Last generation published per layer, to check manifests.
    published: BTreeMap<u64, u64>,
    /// When the cut being published began ([`SegmentPublisher::start_cut`]).
    cut_started_unix_ns: Option<u64>,
    inner: Arc<Mutex<Inner>>,
    stop: Arc<AtomicBool>,
    helper: Option<JoinHandle<()>>,
    stop_notifier: Notifier<Ipc>,
    _readers: EventFactory<Ipc>,
    node: Node<Ipc>,
}

impl std::fmt::Debug for SegmentPublisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SegmentPublisher")
            .field("scene", &self.services.scene())
            .field("session", &self.session)
            .field("published", &self.published)
            .finish_non_exhaustive()
    }
}

impl SegmentPublisher {
    /// The scene name.
    pub fn scene(&self) -> &str {
        self.services.scene()
    }

    /// Random id of this writer instance, carried in every segment header. Readers use it to
    /// tell a restarted writer's generations from the previous writer's.
    pub fn session(&self) -> u64 {
        self.session
    }

    /// Most segments one snapshot may name: [`PublisherBuilder::max_segments`], or less when
    /// readers kept alive a stream an earlier writer created for fewer.
    pub fn max_segments(&self) -> usize {
        self.max_segments
    }

    /// The last generation published for `layer_id`, if any.
    pub fn layer_generation(&self, layer_id: u64) -> Option<u64> {
        self.published.get(&layer_id).copied()
    }

    /// Publishes `len` bytes as generation `generation` of layer `layer_id`.
    ///
    /// `fill` gets the loaned shared-memory buffer of exactly `len` bytes (starting 128-byte
    /// aligned) and must write all of it: its previous content is unspecified. No copy is made.
    /// Readers see the layer only once a manifest names this generation.
    ///
    /// # Errors
    ///
    /// [`PublishError::SharedMemoryFull`] before anything is written if `/dev/shm` lacks room;
    /// see [`PublishError`] for the rest.
    pub fn publish_layer(
        &mut self,
        layer_id: u64,
        generation: u64,
        len: usize,
        fill: impl FnOnce(&mut [u8]),
    ) -> Result<(), PublishError> {
        self.try_publish_layer(layer_id, generation, len, |buf| {
            fill(buf);
            Ok::<_, std::convert::Infallible>(())
        })
    }

    /// Like [`publish_layer`](Self::publish_layer), with a fallible `fill` (for example a
    /// serializer). If `fill` fails nothing is sent.
    ///
    /// # Errors
    ///
    /// As [`publish_layer`](Self::publish_layer), plus [`PublishError::Fill`].
    pub fn try_publish_layer<E>(
        &mut self,
        layer_id: u64,
        generation: u64,
        len: usize,
        fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
    ) -> Result<(), PublishError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        if layer_id == MANIFEST_LAYER_ID {
            return Err(PublishError::ReservedLayerId(layer_id));
        }
        self.start_cut();
        let header = SegmentHeader::new(
            SegmentKind::Layer,
            layer_id,
            self.session,
            generation,
            len as u64,
            self.cut_started_unix_ns.unwrap_or_default(),
        );
        let mut inner = lock(&self.inner);
        let stream = inner.stream.as_mut().ok_or(PublishError::Closed)?;
        send_segment(&mut stream.port, &self.shm_dir, header, len, fill)?;
        stream.retained.receive(None);
        drop(inner);
        self.published.insert(layer_id, generation);
        Ok(())
    }

    /// Publishes snapshot `generation`: the transport prefix listing `entries`, followed by
    /// `len` bytes written by `fill` (the store's manifest), then wakes every reader.
    ///
    /// `entries` must be sorted by layer id without duplicates and name, for each layer of the
    /// snapshot, the generation last published with [`publish_layer`](Self::publish_layer).
    /// The store's bytes start 128-byte aligned.
    ///
    /// # Errors
    ///
    /// [`PublishError::UnsortedManifest`], [`PublishError::UnknownLayerGeneration`],
    /// [`PublishError::TooManyLayers`], [`PublishError::SharedMemoryFull`], and the rest of
    /// [`PublishError`].
    pub fn publish_manifest(
        &mut self,
        generation: u64,
        entries: &[ManifestEntry],
        len: usize,
        fill: impl FnOnce(&mut [u8]),
    ) -> Result<(), PublishError> {
        self.try_publish_manifest(generation, entries, len, |buf| {
            fill(buf);
            Ok::<_, std::convert::Infallible>(())
        })
    }

    /// Like [`publish_manifest`](Self::publish_manifest), with a fallible `fill`.
    ///
    /// # Errors
    ///
    /// As [`publish_manifest`](Self::publish_manifest), plus [`PublishError::Fill`].
    pub fn try_publish_manifest<E>(
        &mut self,
        generation: u64,
        entries: &[ManifestEntry],
        len: usize,
        fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
    ) -> Result<(), PublishError>
    where
        E: Into<Box<dyn std::error::Error + Send + Sync>>,
    {
        if entries.len() > self.max_segments {
            return Err(PublishError::TooManyLayers {
                count: entries.len(),
                max: self.max_segments,
            });
        }
        for pair in entries.windows(2) {
            if pair[0].layer_id >= pair[1].layer_id {
                return Err(PublishError::UnsortedManifest {
                    layer_id: pair[1].layer_id,
                });
            }
        }
        // Both ascend by id (the entries checked above): one walk, not a map lookup per
        // entry.
        let mut published = self.published.iter().peekable();
        for entry in entries {
            while published.next_if(|(id, _)| **id < entry.layer_id).is_some() {}
            let published = published
                .peek()
                .filter(|(id, _)| **id == entry.layer_id)
                .map(|(_, generation)| **generation);
            if published != Some(entry.generation) {
                return Err(PublishError::UnknownLayerGeneration {
                    layer_id: entry.layer_id,
                    generation: entry.generation,
                    published,
                });
            }
        }
        let prefix_len = protocol::manifest_prefix_len(entries.len());
        let total = prefix_len
            .checked_add(len)
            .ok_or(PublishError::TooLarge { len })?;
        self.start_cut();
        let header = SegmentHeader::new(
            SegmentKind::Manifest,
            MANIFEST_LAYER_ID,
            self.session,
            generation,
            total as u64,
            self.cut_started_unix_ns.take().unwrap_or_default(),
        );
        let mut inner = lock(&self.inner);
        let stream = inner.stream.as_mut().ok_or(PublishError::Closed)?;
        send_segment(&mut stream.port, &self.shm_dir, header, total, |buf| {
            let (prefix, rest) = buf.split_at_mut(prefix_len);
            protocol::encode_manifest_prefix(entries, prefix);
            fill(rest)
        })?;
        stream.retained.receive(Some(entries));
        inner.notify(EVENT_SNAPSHOT_PUBLISHED);
        Ok(())
    }

    /// Marks now as the start of the cut being published, unless a layer of it was already
    /// published (the first publish call of a cut marks it otherwise). Every segment of the
    /// cut carries this time in [`SegmentHeader::published_unix_ns`]; call it before building
    /// the first segment so that readers' publish-to-visible latency includes the build.
    pub fn start_cut(&mut self) {
        self.cut_started_unix_ns
            .get_or_insert_with(protocol::unix_ns);
    }

    /// Stops publishing segment `layer_id`: the writer lets go of its last sample, whose
    /// shared memory is reused once no reader holds it. Publish a manifest without the
    /// segment first.
    pub fn retire_layer(&mut self, layer_id: u64) {
        if let Some(stream) = &mut lock(&self.inner).stream {
            stream.retained.forget(layer_id);
        }
        self.published.remove(&layer_id);
    }

    /// Sleeps for `cycle_time`, or less if a signal arrives, like iceoryx2's `Node::wait`.
    ///
    /// The first call installs iceoryx2's SIGINT/SIGTERM handler, so those signals no longer
    /// kill the process: they make this return an error, and the caller should drop the writer
    /// (which removes its shared memory) and exit. A process that handles signals itself should
    /// not call this.
    ///
    /// # Errors
    ///
    /// [`WriterWaitError::Interrupt`] on SIGINT, [`WriterWaitError::TerminationRequest`] on
    /// SIGTERM.
    pub fn wait(&self, cycle_time: Duration) -> Result<(), WriterWaitError> {
        self.node.wait(cycle_time).map_err(|e| match e {
            NodeWaitFailure::Interrupt => WriterWaitError::Interrupt,
            NodeWaitFailure::TerminationRequest => WriterWaitError::TerminationRequest,
        })
    }

    /// Sends the current snapshot to readers that connected since the last publish (a
    /// catch-up burst from the helper thread). The helper does this when a reader announces
    /// itself; calling it is never required.
    pub fn update_connections(&self) {
        let _ = self
            .stop_notifier
            .notify_with_custom_event_id(protocol::EVENT_READER_HELLO);
    }
}

impl Drop for SegmentPublisher {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        let _ = self
            .stop_notifier
            .notify_with_custom_event_id(EVENT_WRITER_STOP);
        if let Some(helper) = self.helper.take() {
            let _ = helper.join();
        }
        let mut inner = lock(&self.inner);
        // Remove the publisher first: readers that get the event then see no publisher.
        inner.stream = None;
        inner.notify(EVENT_WRITER_GONE);
    }
}

/// A new, practically unique writer session id (time and pid, mixed).
fn new_session_id() -> u64 {
    let nanos = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64);
    let mut x = nanos ^ (u64::from(std::process::id()) << 32);
    // splitmix64 finaliser
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (x ^ (x >> 31)).max(1)
}
