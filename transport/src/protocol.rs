//! The shared-memory wire protocol between one writer and its readers.
//!
//! The wire format: the bytes both sides must agree on: the payload block type, the user
//! header, the transport-level manifest prefix and the event ids. The services' names,
//! their iceoryx2 configuration and quality of service are in [`crate::service`]. Nothing
//! here depends on the store.
//!
//! # Services of one scene
//!
//! Three services per scene, whatever its number of layers:
//!
//! | service | pattern | direction | content |
//! |---|---|---|---|
//! | `ygg/<scene>/segments` | publish-subscribe `[Block128]` + [`SegmentHeader`] | writer -> readers | every segment in publish order (a cut's segments, then its manifest), and catch-up bursts |
//! | `ygg/<scene>/events` | event | writer -> readers | [`EVENT_SNAPSHOT_PUBLISHED`], [`EVENT_WRITER_GONE`] |
//! | `ygg/<scene>/readers` | event | readers -> writer | [`EVENT_READER_HELLO`] (a catch-up request) |
//!
//! A segment is identified by its header: kind, segment id ([`SegmentHeader::layer_id`], an
//! opaque `u64` to the transport), writer session and generation. A manifest is a
//! [manifest prefix](encode_manifest_prefix) followed by the store's manifest bytes. A
//! *catch-up burst* ([`FLAG_CATCH_UP`]) is a copy of every segment of the current snapshot
//! followed by its manifest, sent when a reader asks: a reader that connects, or that lost
//! segments to overflow. Its segments may interleave with the cuts being published.
//!
//! # Invariants
//!
//! * A segment's payload starts [`SEGMENT_ALIGN`] (128) bytes aligned, in the writer and in
//!   every reader mapping, so rkyv archives that contain kiddo trees can be accessed in place.
//! * [`SegmentHeader::len`] is the number of meaningful bytes; the payload is `len` rounded up
//!   to whole blocks and the tail is zero. Readers must check `len` against the payload size
//!   ([`check_segment_header`]): shared memory is untrusted input.
//! * A manifest names, for every layer of the snapshot, the generation of the layer segment
//!   that belongs to it. Layer segments are published before the manifest that names them.

use core::fmt;

use iceoryx2::prelude::{EventId, ZeroCopySend};

/// Alignment, in bytes, of the first payload byte of every segment.
pub const SEGMENT_ALIGN: usize = 128;

/// Size of one [`Block128`], in bytes.
pub const BLOCK_SIZE: usize = 128;

/// `"YGGS"`: magic number of [`SegmentHeader::magic`].
pub const SEGMENT_MAGIC: u32 = u32::from_le_bytes(*b"YGGS");

/// `"YGGM"`: magic number at the start of a manifest payload.
pub const MANIFEST_MAGIC: u32 = u32::from_le_bytes(*b"YGGM");

/// Version of this protocol; readers reject segments of another version. Version 4 has
/// 64-bit segment ids (a layer's parts and their chunks); version 3 carried all segments of
/// a scene over one stream service plus a catch-up service (version 2 had a service per
/// layer).
pub const PROTOCOL_VERSION: u16 = 4;

/// Most layers one manifest may name.
pub const MAX_LAYERS: usize = 4096;

/// Size of the fixed part of the manifest prefix (magic, count, reserved).
pub const MANIFEST_FIXED_LEN: usize = 16;

/// Size of one encoded [`ManifestEntry`].
pub const MANIFEST_ENTRY_LEN: usize = 16;

/// [`SegmentHeader::flags`] bit: the segment is a catch-up copy of the current snapshot.
pub const FLAG_CATCH_UP: u32 = 1;

/// Writer -> readers: a new manifest was published (or a catch-up burst was sent).
pub const EVENT_SNAPSHOT_PUBLISHED: EventId = EventId::new(1);

/// Writer -> readers: the writer is shutting down, or was found dead.
pub const EVENT_WRITER_GONE: EventId = EventId::new(2);

/// Reader -> writer: a reader connected, or found a hole in the stream, and asks for a
/// catch-up burst of the current snapshot.
pub const EVENT_READER_HELLO: EventId = EventId::new(3);

/// Writer-internal: wakes the writer's helper thread so it can stop.
pub const EVENT_WRITER_STOP: EventId = EventId::new(4);

/// One 128-byte, 128-aligned block of segment payload.
///
/// Segments are published as `[Block128]` rather than `[u8]` so that iceoryx2 lays the payload
/// out 128-byte aligned (a `[u8]` payload is only 8-aligned), which is what archived kiddo trees
/// need. Overriding `payload_alignment` on a smaller block is no alternative: iceoryx2 pads
/// every slice *element* to the payload alignment.
// Two attributes: iceoryx2's derive recognises `#[repr(C)]` only on its own.
#[repr(C)]
#[repr(align(128))]
#[derive(Clone, Copy, PartialEq, Eq, ZeroCopySend)]
pub struct Block128(pub [u8; BLOCK_SIZE]);

impl Block128 {
    /// A block of zero bytes.
    pub const ZERO: Self = Self([0; BLOCK_SIZE]);
}

impl Default for Block128 {
    fn default() -> Self {
        Self::ZERO
    }
}

impl fmt::Debug for Block128 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Block128(..)")
    }
}

/// Number of [`Block128`] needed to hold `len` bytes.
pub const fn blocks_for(len: usize) -> usize {
    len.div_ceil(BLOCK_SIZE)
}

/// What a segment carries.
#[repr(u16)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentKind {
    /// One layer's bytes.
    Layer = 1,
    /// A manifest: prefix plus the store's manifest bytes.
    Manifest = 2,
}

impl SegmentKind {
    /// The kind encoded as `raw`, if any.
    pub fn from_raw(raw: u16) -> Option<Self> {
        match raw {
            1 => Some(Self::Layer),
            2 => Some(Self::Manifest),
            _ => None,
        }
    }
}

/// Layer id written into the header of a manifest segment.
pub const MANIFEST_LAYER_ID: u64 = u64::MAX;

/// The iceoryx2 user header of every segment.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ZeroCopySend)]
pub struct SegmentHeader {
    /// [`SEGMENT_MAGIC`].
    pub magic: u32,
    /// [`PROTOCOL_VERSION`].
    pub version: u16,
    /// [`SegmentKind`] as `u16`.
    pub kind: u16,
    /// [`FLAG_CATCH_UP`] for a catch-up copy, else zero.
    pub flags: u32,
    /// Zero.
    pub reserved: u32,
    /// The segment id (a layer's part, or a chunk of one; opaque to the transport), or
    /// [`MANIFEST_LAYER_ID`] for a manifest.
    pub layer_id: u64,
    /// Random id of the writer instance; a restarted writer has a new one.
    pub session: u64,
    /// Layer generation, or snapshot generation for a manifest.
    pub generation: u64,
    /// Meaningful payload bytes (the rest of the last block is zero).
    pub len: u64,
    /// When the writer began publishing the cut this segment belongs to, in nanoseconds
    /// since the Unix epoch on the writer's clock (for publish-to-visible latency; not part
    /// of any archive).
    pub published_unix_ns: u64,
}

impl SegmentHeader {
    /// Header for a segment of `kind` with the given identity and length.
    pub fn new(
        kind: SegmentKind,
        layer_id: u64,
        session: u64,
        generation: u64,
        len: u64,
        published_unix_ns: u64,
    ) -> Self {
        Self {
            magic: SEGMENT_MAGIC,
            version: PROTOCOL_VERSION,
            kind: kind as u16,
            flags: 0,
            reserved: 0,
            layer_id,
            session,
            generation,
            len,
            published_unix_ns,
        }
    }
}

/// Nanoseconds since the Unix epoch (0 if the clock is before it).
pub fn unix_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::SystemTime::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// A segment that breaks the protocol. Readers report it instead of touching the bytes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SegmentError {
    /// The header's magic number is wrong.
    #[error("bad segment magic {found:#010x} (expected {SEGMENT_MAGIC:#010x})")]
    BadMagic {
        /// The magic number found.
        found: u32,
    },
    /// The segment was written by another protocol version.
    #[error("segment protocol version {found}, this reader speaks {PROTOCOL_VERSION}")]
    VersionMismatch {
        /// The version found.
        found: u16,
    },
    /// The header names another kind of segment than the service carries.
    #[error("segment kind {found} where {expected:?} was expected")]
    WrongKind {
        /// The raw kind found.
        found: u16,
        /// The kind the service carries.
        expected: SegmentKind,
    },
    /// The header's kind is neither a layer nor a manifest.
    #[error("unknown segment kind {found}")]
    UnknownKind {
        /// The raw kind found.
        found: u16,
    },
    /// The segment id does not fit the kind (a manifest must carry [`MANIFEST_LAYER_ID`], a
    /// layer segment any other id), or is not the one expected.
    #[error("segment id {found} where {expected} was expected")]
    LayerIdMismatch {
        /// The id expected.
        expected: u64,
        /// The id in the header.
        found: u64,
    },
    /// The header claims more bytes than the payload holds.
    #[error("segment claims {len} bytes but its payload holds only {payload}")]
    LengthExceedsPayload {
        /// The claimed length.
        len: u64,
        /// The payload size in bytes.
        payload: usize,
    },
    /// The manifest prefix is shorter than its fixed part or its entry list.
    #[error("manifest of {len} bytes is too short for its prefix of {needed} bytes")]
    ManifestTruncated {
        /// Bytes available.
        len: usize,
        /// Bytes the prefix needs.
        needed: usize,
    },
    /// The manifest prefix has a wrong magic number.
    #[error("bad manifest magic {found:#010x} (expected {MANIFEST_MAGIC:#010x})")]
    BadManifestMagic {
        /// The magic number found.
        found: u32,
    },
    /// The manifest names more layers than [`MAX_LAYERS`].
    #[error("manifest names {count} layers, at most {MAX_LAYERS} are allowed")]
    TooManyLayers {
        /// The count found.
        count: u64,
    },
    /// The payload does not start [`SEGMENT_ALIGN`]-byte aligned in this process.
    #[error("segment payload at {address:#x} is not {SEGMENT_ALIGN}-byte aligned")]
    Misaligned {
        /// The payload address.
        address: usize,
    },
    /// The manifest's layer ids are not strictly increasing.
    #[error("manifest layer ids are not strictly increasing at layer {layer_id}")]
    UnsortedLayers {
        /// The first layer id out of order.
        layer_id: u64,
    },
}

/// Checks a received segment header against the service it arrived on and its payload size.
///
/// `expected_layer` is `None` for the manifest service. Returns the meaningful length.
///
/// # Errors
///
/// Any [`SegmentError`] describing the first violation found.
pub fn check_segment_header(
    header: &SegmentHeader,
    expected_kind: SegmentKind,
    expected_layer: Option<u64>,
    payload_bytes: usize,
) -> Result<usize, SegmentError> {
    if header.magic != SEGMENT_MAGIC {
        return Err(SegmentError::BadMagic {
            found: header.magic,
        });
    }
    if header.version != PROTOCOL_VERSION {
        return Err(SegmentError::VersionMismatch {
            found: header.version,
        });
    }
    if SegmentKind::from_raw(header.kind) != Some(expected_kind) {
        return Err(SegmentError::WrongKind {
            found: header.kind,
            expected: expected_kind,
        });
    }
    if let Some(expected) = expected_layer
        && header.layer_id != expected
    {
        return Err(SegmentError::LayerIdMismatch {
            expected,
            found: header.layer_id,
        });
    }
    match usize::try_from(header.len) {
        Ok(len) if len <= payload_bytes => Ok(len),
        _ => Err(SegmentError::LengthExceedsPayload {
            len: header.len,
            payload: payload_bytes,
        }),
    }
}

/// Checks a segment received from a stream that carries both kinds: finds its kind, checks
/// that a manifest carries [`MANIFEST_LAYER_ID`] (and a layer segment another id), then runs
/// [`check_segment_header`]. Returns the kind and the meaningful length.
///
/// # Errors
///
/// [`SegmentError::UnknownKind`], [`SegmentError::LayerIdMismatch`] or any error of
/// [`check_segment_header`].
pub fn check_stream_header(
    header: &SegmentHeader,
    payload_bytes: usize,
) -> Result<(SegmentKind, usize), SegmentError> {
    if header.magic != SEGMENT_MAGIC {
        return Err(SegmentError::BadMagic {
            found: header.magic,
        });
    }
    let kind = SegmentKind::from_raw(header.kind)
        .ok_or(SegmentError::UnknownKind { found: header.kind })?;
    let is_manifest_id = header.layer_id == MANIFEST_LAYER_ID;
    if is_manifest_id != (kind == SegmentKind::Manifest) {
        return Err(SegmentError::LayerIdMismatch {
            expected: if is_manifest_id { 0 } else { MANIFEST_LAYER_ID },
            found: header.layer_id,
        });
    }
    let expected = is_manifest_id.then_some(MANIFEST_LAYER_ID);
    let len = check_segment_header(header, kind, expected, payload_bytes)?;
    Ok((kind, len))
}

/// One line of the transport-level manifest: which generation of a layer a snapshot uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ManifestEntry {
    /// The segment id.
    pub layer_id: u64,
    /// The generation of the layer segment that belongs to the snapshot.
    pub generation: u64,
}

/// Bytes taken by the manifest prefix for `count` layers, padded to [`SEGMENT_ALIGN`] so that
/// the store's manifest bytes that follow start 128-byte aligned.
pub const fn manifest_prefix_len(count: usize) -> usize {
    (MANIFEST_FIXED_LEN + MANIFEST_ENTRY_LEN * count).next_multiple_of(SEGMENT_ALIGN)
}

/// Writes the manifest prefix for `entries` into `out` (little endian):
///
/// ```text
/// 0   magic  u32 = MANIFEST_MAGIC
/// 4   count  u32
/// 8   zero   u64
/// 16  count x { segment id u64, generation u64 }
///     zero padding up to manifest_prefix_len(count)
/// ```
///
/// # Panics
///
/// If `out` is shorter than [`manifest_prefix_len`]`(entries.len())` or there are more than
/// [`MAX_LAYERS`] entries (the writer checks both before calling).
pub fn encode_manifest_prefix(entries: &[ManifestEntry], out: &mut [u8]) {
    assert!(entries.len() <= MAX_LAYERS, "too many manifest entries");
    let prefix = &mut out[..manifest_prefix_len(entries.len())];
    prefix.fill(0);
    prefix[0..4].copy_from_slice(&MANIFEST_MAGIC.to_le_bytes());
    // Lossless: at most MAX_LAYERS entries.
    prefix[4..8].copy_from_slice(&(entries.len() as u32).to_le_bytes());
    for (i, entry) in entries.iter().enumerate() {
        let at = MANIFEST_FIXED_LEN + i * MANIFEST_ENTRY_LEN;
        prefix[at..at + 8].copy_from_slice(&entry.layer_id.to_le_bytes());
        prefix[at + 8..at + 16].copy_from_slice(&entry.generation.to_le_bytes());
    }
}

/// Parses a manifest payload (its first `len` bytes) into its entries and the offset where
/// the store's manifest bytes start.
///
/// # Errors
///
/// [`SegmentError::ManifestTruncated`], [`SegmentError::BadManifestMagic`],
/// [`SegmentError::TooManyLayers`] or [`SegmentError::UnsortedLayers`].
pub fn decode_manifest_prefix(bytes: &[u8]) -> Result<(Vec<ManifestEntry>, usize), SegmentError> {
    let fixed = bytes
        .get(..MANIFEST_FIXED_LEN)
        .ok_or(SegmentError::ManifestTruncated {
            len: bytes.len(),
            needed: MANIFEST_FIXED_LEN,
        })?;
    let magic = u32::from_le_bytes([fixed[0], fixed[1], fixed[2], fixed[3]]);
    if magic != MANIFEST_MAGIC {
        return Err(SegmentError::BadManifestMagic { found: magic });
    }
    let count = u32::from_le_bytes([fixed[4], fixed[5], fixed[6], fixed[7]]) as usize;
    if count > MAX_LAYERS {
        return Err(SegmentError::TooManyLayers {
            count: count as u64,
        });
    }
    let prefix_len = manifest_prefix_len(count);
    if bytes.len() < prefix_len {
        return Err(SegmentError::ManifestTruncated {
            len: bytes.len(),
            needed: prefix_len,
        });
    }
    let mut entries = Vec::with_capacity(count);
    for i in 0..count {
        let at = MANIFEST_FIXED_LEN + i * MANIFEST_ENTRY_LEN;
        let mut id = [0; 8];
        id.copy_from_slice(&bytes[at..at + 8]);
        let mut generation = [0; 8];
        generation.copy_from_slice(&bytes[at + 8..at + 16]);
        let entry = ManifestEntry {
            layer_id: u64::from_le_bytes(id),
            generation: u64::from_le_bytes(generation),
        };
        if entries
            .last()
            .is_some_and(|last: &ManifestEntry| last.layer_id >= entry.layer_id)
        {
            return Err(SegmentError::UnsortedLayers {
                layer_id: entry.layer_id,
            });
        }
        entries.push(entry);
    }
    Ok((entries, prefix_len))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifest_prefix_roundtrips_and_aligns_the_store_bytes() {
        let entries = [
            ManifestEntry {
                layer_id: 1,
                generation: 7,
            },
            ManifestEntry {
                layer_id: 9,
                generation: u64::MAX,
            },
        ];
        let len = manifest_prefix_len(entries.len());
        assert_eq!(len % SEGMENT_ALIGN, 0);
        let mut buf = vec![0xAA; len + 5];
        encode_manifest_prefix(&entries, &mut buf);
        let (decoded, offset) = decode_manifest_prefix(&buf).expect("valid prefix");
        assert_eq!(decoded, entries);
        assert_eq!(offset, len);
    }

    #[test]
    fn decode_rejects_garbage() {
        assert!(matches!(
            decode_manifest_prefix(&[1, 2, 3]),
            Err(SegmentError::ManifestTruncated { .. })
        ));
        assert!(matches!(
            decode_manifest_prefix(&[0; 64]),
            Err(SegmentError::BadManifestMagic { .. })
        ));
        let mut buf = vec![0; 128];
        buf[..4].copy_from_slice(&MANIFEST_MAGIC.to_le_bytes());
        buf[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            decode_manifest_prefix(&buf),
            Err(SegmentError::TooManyLayers { .. })
        ));
        buf[4..8].copy_from_slice(&100u32.to_le_bytes());
        assert!(matches!(
            decode_manifest_prefix(&buf),
            Err(SegmentError::ManifestTruncated { .. })
        ));
    }

    #[test]
    fn header_check_rejects_length_beyond_payload() {
        let header = SegmentHeader::new(SegmentKind::Layer, 3, 1, 1, 1000, 0);
        assert_eq!(
            check_segment_header(&header, SegmentKind::Layer, Some(3), 1024),
            Ok(1000)
        );
        assert!(matches!(
            check_segment_header(&header, SegmentKind::Layer, Some(3), 896),
            Err(SegmentError::LengthExceedsPayload { .. })
        ));
        assert!(matches!(
            check_segment_header(&header, SegmentKind::Layer, Some(4), 1024),
            Err(SegmentError::LayerIdMismatch { .. })
        ));
        assert!(matches!(
            check_segment_header(&header, SegmentKind::Manifest, None, 1024),
            Err(SegmentError::WrongKind { .. })
        ));
    }

    #[test]
    fn stream_header_check_finds_the_kind() {
        let layer = SegmentHeader::new(SegmentKind::Layer, 3, 1, 1, 100, 0);
        assert_eq!(
            check_stream_header(&layer, 128),
            Ok((SegmentKind::Layer, 100))
        );
        let manifest = SegmentHeader::new(SegmentKind::Manifest, MANIFEST_LAYER_ID, 1, 1, 0, 0);
        assert_eq!(
            check_stream_header(&manifest, 128),
            Ok((SegmentKind::Manifest, 0))
        );
        let mut bad = layer;
        bad.kind = 9;
        assert_eq!(
            check_stream_header(&bad, 128),
            Err(SegmentError::UnknownKind { found: 9 })
        );
        let mut bad = layer;
        bad.layer_id = MANIFEST_LAYER_ID;
        assert!(matches!(
            check_stream_header(&bad, 128),
            Err(SegmentError::LayerIdMismatch { .. })
        ));
    }
}
