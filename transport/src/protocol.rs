//! The shared-memory wire protocol between one writer and its readers.
//!
//! Everything both sides must agree on lives here: service names, the payload block type, the
//! user header, the transport-level manifest prefix, event ids and the quality-of-service
//! constants. The writer crate depends on this module; nothing here depends on the store.
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
//! opaque `u32` to the transport), writer session and generation. A manifest is a
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
use core::time::Duration;

use iceoryx2::config::Config;
use iceoryx2::prelude::{EventId, FileName, Path, SemanticString, ZeroCopySend};

/// The iceoryx2 service flavour used by writer and reader.
///
/// The thread-safe variant has the same shared-memory layout as `ipc::Service`; it makes ports
/// and samples `Send`, so a writer can answer readers from a helper thread and a reader's
/// snapshots can move between threads.
pub type Ipc = iceoryx2::service::ipc_threadsafe::Service;

/// First path component of every Yggdrasil service name.
pub const SERVICE_ROOT: &str = "ygg";

/// Longest accepted scene name, in bytes.
pub const MAX_SCENE_NAME_LEN: usize = 64;

/// Alignment, in bytes, of the first payload byte of every segment.
pub const SEGMENT_ALIGN: usize = 128;

/// Size of one [`Block128`], in bytes.
pub const BLOCK_SIZE: usize = 128;

/// `"YGGS"`: magic number of [`SegmentHeader::magic`].
pub const SEGMENT_MAGIC: u32 = u32::from_le_bytes(*b"YGGS");

/// `"YGGM"`: magic number at the start of a manifest payload.
pub const MANIFEST_MAGIC: u32 = u32::from_le_bytes(*b"YGGM");

/// Version of this protocol; readers reject segments of another version. Version 3 carries
/// all segments of a scene over one stream service plus a catch-up service (version 2 had a
/// service per layer).
pub const PROTOCOL_VERSION: u16 = 3;

/// Most layers one manifest may name.
pub const MAX_LAYERS: usize = 4096;

/// Size of the fixed part of the manifest prefix (magic, count, reserved).
pub const MANIFEST_FIXED_LEN: usize = 16;

/// Size of one encoded [`ManifestEntry`].
pub const MANIFEST_ENTRY_LEN: usize = 16;

/// Default for the most segments one snapshot may name (layers, or chunks of layers): sizes
/// the segment stream's pool (see [`stream_buffer_size`], [`stream_max_borrowed`]).
pub const DEFAULT_MAX_SEGMENTS: usize = 512;

/// Samples a reader's subscription to the segment stream buffers between two receives: one
/// whole snapshot and its manifest, so that neither a catch-up burst nor a cut that changes
/// every segment overflows a reader that keeps up. A reader that falls further behind loses
/// its oldest buffered samples (safe overflow), notices the hole and asks for a catch-up.
pub const fn stream_buffer_size(max_segments: usize) -> usize {
    max_segments + 2
}

/// Samples one subscriber may hold from the segment stream when snapshots name at most
/// `max_segments` segments: the current snapshot's, newer ones waiting for their manifest
/// (or a burst being received), and a few manifests and samples of older snapshots the
/// application still holds. Costs address space and a byte per sample and possible
/// reallocation in each connection: iceoryx2 reuses freed chunks last-in first-out, and the
/// writer gives back the pages a reused chunk no longer needs once the pool holds more than
/// about four snapshots (`publisher::loan`), so unused chunks cost address space, not memory.
pub const fn stream_max_borrowed(max_segments: usize) -> usize {
    2 * max_segments + 16
}

/// Segments per snapshot a stream created with this subscriber buffer size and borrow limit
/// supports: the inverse of [`stream_buffer_size`] and [`stream_max_borrowed`].
pub const fn stream_segments_supported(buffer_size: usize, max_borrowed: usize) -> usize {
    let by_buffer = buffer_size.saturating_sub(2);
    let by_borrowed = max_borrowed.saturating_sub(16) / 2;
    if by_buffer < by_borrowed {
        by_buffer
    } else {
        by_borrowed
    }
}

/// [`SegmentHeader::flags`] bit: the segment is a catch-up copy of the current snapshot.
pub const FLAG_CATCH_UP: u32 = 1;

/// Samples the writer may hold on loan per service (it fills one at a time).
pub const PUBLISHER_MAX_LOANED: usize = 1;

/// Default number of readers a scene supports at once.
pub const DEFAULT_MAX_READERS: usize = 8;

/// Highest event id used on the event services.
pub const EVENT_ID_MAX: usize = 7;

/// Writer -> readers: a new manifest was published (or a catch-up burst was sent).
pub const EVENT_SNAPSHOT_PUBLISHED: EventId = EventId::new(1);

/// Writer -> readers: the writer is shutting down, or was found dead.
pub const EVENT_WRITER_GONE: EventId = EventId::new(2);

/// Reader -> writer: a reader connected, or found a hole in the stream, and asks for a
/// catch-up burst of the current snapshot.
pub const EVENT_READER_HELLO: EventId = EventId::new(3);

/// Writer-internal: wakes the writer's helper thread so it can stop.
pub const EVENT_WRITER_STOP: EventId = EventId::new(4);

/// Environment variable that overrides the iceoryx2 file-name prefix (default `iox2_`).
///
/// Every shared-memory object and node file the transport creates starts with this prefix, so a
/// distinct prefix isolates a group of processes (the integration tests use one per test).
/// Writer and readers of one scene must use the same prefix.
pub const ENV_IOX2_PREFIX: &str = "YGG_IOX2_PREFIX";

/// Default path of the POSIX shared-memory file system that iceoryx2 allocates from.
pub const DEFAULT_SHM_DIR: &str = "/dev/shm";

/// Where iceoryx2 keeps its node and service files for Yggdrasil (its own default is
/// `/tmp/iceoryx2/`): on the shared-memory tmpfs, because iceoryx2 fsyncs every node and
/// port file it writes, 7 fsyncs per attaching reader that cost 5-8 ms of a ~20 ms attach on
/// a disk-backed `/tmp`. Every Yggdrasil process uses it ([`iceoryx_config`]); iceoryx2's
/// own tools see these scenes when their config names the same root.
pub const ICEORYX2_ROOT: &str = "/dev/shm/iceoryx2/";

/// How often helper threads and waiting readers check peers for liveness.
pub const DEFAULT_LIVENESS_INTERVAL: Duration = Duration::from_millis(200);

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
pub const MANIFEST_LAYER_ID: u32 = u32::MAX;

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
    /// The segment id (a layer, or a chunk of one; opaque to the transport), or
    /// [`MANIFEST_LAYER_ID`] for a manifest.
    pub layer_id: u32,
    /// [`FLAG_CATCH_UP`] for a catch-up copy, else zero.
    pub flags: u32,
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
        layer_id: u32,
        session: u64,
        generation: u64,
        len: u64,
        published_unix_ns: u64,
    ) -> Self {
        Self {
            magic: SEGMENT_MAGIC,
            version: PROTOCOL_VERSION,
            kind: kind as u16,
            layer_id,
            flags: 0,
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
        expected: u32,
        /// The id in the header.
        found: u32,
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
        layer_id: u32,
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
    expected_layer: Option<u32>,
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
    /// The layer id (the number in the layer's service name).
    pub layer_id: u32,
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
/// 16  count x { layer_id u32, zero u32, generation u64 }
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
        prefix[at..at + 4].copy_from_slice(&entry.layer_id.to_le_bytes());
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
        let mut id = [0; 4];
        id.copy_from_slice(&bytes[at..at + 4]);
        let mut generation = [0; 8];
        generation.copy_from_slice(&bytes[at + 8..at + 16]);
        let entry = ManifestEntry {
            layer_id: u32::from_le_bytes(id),
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

/// A scene name that cannot name iceoryx2 services.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SceneNameError {
    /// The name is empty.
    #[error("the scene name is empty")]
    Empty,
    /// The name is longer than [`MAX_SCENE_NAME_LEN`].
    #[error("the scene name is {len} bytes long, at most {MAX_SCENE_NAME_LEN} are allowed")]
    TooLong {
        /// Its length.
        len: usize,
    },
    /// The name contains a character other than ASCII letters, digits, `-`, `_` and `.`.
    #[error("the scene name contains {found:?}; use ASCII letters, digits, '-', '_' or '.'")]
    InvalidCharacter {
        /// The first offending character.
        found: char,
    },
}

/// The names of the services of one scene.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneServices {
    scene: String,
}

impl SceneServices {
    /// Validates `scene` and returns its service names.
    ///
    /// # Errors
    ///
    /// [`SceneNameError`] if the name is empty, too long or has characters outside
    /// `[A-Za-z0-9._-]`.
    pub fn new(scene: &str) -> Result<Self, SceneNameError> {
        if scene.is_empty() {
            return Err(SceneNameError::Empty);
        }
        if scene.len() > MAX_SCENE_NAME_LEN {
            return Err(SceneNameError::TooLong { len: scene.len() });
        }
        if let Some(found) = scene
            .chars()
            .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.')))
        {
            return Err(SceneNameError::InvalidCharacter { found });
        }
        Ok(Self {
            scene: scene.to_owned(),
        })
    }

    /// The scene name.
    pub fn scene(&self) -> &str {
        &self.scene
    }

    /// `ygg/<scene>/segments`: every segment, in publish order, and catch-up bursts.
    pub fn segments(&self) -> String {
        format!("{SERVICE_ROOT}/{}/segments", self.scene)
    }

    /// `ygg/<scene>/events` (writer -> readers).
    pub fn events(&self) -> String {
        format!("{SERVICE_ROOT}/{}/events", self.scene)
    }

    /// `ygg/<scene>/readers` (readers -> writer).
    pub fn readers(&self) -> String {
        format!("{SERVICE_ROOT}/{}/readers", self.scene)
    }
}

/// An iceoryx2 file-name prefix that iceoryx2 does not accept.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid iceoryx2 prefix {prefix:?} (from {ENV_IOX2_PREFIX} or the builder): {reason}")]
pub struct PrefixError {
    /// The rejected prefix.
    pub prefix: String,
    /// Why iceoryx2 rejected it.
    pub reason: String,
}

/// The iceoryx2 configuration used by writer and readers: iceoryx2's global configuration,
/// with the file-name prefix replaced by `prefix` if given, else by [`ENV_IOX2_PREFIX`] if set.
///
/// # Errors
///
/// [`PrefixError`] if the prefix is not a valid file name.
pub fn iceoryx_config(prefix: Option<&str>) -> Result<Config, PrefixError> {
    let mut config = Config::global_config().clone();
    let root = Path::new(ICEORYX2_ROOT.as_bytes()).expect("ICEORYX2_ROOT is a valid path");
    config.global.set_root_path(&root);
    let from_env = std::env::var(ENV_IOX2_PREFIX).ok();
    if let Some(prefix) = prefix.or(from_env.as_deref()) {
        config.global.prefix = FileName::new(prefix.as_bytes()).map_err(|e| PrefixError {
            prefix: prefix.to_owned(),
            reason: format!("{e:?}"),
        })?;
    }
    Ok(config)
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
    fn a_stream_supports_the_segments_it_was_sized_for() {
        for n in [1, 8, 42, 128, 512, MAX_LAYERS] {
            assert_eq!(
                stream_segments_supported(stream_buffer_size(n), stream_max_borrowed(n)),
                n
            );
        }
        // The smaller of the two limits wins.
        assert_eq!(
            stream_segments_supported(stream_buffer_size(64), stream_max_borrowed(8)),
            8
        );
        assert_eq!(stream_segments_supported(0, 0), 0);
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

    #[test]
    fn scene_names_are_checked() {
        assert!(SceneServices::new("office-1.a_b").is_ok());
        assert_eq!(SceneServices::new(""), Err(SceneNameError::Empty));
        assert!(matches!(
            SceneServices::new("a/b"),
            Err(SceneNameError::InvalidCharacter { found: '/' })
        ));
        let s = SceneServices::new("s").expect("valid");
        assert_eq!(s.segments(), "ygg/s/segments");
    }
}
