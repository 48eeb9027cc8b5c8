//! `ygg bridge ros2`: Hydra's `hydra_msgs/msg/DsgUpdate` over ROS 2 (DDS) into a scene,
//! through the shared core [`super::publish`], with `ygg-ros2` (RustDDS: no ROS
//! installation, no C library).
//!
//! Subscribes as a ROS 2 node would: DDS topic `rt<topic>`, type
//! `hydra_msgs::msg::dds_::DsgUpdate_`, CDR, hydra_ros's QoS (reliable, transient local:
//! the last graph Hydra sent before the bridge started arrives first). Each message is
//! applied in `sequence_number` order ([`super::sequence`]): a full update is decoded as
//! `bridge zmq` decodes a frame; an incremental one (`full_update = false`) is applied
//! to the last graph ([`ygg_dsg::DsgGraph::apply_update`]).

use std::time::Duration;

use bytes::Bytes;
use ygg_ros2::{DsgUpdate, DsgUpdateSubscriber};

use super::follow::Delta;
use super::publish::{Message, PublishArgs, ScenePublisher};

/// How often the loop wakes without a message, to see signals and `--seconds`.
const TICK: Duration = Duration::from_millis(500);

/// Arguments of `ygg bridge ros2`.
#[derive(clap::Parser, Debug)]
pub struct Ros2Args {
    /// The ROS 2 topic Hydra publishes its scene graph on (hydra_ros: `<node>/backend/dsg`).
    #[arg(long, default_value = ygg_ros2::HYDRA_TOPIC)]
    topic: String,
    /// The DDS domain; default: ROS 2's `ROS_DOMAIN_ID`, else 0.
    #[arg(long)]
    domain_id: Option<u16>,
    /// The scene to publish and its layout.
    #[command(flatten)]
    publish: PublishArgs,
    /// Stop after this many seconds; default: run until signalled.
    #[arg(long)]
    seconds: Option<f64>,
}

/// The shared core's message for a DsgUpdate.
fn message(update: DsgUpdate) -> Message {
    let contents = Bytes::from(update.layer_contents);
    if update.full_update {
        Message::Full(vec![contents])
    } else {
        Message::Incremental(Delta {
            contents,
            deleted_nodes: update.deleted_nodes,
            deleted_edges: update.deleted_edges,
        })
    }
}

/// The domain id: `given`, else `ROS_DOMAIN_ID` as ROS 2 reads it, else 0.
///
/// # Errors
/// A `ROS_DOMAIN_ID` that is not a number.
pub fn domain_id(given: Option<u16>) -> Result<u16, String> {
    if let Some(id) = given {
        return Ok(id);
    }
    match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) if !v.trim().is_empty() => v
            .trim()
            .parse()
            .map_err(|_| format!("ROS_DOMAIN_ID={v:?} is not a domain id (0 to 232)")),
        _ => Ok(0),
    }
}

/// Runs the bridge until a signal, `--seconds`, or a fatal error.
pub fn run(args: &Ros2Args) -> Result<(), Box<dyn std::error::Error>> {
    if args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err("--seconds must be a positive number".into());
    }
    let mut scene = ScenePublisher::new(&args.publish, "DsgUpdate.layer_contents")?;
    let domain_id = domain_id(args.domain_id)?;
    let dds_topic = ygg_ros2::dds_topic_name(&args.topic)?;
    let mut subscriber = DsgUpdateSubscriber::new(domain_id, &args.topic)?;
    let receive_buffer = subscriber.receive_buffer_bytes();
    println!(
        "{}",
        serde_json::json!({"event": "subscribed", "topic": args.topic, "dds_topic": dds_topic,
            "type": ygg_ros2::TYPE_NAME, "domain_id": domain_id,
            "receive_buffer_bytes": receive_buffer})
    );
    if receive_buffer.is_some_and(|n| n < ygg_ros2::RECEIVE_BUFFER_BYTES) {
        eprintln!(
            "ygg bridge ros2: warning: the DDS sockets' receive buffers are {} bytes \
             (net.core.rmem_max caps them; {} asked for): large updates will arrive slower. \
             Raise it (sysctl -w net.core.rmem_max={}) or run with CAP_NET_ADMIN.",
            receive_buffer.unwrap_or_default(),
            ygg_ros2::RECEIVE_BUFFER_BYTES,
            ygg_ros2::RECEIVE_BUFFER_BYTES
        );
    }
    let stop = loop {
        if let Some(why) = scene.stopped() {
            break why;
        }
        if args
            .seconds
            .is_some_and(|s| scene.elapsed().as_secs_f64() >= s)
        {
            break "time limit".to_owned();
        }
        for received in subscriber.recv_timeout(TICK)? {
            match received {
                Ok(update) => scene.numbered(update.sequence_number, message(update))?,
                Err(e) => scene.undecodable(&e),
            }
        }
    };
    scene.finish(&stop);
    Ok(())
}
