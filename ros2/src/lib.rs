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
//! Discovery is RustDDS's: SPDP over UDP multicast (239.255.0.1) on every non-loopback
//! interface, as a ROS 2 node with its default rmw settings does; RustDDS 0.11 has no
//! unicast-only peer list, so the tests run it in a network namespace they create.

mod dds;
mod message;

#[doc(inline)]
pub use self::dds::{
    DsgUpdateCdr, DsgUpdateDecoder, DsgUpdatePublisher, DsgUpdateSubscriber, HYDRA_TOPIC, Received,
    Ros2Error, TYPE_NAME, dds_topic_name, hydra_qos,
};
#[doc(inline)]
pub use self::message::{CdrError, DsgUpdate, Encoding, Header, Time};
