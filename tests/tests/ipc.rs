//! Cross-process tests of the shared-memory transport: real `ygg-test-writer` /
//! `ygg-test-reader` processes (ygg-testkit's drivers) (plus in-process readers and writers where a test needs to look inside).
//!
//! Every test has its own scene name and iceoryx2 prefix, a watchdog, and checks that it left
//! nothing in `/dev/shm` (see `ygg_tests`).

use std::sync::Arc;
use std::time::{Duration, Instant};

use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::{NodeBuilder, ServiceName};
use rustix::process::Signal;
use ygg_testkit::{TestScene, Watchdog, field, test_pattern, wait_until};
use ygg_transport::protocol::{
    self, BLOCK_SIZE, Block128, EVENT_SNAPSHOT_PUBLISHED, MANIFEST_LAYER_ID, MANIFEST_MAGIC,
    ManifestEntry, SegmentError, SegmentHeader, SegmentKind,
};
use ygg_transport::service::{self, Ipc};
use ygg_transport::{
    PublishError, PublisherBuilder, ReceiveError, SegmentSubscriber, Snapshot, SubscriberBuilder,
    WriterStatus,
};

/// Generous bound for any single step (debug builds on a busy 2-core machine).
const STEP: Duration = Duration::from_secs(30);
/// Per-test watchdog.
const WATCHDOG: Duration = Duration::from_secs(120);

/// A writer builder for `scene` (its name and prefix).
fn publisher(scene: &TestScene) -> PublisherBuilder {
    PublisherBuilder::new(&scene.name).iceoryx_prefix(&scene.prefix)
}

/// A reader builder for `scene` (its name and prefix).
fn subscriber(scene: &TestScene) -> SubscriberBuilder {
    SubscriberBuilder::new(&scene.name).iceoryx_prefix(&scene.prefix)
}

fn open_reader(scene: &TestScene) -> SegmentSubscriber {
    subscriber(scene).open().expect("open reader")
}

/// Waits for the next snapshot, skipping nothing else.
fn next_snapshot(reader: &mut SegmentSubscriber) -> Arc<Snapshot> {
    let start = Instant::now();
    loop {
        match reader.wait_next(Duration::from_millis(500)) {
            Ok(Some(snapshot)) => return snapshot,
            Ok(None) if start.elapsed() < STEP => {}
            other => panic!("expected a snapshot, got {other:?}"),
        }
    }
}

fn assert_synthetic(snapshot: &Snapshot) {
    assert!(snapshot.layer_count() > 0);
    for (entry, bytes) in snapshot.layers() {
        test_pattern::check(bytes, entry).unwrap_or_else(|e| panic!("inconsistent snapshot: {e}"));
        assert_eq!(bytes.as_ptr().addr() % protocol::SEGMENT_ALIGN, 0);
    }
    assert_eq!(
        snapshot.manifest_bytes().as_ptr().addr() % protocol::SEGMENT_ALIGN,
        0
    );
}

/// Asserts that `e` is a [`ReceiveError::Corrupt`] whose source matches `pattern`.
macro_rules! assert_corrupt {
    ($e:expr, $pattern:pat) => {
        assert!(
            matches!(
                &$e,
                ReceiveError::Corrupt {
                    source: $pattern,
                    ..
                }
            ),
            "{:?}",
            $e
        )
    };
}

fn is_snapshot(line: &str) -> bool {
    line.starts_with("snapshot ")
}

#[test]
fn late_joiner_gets_the_current_snapshot_quickly() {
    let scene = TestScene::new("late");
    let dog = Watchdog::new(WATCHDOG);
    // --rate 0: publish once, then idle. Only the readers' announcement can deliver history.
    let mut writer =
        scene.spawn_writer(&["--layers", "3", "--bytes", "100000", "--rate", "0"], &dog);
    writer.expect_line(STEP, |l| l == "published generation=1");

    let start = Instant::now();
    let mut dump = scene.spawn_reader("dump", &["--timeout", "20"], &dog);
    let status = dump.wait_exit(STEP);
    let process_elapsed = start.elapsed();
    assert!(status.success(), "dump failed: {:?}", dump.stderr());
    let line = dump.expect_line(STEP, is_snapshot);
    assert_eq!(field(&line, "generation"), Some("1"));
    assert_eq!(field(&line, "layers"), Some("0:1,1:1,2:1"));
    assert_eq!(field(&line, "check"), Some("ok"));

    let start = Instant::now();
    let mut reader = open_reader(&scene);
    let snapshot = next_snapshot(&mut reader);
    let latency = start.elapsed();
    assert_eq!(snapshot.generation(), 1);
    assert_eq!(snapshot.layer_count(), 3);
    assert_synthetic(&snapshot);
    eprintln!(
        "late joiner: dump process start-to-exit {process_elapsed:?}, in-process open-to-snapshot {latency:?}"
    );
    drop((snapshot, reader));

    writer.signal(Signal::INT);
    assert!(writer.wait_exit(STEP).success());
    scene.assert_no_leftovers(STEP);
}

/// A writer publishing `layers` synthetic layers of `bytes` bytes at 400 Hz, one layer
/// changed per cut, and a reader process checking 150 consecutive snapshots: each one a
/// consistent cut (every segment's bytes those of the generation its entry names), in
/// increasing generations.
fn fast_publishing_gives_consistent_cuts(tag: &str, layers: &str, bytes: &str) {
    let scene = TestScene::new(tag);
    let dog = Watchdog::new(WATCHDOG);
    let mut writer = scene.spawn_writer(
        &[
            "--layers", layers, "--bytes", bytes, "--rate", "400", "--quiet",
        ],
        &dog,
    );
    writer.expect_line(STEP, |l| l.starts_with("ready"));
    let mut watch = scene.spawn_reader(
        "watch",
        &["--count", "150", "--wait-for-writer", "10"],
        &dog,
    );
    assert!(watch.wait_exit(STEP).success(), "{:?}", watch.stderr());
    let snapshots: Vec<String> = watch
        .stdout()
        .into_iter()
        .filter(|l| is_snapshot(l))
        .collect();
    assert_eq!(snapshots.len(), 150);
    let mut last = 0u64;
    for line in &snapshots {
        assert_eq!(field(line, "check"), Some("ok"), "{line}");
        let generation: u64 = field(line, "generation")
            .and_then(|g| g.parse().ok())
            .expect("generation");
        assert!(generation > last, "generations must increase: {line}");
        last = generation;
    }
    writer.signal(Signal::TERM);
    assert!(writer.wait_exit(STEP).success());
    scene.assert_no_leftovers(STEP);
}

#[test]
fn snapshots_are_consistent_cuts_under_fast_publishing() {
    fast_publishing_gives_consistent_cuts("fast", "4", "20000");
}

#[test]
fn cuts_of_many_segments_stay_consistent_under_fast_publishing() {
    // 70 segments, one changed per cut: the reader assembles each cut from the one
    // changed segment and 69 it holds already.
    fast_publishing_gives_consistent_cuts("fast-many", "70", "2000");
}

#[test]
fn a_stuck_reader_holding_samples_does_not_block_the_writer() {
    let scene = TestScene::new("stuck");
    let dog = Watchdog::new(WATCHDOG);
    let mut writer =
        scene.spawn_writer(&["--layers", "2", "--bytes", "65536", "--rate", "0"], &dog);
    writer.expect_line(STEP, |l| l == "published generation=1");

    // A reader in this process takes a snapshot, then stops receiving entirely.
    let mut reader = open_reader(&scene);
    let held = next_snapshot(&mut reader);
    // A reader process that holds each snapshot for a minute.
    let mut slow = scene.spawn_reader("watch", &["--hold-ms", "60000"], &dog);
    slow.expect_line(STEP, is_snapshot);
    writer.signal(Signal::INT);
    assert!(writer.wait_exit(STEP).success());

    // The same scene, now with a writer publishing 300 snapshots as fast as it can.
    let mut writer = scene.spawn_writer(
        &[
            "--layers", "2", "--bytes", "65536", "--rate", "2000", "--count", "300", "--quiet",
        ],
        &dog,
    );
    let status = writer.wait_exit(STEP);
    assert!(status.success(), "writer: {:?}", writer.stderr());
    writer.expect_line(STEP, |l| l.ends_with("published 300 snapshots"));

    // The held samples were never reused by the writer.
    assert_synthetic(&held);
    assert_eq!(held.generation(), 1);
    drop(held);
    drop(reader);
    slow.signal(Signal::INT);
    assert!(slow.wait_exit(STEP).success(), "{:?}", slow.stderr());
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_sigkilled_reader_does_not_stop_the_writer() {
    let scene = TestScene::new("rkill");
    let dog = Watchdog::new(WATCHDOG);
    let mut writer =
        scene.spawn_writer(&["--layers", "3", "--bytes", "4096", "--rate", "100"], &dog);
    writer.expect_line(STEP, |l| l.starts_with("published"));
    let mut victim = scene.spawn_reader("watch", &["--hold-ms", "60000"], &dog);
    victim.expect_line(STEP, is_snapshot);
    victim.signal(Signal::KILL);
    let _ = victim.wait_exit(STEP);

    let (index, line) = writer
        .wait_line_after(0, STEP, |l| l.starts_with("published"))
        .expect("published");
    let before: u64 = field(&line, "generation")
        .and_then(|g| g.parse().ok())
        .expect("gen");
    let seen = writer.count_lines(|l| l.starts_with("published"));
    writer
        .wait_line_after(index.max(seen), STEP, |l| {
            field(l, "generation")
                .and_then(|g| g.parse::<u64>().ok())
                .is_some_and(|g| g > before + 100)
        })
        .expect("the writer keeps publishing after a reader was killed");

    let mut reader = open_reader(&scene);
    assert_synthetic(&next_snapshot(&mut reader));
    drop(reader);
    // The killed reader's node is removed while the writer runs (by its helper, which
    // watches the reader's process, or by the reader opened since): only the writer's
    // node is left.
    wait_until(STEP, "only the writer's iceoryx2 node is left", || {
        scene.node_count() == 1
    });
    writer.signal(Signal::INT);
    assert!(writer.wait_exit(STEP).success(), "{:?}", writer.stderr());
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_sigkilled_readers_slot_is_freed_at_once() {
    let scene = TestScene::new("slot");
    let dog = Watchdog::new(WATCHDOG);
    // iceoryx2 is asked about readers once an hour: only the watch of the reader's process
    // can free its slot in time.
    let mut writer = publisher(&scene)
        .max_readers(1)
        .liveness_interval(Duration::from_secs(3600))
        .create()
        .expect("writer");
    scene_reader_ready(&scene, &mut writer);
    let mut victim = scene.spawn_reader("watch", &["--hold-ms", "60000"], &dog);
    victim.expect_line(STEP, is_snapshot);
    subscriber(&scene)
        .open()
        .expect_err("the one reader slot is taken");
    victim.signal(Signal::KILL);
    let _ = victim.wait_exit(STEP);
    // No event says the slot is free: try to take it until it is.
    let mut reader = None;
    let freed = wait_until(STEP, "the killed reader's slot is freed", || {
        reader = subscriber(&scene).open().ok();
        reader.is_some()
    });
    // About 50 ms here; iceoryx2's periodic check alone would take up to an hour.
    assert!(
        freed < Duration::from_millis(500),
        "slot freed {freed:?} after the kill"
    );
    drop((reader, writer));
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_sigkilled_writer_is_reported_and_a_restarted_one_is_picked_up() {
    let scene = TestScene::new("wkill");
    let dog = Watchdog::new(WATCHDOG);
    let mut first = scene.spawn_writer(&["--layers", "3", "--bytes", "8192", "--rate", "50"], &dog);
    let ready = first.expect_line(STEP, |l| l.starts_with("ready"));
    let first_session = field(&ready, "session").expect("session").to_owned();

    let mut reader = open_reader(&scene);
    let held = next_snapshot(&mut reader);
    assert_eq!(reader.writer_status(), WriterStatus::Alive);
    let mut watch = scene.spawn_reader("watch", &[], &dog);
    watch.expect_line(STEP, is_snapshot);

    first.signal(Signal::KILL);
    let _ = first.wait_exit(STEP);

    let start = Instant::now();
    loop {
        match reader.wait_next(Duration::from_millis(500)) {
            Err(ReceiveError::WriterGone { .. }) => break,
            Ok(_) if start.elapsed() < STEP => {}
            other => panic!("expected WriterGone, got {other:?}"),
        }
    }
    eprintln!("writer death noticed after {:?}", start.elapsed());
    assert_eq!(reader.writer_status(), WriterStatus::Gone);
    let kept = reader.current().expect("the last snapshot is kept");
    assert_synthetic(&kept);
    assert_synthetic(&held);
    assert!(matches!(reader.latest(), Ok(Some(_))));
    watch.expect_line(STEP, |l| l.starts_with("writer gone"));

    // A restarted writer takes over the scene (dead resources are cleaned up).
    let mut second =
        scene.spawn_writer(&["--layers", "2", "--bytes", "8192", "--rate", "50"], &dog);
    let ready = second.expect_line(STEP, |l| l.starts_with("ready"));
    let second_session = field(&ready, "session").expect("session").to_owned();
    assert_ne!(first_session, second_session);

    let fresh = next_snapshot(&mut reader);
    assert_eq!(format!("{:#x}", fresh.session()), second_session);
    assert_eq!(fresh.layer_count(), 2);
    assert_synthetic(&fresh);
    assert_eq!(reader.writer_status(), WriterStatus::Alive);
    watch.expect_line(STEP, |l| {
        is_snapshot(l) && field(l, "session") == Some(second_session.as_str())
    });
    // The old snapshot is still readable after the writer that made it died.
    assert_synthetic(&held);

    drop((held, kept, fresh, reader));
    watch.signal(Signal::INT);
    assert!(watch.wait_exit(STEP).success());
    second.signal(Signal::INT);
    assert!(second.wait_exit(STEP).success());
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_second_writer_on_the_same_scene_fails_clearly() {
    let scene = TestScene::new("twice");
    let dog = Watchdog::new(WATCHDOG);
    let mut first = scene.spawn_writer(&["--layers", "1", "--rate", "20"], &dog);
    let ready = first.expect_line(STEP, |l| l.starts_with("ready"));
    let session = field(&ready, "session").expect("session").to_owned();

    let mut second = scene.spawn_writer(&["--layers", "1", "--rate", "20"], &dog);
    let status = second.wait_exit(STEP);
    assert!(!status.success());
    let stderr = second.stderr().join("\n");
    assert!(
        stderr.contains("already has a live writer"),
        "stderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "stderr: {stderr}");

    // In-process too: the typed error.
    let err = publisher(&scene).create().expect_err("second writer");
    assert!(
        matches!(err, ygg_writer::WriterCreateError::AlreadyRunning { .. }),
        "{err:?}"
    );

    // The first writer is unaffected.
    let mut reader = open_reader(&scene);
    let snapshot = next_snapshot(&mut reader);
    assert_eq!(format!("{:#x}", snapshot.session()), session);
    drop((snapshot, reader));
    first.signal(Signal::INT);
    assert!(first.wait_exit(STEP).success());
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_restarted_writer_asking_for_more_segments_keeps_the_stream_readers_hold() {
    let scene = TestScene::new("bound");
    let _dog = Watchdog::new(WATCHDOG);
    let publish_cut = |writer: &mut ygg_transport::SegmentPublisher, generation: u64, ids| {
        let entries: Vec<ManifestEntry> = (1..=ids)
            .map(|layer_id| ManifestEntry {
                layer_id,
                generation,
            })
            .collect();
        for entry in &entries {
            writer.publish_layer(entry.layer_id, generation, 64, |b| {
                test_pattern::write(b, entry.layer_id, generation)
            })?;
        }
        writer.publish_manifest(generation, &entries, 0, |_| {})
    };
    let mut first = publisher(&scene).max_segments(8).create().expect("writer");
    assert_eq!(first.max_segments(), 8);
    publish_cut(&mut first, 1, 8).expect("8 segments fit");
    let mut reader = open_reader(&scene);
    let held = next_snapshot(&mut reader);
    assert_eq!(held.layer_count(), 8);
    drop(first);

    // The reader keeps the stream alive: a new writer asking for 64 gets the stream as it
    // is, and says so, instead of failing to start.
    let mut second = publisher(&scene)
        .max_segments(64)
        .create()
        .expect("restart");
    assert_eq!(second.max_segments(), 8);
    let err = publish_cut(&mut second, 2, 9).expect_err("9 segments exceed the stream");
    assert!(
        matches!(err, PublishError::TooManyLayers { count: 9, max: 8 }),
        "{err:?}"
    );
    assert!(err.to_string().contains("max_layers"), "{err}");
    publish_cut(&mut second, 3, 8).expect("8 segments still fit");
    let fresh = loop {
        let snapshot = next_snapshot(&mut reader);
        if snapshot.session() == second.session() {
            break snapshot;
        }
    };
    assert_eq!(fresh.layer_count(), 8);
    assert_synthetic(&fresh);
    assert_synthetic(&held);
    drop((held, fresh, reader, second));
    scene.assert_no_leftovers(STEP);
}

#[test]
fn sigint_and_sigterm_exit_cleanly_and_remove_shared_memory() {
    for signal in [Signal::INT, Signal::TERM] {
        let scene = TestScene::new("signal");
        let dog = Watchdog::new(WATCHDOG);
        let mut writer = scene.spawn_writer(&["--layers", "2", "--rate", "20"], &dog);
        writer.expect_line(STEP, |l| l.starts_with("published"));
        let mut watch = scene.spawn_reader("watch", &[], &dog);
        watch.expect_line(STEP, is_snapshot);
        assert!(
            !scene.leftovers().is_empty(),
            "the scene lives in shared memory"
        );

        watch.signal(signal);
        assert!(watch.wait_exit(STEP).success(), "{:?}", watch.stderr());
        watch.expect_line(STEP, |l| l == "terminated");
        writer.signal(signal);
        assert!(writer.wait_exit(STEP).success(), "{:?}", writer.stderr());
        writer.expect_line(STEP, |l| l.starts_with("stopped:"));
        scene.assert_no_leftovers(STEP);
    }
}

#[test]
fn shared_memory_full_is_an_error_before_anything_is_written() {
    let scene = TestScene::new("full");
    let mut writer = publisher(&scene).create().expect("writer");
    let free = ygg_transport::shm::free_bytes(std::path::Path::new(service::DEFAULT_SHM_DIR))
        .expect("statvfs");
    let too_big = usize::try_from(free).expect("64-bit") + (1 << 30);
    let mut called = false;
    let err = writer
        .publish_layer(1, 1, too_big, |_| called = true)
        .expect_err("must not fit");
    assert!(!called, "nothing may be written");
    match err {
        PublishError::SharedMemoryFull {
            needed, available, ..
        } => {
            assert!(needed > available);
        }
        other => panic!("expected SharedMemoryFull, got {other:?}"),
    }
    assert!(
        err_text(&writer.publish_layer(1, 1, too_big, |_| {})).contains("shared memory is full")
    );
    // The writer still works: a small layer and its manifest go out.
    scene_reader_ready(&scene, &mut writer);
    drop(writer);
    scene.assert_no_leftovers(STEP);
}

fn err_text<T>(result: &Result<T, PublishError>) -> String {
    result
        .as_ref()
        .err()
        .map(ToString::to_string)
        .unwrap_or_default()
}

#[test]
fn manifests_must_name_published_generations() {
    let scene = TestScene::new("manifest");
    let mut writer = publisher(&scene).create().expect("writer");
    writer
        .publish_layer(2, 5, 16, |b| b.fill(1))
        .expect("layer");
    writer
        .publish_layer(1, 5, 16, |b| b.fill(1))
        .expect("layer");
    let e = |layer_id, generation| ManifestEntry {
        layer_id,
        generation,
    };
    assert!(matches!(
        writer.publish_manifest(1, &[e(1, 4)], 0, |_| {}),
        Err(PublishError::UnknownLayerGeneration {
            published: Some(5),
            ..
        })
    ));
    assert!(matches!(
        writer.publish_manifest(1, &[e(2, 5), e(1, 5)], 0, |_| {}),
        Err(PublishError::UnsortedManifest { layer_id: 1 })
    ));
    assert!(matches!(
        writer.publish_layer(MANIFEST_LAYER_ID, 1, 1, |_| {}),
        Err(PublishError::ReservedLayerId(_))
    ));
    let failed: Result<(), PublishError> =
        writer.try_publish_layer(3, 1, 8, |_| Err::<(), _>("serializer failed"));
    assert!(matches!(failed, Err(PublishError::Fill(_))));
    // Layers never published, before, between and after published ones.
    for entries in [[e(0, 1), e(2, 5)], [e(1, 5), e(3, 1)], [e(2, 5), e(9, 1)]] {
        let unknown = entries.iter().find(|x| x.generation == 1).expect("listed");
        assert!(matches!(
            writer.publish_manifest(1, &entries, 0, |_| {}),
            Err(PublishError::UnknownLayerGeneration {
                layer_id,
                published: None,
                ..
            }) if layer_id == unknown.layer_id
        ));
    }
    writer
        .publish_manifest(1, &[e(1, 5), e(2, 5)], 3, |b| b.copy_from_slice(b"abc"))
        .expect("valid manifest");

    let mut reader = open_reader(&scene);
    let snapshot = next_snapshot(&mut reader);
    // latest() does not block and returns the same snapshot again.
    let again = reader.latest().expect("latest").expect("a snapshot");
    assert!(Arc::ptr_eq(&snapshot, &again));
    assert!(matches!(reader.wait_next(Duration::ZERO), Ok(None)));
    // A snapshot outlives its reader.
    drop((again, reader));
    assert_eq!(snapshot.manifest_bytes(), b"abc");
    assert_eq!(snapshot.layer(1), Some(&[1u8; 16][..]));
    assert_eq!(snapshot.layer_generation(2), Some(5));
    assert_eq!(snapshot.layer(3), None);
    drop((snapshot, writer));
    scene.assert_no_leftovers(STEP);
}

/// A writer that speaks the protocol badly: raw iceoryx2 ports with our wire types.
struct FakeWriter {
    segments: Publisher<Ipc, [Block128], SegmentHeader>,
    events: iceoryx2::port::notifier::Notifier<Ipc>,
    _services: Vec<Box<dyn std::any::Any>>,
    _node: iceoryx2::prelude::Node<Ipc>,
}

impl FakeWriter {
    const LAYER: u64 = 7;

    fn new(scene: &TestScene) -> Self {
        let names = service::SceneServices::new(&scene.name).expect("scene name");
        let config = service::iceoryx_config(Some(&scene.prefix)).expect("config");
        let node = NodeBuilder::new()
            .config(&config)
            .create::<Ipc>()
            .expect("node");
        let pubsub = |name: &str| {
            node.service_builder(&ServiceName::new(name).expect("name"))
                .publish_subscribe::<[Block128]>()
                .user_header::<SegmentHeader>()
                .history_size(1)
                .subscriber_max_buffer_size(2)
                .enable_safe_overflow(true)
                .open_or_create()
                .expect("pubsub service")
        };
        let segments_service = pubsub(&names.segments());
        let event = |name: &str| {
            node.service_builder(&ServiceName::new(name).expect("name"))
                .event()
                .event_id_max_value(service::EVENT_ID_MAX)
                .open_or_create()
                .expect("event service")
        };
        let events_service = event(&names.events());
        let readers_service = event(&names.readers());
        let segments = segments_service
            .publisher_builder()
            .initial_max_slice_len(64)
            .create()
            .expect("publisher");
        let events = events_service
            .notifier_builder()
            .create()
            .expect("notifier");
        Self {
            segments,
            events,
            _services: vec![
                Box::new(segments_service),
                Box::new(events_service),
                Box::new(readers_service),
            ],
            _node: node,
        }
    }

    /// Sends `blocks` blocks with `header`, the payload written by `fill`.
    fn send(
        publisher: &Publisher<Ipc, [Block128], SegmentHeader>,
        header: SegmentHeader,
        blocks: usize,
        fill: impl FnOnce(&mut [u8]),
    ) {
        let sample = publisher.loan_slice_uninit(blocks).expect("loan");
        let mut sample = sample.write_from_fn(|_| Block128::ZERO);
        *sample.user_header_mut() = header;
        let mut bytes = vec![0u8; blocks * BLOCK_SIZE];
        fill(&mut bytes);
        for (block, chunk) in sample
            .payload_mut()
            .iter_mut()
            .zip(bytes.chunks(BLOCK_SIZE))
        {
            block.0.copy_from_slice(chunk);
        }
        sample.send().expect("send");
    }

    fn manifest(&self, header: SegmentHeader, blocks: usize, fill: impl FnOnce(&mut [u8])) {
        Self::send(&self.segments, header, blocks, fill);
        let _ = self
            .events
            .notify_with_custom_event_id(EVENT_SNAPSHOT_PUBLISHED);
    }

    fn layer(&self, header: SegmentHeader, blocks: usize) {
        Self::send(&self.segments, header, blocks, |b| b.fill(0x5a));
    }

    /// What the real writer's helper thread does on a reader's announcement: deliver the
    /// history to new subscribers and wake the readers.
    fn pump(&self) {
        use iceoryx2::port::update_connections::UpdateConnections;
        let _ = self.segments.update_connections();
        let _ = self
            .events
            .notify_with_custom_event_id(EVENT_SNAPSHOT_PUBLISHED);
    }
}

fn valid_manifest_prefix(buf: &mut [u8], generation: u64) {
    protocol::encode_manifest_prefix(
        &[ManifestEntry {
            layer_id: FakeWriter::LAYER,
            generation,
        }],
        buf,
    );
}

/// Pumps the fake writer until the reader reports an error.
fn next_error(reader: &mut SegmentSubscriber, fake: &FakeWriter) -> ReceiveError {
    let start = Instant::now();
    loop {
        fake.pump();
        match reader.wait_next(Duration::from_millis(50)) {
            Err(e) => return e,
            Ok(None) if start.elapsed() < STEP => {}
            Ok(other) => panic!("expected an error, got {other:?}"),
        }
    }
}

/// Pumps the fake writer until the reader has a snapshot.
fn pumped_snapshot(reader: &mut SegmentSubscriber, fake: &FakeWriter) -> Arc<Snapshot> {
    let start = Instant::now();
    loop {
        fake.pump();
        match reader.wait_next(Duration::from_millis(50)) {
            Ok(Some(snapshot)) => return snapshot,
            Ok(None) if start.elapsed() < STEP => {}
            other => panic!("expected a snapshot, got {other:?}"),
        }
    }
}

#[test]
fn garbage_segments_are_reported_not_crashed_on() {
    let scene = TestScene::new("garbage");
    let dog = Watchdog::new(WATCHDOG);
    let fake = FakeWriter::new(&scene);
    let mut reader = open_reader(&scene);
    let manifest = |generation, len| {
        SegmentHeader::new(
            SegmentKind::Manifest,
            MANIFEST_LAYER_ID,
            1,
            generation,
            len,
            0,
        )
    };

    // A header claiming more bytes than the payload holds.
    fake.manifest(manifest(1, 10_000), 1, |b| valid_manifest_prefix(b, 1));
    let e = next_error(&mut reader, &fake);
    assert_corrupt!(
        e,
        SegmentError::LengthExceedsPayload {
            len: 10_000,
            payload: 128
        }
    );

    // A wrong magic number.
    let mut bad = manifest(2, 128);
    bad.magic = 0xdead_beef;
    fake.manifest(bad, 1, |b| valid_manifest_prefix(b, 1));
    let e = next_error(&mut reader, &fake);
    assert_corrupt!(e, SegmentError::BadMagic { .. });

    // A manifest prefix that claims 100 layers in one block, and one claiming too many.
    fake.manifest(manifest(3, 128), 1, |b| {
        b[..4].copy_from_slice(&MANIFEST_MAGIC.to_le_bytes());
        b[4..8].copy_from_slice(&100u32.to_le_bytes());
    });
    let e = next_error(&mut reader, &fake);
    assert_corrupt!(e, SegmentError::ManifestTruncated { .. });
    fake.manifest(manifest(4, 128), 1, |b| {
        b[..4].copy_from_slice(&MANIFEST_MAGIC.to_le_bytes());
        b[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    });
    let e = next_error(&mut reader, &fake);
    assert_corrupt!(e, SegmentError::TooManyLayers { .. });

    // Random bytes as the manifest payload.
    fake.manifest(manifest(5, 256), 2, |b| {
        let mut x = 0x1234_5678_u32;
        for byte in b.iter_mut() {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            *byte = x as u8;
        }
    });
    let e = next_error(&mut reader, &fake);
    assert!(matches!(&e, ReceiveError::Corrupt { .. }), "{e:?}");

    // A segment of an unknown kind, then one too short for its header.
    let mut unknown = SegmentHeader::new(SegmentKind::Layer, 8, 1, 6, 16, 0);
    unknown.kind = 9;
    fake.layer(unknown, 1);
    fake.manifest(manifest(6, 256), 2, |b| valid_manifest_prefix(b, 6));
    let e = next_error(&mut reader, &fake);
    assert_corrupt!(e, SegmentError::UnknownKind { found: 9 });
    fake.layer(
        SegmentHeader::new(SegmentKind::Layer, FakeWriter::LAYER, 1, 6, 1 << 40, 0),
        1,
    );
    let e = next_error(&mut reader, &fake);
    assert_corrupt!(e, SegmentError::LengthExceedsPayload { .. });
    assert!(reader.current().is_none(), "no snapshot from garbage");

    // A good layer completes the pending manifest: the reader recovered.
    fake.layer(
        SegmentHeader::new(SegmentKind::Layer, FakeWriter::LAYER, 1, 6, 200, 0),
        2,
    );
    let snapshot = pumped_snapshot(&mut reader, &fake);
    assert_eq!(snapshot.generation(), 6);
    assert_eq!(snapshot.layer(FakeWriter::LAYER), Some(&[0x5a; 200][..]));
    drop((snapshot, reader));

    // The reader binary: an error message and exit code 3, no crash.
    fake.manifest(manifest(7, 1 << 20), 1, |b| valid_manifest_prefix(b, 6));
    let mut dump = scene.spawn_reader("dump", &["--timeout", "20"], &dog);
    // The fake writer has no helper thread: deliver history to the new reader by hand.
    let start = Instant::now();
    let status = loop {
        fake.pump();
        if let Some(status) = dump.wait_timeout(Duration::from_millis(20)) {
            break status;
        }
        assert!(start.elapsed() < STEP, "dump did not finish");
    };
    let stderr = dump.stderr().join("\n");
    assert_eq!(
        status.code(),
        Some(3),
        "stdout {:?} stderr {stderr}",
        dump.stdout()
    );
    assert!(stderr.contains("claims 1048576 bytes"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");

    drop(fake);
    scene.assert_no_leftovers(STEP);
}

#[test]
fn a_writer_that_exits_cleanly_is_reported_gone_at_once() {
    let scene = TestScene::new("exit");
    let dog = Watchdog::new(WATCHDOG);
    let mut writer = scene.spawn_writer(&["--layers", "2", "--rate", "20"], &dog);
    writer.expect_line(STEP, |l| l.starts_with("published"));
    let mut reader = subscriber(&scene)
        // A killed writer would take this long to notice; a clean exit is announced.
        .liveness_interval(Duration::from_secs(3600))
        .open()
        .expect("reader");
    let last = next_snapshot(&mut reader);
    writer.signal(Signal::TERM);
    assert!(writer.wait_exit(STEP).success());
    let start = Instant::now();
    loop {
        match reader.wait_next(STEP) {
            Err(ReceiveError::WriterGone { .. }) => break,
            Ok(Some(_)) => {}
            other => panic!("expected WriterGone, got {other:?}"),
        }
    }
    eprintln!("clean writer exit noticed after {:?}", start.elapsed());
    assert_synthetic(&last);
    assert!(reader.current().is_some());
    drop((last, reader));
    scene.assert_no_leftovers(STEP);
}

#[test]
fn readers_beyond_max_readers_get_a_clear_error() {
    let scene = TestScene::new("crowd");
    let mut writer = publisher(&scene).max_readers(1).create().expect("writer");
    let first = open_reader(scene_reader_ready(&scene, &mut writer));
    let err = subscriber(&scene)
        .open()
        .expect_err("second reader must not fit");
    assert!(
        matches!(
            err,
            ygg_transport::ReaderOpenError::Setup(ygg_transport::SetupError::Port { .. })
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("ygg/"), "{err}");
    drop((first, writer));
    scene.assert_no_leftovers(STEP);
}

#[test]
fn layers_grow_retire_and_stay_128_byte_aligned() {
    let scene = TestScene::new("grow");
    let mut writer = publisher(&scene)
        .initial_segment_bytes(1024)
        .create()
        .expect("writer");
    let mut reader = open_reader(scene_reader_ready(&scene, &mut writer));
    assert_eq!(next_snapshot(&mut reader).generation(), 1);
    let mut generation = 1;
    for len in [1000, 300_000, 5_000_000, 700] {
        generation += 1;
        for layer in [1, 2] {
            writer
                .publish_layer(layer, generation, len, |buf| {
                    assert_eq!(buf.as_ptr().addr() % protocol::SEGMENT_ALIGN, 0);
                    assert_eq!(buf.len(), len);
                    test_pattern::write(buf, layer, generation);
                })
                .expect("layer");
        }
        let entries = [1, 2].map(|layer_id| ManifestEntry {
            layer_id,
            generation,
        });
        writer
            .publish_manifest(generation, &entries, 5, |b| {
                assert_eq!(b.as_ptr().addr() % protocol::SEGMENT_ALIGN, 0);
                b.copy_from_slice(b"hello");
            })
            .expect("manifest");
        let snapshot = next_snapshot(&mut reader);
        assert_eq!(snapshot.generation(), generation);
        assert_eq!(snapshot.layer(1).map(<[u8]>::len), Some(len));
        assert_synthetic(&snapshot);
    }

    // Only layer 1 changes; layer 2 leaves the scene.
    generation += 1;
    writer
        .publish_layer(1, generation, 64, |b| test_pattern::write(b, 1, generation))
        .expect("layer");
    writer
        .publish_manifest(
            generation,
            &[ManifestEntry {
                layer_id: 1,
                generation,
            }],
            0,
            |_| {},
        )
        .expect("manifest");
    writer.retire_layer(2);
    let snapshot = next_snapshot(&mut reader);
    assert_eq!(snapshot.layer_count(), 1);
    assert_eq!(snapshot.layer(2), None);
    assert_synthetic(&snapshot);
    drop((snapshot, reader, writer));
    scene.assert_no_leftovers(STEP);
}

/// Publishes generation 1 (layer 1 only, 16 bytes) so that a reader can open the scene.
fn scene_reader_ready<'a>(
    scene: &'a TestScene,
    writer: &mut ygg_transport::SegmentPublisher,
) -> &'a TestScene {
    writer
        .publish_layer(1, 1, 16, |b| test_pattern::write(b, 1, 1))
        .expect("layer");
    writer
        .publish_manifest(
            1,
            &[ManifestEntry {
                layer_id: 1,
                generation: 1,
            }],
            0,
            |_| {},
        )
        .expect("manifest");
    scene
}
