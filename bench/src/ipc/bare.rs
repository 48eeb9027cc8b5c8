//! The physical floor: a bare iceoryx2 publisher and subscriber, no Yggdrasil code.
//!
//! The same iceoryx2 service flavour as the transport (thread-safe IPC), a `[u8]` payload of
//! a given size with the sequence number in the user header, the same kind of wake-up (an
//! event after each send, the subscriber blocked on its listener), timed the same way:
//! Unix ns just before the publish call in the publisher, Unix ns once the subscriber holds
//! the sample. The publish call loans, writes every payload byte (as serializing into the
//! loan does), sends and notifies. The subscriber records (sequence, held, thread CPU ns spent
//! since it last blocked) and reports them like a latency reader (`seen` lines).

use super::clock::{thread_cpu_ns, unix_ns};
use super::commands::{Cmd, print_records};
use super::error::Res;
use iceoryx2::config::Config;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::{FileName, Node, NodeBuilder, Path, SemanticString, ServiceName};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Duration;

type Flavour = iceoryx2::service::ipc_threadsafe::Service;

/// Node and services of one bare pair, named after `scene`, files prefixed with `prefix`.
struct Bare {
    node: Node<Flavour>,
    data: ServiceName,
    wake: ServiceName,
}

impl Bare {
    fn new(scene: &str, prefix: &str) -> Res<Self> {
        // iceoryx2's own configuration but for the prefix and the root of its node files
        // (Yggdrasil's, so the case's files are found and removed like every other case's).
        let mut config = Config::global_config().clone();
        config.global.prefix =
            FileName::new(prefix.as_bytes()).map_err(|e| format!("prefix: {e:?}"))?;
        config.global.set_root_path(
            &Path::new(ygg_transport::service::ICEORYX2_ROOT.as_bytes())
                .map_err(|e| format!("root: {e:?}"))?,
        );
        let node = NodeBuilder::new().config(&config).create::<Flavour>()?;
        Ok(Bare {
            node,
            data: ServiceName::new(&format!("bare/{scene}/data"))?,
            wake: ServiceName::new(&format!("bare/{scene}/wake"))?,
        })
    }
}

/// The publishing half, in the benchmark process.
pub(crate) struct BarePublisher {
    publisher: Publisher<Flavour, [u8], u64>,
    notifier: Notifier<Flavour>,
    len: usize,
    _bare: Bare,
}

impl BarePublisher {
    /// Creates the services (one publisher, `readers` subscribers) for payloads of `len`
    /// bytes.
    pub(crate) fn new(scene: &str, prefix: &str, len: usize, readers: usize) -> Res<Self> {
        let bare = Bare::new(scene, prefix)?;
        let data = bare
            .node
            .service_builder(&bare.data)
            .publish_subscribe::<[u8]>()
            .user_header::<u64>()
            .max_subscribers(readers)
            .subscriber_max_buffer_size(2)
            .history_size(1)
            .enable_safe_overflow(true)
            .create()?;
        let publisher = data
            .publisher_builder()
            .initial_max_slice_len(len)
            .create()?;
        let wake = bare.node.service_builder(&bare.wake).event().create()?;
        let notifier = wake.notifier_builder().create()?;
        Ok(BarePublisher {
            publisher,
            notifier,
            len,
            _bare: bare,
        })
    }

    /// Publishes payload number `seq`: loan, write every byte, send, wake the subscriber.
    pub(crate) fn publish(&self, seq: u64) -> Res<()> {
        self.publish_bytes(seq, self.len)
    }

    /// [`BarePublisher::publish`] of a payload of `len` bytes (at least 1, at most the
    /// length the publisher was created for).
    pub(crate) fn publish_bytes(&self, seq: u64, len: usize) -> Res<()> {
        let mut sample = self.publisher.loan_slice_uninit(len.clamp(1, self.len))?;
        *sample.user_header_mut() = seq;
        let sample = sample.write_from_fn(|i| (i as u64 ^ seq) as u8);
        sample.send()?;
        self.notifier.notify()?;
        Ok(())
    }
}

/// The subscribing half: `ygg-bench ipc reader --mode bare`. Prints `ready 0` once
/// connected, then records every sample until stdin closes; `report` prints the records.
pub(crate) fn subscriber_main(scene: &str, prefix: &str, commands: &Receiver<Cmd>) -> Res<()> {
    let bare = Bare::new(scene, prefix)?;
    let data = bare
        .node
        .service_builder(&bare.data)
        .publish_subscribe::<[u8]>()
        .user_header::<u64>()
        .open()?;
    let subscriber: Subscriber<Flavour, [u8], u64> = data.subscriber_builder().create()?;
    let wake = bare.node.service_builder(&bare.wake).event().open()?;
    let listener: Listener<Flavour> = wake.listener_builder().create()?;
    println!("ready 0");
    // (sequence, held ns, thread CPU ns since blocking)
    let mut records: Vec<[u64; 3]> = Vec::with_capacity(4096);
    loop {
        match commands.try_recv() {
            Ok(Cmd::Report) => print_records(&mut records)?,
            Ok(Cmd::Exit) | Err(TryRecvError::Disconnected) => return Ok(()),
            Ok(_) | Err(TryRecvError::Empty) => {}
        }
        let cpu_before = thread_cpu_ns();
        listener.timed_wait(|_| {}, Duration::from_millis(20))?;
        while let Some(sample) = subscriber.receive()? {
            let held = unix_ns();
            std::hint::black_box(sample.payload().first());
            records.push([*sample.user_header(), held, thread_cpu_ns() - cpu_before]);
        }
    }
}
