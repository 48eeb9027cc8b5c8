//! The core every bridge source shares: each message's frames become the live graph
//! ([`Follower`]) and a publish of only the changed layers, reported as the bridge's JSON
//! lines (`ready`, `update`, `bad-frame`, `summary`). It knows no socket.

use std::time::{Duration, Instant};

use bytes::Bytes;
use ygg_dsg::layout::Layout;
use ygg_writer::SceneWriter;

use super::follow::{Delta, Follower};
use super::sequence::{Sequence, Verdict};

/// One message of a source: a full graph (Spark-DSG's frames) or an incremental update.
pub enum Message {
    /// The frames of a full-state message (one Spark-DSG body).
    Full(Vec<Bytes>),
    /// An incremental update of the last graph.
    Incremental(Delta),
}

/// Where and how a bridge publishes: the options every source takes.
#[derive(clap::Args, Debug)]
pub struct PublishArgs {
    /// Scene name to publish under (ASCII letters, digits, '-', '_', '.').
    #[arg(long)]
    pub scene: String,
    /// Layout to build each received graph in (vanilla, chocolate, mint, saffron).
    #[arg(long, default_value = "mint")]
    pub layout: Layout,
    /// Readers the scene supports at once.
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_READERS)]
    pub max_readers: usize,
    /// Most layers the bridged scene may grow to (a Hydra scene grows room by room and
    /// per-room layouts add layers per room); a lower bound makes readers attach faster.
    #[arg(long, default_value_t = ygg_transport::service::DEFAULT_MAX_SEGMENTS)]
    pub max_layers: usize,
    /// The Spark-DSG version of the sender (its bodies carry no header and are read as
    /// the sender's own version): 1.1.3 (the released spark_dsg), or 1.1.4 (its
    /// `develop` branch, another `Place2dNodeAttributes` layout).
    #[arg(long, default_value = "1.1.3")]
    pub spark_dsg_version: ygg_dsg::DsgVersion,
}

/// A bridge's scene: created from the first good message, then brought to each next
/// message's graph and published.
pub struct ScenePublisher<'a> {
    args: &'a PublishArgs,
    writer: Option<SceneWriter>,
    follower: Follower,
    start: Instant,
    /// Messages received (stale ones included), skipped as stale, bad, and publishes.
    received: u64,
    skipped: u64,
    bad: u64,
    published: u64,
    /// Where a numbered stream stands ([`ScenePublisher::numbered`]).
    sequence: Sequence,
    /// Numbered messages skipped for their number (stale, after a gap, waiting).
    out_of_sequence: u64,
}

impl<'a> ScenePublisher<'a> {
    /// A bridge with no scene yet (it is created by the first good message); `source`
    /// names its messages in errors (`zmq message`).
    ///
    /// # Errors
    /// When the scene name is not valid (checked before the source connects).
    pub fn new(args: &'a PublishArgs, source: &str) -> Result<Self, Box<dyn std::error::Error>> {
        ygg_transport::service::SceneServices::new(&args.scene)?;
        Ok(Self {
            args,
            writer: None,
            follower: Follower::new(args.layout, source, args.spark_dsg_version),
            start: Instant::now(),
            received: 0,
            skipped: 0,
            bad: 0,
            published: 0,
            sequence: Sequence::default(),
            out_of_sequence: 0,
        })
    }

    /// Why the scene's writer stops (a termination signal), once it was created.
    pub fn stopped(&self) -> Option<String> {
        let writer = self.writer.as_ref()?;
        writer
            .publisher()
            .wait(Duration::ZERO)
            .err()
            .map(|e| e.to_string())
    }

    /// Seconds since the bridge started.
    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }

    /// Applies the newest message (`frames`; `stale` older ones were skipped in its
    /// favour) and publishes what changed, printing its `ready`, `update` or `bad-frame`
    /// line. A message that does not decode is skipped.
    ///
    /// # Errors
    /// When the scene cannot be created or published.
    pub fn message(
        &mut self,
        frames: Vec<Bytes>,
        stale: u64,
    ) -> Result<(), Box<dyn std::error::Error>> {
        self.received += 1 + stale;
        self.skipped += stale;
        self.apply(Message::Full(frames), stale, None).map(drop)
    }

    /// Applies a message numbered `number` (hydra_msgs' `DsgUpdate.sequence_number`) in
    /// order ([`super::sequence`]): an incremental one only on top of the one numbered
    /// just before it, else it is skipped with a `skipped` line (a gap makes the bridge
    /// wait for the next full update); then as [`ScenePublisher::message`].
    ///
    /// # Errors
    /// When the scene cannot be created or published.
    pub fn numbered(
        &mut self,
        number: i64,
        message: Message,
    ) -> Result<(), Box<dyn std::error::Error>> {
        self.received += 1;
        let full = matches!(message, Message::Full(_));
        let verdict = self.sequence.admit(number, full);
        if verdict != Verdict::Apply {
            self.out_of_sequence += 1;
            let expected = match verdict {
                Verdict::Gap { expected } => Some(expected),
                _ => None,
            };
            eprintln!(
                "ygg bridge: skipped update {number} ({}{})",
                verdict.name(),
                expected.map_or(String::new(), |e| format!(": {e} is missing"))
            );
            println!(
                "{}",
                serde_json::json!({"event": "skipped", "sequence_number": number,
                    "reason": verdict.name(), "expected": expected})
            );
            return Ok(());
        }
        let ok = self.apply(message, 0, Some((number, full)))?;
        self.sequence.applied(number, ok);
        Ok(())
    }

    /// Counts and reports a message whose bytes are not one (a `bad-frame` line); the
    /// numbered stream then waits for a full update (the message may have been one).
    pub fn undecodable(&mut self, e: &dyn std::fmt::Display) {
        self.received += 1;
        self.bad += 1;
        self.sequence = Sequence::default();
        eprintln!("ygg bridge: skipped a message that does not decode: {e}");
        println!(
            "{}",
            serde_json::json!({"event": "bad-frame", "bytes": null, "error": e.to_string()})
        );
    }

    /// Applies one message; `Ok(false)` when it was bad (and skipped).
    fn apply(
        &mut self,
        message: Message,
        stale: u64,
        numbered: Option<(i64, bool)>,
    ) -> Result<bool, Box<dyn std::error::Error>> {
        let t0 = Instant::now();
        let (number, full) = numbered.unzip();
        let bytes: usize = match &message {
            Message::Full(frames) => frames.iter().map(Bytes::len).sum(),
            Message::Incremental(d) => d.contents.len(),
        };
        let bad_frame = |e: &dyn std::fmt::Display| {
            eprintln!("ygg bridge: skipped a bad frame ({bytes} bytes): {e}");
            println!(
                "{}",
                serde_json::json!({"event": "bad-frame", "bytes": bytes, "error": e.to_string()})
            );
        };
        let Some(w) = self.writer.as_mut() else {
            let first = match message {
                Message::Full(frames) => self.follower.first(frames),
                Message::Incremental(_) => Err(ygg_dsg::UpdateError::NoGraph.into()),
            };
            let target = match first {
                Ok(Some(g)) => g,
                Ok(None) => return Ok(true),
                Err(e) => {
                    self.bad += 1;
                    bad_frame(&e);
                    return Ok(false);
                }
            };
            let t1 = Instant::now();
            let nodes = target.node_count();
            let layers = ygg_store::SceneView::layers(&target).count();
            let mut w = SceneWriter::builder(&self.args.scene)
                .max_readers(self.args.max_readers)
                .max_layers(self.args.max_layers)
                .create(target)?;
            let r = w.publish()?;
            self.published += 1;
            println!(
                "{}",
                serde_json::json!({"event": "ready", "scene": self.args.scene,
                    "session": w.publisher().session(), "generation": r.generation,
                    "nodes": nodes, "layers": layers, "bytes": bytes,
                    "sequence_number": number,
                    "decode_us": (t1 - t0).as_secs_f64() * 1e6,
                    "publish_us": t1.elapsed().as_secs_f64() * 1e6})
            );
            self.writer = Some(w);
            return Ok(true);
        };
        let applied = match message {
            Message::Full(frames) => self.follower.apply(frames, w.graph_mut()),
            Message::Incremental(delta) => self.follower.apply_update(&delta, w.graph_mut()),
        };
        let applied = match applied {
            Ok(a) => a,
            Err(e) => {
                self.bad += 1;
                bad_frame(&e);
                return Ok(false);
            }
        };
        let t2 = Instant::now();
        let report = &applied.report;
        let generation = if report.is_empty() {
            w.generation()
        } else {
            self.published += 1;
            w.publish()?.generation
        };
        println!(
            "{}",
            serde_json::json!({"event": "update", "generation": generation, "bytes": bytes,
                "skipped": stale, "path": applied.path.name(), "mesh_reused": applied.mesh_reused,
                "sequence_number": number, "full_update": full,
                "changed_layers": report.changed_layers,
                "nodes_added": report.nodes_added, "nodes_removed": report.nodes_removed,
                "nodes_moved": report.nodes_moved, "nodes_changed": report.nodes_changed,
                "decode_us": applied.decode.as_secs_f64() * 1e6,
                "sync_us": applied.sync.as_secs_f64() * 1e6,
                "publish_us": t2.elapsed().as_secs_f64() * 1e6,
                "total_us": t0.elapsed().as_secs_f64() * 1e6})
        );
        Ok(true)
    }

    /// Removes the scene (readers keep their last snapshot) and prints the `summary` line
    /// with the reason the bridge stopped.
    pub fn finish(mut self, stop: &str) {
        drop(self.writer.take());
        println!(
            "{}",
            serde_json::json!({"event": "summary", "stop": stop, "received": self.received,
                "skipped_stale": self.skipped, "out_of_sequence": self.out_of_sequence,
                "bad_frames": self.bad, "published": self.published,
                "seconds": self.start.elapsed().as_secs_f64()})
        );
    }
}
