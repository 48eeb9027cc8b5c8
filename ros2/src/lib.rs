//! Hydra's `hydra_msgs/msg/DsgUpdate` over ROS 2's DDS, without a ROS installation: the
//! message and its CDR encoding ([`DsgUpdate`]), the names and QoS a ROS 2 node uses for
//! it ([`dds_topic_name`], [`TYPE_NAME`], [`hydra_qos`]), and a subscriber and a publisher
//! ([`DsgUpdateSubscriber`], [`DsgUpdatePublisher`]) over RustDDS, a pure-Rust DDS: no C
//! library at build time, no ROS 2 sourced at run time.
//!
//! Start with [`DsgUpdateSubscriber::new`]; `ygg bridge ros2` and `ygg export ros2`
//! (crate `ygg-cli`) are its users. The crate knows no Spark-DSG and no shared memory:
//! `layer_contents` stays bytes here.
//!
//! Discovery is RustDDS's: SPDP announced on UDP multicast (239.255.0.1) on every
//! non-loopback interface, as a ROS 2 node with its default rmw settings does, and answered
//! by unicast to a participant heard from; RustDDS 0.11 has no peer list of its own, so the
//! tests give Cyclone DDS the bridge as its unicast peer, in a network namespace they
//! create. The participant's UDP sockets get larger receive buffers
//! ([`RECEIVE_BUFFER_BYTES`]) than RustDDS gives them.

mod dds;
mod message;
mod receive_buffers;

#[doc(inline)]
pub use self::dds::{
    DsgUpdateCdr, DsgUpdateDecoder, DsgUpdatePublisher, DsgUpdateSubscriber, HYDRA_TOPIC, Received,
    Ros2Error, TYPE_NAME, dds_topic_name, hydra_qos,
};
#[doc(inline)]
pub use self::message::{CdrError, DsgUpdate, Encoding, Header, Time};
#[doc(inline)]
pub use self::receive_buffers::RECEIVE_BUFFER_BYTES;
