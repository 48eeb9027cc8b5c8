//! `hydra_msgs/msg/DsgUpdate` as plain data, and its CDR encoding (what a ROS 2 node puts
//! on the wire for it through any DDS-based rmw).
//!
//! The layout follows the OMG CDR rules as Cyclone DDS applies them (checked byte for byte
//! against its Python binding in the tests of `ygg-tests`): every primitive is aligned to
//! its size (XCDR1: up to 8; XCDR2: up to 4) counted from the start of the payload,
//! strings are a `u32` length including the NUL, then the bytes and the NUL; sequences a
//! `u32` count, then the elements (an empty sequence adds no padding).
//!
//! ```text
//! std_msgs/Header header   (builtin_interfaces/Time stamp {int32 sec, uint32 nanosec}, string frame_id)
//! uint8[]  layer_contents   Spark-DSG binary body (spark_dsg `to_binary`)
//! uint64[] deleted_nodes
//! uint64[] deleted_edges    pairs: source, target, source, target, ...
//! bool     full_update
//! int64    sequence_number
//! ```
//!
//! Decoding checks every length against the bytes left before allocating, and never panics.

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    /// When the graph was current.
    pub stamp: Time,
    /// The frame the graph's positions are in (Hydra: `map` or `odom`).
    pub frame_id: String,
}

/// `hydra_msgs/msg/DsgUpdate`: a scene graph update as Hydra publishes it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DsgUpdate {
    /// Stamp and frame.
    pub header: Header,
    /// A header-less Spark-DSG binary body (spark_dsg's `to_binary()`): the whole graph
    /// when `full_update`, else the nodes that changed or were added (and the edges added,
    /// with the nodes they join).
    pub layer_contents: Vec<u8>,
    /// Nodes removed since the previous update (incremental updates only).
    pub deleted_nodes: Vec<u64>,
    /// Edges removed since the previous update, as consecutive (source, target) pairs.
    pub deleted_edges: Vec<u64>,
    /// Whether `layer_contents` is the whole graph.
    pub full_update: bool,
    /// The sender's count of updates: each one is the previous one's plus one.
    pub sequence_number: i64,
}

/// A CDR buffer that is not a `DsgUpdate`.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum CdrError {
    /// The bytes end inside a field.
    #[error("DsgUpdate CDR ends inside {field} (offset {offset}, {len} bytes)")]
    Truncated {
        /// The field being read.
        field: &'static str,
        /// Its offset in the payload.
        offset: usize,
        /// The payload's length.
        len: usize,
    },
    /// A string without its NUL or not UTF-8.
    #[error(
        "DsgUpdate CDR: header.frame_id at offset {offset} is not a NUL-terminated UTF-8 string"
    )]
    BadString {
        /// Its offset in the payload.
        offset: usize,
    },
    /// A bool other than 0 or 1.
    #[error("DsgUpdate CDR: full_update at offset {offset} is {value}, not 0 or 1")]
    BadBool {
        /// Its offset in the payload.
        offset: usize,
        /// The byte found.
        value: u8,
    },
    /// An encapsulation this decoder does not read (only plain CDR, XCDR1 and XCDR2).
    #[error("DsgUpdate CDR: unsupported encapsulation {0:#06x} (plain CDR or XCDR2 expected)")]
    Encapsulation(u16),
}

/// How a payload is encoded: byte order and the largest alignment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Encoding {
    /// Little-endian (else big-endian).
    pub little_endian: bool,
    /// The largest alignment: 8 for XCDR1 (plain CDR), 4 for XCDR2.
    pub max_align: usize,
}

impl Encoding {
    /// XCDR1 little-endian (`CDR_LE`, `0x0001`): what ROS 2 rmw implementations send.
    pub const CDR_LE: Self = Self {
        little_endian: true,
        max_align: 8,
    };

    /// The encoding of an RTPS encapsulation identifier (the first two bytes of a
    /// serialized payload, big-endian): `0x0000`/`0x0001` plain CDR, `0x0006`..`0x0009`
    /// XCDR2 (plain or delimited, big or little-endian).
    ///
    /// # Errors
    /// [`CdrError::Encapsulation`] for any other (parameter lists, XML, ...).
    pub fn from_identifier(id: u16) -> Result<Self, CdrError> {
        match id {
            0x0000 | 0x0001 => Ok(Self {
                little_endian: id == 0x0001,
                max_align: 8,
            }),
            0x0006..=0x0009 => Ok(Self {
                little_endian: id % 2 == 1,
                max_align: 4,
            }),
            other => Err(CdrError::Encapsulation(other)),
        }
    }
}

impl DsgUpdate {
    /// The CDR payload of this message (without the 4-byte encapsulation header), in
    /// [`Encoding::CDR_LE`].
    pub fn to_cdr(&self) -> Vec<u8> {
        let mut w = Writer {
            out: Vec::with_capacity(
                64 + self.frame_id_len()
                    + self.layer_contents.len()
                    + 8 * (self.deleted_nodes.len() + self.deleted_edges.len()),
            ),
        };
        w.out
            .extend_from_slice(&self.header.stamp.sec.to_le_bytes());
        w.out
            .extend_from_slice(&self.header.stamp.nanosec.to_le_bytes());
        w.u32(u32_len(self.frame_id_len()));
        w.out.extend_from_slice(self.header.frame_id.as_bytes());
        w.out.push(0);
        w.u32(u32_len(self.layer_contents.len()));
        w.out.extend_from_slice(&self.layer_contents);
        w.u64s(&self.deleted_nodes);
        w.u64s(&self.deleted_edges);
        w.out.push(u8::from(self.full_update));
        w.align(8);
        w.out.extend_from_slice(&self.sequence_number.to_le_bytes());
        w.out
    }

    /// Decodes a CDR payload (without the encapsulation header) in `encoding`.
    ///
    /// # Errors
    /// A [`CdrError`] naming the field and offset where the bytes stop fitting.
    pub fn from_cdr(bytes: &[u8], encoding: Encoding) -> Result<Self, CdrError> {
        let mut r = Reader {
            bytes,
            at: 0,
            encoding,
        };
        let sec = r.u32("header.stamp.sec")? as i32;
        let nanosec = r.u32("header.stamp.nanosec")?;
        let frame_len = r.u32("header.frame_id")? as usize;
        let at = r.at;
        let raw = r.take(frame_len, "header.frame_id")?;
        let frame_id = match raw.split_last() {
            Some((0, text)) => std::str::from_utf8(text).ok(),
            _ => None,
        }
        .ok_or(CdrError::BadString { offset: at })?
        .to_owned();
        let n = r.u32("layer_contents")? as usize;
        let layer_contents = r.take(n, "layer_contents")?.to_vec();
        let deleted_nodes = r.u64s("deleted_nodes")?;
        let deleted_edges = r.u64s("deleted_edges")?;
        let at = r.at;
        let full_update = match r.take(1, "full_update")?[0] {
            0 => false,
            1 => true,
            value => return Err(CdrError::BadBool { offset: at, value }),
        };
        let sequence_number = r.u64("sequence_number")? as i64;
        Ok(Self {
            header: Header {
                stamp: Time { sec, nanosec },
                frame_id,
            },
            layer_contents,
            deleted_nodes,
            deleted_edges,
            full_update,
            sequence_number,
        })
    }

    fn frame_id_len(&self) -> usize {
        self.header.frame_id.len() + 1
    }
}

/// A length as CDR's `u32`; lengths past 4 GiB cannot be sent in one message.
fn u32_len(n: usize) -> u32 {
    u32::try_from(n).expect("a DsgUpdate field of 4 GiB or more cannot be encoded in CDR")
}

struct Writer {
    out: Vec<u8>,
}

impl Writer {
    fn align(&mut self, to: usize) {
        let pad = self.out.len().next_multiple_of(to) - self.out.len();
        self.out.resize(self.out.len() + pad, 0);
    }

    fn u32(&mut self, v: u32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }

    fn u64s(&mut self, vs: &[u64]) {
        self.u32(u32_len(vs.len()));
        if !vs.is_empty() {
            self.align(8);
        }
        for v in vs {
            self.out.extend_from_slice(&v.to_le_bytes());
        }
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
}

impl<'a> Reader<'a> {
    fn align(&mut self, size: usize) {
        self.at = self.at.next_multiple_of(size.min(self.encoding.max_align));
    }

    fn take(&mut self, n: usize, field: &'static str) -> Result<&'a [u8], CdrError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(CdrError::Truncated {
                field,
                offset: self.at,
                len: self.bytes.len(),
            });
        };
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        self.align(4);
        let b: [u8; 4] = self.take(4, field)?.try_into().expect("4 bytes");
        Ok(if self.encoding.little_endian {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn u64(&mut self, field: &'static str) -> Result<u64, CdrError> {
        self.align(8);
        let b: [u8; 8] = self.take(8, field)?.try_into().expect("8 bytes");
        Ok(if self.encoding.little_endian {
            u64::from_le_bytes(b)
        } else {
            u64::from_be_bytes(b)
        })
    }

    fn u64s(&mut self, field: &'static str) -> Result<Vec<u64>, CdrError> {
        let n = self.u32(field)? as usize;
        if n == 0 {
            return Ok(Vec::new());
        }
        self.align(8);
        // The count is checked against the bytes left before allocating.
        let bytes = self.take(n.saturating_mul(8), field)?;
        Ok(bytes
            .chunks_exact(8)
            .map(|c| {
                let b: [u8; 8] = c.try_into().expect("8 bytes");
                if self.encoding.little_endian {
                    u64::from_le_bytes(b)
                } else {
                    u64::from_be_bytes(b)
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(s: &str) -> Vec<u8> {
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
            .collect()
    }

    /// Bytes Cyclone DDS's Python binding (cyclonedds 11.0.1) serialized for two messages
    /// (`IdlStruct.serialize()`, encapsulation header removed).
    #[test]
    fn encodes_and_decodes_what_cyclone_dds_does() {
        let cases = [
            (
                DsgUpdate {
                    header: Header {
                        stamp: Time { sec: 1, nanosec: 2 },
                        frame_id: "odom".into(),
                    },
                    layer_contents: b"abc".to_vec(),
                    deleted_nodes: vec![],
                    deleted_edges: vec![5, 6],
                    full_update: true,
                    sequence_number: 7,
                },
                "0100000002000000050000006f646f6d000000000300000061626300000000000200000000000000\
                 0500000000000000060000000000000001000000000000000700000000000000",
            ),
            (
                DsgUpdate {
                    header: Header {
                        stamp: Time { sec: 1, nanosec: 2 },
                        frame_id: "od".into(),
                    },
                    layer_contents: b"abcde".to_vec(),
                    deleted_nodes: vec![9],
                    deleted_edges: vec![],
                    full_update: false,
                    sequence_number: -1,
                },
                "0100000002000000030000006f6400000500000061626364650000000100000009000000000000000\
                 000000000000000ffffffffffffffff",
            ),
        ];
        for (message, cyclone) in cases {
            let bytes = hex(cyclone);
            assert_eq!(message.to_cdr(), bytes);
            assert_eq!(DsgUpdate::from_cdr(&bytes, Encoding::CDR_LE), Ok(message));
        }
    }

    #[test]
    fn every_cut_or_corrupted_payload_is_an_error_not_a_panic() {
        let message = DsgUpdate {
            header: Header {
                stamp: Time { sec: 3, nanosec: 4 },
                frame_id: "map".into(),
            },
            layer_contents: vec![7; 33],
            deleted_nodes: vec![1, 2, 3],
            deleted_edges: vec![4, 5],
            full_update: false,
            sequence_number: 12,
        };
        let bytes = message.to_cdr();
        for cut in 0..bytes.len() {
            assert!(DsgUpdate::from_cdr(&bytes[..cut], Encoding::CDR_LE).is_err());
        }
        for k in 0..bytes.len() {
            let mut bad = bytes.clone();
            bad[k] = 0xff;
            let _ = DsgUpdate::from_cdr(&bad, Encoding::CDR_LE);
        }
        let mut huge = bytes.clone();
        huge[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            DsgUpdate::from_cdr(&huge, Encoding::CDR_LE),
            Err(CdrError::Truncated { .. })
        ));
        assert_eq!(
            Encoding::from_identifier(0x0003),
            Err(CdrError::Encapsulation(3))
        );
    }
}
