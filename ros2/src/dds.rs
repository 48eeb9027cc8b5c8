//! DsgUpdate on a DDS domain as a ROS 2 node sees it: the topic and type names ROS 2
//! mangles to, the QoS hydra_ros publishes with, and a blocking subscriber and a
//! publisher over RustDDS.

use std::convert::Infallible;
use std::time::Duration;

use bytes::Bytes;
use rustdds::no_key::{
    DataReader, DataWriter, Decode, DefaultDecoder, DeserializerAdapter, SerializerAdapter,
};
use rustdds::policy::{Durability, History, Reliability};
use rustdds::{
    DomainParticipant, QosPolicies, QosPolicyBuilder, RepresentationIdentifier, Topic, TopicKind,
};

use crate::message::{CdrError, DsgUpdate, Encoding};
use crate::receive_buffers;

/// The DDS type name of `hydra_msgs/msg/DsgUpdate` (ROS 2's `<pkg>::msg::dds_::<Msg>_`).
pub const TYPE_NAME: &str = "hydra_msgs::msg::dds_::DsgUpdate_";

/// The ROS 2 topic Hydra publishes its backend graph on.
pub const HYDRA_TOPIC: &str = "/hydra/backend/dsg";

/// History depth of the subscriber: incremental updates that arrive while the bridge
/// applies one wait here instead of replacing each other (a replaced one would be a gap).
const READER_DEPTH: i32 = 64;

/// A setup that cannot work.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// Not a ROS 2 topic name.
    #[error(
        "topic {0:?} is not a ROS 2 topic name (absolute, like /hydra/backend/dsg: '/'-separated \
         tokens of letters, digits and '_', not starting with a digit)"
    )]
    TopicName(String),
    /// A domain id DDS does not allow.
    #[error("domain id {0} is out of range (0 to 232)")]
    Domain(u16),
    /// RustDDS refused to create an entity.
    #[error("cannot create the DDS {what}: {error}")]
    Create {
        /// The entity.
        what: &'static str,
        /// RustDDS's reason.
        error: String,
    },
    /// Reading or waiting failed.
    #[error("DDS {what}: {error}")]
    Io {
        /// What failed.
        what: &'static str,
        /// The reason.
        error: String,
    },
}

/// The DDS topic of a ROS 2 topic name: `/hydra/backend/dsg` is `rt/hydra/backend/dsg`.
///
/// # Errors
/// [`Ros2Error::TopicName`] for a name that is not absolute or has an empty or invalid
/// token.
///
/// # Examples
/// ```
/// assert_eq!(ygg_ros2::dds_topic_name("/hydra/backend/dsg")?, "rt/hydra/backend/dsg");
/// assert!(ygg_ros2::dds_topic_name("hydra//dsg").is_err());
/// # Ok::<(), ygg_ros2::Ros2Error>(())
/// ```
pub fn dds_topic_name(ros_topic: &str) -> Result<String, Ros2Error> {
    let bad = || Ros2Error::TopicName(ros_topic.to_owned());
    let rest = ros_topic.strip_prefix('/').ok_or_else(bad)?;
    let valid_token = |t: &str| {
        t.chars().next().is_some_and(|c| !c.is_ascii_digit())
            && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    if rest.split('/').all(valid_token) {
        Ok(format!("rt/{rest}"))
    } else {
        Err(bad())
    }
}

/// The QoS hydra_ros's `DsgSender` publishes with (`rclcpp::QoS(1).reliable()
/// .transient_local()`): reliable, transient-local, keep last 1. A subscriber asking for
/// the same gets the last graph sent before it joined.
pub fn hydra_qos() -> QosPolicies {
    qos(1)
}

fn qos(depth: i32) -> QosPolicies {
    QosPolicyBuilder::new()
        .reliability(Reliability::Reliable {
            max_blocking_time: rustdds::Duration::from_millis(100),
        })
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth })
        .build()
}

fn create<T>(what: &'static str, r: Result<T, impl std::fmt::Display>) -> Result<T, Ros2Error> {
    r.map_err(|e| Ros2Error::Create {
        what,
        error: e.to_string(),
    })
}

/// A domain participant, the DsgUpdate topic on it, and the smallest receive buffer of
/// its UDP sockets after [`receive_buffers::enlarge`] (`None`: none found).
fn topic(
    domain: u16,
    ros_topic: &str,
) -> Result<(DomainParticipant, Topic, Option<usize>), Ros2Error> {
    if domain > 232 {
        return Err(Ros2Error::Domain(domain));
    }
    let name = dds_topic_name(ros_topic)?;
    // RustDDS opens the participant's sockets in `new`: the descriptors new after it.
    let before = receive_buffers::open_fds();
    let participant = create("domain participant", DomainParticipant::new(domain))?;
    let receive_buffer =
        receive_buffers::enlarge(receive_buffers::open_fds().difference(&before).copied());
    let topic = create(
        "topic",
        participant.create_topic(name, TYPE_NAME.to_owned(), &hydra_qos(), TopicKind::NoKey),
    )?;
    Ok((participant, topic, receive_buffer))
}

/// One sample as received: a message, or why its bytes are not one.
pub type Received = Result<DsgUpdate, CdrError>;

/// The RustDDS adapter that encodes and decodes [`DsgUpdate`] (plain CDR, XCDR2).
pub struct DsgUpdateCdr;

const ENCODINGS: [RepresentationIdentifier; 6] = [
    RepresentationIdentifier::CDR_LE,
    RepresentationIdentifier::CDR_BE,
    RepresentationIdentifier::CDR2_LE,
    RepresentationIdentifier::CDR2_BE,
    RepresentationIdentifier::D_CDR2_LE,
    RepresentationIdentifier::D_CDR2_BE,
];

impl DeserializerAdapter<Received> for DsgUpdateCdr {
    type Error = Infallible;
    type Decoded = Received;

    fn supported_encodings() -> &'static [RepresentationIdentifier] {
        &ENCODINGS
    }

    fn transform_decoded(decoded: Received) -> Received {
        decoded
    }
}

/// Decodes a payload into a [`Received`]: malformed bytes become its error, so that the
/// subscriber sees (and reports) them instead of RustDDS dropping them.
#[derive(Clone, Copy)]
pub struct DsgUpdateDecoder;

impl Decode<Received> for DsgUpdateDecoder {
    type Error = Infallible;

    fn decode_bytes(
        self,
        input_bytes: &[u8],
        encoding: RepresentationIdentifier,
    ) -> Result<Received, Infallible> {
        let id = u16::from_be_bytes(encoding.to_bytes());
        Ok(Encoding::from_identifier(id).and_then(|e| DsgUpdate::from_cdr(input_bytes, e)))
    }
}

impl DefaultDecoder<Received> for DsgUpdateCdr {
    type Decoder = DsgUpdateDecoder;
    const DECODER: Self::Decoder = DsgUpdateDecoder;
}

impl SerializerAdapter<DsgUpdate> for DsgUpdateCdr {
    type Error = Infallible;

    fn output_encoding() -> RepresentationIdentifier {
        RepresentationIdentifier::CDR_LE
    }

    fn to_bytes(value: &DsgUpdate) -> Result<Bytes, Infallible> {
        Ok(Bytes::from(value.to_cdr()))
    }
}

/// Takes DsgUpdate messages from a ROS 2 topic, as a ROS 2 subscription with hydra_ros's
/// QoS would (a deeper history: see `READER_DEPTH`).
pub struct DsgUpdateSubscriber {
    // Field order: the reader goes before its participant.
    poll: mio_08::Poll,
    events: mio_08::Events,
    reader: DataReader<Received, DsgUpdateCdr>,
    receive_buffer: Option<usize>,
    _participant: DomainParticipant,
}

impl DsgUpdateSubscriber {
    /// Joins DDS domain `domain` (ROS 2's `ROS_DOMAIN_ID`) and subscribes to `ros_topic`.
    ///
    /// # Errors
    /// A bad topic name or domain id, or an entity RustDDS could not create.
    pub fn new(domain: u16, ros_topic: &str) -> Result<Self, Ros2Error> {
        let (participant, topic, receive_buffer) = topic(domain, ros_topic)?;
        let subscriber = create(
            "subscriber",
            participant.create_subscriber(&qos(READER_DEPTH)),
        )?;
        let mut reader = create(
            "data reader",
            subscriber.create_datareader_no_key::<Received, DsgUpdateCdr>(
                &topic,
                Some(qos(READER_DEPTH)),
            ),
        )?;
        let poll = create("poll", mio_08::Poll::new())?;
        create(
            "reader registration",
            poll.registry()
                .register(&mut reader, mio_08::Token(0), mio_08::Interest::READABLE),
        )?;
        Ok(Self {
            poll,
            events: mio_08::Events::with_capacity(4),
            reader,
            receive_buffer,
            _participant: participant,
        })
    }

    /// The smallest receive buffer granted to the participant's UDP sockets; `None` when
    /// they could not be found. Below [`RECEIVE_BUFFER_BYTES`](crate::RECEIVE_BUFFER_BYTES),
    /// `net.core.rmem_max` capped it: large graphs then arrive slower (lost fragments are
    /// sent again).
    pub fn receive_buffer_bytes(&self) -> Option<usize> {
        self.receive_buffer
    }

    /// Every message already received, oldest first, waiting up to `timeout` for the first
    /// one; empty when none came.
    ///
    /// # Errors
    /// [`Ros2Error::Io`] when waiting or reading fails.
    pub fn recv_timeout(&mut self, timeout: Duration) -> Result<Vec<Received>, Ros2Error> {
        let mut out = self.take_all()?;
        if out.is_empty() {
            let io = |e: std::io::Error| Ros2Error::Io {
                what: "wait",
                error: e.to_string(),
            };
            match self.poll.poll(&mut self.events, Some(timeout)) {
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                r => r.map_err(io)?,
            }
            out = self.take_all()?;
        }
        Ok(out)
    }

    fn take_all(&mut self) -> Result<Vec<Received>, Ros2Error> {
        let mut out = Vec::new();
        loop {
            match self.reader.take_next_sample() {
                Ok(Some(s)) => out.push(s.into_value()),
                Ok(None) => return Ok(out),
                Err(e) => {
                    return Err(Ros2Error::Io {
                        what: "take",
                        error: e.to_string(),
                    });
                }
            }
        }
    }
}

/// Publishes DsgUpdate messages on a ROS 2 topic with hydra_ros's QoS ([`hydra_qos`]).
pub struct DsgUpdatePublisher {
    writer: DataWriter<DsgUpdate, DsgUpdateCdr>,
    _participant: DomainParticipant,
}

impl DsgUpdatePublisher {
    /// Joins DDS domain `domain` and advertises `ros_topic`.
    ///
    /// # Errors
    /// A bad topic name or domain id, or an entity RustDDS could not create.
    pub fn new(domain: u16, ros_topic: &str) -> Result<Self, Ros2Error> {
        let (participant, topic, _) = topic(domain, ros_topic)?;
        let publisher = create("publisher", participant.create_publisher(&hydra_qos()))?;
        let writer = create(
            "data writer",
            publisher
                .create_datawriter_no_key::<DsgUpdate, DsgUpdateCdr>(&topic, Some(hydra_qos())),
        )?;
        Ok(Self {
            writer,
            _participant: participant,
        })
    }

    /// Sends `message` (reliably: it may block up to the QoS's 100 ms when readers lag).
    ///
    /// # Errors
    /// [`Ros2Error::Io`] when RustDDS could not send it.
    pub fn send(&self, message: DsgUpdate) -> Result<(), Ros2Error> {
        self.writer.write(message, None).map_err(|e| Ros2Error::Io {
            what: "write",
            error: e.to_string(),
        })
    }
}
