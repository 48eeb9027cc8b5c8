//! [`SubscriberBuilder`] and [`SegmentSubscriber`]: attaching to a scene and assembling
//! consistent snapshots.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use iceoryx2::config::Config;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::port::ReceiveError as IoxReceiveError;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::{CallbackProgression, Node};
use iceoryx2::service::builder::event::EventOpenError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2_bb_posix::signal::SignalHandler;

use super::assembly::Assembly;
use super::segment::HeldSegment;
use super::snapshot::Snapshot;
use super::{ReaderOpenError, ReceiveError};
use crate::SetupError;
use crate::process_watch::{Liveness, ProcessWatch};
use crate::protocol::{self, Block128, EVENT_READER_HELLO, EVENT_WRITER_GONE, SegmentHeader};
use crate::service::{self, DEFAULT_LIVENESS_INTERVAL, Ipc, SceneServices};
use crate::wake;

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
/// How long a reader waits for the catch-up burst it asked for before it asks again (the
/// writer skips a burst when shared memory is short).
const CATCH_UP_RETRY: Duration = Duration::from_millis(100);

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

    /// The iceoryx2 file-name prefix; overrides [`service::ENV_IOX2_PREFIX`]. Must match the
    /// writer's.
    pub fn iceoryx_prefix(mut self, prefix: &str) -> Self {
        self.iceoryx_prefix = Some(prefix.to_owned());
        self
    }

    /// How often a waiting reader checks that the writer process is alive (default 200 ms).
    /// A writer that exits cleanly is noticed at once, and so is a killed one whose process
    /// the reader can watch (same pid namespace, Linux 5.3+); another killed one within
    /// this interval.
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
            service::iceoryx_config(self.iceoryx_prefix.as_deref()).map_err(SetupError::from)?;
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
        let stream = open_segment_sub(&node, &services, &services.segments())?;
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
            stream,
            assembly: Assembly::default(),
            catch_up_asked: None,
            delivered: None,
            status: WriterStatus::Unknown,
            gone_session: None,
            gone_unreported: false,
            next_liveness_check: Instant::now(),
            fast_checks_until: None,
            writer_process: ProcessWatch::default(),
            events,
            hello,
            _events_service: events_service,
            _readers_service: readers_service,
            _node: node,
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

/// A subscriber port with its service.
struct SubPort {
    name: String,
    subscriber: SegmentSub,
    service: SegmentFactory,
}

/// Receives consistent snapshots of one scene (DESIGN.md §5).
///
/// It takes the newest manifest and, for each segment it names, the segment of the named
/// generation, and hands them out as an [`Arc<Snapshot>`] that keeps the samples alive. All
/// segments arrive over one subscription whatever their number, the scene's segment stream; a
/// connecting reader, or one that lost segments to overflow, asks the writer for a catch-up
/// burst of the current snapshot on it. Waiting blocks on an iceoryx2 event,
/// never polls. If the writer exits or dies, the reader reports [`ReceiveError::WriterGone`]
/// once, keeps the last snapshot and picks up a restarted writer.
pub struct SegmentSubscriber {
    services: SceneServices,
    config: Config,
    liveness_interval: Duration,
    handle_signals: bool,
    /// A termination signal was seen (iceoryx2 reports each one only once).
    terminated: AtomicBool,
    stream: SubPort,
    assembly: Assembly,
    /// When the last catch-up burst was asked for, while one is awaited.
    catch_up_asked: Option<Instant>,
    /// (session, generation) of the snapshot last handed out.
    delivered: Option<(u64, u64)>,
    status: WriterStatus,
    /// The session of the current snapshot when the writer was found gone.
    gone_session: Option<u64>,
    gone_unreported: bool,
    next_liveness_check: Instant,
    fast_checks_until: Option<Instant>,
    /// The writer's process, between iceoryx2's checks of its node.
    writer_process: ProcessWatch,
    events: Listener<Ipc>,
    hello: Notifier<Ipc>,
    _events_service: EventFactory<Ipc>,
    _readers_service: EventFactory<Ipc>,
    /// This reader's iceoryx2 node: it owns the ports above, so it is dropped last.
    _node: Node<Ipc>,
}

impl std::fmt::Debug for SegmentSubscriber {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SegmentSubscriber")
            .field("scene", &self.services.scene())
            .field("status", &self.status)
            .field("current", &self.assembly.current().map(|s| s.key()))
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
            // iceoryx2 hands out each signal once: remember it. (Asked of its signal handler
            // directly: `Node::wait` would cost a `nanosleep` system call on every wake-up.)
            let seen = SignalHandler::termination_requested();
            self.terminated.fetch_or(seen, Ordering::Relaxed);
        }
        self.terminated.load(Ordering::Relaxed)
    }

    /// The newest complete snapshot received so far, without receiving anything.
    pub fn current(&self) -> Option<Arc<Snapshot>> {
        self.assembly.current().cloned()
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
        let current = self.assembly.current().cloned();
        if let Some(snapshot) = &current {
            self.delivered = Some(snapshot.key());
        }
        Ok(current)
    }

    /// Blocks until a snapshot newer than the last one returned is complete, or `timeout`
    /// passes (`Ok(None)`). Wakes on iceoryx2 events and, when the writer's process can be
    /// watched (a Linux pidfd), on its exit; otherwise it checks every liveness interval
    /// that the writer lives.
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
            if let Some(snapshot) = self.assembly.current()
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
            // While a catch-up burst is awaited, wake to ask again if it does not come.
            let until_retry = self.catch_up_asked.map_or(Duration::MAX, |at| {
                CATCH_UP_RETRY.saturating_sub(at.elapsed())
            });
            let slice = (timeout - elapsed)
                .min(until_check)
                .min(until_retry)
                .max(Duration::from_micros(100));
            let mut writer_gone = false;
            let exit_fd = self.writer_process.exit_fd();
            let exited = wake::wait(&self.events, exit_fd.as_slice(), slice, |id| {
                writer_gone |= id == EVENT_WRITER_GONE
            })
            .map_err(|e| ReceiveError::Wait { reason: e.reason() })?;
            if self.termination_requested() {
                return Err(ReceiveError::Terminated);
            }
            if writer_gone {
                // The writer announces its exit just before removing its ports: check now and
                // then briefly at a fast pace.
                let now = Instant::now();
                self.fast_checks_until = Some(now + FAST_CHECK_WINDOW);
                self.next_liveness_check = now;
            } else if exited {
                self.next_liveness_check = Instant::now();
            }
        }
    }

    /// Receives everything that arrived and assembles the newest complete snapshot; asks for
    /// a catch-up burst if a manifest cannot be completed.
    fn sync(&mut self) -> Result<(), ReceiveError> {
        let assembly = &mut self.assembly;
        let first_error = drain(&self.stream, |segment| assembly.accept(segment));
        self.assembly.retry_pending();
        // A snapshot of another writer session after the writer was found gone: a restarted
        // writer publishes; find out now rather than at the next periodic check.
        if self.status == WriterStatus::Gone
            && self.assembly.current().map(|c| c.session) != self.gone_session
        {
            self.check_liveness();
        }
        // Stuck on a manifest, or no snapshot at all yet (the answer to the first hello may
        // have been empty or lost): ask (again) for a catch-up.
        let waiting = self.assembly.is_stuck() || self.assembly.current().is_none();
        if !waiting {
            self.catch_up_asked = None;
        } else if self
            .catch_up_asked
            .is_none_or(|at| at.elapsed() >= CATCH_UP_RETRY)
        {
            self.say_hello();
        }
        first_error.map_or(Ok(()), Err)
    }

    /// Asks the writer for a catch-up burst of the current snapshot.
    fn say_hello(&mut self) {
        self.catch_up_asked = Some(Instant::now());
        // Without a writer nobody listens; the next writer's first publish arrives anyway.
        let _ = self.hello.notify();
    }

    /// Finds out whether the writer (the publisher of the segment stream) is alive, removes
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
        self.stream
            .service
            .dynamic_config()
            .list_publishers(|details| {
                writer = Some(details.node_id);
                CallbackProgression::Stop
            });
        let alive = match writer {
            None => false,
            Some(id) => match self.writer_process.check(id, &self.config) {
                Liveness::Alive => true,
                // A dead writer's resources are removed; held samples stay mapped.
                Liveness::Gone => false,
                // Cannot tell: assume nothing changed.
                Liveness::Unknown => self.status == WriterStatus::Alive,
            },
        };
        match (alive, self.status) {
            (true, _) => {
                self.status = WriterStatus::Alive;
                self.fast_checks_until = None;
                // The exit of a watched process wakes the wait (see `wake`): until then only
                // iceoryx2's periodic confirmation is due.
                if self.writer_process.exit_fd().is_some()
                    && let Some(due) = self.writer_process.confirm_due()
                {
                    self.next_liveness_check = self.next_liveness_check.max(due);
                }
            }
            (false, WriterStatus::Gone) => {}
            (false, _) => {
                self.status = WriterStatus::Gone;
                self.gone_session = self.assembly.current().map(|c| c.session);
                self.gone_unreported = true;
                self.fast_checks_until = None;
                // Whatever the dead writer left half-published can never complete.
                self.assembly.drop_incomplete();
                self.catch_up_asked = None;
            }
        }
    }
}

/// Receives the samples waiting on `port` one at a time, checks each header and hands the
/// segment to `accept` before the next is received (so at most one extra sample is
/// borrowed). Returns the first failure; a rejected sample is dropped and receiving goes on.
fn drain(
    port: &SubPort,
    mut accept: impl FnMut(HeldSegment) -> Result<(), protocol::SegmentError>,
) -> Option<ReceiveError> {
    let mut first_error = None;
    loop {
        match port.subscriber.receive() {
            Ok(Some(sample)) => {
                if let Err(source) = HeldSegment::new(sample).and_then(&mut accept) {
                    first_error.get_or_insert(ReceiveError::Corrupt {
                        service: port.name.clone(),
                        source,
                    });
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
