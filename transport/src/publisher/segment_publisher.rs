//! [`PublisherBuilder`] and [`SegmentPublisher`]: one scene's publishing side.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime};

use crate::SetupError;
use crate::protocol::{
    self, BLOCK_SIZE, Block128, DEFAULT_LIVENESS_INTERVAL, DEFAULT_MAX_READERS, EVENT_ID_MAX,
    EVENT_READER_HELLO, EVENT_SNAPSHOT_PUBLISHED, EVENT_WRITER_GONE, EVENT_WRITER_STOP,
    HISTORY_SIZE, Ipc, MANIFEST_LAYER_ID, MAX_LAYERS, ManifestEntry, PUBLISHER_MAX_LOANED,
    SUBSCRIBER_BUFFER_SIZE, SUBSCRIBER_MAX_BORROWED, SceneServices, SegmentHeader, SegmentKind,
};
use iceoryx2::config::Config;
use iceoryx2::node::NodeWaitFailure;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::{Publisher, PublisherCreateError};
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{AllocationStrategy, CallbackProgression, EventId, Node, NodeState};
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use super::{PublishError, WriterCreateError, WriterWaitError, loan, shm};

type SegmentFactory = PubSubFactory<Ipc, [Block128], SegmentHeader>;
type SegmentPort = Publisher<Ipc, [Block128], SegmentHeader>;

/// Default initial capacity of a segment before iceoryx2 grows it (power-of-two steps).
pub const DEFAULT_INITIAL_SEGMENT_BYTES: usize = 64 * 1024;

/// How often the helper thread removes resources of dead readers.
const CLEANUP_INTERVAL: Duration = Duration::from_secs(1);

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
            initial_segment_bytes: DEFAULT_INITIAL_SEGMENT_BYTES,
            shm_dir: PathBuf::from(protocol::DEFAULT_SHM_DIR),
            iceoryx_prefix: None,
            liveness_interval: DEFAULT_LIVENESS_INTERVAL,
        }
    }

    /// Readers the scene supports at once (default [`DEFAULT_MAX_READERS`]).
    ///
    /// On create this sizes every service; each extra reader costs
    /// `SUBSCRIBER_BUFFER_SIZE + SUBSCRIBER_MAX_BORROWED` more chunks of address space per
    /// segment pool (tmpfs pages are used only when written). A restarted writer that asks for
    /// more readers than the existing services support fails with
    /// [`SetupError::Service`](crate::SetupError::Service) while readers keep those services alive.
    pub fn max_readers(mut self, value: usize) -> Self {
        self.max_readers = value.max(1);
        self
    }

    /// Bytes a segment can hold before iceoryx2 allocates a larger shared-memory segment
    /// (growth is in powers of two). A good value is the expected size of the largest layer;
    /// too small costs a few reallocations early on, too large only address space.
    pub fn initial_segment_bytes(mut self, value: usize) -> Self {
        self.initial_segment_bytes = value.max(1);
        self
    }

    /// The shared-memory file system whose free space is checked before each publish
    /// (default `/dev/shm`).
    pub fn shm_dir(mut self, path: impl Into<PathBuf>) -> Self {
        self.shm_dir = path.into();
        self
    }

    /// The iceoryx2 file-name prefix; overrides [`protocol::ENV_IOX2_PREFIX`]. Readers must use
    /// the same prefix.
    pub fn iceoryx_prefix(mut self, prefix: &str) -> Self {
        self.iceoryx_prefix = Some(prefix.to_owned());
        self
    }

    /// How long the helper thread waits for reader announcements between housekeeping rounds.
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
            protocol::iceoryx_config(self.iceoryx_prefix.as_deref()).map_err(SetupError::from)?;
        let node = crate::service::create_node("ygg-writer", services.scene(), &config)?;
        // Removes services and ports of a writer that was killed, so that its publisher slot is
        // free again. (Node creation does this as well under iceoryx2's default config.)
        node.try_cleanup_dead_nodes();

        let settings = PortSettings {
            max_readers: self.max_readers,
            initial_blocks: self.initial_segment_bytes.div_ceil(BLOCK_SIZE),
        };
        let manifest = open_segment_port(&node, &services.manifest(), settings)?;

        let events_name = services.events();
        let events = open_event_service(&node, &events_name, self.max_readers, true)?;
        let events_notifier = events
            .notifier_builder()
            .default_event_id(EVENT_SNAPSHOT_PUBLISHED)
            .create()
            .map_err(|e| crate::service::port_failure(&events_name, e))?;

        let readers_name = services.readers();
        let readers = open_event_service(&node, &readers_name, self.max_readers, false)?;
        let hello_listener = readers
            .listener_builder()
            .create()
            .map_err(|e| crate::service::port_failure(&readers_name, e))?;
        let stop_notifier = readers
            .notifier_builder()
            .default_event_id(EVENT_WRITER_STOP)
            .create()
            .map_err(|e| crate::service::port_failure(&readers_name, e))?;

        let inner = Arc::new(Mutex::new(Inner {
            ports: BTreeMap::from([(MANIFEST_LAYER_ID, manifest)]),
            events_notifier,
            _events: events,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let helper = std::thread::Builder::new()
            .name(format!("ygg-writer-{}", services.scene()))
            .spawn({
                let inner = Arc::clone(&inner);
                let stop = Arc::clone(&stop);
                let interval = self.liveness_interval;
                let config = config.clone();
                move || helper_loop(&inner, &hello_listener, &stop, interval, &config)
            })
            .map_err(WriterCreateError::Thread)?;

        Ok(SegmentPublisher {
            session: new_session_id(),
            shm_dir: self.shm_dir,
            settings,
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

#[derive(Debug, Clone, Copy)]
struct PortSettings {
    max_readers: usize,
    initial_blocks: usize,
}

/// A publisher port with the service it belongs to.
struct SegmentService {
    name: String,
    publisher: SegmentPort,
    service: SegmentFactory,
}

/// State shared with the helper thread.
struct Inner {
    /// Publisher ports by layer id; the manifest's under [`MANIFEST_LAYER_ID`].
    ports: BTreeMap<u32, SegmentService>,
    events_notifier: Notifier<Ipc>,
    _events: EventFactory<Ipc>,
}

impl Inner {
    /// Connects new subscribers and hands them the history (the newest sample of each service).
    fn update_connections(&self) {
        for service in self.ports.values() {
            // A failing connection is retried on the next publish; nothing to report here.
            let _ = service.publisher.update_connections();
        }
    }

    /// Readers connected to the scene now (the manifest's subscribers).
    fn reader_count(&self) -> usize {
        self.ports
            .get(&MANIFEST_LAYER_ID)
            .map_or(0, |s| s.service.dynamic_config().number_of_subscribers())
    }

    fn notify(&self, event: EventId) {
        // Readers without a listener (or none at all) are no error for the writer.
        let _ = self.events_notifier.notify_with_custom_event_id(event);
    }
}

/// Publishes one scene's segments: per-layer byte segments and a manifest naming a consistent
/// cut of them (DESIGN.md §5).
///
/// Call [`publish_layer`](Self::publish_layer) for every changed layer, then
/// [`publish_manifest`](Self::publish_manifest) naming the generation of every layer of the
/// snapshot. Publishing never blocks on readers: slow readers lose intermediate samples
/// (safe overflow), and a reader holding samples only holds its own share of the pool.
///
/// Dropping the writer tells readers it is gone and removes its shared memory.
pub struct SegmentPublisher {
    session: u64,
    shm_dir: PathBuf,
    settings: PortSettings,
    services: SceneServices,
    /// Last generation published per layer, to check manifests.
    published: BTreeMap<u32, u64>,
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

    /// The last generation published for `layer_id`, if any.
    pub fn layer_generation(&self, layer_id: u32) -> Option<u64> {
        self.published.get(&layer_id).copied()
    }

    /// Publishes `len` bytes as generation `generation` of layer `layer_id`.
    ///
    /// `fill` gets the loaned shared-memory buffer of exactly `len` bytes (starting 128-byte
    /// aligned) and must write all of it: its previous content is unspecified. No copy is made.
    /// Readers see the layer only once a manifest names this generation.
    ///
    /// The layer's service is created on first use.
    ///
    /// # Errors
    ///
    /// [`PublishError::SharedMemoryFull`] before anything is written if `/dev/shm` lacks room;
    /// see [`PublishError`] for the rest.
    pub fn publish_layer(
        &mut self,
        layer_id: u32,
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
        layer_id: u32,
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
        let service =
            match inner.ports.entry(layer_id) {
                std::collections::btree_map::Entry::Occupied(entry) => entry.into_mut(),
                std::collections::btree_map::Entry::Vacant(entry) => entry.insert(
                    open_segment_port(&self.node, &self.services.layer(layer_id), self.settings)?,
                ),
            };
        send_segment(service, &self.shm_dir, header, len, fill)?;
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
        if entries.len() > MAX_LAYERS {
            return Err(PublishError::TooManyLayers {
                count: entries.len(),
                max: MAX_LAYERS,
            });
        }
        for pair in entries.windows(2) {
            if pair[0].layer_id >= pair[1].layer_id {
                return Err(PublishError::UnsortedManifest {
                    layer_id: pair[1].layer_id,
                });
            }
        }
        for entry in entries {
            let published = self.published.get(&entry.layer_id).copied();
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
        let inner = lock(&self.inner);
        let manifest = inner
            .ports
            .get(&MANIFEST_LAYER_ID)
            .ok_or(PublishError::Closed)?;
        send_segment(manifest, &self.shm_dir, header, total, |buf| {
            let (prefix, rest) = buf.split_at_mut(prefix_len);
            protocol::encode_manifest_prefix(entries, prefix);
            fill(rest)
        })?;
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

    /// Stops publishing `layer_id` and removes its service once no reader holds it. Publish a
    /// manifest without the layer first.
    pub fn retire_layer(&mut self, layer_id: u32) {
        if layer_id != MANIFEST_LAYER_ID {
            lock(&self.inner).ports.remove(&layer_id);
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

    /// Delivers the newest segments to readers that connected since the last publish. The
    /// helper thread does this when a reader announces itself; calling it is never required.
    pub fn update_connections(&self) {
        let inner = lock(&self.inner);
        inner.update_connections();
        inner.notify(EVENT_SNAPSHOT_PUBLISHED);
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
        // Remove the publishers first: readers that get the event then see no publisher.
        inner.ports.clear();
        inner.notify(EVENT_WRITER_GONE);
    }
}

fn lock(inner: &Mutex<Inner>) -> MutexGuard<'_, Inner> {
    // A panic in the helper thread leaves the ports intact; keep using them.
    inner.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Loans, fills and sends one segment after checking shared-memory space.
fn send_segment<E>(
    service: &SegmentService,
    shm_dir: &std::path::Path,
    header: SegmentHeader,
    len: usize,
    fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
) -> Result<(), PublishError>
where
    E: Into<Box<dyn std::error::Error + Send + Sync>>,
{
    let blocks = protocol::blocks_for(len).max(1);
    let payload_bytes = blocks
        .checked_mul(BLOCK_SIZE)
        .ok_or(PublishError::TooLarge { len })?;
    shm::ensure_free(shm_dir, payload_bytes as u64)?;
    let mut sample = service
        .publisher
        .loan_slice_uninit(blocks)
        .map_err(|source| PublishError::Loan {
            service: service.name.clone(),
            source,
        })?;
    *sample.user_header_mut() = header;
    let sample = loan::fill_sample(sample, len, fill).map_err(|e| PublishError::Fill(e.into()))?;
    sample.send().map_err(|source| PublishError::Send {
        service: service.name.clone(),
        source,
    })?;
    Ok(())
}

/// Opens or creates a segment service with the never-block QoS and claims its only publisher.
fn open_segment_port(
    node: &Node<Ipc>,
    name: &str,
    settings: PortSettings,
) -> Result<SegmentService, WriterCreateError> {
    let service = node
        .service_builder(&crate::service::service_name(name)?)
        .publish_subscribe::<[Block128]>()
        .user_header::<SegmentHeader>()
        .max_publishers(1)
        .max_subscribers(settings.max_readers)
        .max_nodes(settings.max_readers + 2)
        .history_size(HISTORY_SIZE)
        .subscriber_max_buffer_size(SUBSCRIBER_BUFFER_SIZE)
        .subscriber_max_borrowed_samples(SUBSCRIBER_MAX_BORROWED)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| WriterCreateError::from(crate::service::service_failure(name, e)))?;
    let publisher = service
        .publisher_builder()
        .max_loaned_samples(PUBLISHER_MAX_LOANED)
        .initial_max_slice_len(settings.initial_blocks)
        .allocation_strategy(AllocationStrategy::PowerOfTwo)
        .create()
        .map_err(|e| match e {
            PublisherCreateError::ExceedsMaxSupportedPublishers => {
                WriterCreateError::AlreadyRunning {
                    scene: scene_of(name),
                }
            }
            e => crate::service::port_failure(name, e).into(),
        })?;
    Ok(SegmentService {
        name: name.to_owned(),
        publisher,
        service,
    })
}

/// `ygg/<scene>/...` -> `<scene>`.
fn scene_of(service: &str) -> String {
    service.split('/').nth(1).unwrap_or(service).to_owned()
}

/// Opens or creates an event service. On the writer -> readers service, a writer that drops
/// or is found dead emits [`EVENT_WRITER_GONE`].
fn open_event_service(
    node: &Node<Ipc>,
    name: &str,
    max_readers: usize,
    to_readers: bool,
) -> Result<EventFactory<Ipc>, WriterCreateError> {
    let mut builder = node
        .service_builder(&crate::service::service_name(name)?)
        .event()
        .max_nodes(max_readers + 2)
        .max_listeners(max_readers + 2)
        .max_notifiers(max_readers + 2)
        .event_id_max_value(EVENT_ID_MAX);
    if to_readers {
        builder = builder
            .notifier_dead_event(EVENT_WRITER_GONE)
            .notifier_dropped_event(EVENT_WRITER_GONE);
    }
    builder
        .open_or_create()
        .map_err(|e| WriterCreateError::from(crate::service::service_failure(name, e)))
}

/// Answers reader announcements, removes resources of dead readers and drops connections of
/// departed ones until `stop` is set.
fn helper_loop(
    inner: &Mutex<Inner>,
    listener: &Listener<Ipc>,
    stop: &AtomicBool,
    interval: Duration,
    config: &Config,
) {
    let mut last_cleanup = Instant::now();
    let mut readers_before = lock(inner).reader_count();
    while !stop.load(Ordering::SeqCst) {
        let mut hello = false;
        let waited = listener.timed_wait(
            |activation| hello |= activation.id == EVENT_READER_HELLO,
            interval,
        );
        if stop.load(Ordering::SeqCst) {
            break;
        }
        if waited.is_err() {
            // Interrupted by a signal or a broken listener: do not spin.
            std::thread::sleep(interval.min(Duration::from_millis(50)));
        }
        if hello {
            let inner = lock(inner);
            inner.update_connections();
            inner.notify(EVENT_SNAPSHOT_PUBLISHED);
        }
        if last_cleanup.elapsed() >= CLEANUP_INTERVAL {
            cleanup_dead_nodes(config);
            // Drops the connections (shared-memory files and descriptors) of readers that
            // left or died; a layer that is not republished would otherwise keep them
            // until the next reader announces itself.
            let readers = {
                let inner = lock(inner);
                inner.update_connections();
                inner.reader_count()
            };
            // A reader left or died (and whoever noticed first, a reader or this thread,
            // removed its resources): give the heap that freed back.
            if readers < readers_before {
                super::heap::release_free_heap();
            }
            readers_before = readers;
            last_cleanup = Instant::now();
        }
    }
}

/// Removes the resources of dead processes (readers killed without cleanup), freeing their
/// subscriber slots and the samples they held.
fn cleanup_dead_nodes(config: &Config) {
    let _ = Node::<Ipc>::list(config, |state| {
        if let NodeState::Dead(view) = state {
            // Another process may be cleaning up the same node; that is fine.
            let _ = view.try_remove_stale_resources();
        }
        CallbackProgression::Continue
    });
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
