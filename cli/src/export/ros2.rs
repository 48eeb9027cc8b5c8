//! `ygg export ros2`: a live scene to ROS 2 as hydra_msgs' `DsgUpdate`, so that
//! hydra_ros's subscribers (hydra_visualizer, RViz through it, any node reading
//! `/hydra/backend/dsg`) follow a scene whose writer is a Yggdrasil writer.
//!
//! Each new snapshot becomes its Spark-DSG graph ([`ygg_dsg::layout::to_dsg`]: what a
//! layout keeps of it) and is sent as an incremental update from the last graph sent
//! ([`ygg_dsg::update_between`]); a full update goes out first, then every `--full-every`
//! seconds (also without a new snapshot), so that a subscriber that joined late or lost
//! an update (it sees the gap in `sequence_number`) has the whole graph again within that
//! time. The publisher uses hydra_ros's QoS (reliable, transient local, keep last 1).

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use ygg_dsg::DsgGraph;
use ygg_reader::{ReceiveError, SceneReader, SceneReceiveError};
use ygg_ros2::{DsgUpdate, DsgUpdatePublisher, Header, Time};

use crate::bridge::domain_id;
use crate::query::seconds;

/// Longest wait for a snapshot before looking at the clock (full updates, `--seconds`).
const TICK: Duration = Duration::from_millis(100);

/// Arguments of `ygg export ros2`.
#[derive(clap::Parser, Debug)]
pub struct Ros2ExportArgs {
    /// The live scene to publish (built by `ygg import`, `serve` or a bridge in one of the
    /// paper's layouts).
    #[arg(long)]
    scene: String,
    /// The ROS 2 topic to publish on.
    #[arg(long, default_value = ygg_ros2::HYDRA_TOPIC)]
    topic: String,
    /// The DDS domain; default: ROS 2's `ROS_DOMAIN_ID`, else 0.
    #[arg(long)]
    domain_id: Option<u16>,
    /// Seconds between full updates (incremental ones go between); 0 sends every update
    /// in full.
    #[arg(long, default_value_t = 1.0)]
    full_every: f64,
    /// The messages' `header.frame_id`.
    #[arg(long, default_value = "map")]
    frame_id: String,
    /// Seconds to wait for the scene's writer.
    #[arg(long, default_value_t = 5.0)]
    timeout: f64,
    /// Stop after this many seconds; default: run until signalled.
    #[arg(long)]
    seconds: Option<f64>,
}

/// The stream of updates: the last graph sent and the next sequence number.
struct Sender {
    publisher: DsgUpdatePublisher,
    frame_id: String,
    sent: Option<DsgGraph>,
    next: i64,
    last_full: Instant,
}

impl Sender {
    /// Sends `graph` (generation `generation`) in full or as the update from the last one
    /// sent; prints a `sent` line; nothing when it equals the last one sent.
    fn send(
        &mut self,
        graph: DsgGraph,
        generation: u64,
        full: bool,
    ) -> Result<(), Box<dyn std::error::Error>> {
        let t0 = Instant::now();
        let mut message = match (&self.sent, full) {
            (Some(sent), false) => {
                let update = ygg_dsg::update_between(sent, &graph);
                if update.is_empty() {
                    return Ok(());
                }
                DsgUpdate {
                    layer_contents: ygg_dsg::to_binary_body(&update.part)?,
                    deleted_nodes: update.deleted_nodes,
                    deleted_edges: update.deleted_edges,
                    ..DsgUpdate::default()
                }
            }
            _ => {
                self.last_full = Instant::now();
                DsgUpdate {
                    layer_contents: ygg_dsg::to_binary_body(&graph)?,
                    full_update: true,
                    ..DsgUpdate::default()
                }
            }
        };
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        message.header = Header {
            stamp: Time {
                sec: i32::try_from(now.as_secs()).unwrap_or(i32::MAX),
                nanosec: now.subsec_nanos(),
            },
            frame_id: self.frame_id.clone(),
        };
        message.sequence_number = self.next;
        self.next += 1;
        let (bytes, full_update, number) = (
            message.layer_contents.len(),
            message.full_update,
            message.sequence_number,
        );
        let encode = t0.elapsed();
        self.publisher.send(message)?;
        println!(
            "{}",
            serde_json::json!({"event": "sent", "sequence_number": number,
                "full_update": full_update, "generation": generation, "bytes": bytes,
                "nodes": graph.nodes.len(),
                "encode_us": encode.as_secs_f64() * 1e6,
                "send_us": (t0.elapsed() - encode).as_secs_f64() * 1e6})
        );
        self.sent = Some(graph);
        Ok(())
    }
}

/// Runs `ygg export ros2` until a signal, `--seconds`, or a fatal error.
///
/// # Errors
/// Bad options, a scene without a writer in time, or DDS failing.
pub fn run(args: &Ros2ExportArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.full_every.is_finite() && args.full_every >= 0.0) {
        return Err("--full-every must be a non-negative number of seconds".into());
    }
    if args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err("--seconds must be a positive number".into());
    }
    let full_every = Duration::from_secs_f64(args.full_every);
    let domain = domain_id(args.domain_id)?;
    let dds_topic = ygg_ros2::dds_topic_name(&args.topic)?;
    let mut reader = SceneReader::builder(&args.scene)
        .handle_termination_signals(true)
        .wait_for_writer(seconds(args.timeout, "--timeout")?)
        .open()
        .map_err(|e| format!("scene {}: {e}", args.scene))?;
    let mut sender = Sender {
        publisher: DsgUpdatePublisher::new(domain, &args.topic)?,
        frame_id: args.frame_id.clone(),
        sent: None,
        next: 0,
        last_full: Instant::now(),
    };
    println!(
        "{}",
        serde_json::json!({"event": "advertised", "scene": args.scene, "topic": args.topic,
            "dds_topic": dds_topic, "type": ygg_ros2::TYPE_NAME, "domain_id": domain})
    );
    let start = Instant::now();
    let mut generation = 0;
    let stop = loop {
        if args
            .seconds
            .is_some_and(|s| start.elapsed().as_secs_f64() >= s)
        {
            break "time limit";
        }
        let due = sender.last_full.elapsed() >= full_every;
        // The snapshot already published when attaching, then each new one.
        let next = match sender.sent {
            None => reader
                .latest()
                .transpose()
                .or_else(|| reader.wait_next(TICK).transpose()),
            Some(_) => reader.wait_next(TICK).transpose(),
        };
        match next.transpose() {
            Ok(Some(snapshot)) => {
                generation = snapshot.generation();
                let graph = ygg_dsg::layout::to_dsg(&snapshot.view(), &args.scene);
                drop(snapshot);
                sender.send(graph, generation, due)?;
            }
            Ok(None) => {
                if due && let Some(graph) = sender.sent.take() {
                    sender.send(graph, generation, true)?;
                }
            }
            Err(SceneReceiveError::Receive(ReceiveError::Terminated)) => break "terminated",
            Err(SceneReceiveError::Receive(ReceiveError::WriterGone { .. })) => {
                break "writer gone";
            }
            Err(e) => return Err(format!("scene {}: {e}", args.scene).into()),
        }
    };
    println!(
        "{}",
        serde_json::json!({"event": "summary", "stop": stop, "sent": sender.next})
    );
    Ok(())
}
