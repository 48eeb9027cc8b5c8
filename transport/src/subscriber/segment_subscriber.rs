//! [`SubscriberBuilder`] and [`SegmentSubscriber`]: attaching to a scene and assembling
//! consistent snapshots.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Weak};
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::port::ReceiveError as IoxReceiveError;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::{CallbackProgression, Node, NodeState};
use iceoryx2::service::builder::event::EventOpenError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;

use super::segment::{HeldSegment, SegmentSample};
use super::snapshot::{Snapshot, SnapshotLayer};
use super::{ReaderOpenError, ReceiveError};
use crate::SetupError;
use crate::protocol::{
    self, Block128, DEFAULT_LIVENESS_INTERVAL, EVENT_READER_HELLO, EVENT_WRITER_GONE, Ipc,
    ManifestEntry, SceneServices, SegmentHeader, SegmentKind,
};

type SegmentFactory = PubSubFactory<Ipc, [Block128], SegmentHeader>;
type SegmentSub = Subscriber<Ipc, [Block128], SegmentHeader>;

/// How often [`SubscriberBuilder::open`] looks for the scene's services while it waits for a
/// writer ([`SubscriberBuilder::wait_for_writer`]).
const WRITER_APPEARS_CHECK: Duration = Duration::from_millis(20);
/// After a writer-gone event, how often liveness is re-checked until the writer's ports are
/// gone (a writer announces its exit just before it removes them).
const FAST_CHECK: Duration = Duration::from_millis(5);
/// How long the fast checks go on after a writer-gone event.
const FAST_CHECK_WINDOW: Duration = Duration::from_millis(250);
/// Received layer segments kept per layer beyond the current snapshot's: the subscriber
/// buffer size, i.e. one publish racing the read (DESIGN.md §5).
const MAX_PENDING: usize = protocol::SUBSCRIBER_BUFFER_SIZE;

/// Configures and opens a [`SegmentSubscriber`].
///
/// ```no_run
/// # fn main() -> Result<(), Box<dyn core::error::Error>> {
/// use std::time::Duration;
/// use ygg_transport::SubscriberBuilder;
/// let mut reader = SubscriberBuilder::new("office").open()?;
/// if let Some(snapshot) = reader.wait_next(Duration::from_secs(1))? {
///     for (entry, bytes) in snapshot.layers() {
///         println!("layer {} generation {}: {} bytes", entry.layer_id, entry.generation, bytes.len());
///     }
/// }
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone)]
pub struct SubscriberBuilder {
    scene: String,
    iceoryx_prefix: Option<String>,
    liveness_interval: Duration,
    handle_termination_signals: bool,
    wait_for_writer: Duration,
}

impl SubscriberBuilder {
    /// A builder for a reader of `scene` with default settings.
    pub fn new(scene: &str) -> Self {
        Self {
            scene: scene.to_owned(),
            iceoryx_prefix: None,
            liveness_interval: DEFAULT_LIVENESS_INTERVAL,
            handle_termination_signals: false,
            wait_for_writer: Duration::ZERO,
        }
    }

    /// How long [`SubscriberBuilder::open`] waits for a writer to create the scene before it
    /// gives up with [`ReaderOpenError::NoWriter`] (default zero: fail at once). iceoryx2
    /// announces no service creation, so the wait checks for the scene's services every
    /// 20 ms.
    pub fn wait_for_writer(mut self, value: Duration) -> Self {
        self.wait_for_writer = value;
        self
    }

    /// The iceoryx2 file-name prefix; overrides [`protocol::ENV_IOX2_PREFIX`]. Must match the
    /// writer's.
    pub fn iceoryx_prefix(mut self, prefix: &str) -> Self {
        self.iceoryx_prefix = Some(prefix.to_owned());
        self
    }

    /// How often a waiting reader checks that the writer process is alive (default 200 ms).
    /// A writer that exits cleanly is noticed at once; a killed one within this interval.
    pub fn liveness_interval(mut self, value: Duration) -> Self {
        self.liveness_interval = value.max(Duration::from_millis(1));
        self
    }

    /// If true, `open` installs iceoryx2's SIGINT/SIGTERM handler and
    /// [`SegmentSubscriber::wait_next`] returns [`ReceiveError::Terminated`] on those signals,
    /// so that the process can drop the reader and exit cleanly. Off by default: a library
    /// should not take over an application's signals.
    pub fn handle_termination_signals(mut self, value: bool) -> Self {
        self.handle_termination_signals = value;
        self
    }

    /// Attaches to the scene and asks the writer for the current segments; the first
    /// [`SegmentSubscriber::wait_next`] returns the current snapshot within milliseconds.
    ///
    /// Succeeds when the scene's services exist even if their writer is gone; the reader then
    /// picks up the next writer.
    ///
    /// # Errors
    ///
    /// [`ReaderOpenError::NoWriter`] if no writer ever created the scene (or all are gone and
    /// cleaned up), [`ReaderOpenError::Terminated`] on SIGINT/SIGTERM while waiting for one
    /// (when [`SubscriberBuilder::handle_termination_signals`] is on), otherwise the variant
    /// naming the failing resource.
    pub fn open(self) -> Result<SegmentSubscriber, ReaderOpenError> {
        let deadline = Instant::now() + self.wait_for_writer;
        loop {
            match self.open_once() {
                Err(ReaderOpenError::NoWriter { .. }) if Instant::now() < deadline => {
                    std::thread::sleep(WRITER_APPEARS_CHECK);
                }
                result => return result,
            }
        }
    }

    fn open_once(&self) -> Result<SegmentSubscriber, ReaderOpenError> {
        let services = SceneServices::new(&self.scene).map_err(SetupError::from)?;
        let config =
            protocol::iceoryx_config(self.iceoryx_prefix.as_deref()).map_err(SetupError::from)?;
        let node = crate::service::create_node("ygg-reader", services.scene(), &config)?;
        // The first wait installs iceoryx2's signal handler; a zero wait returns at once, with
        // an error when a signal arrived since the last attempt (while waiting for a writer).
        if self.handle_termination_signals && node.wait(Duration::ZERO).is_err() {
            return Err(ReaderOpenError::Terminated);
        }

        // Listener first, so that no event sent after the subscribers exist is missed.
        let events_service = open_event_service(&node, &services, &services.events())?;
        let events = events_service
            .listener_builder()
            .create()
            .map_err(|e| crate::service::port_failure(&services.events(), e))?;
        let manifest = open_segment_sub(&node, &services, &services.manifest())?;
        let readers_service = open_event_service(&node, &services, &services.readers())?;
        let hello = readers_service
            .notifier_builder()
            .default_event_id(EVENT_READER_HELLO)
            .create()
            .map_err(|e| crate::service::port_failure(&services.readers(), e))?;

        let mut reader = SegmentSubscriber {
            services,
            config,
            liveness_interval: self.liveness_interval,
            handle_signals: self.handle_termination_signals,
            terminated: AtomicBool::new(false),
            manifest,
            layers: BTreeMap::new(),
            pending_manifest: None,
            current: None,
            retired: None,
            delivered: None,
            status: WriterStatus::Unknown,
            gone_unreported: false,
            next_liveness_check: Instant::now(),
            fast_checks_until: None,
            events,
            hello,
            _events_service: events_service,
            _readers_service: readers_service,
            node,
        };
        reader.check_liveness();
        reader.say_hello();
        Ok(reader)
    }
}

/// What the reader knows about the scene's writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriterStatus {
    /// Not checked yet.
    Unknown,
    /// A live writer publishes the scene.
    Alive,
    /// The writer exited or died; the last snapshot stays available.
    Gone,
}

/// A subscription to one layer's service, with samples received but not yet used.
struct LayerPort {
    port: SubPort,
    /// Received segments newer than the current snapshot's, oldest first.
    pending: Vec<Arc<HeldSegment>>,
}

struct SubPort {
    name: String,
    subscriber: SegmentSub,
    service: SegmentFactory,
}

/// The newest manifest received and not yet assembled into a snapshot.
struct PendingManifest {
    segment: Arc<HeldSegment>,
    entries: Vec<ManifestEntry>,
    offset: usize,
}

/// Receives consistent snapshots of one scene (DESIGN.md §5).
///
/// It takes the newest manifest and, for each layer it names, the layer segment of the named
/// generation, and hands them out as an [`Arc<Snapshot>`] that keeps the samples alive. Waiting
/// blocks on an iceoryx2 event, never polls. If the writer exits or dies, the reader reports
/// [`ReceiveError::WriterGone`] once, keeps the last snapshot and picks up a restarted writer.
pub struct SegmentSubscriber {
    services: SceneServices,
    config: Config,
    liveness_interval: Duration,
    handle_signals: bool,
    /// A termination signal was seen (iceoryx2 reports each one only once).
    terminated: AtomicBool,
    manifest: SubPort,
    layers: BTreeMap<u32, LayerPort>,
    pending_manifest: Option<PendingManifest>,
    current: Option<Arc<Snapshot>>,
    /// The last snapshot of an earlier writer session, until the application drops it:
    /// iceoryx2 drops a reader's connections to a writer that is gone only in a receive
    /// after their samples were returned, so every layer is received once more then.
    retired: Option<Weak<Snapshot>>,
    /// (session, generation) of the snapshot last handed out.
    delivered: Option<(u64, u64)>,
    status: WriterStatus,
    gone_unreported: bool,
    next_liveness_check: Instant,
    fast_checks_until: Option<Instant>,
    events: Listener<Ipc>,
    hello: Notifier<Ipc>,
    _events_service: EventFactory<Ipc>,
    _readers_service: EventFactory<Ipc>,
    node: Node<Ipc>,
}

impl std::fmt::Debug for SegmentSubscriber {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SegmentSubscriber")
            .field("scene", &self.services.scene())
            .field("status", &self.status)
            .field("current", &self.current.as_ref().map(|s| s.key()))
            .finish_non_exhaustive()
    }
}

impl SegmentSubscriber {
    /// The scene name.
    pub fn scene(&self) -> &str {
        self.services.scene()
    }

    /// What the reader last found out about the writer.
    pub fn writer_status(&self) -> WriterStatus {
        self.status
    }

    /// Whether SIGINT or SIGTERM arrived since the reader was opened (always false unless
    /// [`SubscriberBuilder::handle_termination_signals`] is on); once true it stays true, also
    /// after [`wait_next`](Self::wait_next) returned [`ReceiveError::Terminated`]. Lets an
    /// application that waits elsewhere notice the request.
    pub fn termination_requested(&self) -> bool {
        if self.handle_signals && !self.terminated.load(Ordering::Relaxed) {
            // iceoryx2 hands out each signal once: remember it.
            let seen = self.node.wait(Duration::ZERO).is_err();
            self.terminated.fetch_or(seen, Ordering::Relaxed);
        }
        self.terminated.load(Ordering::Relaxed)
    }

    /// The newest complete snapshot received so far, without receiving anything.
    pub fn current(&self) -> Option<Arc<Snapshot>> {
        self.current.clone()
    }

    /// Receives what has arrived without blocking and returns the newest complete snapshot
    /// (possibly one returned before), or `None` if none is complete yet.
    ///
    /// # Errors
    ///
    /// [`ReceiveError::Corrupt`] and the other receive failures; the previous snapshot stays
    /// available through [`current`](Self::current).
    pub fn latest(&mut self) -> Result<Option<Arc<Snapshot>>, ReceiveError> {
        self.sync()?;
        if Instant::now() >= self.next_liveness_check {
            self.check_liveness();
        }
        if let Some(snapshot) = &self.current {
            self.delivered = Some(snapshot.key());
        }
        Ok(self.current.clone())
    }

    /// Blocks until a snapshot newer than the last one returned is complete, or `timeout`
    /// passes (`Ok(None)`). Wakes on iceoryx2 events; between events it only checks, every
    /// liveness interval, that the writer lives.
    ///
    /// # Errors
    ///
    /// [`ReceiveError::WriterGone`] once when the writer exits or dies (call again to wait for
    /// a restarted writer), [`ReceiveError::Corrupt`] for a segment that breaks the protocol,
    /// [`ReceiveError::Terminated`] on SIGINT/SIGTERM if enabled, and the other receive
    /// failures.
    pub fn wait_next(&mut self, timeout: Duration) -> Result<Option<Arc<Snapshot>>, ReceiveError> {
        let start = Instant::now();
        loop {
            self.sync()?;
            if let Some(snapshot) = &self.current
                && self.delivered != Some(snapshot.key())
            {
                self.delivered = Some(snapshot.key());
                return Ok(Some(Arc::clone(snapshot)));
            }
            let now = Instant::now();
            if now >= self.next_liveness_check {
                self.check_liveness();
            }
            if self.gone_unreported {
                self.gone_unreported = false;
                return Err(ReceiveError::WriterGone {
                    scene: self.services.scene().to_owned(),
                });
            }
            let elapsed = now.duration_since(start);
            if elapsed >= timeout {
                return Ok(None);
            }
            let until_check = self.next_liveness_check.saturating_duration_since(now);
            let slice = (timeout - elapsed)
                .min(until_check)
                .max(Duration::from_micros(100));
            let mut writer_gone = false;
            match self
                .events
                .timed_wait(|e| writer_gone |= e.id == EVENT_WRITER_GONE, slice)
            {
                Ok(_) | Err(ListenerWaitError::InterruptSignal) => {}
                Err(e) => {
                    return Err(ReceiveError::Wait {
                        reason: e.to_string(),
                    });
                }
            }
            if self.termination_requested() {
                return Err(ReceiveError::Terminated);
            }
            if writer_gone {
                // The writer announces its exit just before removing its ports: check now and
                // then briefly at a fast pace.
                let now = Instant::now();
                self.fast_checks_until = Some(now + FAST_CHECK_WINDOW);
                self.next_liveness_check = now;
            }
        }
    }

    /// Receives everything that arrived and assembles the newest complete snapshot.
    fn sync(&mut self) -> Result<(), ReceiveError> {
        let mut first_error: Option<ReceiveError> = None;

        // 1. Manifests: keep only the newest valid one (one at a time, to bound borrows).
        let manifest_port = &self.manifest;
        let pending_manifest = &mut self.pending_manifest;
        let error = drain(manifest_port, |sample| {
            let manifest = accept_manifest(sample).map_err(|source| ReceiveError::Corrupt {
                service: manifest_port.name.clone(),
                source,
            })?;
            *pending_manifest = Some(manifest);
            Ok(())
        });
        first_error = first_error.or(error);

        // 2. Subscribe to layers the pending manifest names for the first time.
        let mut new_subscribers = false;
        if let Some(manifest) = &self.pending_manifest {
            for entry in &manifest.entries {
                if self.layers.contains_key(&entry.layer_id) {
                    continue;
                }
                let name = self.services.layer(entry.layer_id);
                match open_segment_sub(&self.node, &self.services, &name) {
                    Ok(port) => {
                        self.layers.insert(
                            entry.layer_id,
                            LayerPort {
                                port,
                                pending: Vec::new(),
                            },
                        );
                        new_subscribers = true;
                    }
                    Err(e) => {
                        first_error.get_or_insert(e.into());
                    }
                }
            }
        }

        // 3. Layer segments, from the layers whose segment the pending manifest wants and
        //    that is not at hand yet (segments of other layers wait in their queues, where
        //    the writer's next sample would replace them).
        let current = self.current.as_deref();
        for (&layer_id, layer) in &mut self.layers {
            // The generation the pending manifest wants from this layer, if any.
            let Some(wanted) = self.pending_manifest.as_ref().and_then(|m| {
                let entry = m.entries.iter().find(|e| e.layer_id == layer_id)?;
                Some((m.segment.header().session, entry.generation))
            }) else {
                continue;
            };
            let is_wanted = |s: &HeldSegment| (s.header().session, s.header().generation) == wanted;
            let at_hand = layer.pending.iter().any(|s| is_wanted(s))
                || current.is_some_and(|c| {
                    c.layers
                        .iter()
                        .any(|l| l.entry.layer_id == layer_id && is_wanted(&l.segment))
                });
            if at_hand {
                continue;
            }
            let wanted = Some(wanted);
            let port = &layer.port;
            let pending = &mut layer.pending;
            let error = drain(port, |sample| {
                let segment = HeldSegment::new(sample, SegmentKind::Layer, Some(layer_id))
                    .map_err(|source| ReceiveError::Corrupt {
                        service: port.name.clone(),
                        source,
                    })?;
                keep_pending(pending, wanted, segment);
                Ok(())
            });
            first_error = first_error.or(error);
        }

        // 4. Once the last snapshot of an earlier writer is released, receive from every
        //    layer: iceoryx2 then drops the connections to that writer (shared-memory files
        //    and descriptors), which a layer that is never republished would keep.
        if self.retired.as_ref().is_some_and(|w| w.strong_count() == 0) {
            self.retired = None;
            let session = self.current.as_ref().map(|c| c.session);
            for (&layer_id, layer) in &mut self.layers {
                let wanted = self
                    .current
                    .as_ref()
                    .and_then(|c| Some((c.session, c.layer_generation(layer_id)?)));
                let (port, pending) = (&layer.port, &mut layer.pending);
                let error = drain(port, |sample| {
                    let segment = HeldSegment::new(sample, SegmentKind::Layer, Some(layer_id))
                        .map_err(|source| ReceiveError::Corrupt {
                            service: port.name.clone(),
                            source,
                        })?;
                    if Some(segment.header().session) == session {
                        keep_pending(pending, wanted, segment);
                    }
                    Ok(())
                });
                first_error = first_error.or(error);
            }
        }

        // 5. Assemble.
        self.try_assemble();

        if new_subscribers {
            self.say_hello();
        }
        first_error.map_or(Ok(()), Err)
    }

    /// Builds a snapshot from the pending manifest if every layer it names has arrived.
    fn try_assemble(&mut self) {
        let Some(manifest) = &self.pending_manifest else {
            return;
        };
        let session = manifest.segment.header().session;
        let mut layers = Vec::with_capacity(manifest.entries.len());
        for entry in &manifest.entries {
            let matches = |s: &Arc<HeldSegment>| {
                s.header().session == session && s.header().generation == entry.generation
            };
            let from_pending = self
                .layers
                .get(&entry.layer_id)
                .and_then(|l| l.pending.iter().rev().find(|s| matches(s)).cloned());
            let from_current = || {
                self.current
                    .as_ref()
                    .and_then(|c| c.layers.iter().find(|l| l.entry == *entry))
                    .filter(|l| matches(&l.segment))
                    .map(|l| Arc::clone(&l.segment))
            };
            match from_pending.or_else(from_current) {
                Some(segment) => layers.push(SnapshotLayer {
                    entry: *entry,
                    segment,
                }),
                // Not arrived yet (or overflowed: a newer manifest is on its way).
                None => return,
            }
        }
        let Some(manifest) = self.pending_manifest.take() else {
            return;
        };
        let snapshot = Snapshot {
            session,
            generation: manifest.segment.header().generation,
            manifest: manifest.segment,
            manifest_offset: manifest.offset,
            layers,
        };
        // Drop segments the new snapshot superseded, and layers it no longer has.
        self.layers.retain(|id, layer| {
            let Some(generation) = snapshot.layer_generation(*id) else {
                return false;
            };
            layer
                .pending
                .retain(|s| s.header().session == session && s.header().generation > generation);
            true
        });
        if let Some(old) = self.current.as_ref().filter(|c| c.session != session) {
            self.retired = Some(Arc::downgrade(old));
        }
        self.current = Some(Arc::new(snapshot));
    }

    /// Asks the writer to deliver the newest segments to this reader's new subscribers.
    fn say_hello(&self) {
        // Without a writer nobody listens; the next writer delivers on its first publish.
        let _ = self.hello.notify();
    }

    /// Finds out whether the writer (the publisher of the manifest service) is alive, removes
    /// the resources of a dead one and records a transition to [`WriterStatus::Gone`].
    fn check_liveness(&mut self) {
        let now = Instant::now();
        self.next_liveness_check = match self.fast_checks_until {
            Some(until) if now < until => now + FAST_CHECK,
            _ => {
                self.fast_checks_until = None;
                now + self.liveness_interval
            }
        };
        let mut writer: Option<UniqueNodeId> = None;
        self.manifest
            .service
            .dynamic_config()
            .list_publishers(|details| {
                writer = Some(details.node_id);
                CallbackProgression::Stop
            });
        let alive = match writer {
            None => false,
            Some(id) => match Node::<Ipc>::state_of(&self.config, id) {
                Ok(Some(NodeState::Alive(_))) => true,
                Ok(Some(NodeState::Dead(_)) | None) => {
                    // Frees the dead writer's publisher slot (so a restarted writer can claim
                    // it) and wakes other readers. Held samples stay mapped.
                    self.node.try_cleanup_dead_nodes();
                    false
                }
                // Cannot tell: assume nothing changed.
                Ok(Some(_)) | Err(_) => self.status == WriterStatus::Alive,
            },
        };
        match (alive, self.status) {
            (true, _) => {
                self.status = WriterStatus::Alive;
                self.fast_checks_until = None;
            }
            (false, WriterStatus::Gone) => {}
            (false, _) => {
                self.status = WriterStatus::Gone;
                self.gone_unreported = true;
                self.fast_checks_until = None;
                // Whatever the dead writer left half-published can never complete.
                self.pending_manifest = None;
                for layer in self.layers.values_mut() {
                    layer.pending.clear();
                }
            }
        }
    }
}

/// Receives the samples waiting on `port` one at a time, handing each to `accept` before the
/// next is received (so at most one extra sample is borrowed). Returns the first failure; a
/// sample that `accept` rejects is dropped and receiving goes on.
fn drain(
    port: &SubPort,
    mut accept: impl FnMut(SegmentSample) -> Result<(), ReceiveError>,
) -> Option<ReceiveError> {
    let mut first_error = None;
    loop {
        match port.subscriber.receive() {
            Ok(Some(sample)) => {
                if let Err(e) = accept(sample) {
                    first_error.get_or_insert(e);
                }
            }
            Ok(None) => return first_error,
            Err(IoxReceiveError::ExceedsMaxBorrows) => {
                return first_error.or(Some(ReceiveError::BorrowLimit {
                    service: port.name.clone(),
                }));
            }
            Err(e) => {
                return first_error.or(Some(ReceiveError::Connection {
                    service: port.name.clone(),
                    reason: e.to_string(),
                }));
            }
        }
    }
}

/// Adds `segment` to a layer's pending segments, dropping those no snapshot can use any more:
/// other writer sessions, generations older than the one `wanted` by the pending manifest, and
/// beyond [`MAX_PENDING`] the oldest (a newer manifest will name a newer one).
fn keep_pending(
    pending: &mut Vec<Arc<HeldSegment>>,
    wanted: Option<(u64, u64)>,
    segment: HeldSegment,
) {
    let session = segment.header().session;
    pending.retain(|s| {
        let h = s.header();
        h.session == session && wanted.is_none_or(|(ws, wg)| ws != session || h.generation >= wg)
    });
    while pending.len() >= MAX_PENDING {
        pending.remove(0);
    }
    pending.push(Arc::new(segment));
}

fn accept_manifest(sample: SegmentSample) -> Result<PendingManifest, protocol::SegmentError> {
    let segment = HeldSegment::new(sample, SegmentKind::Manifest, None)?;
    let (entries, offset) = protocol::decode_manifest_prefix(segment.bytes())?;
    Ok(PendingManifest {
        segment: Arc::new(segment),
        entries,
        offset,
    })
}

fn open_segment_sub(
    node: &Node<Ipc>,
    services: &SceneServices,
    name: &str,
) -> Result<SubPort, ReaderOpenError> {
    let service = node
        .service_builder(&crate::service::service_name(name)?)
        .publish_subscribe::<[Block128]>()
        .user_header::<SegmentHeader>()
        .open()
        .map_err(|e| match e {
            PublishSubscribeOpenError::DoesNotExist => ReaderOpenError::NoWriter {
                scene: services.scene().to_owned(),
            },
            e => ReaderOpenError::from(crate::service::service_failure(name, e)),
        })?;
    let subscriber = service
        .subscriber_builder()
        .create()
        .map_err(|e| crate::service::port_failure(name, e))?;
    Ok(SubPort {
        name: name.to_owned(),
        subscriber,
        service,
    })
}

fn open_event_service(
    node: &Node<Ipc>,
    services: &SceneServices,
    name: &str,
) -> Result<EventFactory<Ipc>, ReaderOpenError> {
    node.service_builder(&crate::service::service_name(name)?)
        .event()
        .open()
        .map_err(|e| match e {
            EventOpenError::DoesNotExist => ReaderOpenError::NoWriter {
                scene: services.scene().to_owned(),
            },
            e => ReaderOpenError::from(crate::service::service_failure(name, e)),
        })
}
