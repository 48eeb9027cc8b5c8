//! `ygg bridge <source>`: live bridges from another system's scene-graph stream into a
//! scene in shared memory. `ygg bridge zmq` follows Spark-DSG's ZeroMQ stream (Hydra),
//! `ygg bridge ros2` Hydra's ROS 2 `DsgUpdate` topic.
//!
//! Every source shares one core, [`publish`]: a source hands it each message's frames
//! (a Spark-DSG binary body) and it decodes, brings its live graph to equal the message's
//! graph and publishes only the changed layers, printing the bridge's JSON lines. The
//! source modules ([`zmq`], [`ros2`]) only receive bytes. A numbered source (ROS 2) also
//! sends incremental updates, applied in order ([`sequence`]) to the last graph.
//!
//! Spark-DSG publishes the whole graph in every message: one frame, the header-less
//! binary body of `to_binary()`. The bridge decodes each message once, builds it in the
//! chosen layout, brings its live graph to equal it with
//! [`ygg_store::SceneGraph::sync_to_owned`] (only the differences become mutations; an
//! index that changes much takes over the built graph's tree instead of being patched
//! point by point) and publishes: only the layers that changed are resent to readers.
//!
//! Most of each message is what the last one held, so [`follow`] does not redo it: a
//! message equal to the last byte for byte is dropped, an unchanged mesh section is
//! compared rather than decoded, when only some node records changed only those are
//! decoded ([`ygg_dsg::BodyStream`]), and a message in which nodes
//! only moved becomes those nodes' mutations without building the layout ([`patch`]);
//! anything else takes the general path above. Each `update` line names the `path` taken.
//!
//! A frame that does not decode is logged and skipped; readers keep the last good graph.
//! The scene is created (and readers can attach) when the first good graph arrives.

mod follow;
mod patch;
mod publish;
mod ros2;
mod sequence;
mod zmq;

use clap::Subcommand;

pub use ros2::domain_id;

/// The sources `ygg bridge` follows.
#[derive(Subcommand, Debug)]
pub enum BridgeCommand {
    /// Bridge a Spark-DSG ZeroMQ stream (spark_dsg's DsgSender, Hydra's ZmqSender) into
    /// a scene: decode each message, apply only its differences, publish only the
    /// changed layers.
    ///
    /// Prints `{"event":"connected"}` once subscribed, `{"event":"ready",...}` after the
    /// first graph is published, one `{"event":"update",...}` line per message (the
    /// layers it changed) or `{"event":"bad-frame",...}` for one that does not decode
    /// (it is skipped; readers keep the last good graph), and a final
    /// `{"event":"summary",...}`. Exits cleanly, removing its shared memory, on
    /// SIGINT/SIGTERM or after --seconds.
    Zmq(zmq::ZmqArgs),
    /// Bridge Hydra's ROS 2 output (`hydra_msgs/msg/DsgUpdate` on /hydra/backend/dsg)
    /// into a scene, as a ROS 2 subscriber with hydra_ros's QoS, without ROS installed:
    /// full updates as `bridge zmq` applies frames, incremental ones in sequence_number
    /// order (after a gap it waits for the next full update).
    ///
    /// Prints `{"event":"subscribed",...}`, then the lines of `bridge zmq` (`ready`,
    /// `update`, `bad-frame`, `summary`) with the message's `sequence_number`, and
    /// `{"event":"skipped",...}` for an incremental update out of sequence.
    Ros2(ros2::Ros2Args),
}

/// Runs the bridge `command` until a signal, `--seconds`, or a fatal error.
///
/// # Errors
/// An option out of range, a source that cannot be reached, or a scene that cannot be
/// created or published.
pub fn run(command: &BridgeCommand) -> Result<(), Box<dyn std::error::Error>> {
    match command {
        BridgeCommand::Zmq(args) => zmq::run(args),
        BridgeCommand::Ros2(args) => ros2::run(args),
    }
}
