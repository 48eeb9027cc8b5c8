//! The bytes of a recording's files: the file header, record headers with their CRC, and
//! the cut record's payload (the manifest, then the segment entries that changed).

use crate::bytes::ARCHIVE_ALIGN;

/// First eight bytes of every file of a recording.
pub const RECORDING_FILE_MAGIC: &[u8; 8] = b"YGGREC\0\x01";
/// Version of the recording container (records, cut entries); the archived segments in it
/// carry the store's own format version.
pub const RECORDING_VERSION: u32 = 1;
/// Bytes of a file's header; the first record's header follows at `FILE_HEADER_LEN +
/// ARCHIVE_ALIGN - RECORD_HEADER_LEN`, so that its payload starts aligned.
pub(crate) const FILE_HEADER_LEN: usize = ARCHIVE_ALIGN;
/// Bytes of a record's header; the payload follows it, [`ARCHIVE_ALIGN`]-aligned.
pub(crate) const RECORD_HEADER_LEN: usize = 64;
/// The four bytes that open every record header.
const RECORD_MAGIC: u32 = u32::from_le_bytes(*b"YREC");
/// Bytes of one segment entry of a cut record: segment id, generation, record offset.
pub(crate) const CUT_ENTRY_LEN: usize = 24;
/// Bytes of the fixed part of a cut record's entry list: flags, set count, removed
/// count, reserved.
const CUT_LIST_HEADER_LEN: usize = 16;
/// Cut-list flag: the list names every segment of the cut, not what changed since the
/// previous cut of the file.
pub(crate) const CUT_CHECKPOINT: u32 = 1;

/// What a record holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RecordKind {
    /// One archived segment: `words = [segment id, generation, session, 0, 0]`.
    Segment = 1,
    /// One cut: `words = [generation, session, writer unix ns, recorder unix ns,
    /// manifest length]`; the payload is the manifest, then the cut's entry list.
    Cut = 2,
}

/// A record's header: kind, payload length and five kind-specific words, then a CRC-32 of
/// the header's first 56 bytes and the payload, and four reserved zero bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RecordHeader {
    pub kind: RecordKind,
    pub len: u64,
    pub words: [u64; 5],
}

/// Why the bytes at an offset are not a complete record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum RecordDefect {
    /// The file ends inside the record (a recorder stopped while writing it).
    Truncated,
    /// The header or payload is not what was written.
    Corrupt(String),
}

/// Where the record after one ending at `end` starts: the next offset whose payload is
/// aligned.
pub(crate) fn next_record_at(end: usize) -> usize {
    (end + RECORD_HEADER_LEN).div_ceil(ARCHIVE_ALIGN) * ARCHIVE_ALIGN - RECORD_HEADER_LEN
}

/// Where the first record of a file starts.
pub(crate) const FIRST_RECORD_AT: usize = FILE_HEADER_LEN + ARCHIVE_ALIGN - RECORD_HEADER_LEN;

/// The header of file number `number` of a recording, created at `created_unix_ns`.
pub(crate) fn file_header(number: u64, created_unix_ns: u64, store_version: u32) -> Vec<u8> {
    let mut h = vec![0u8; FILE_HEADER_LEN];
    h[..8].copy_from_slice(RECORDING_FILE_MAGIC);
    h[8..12].copy_from_slice(&RECORDING_VERSION.to_le_bytes());
    h[12..16].copy_from_slice(&store_version.to_le_bytes());
    h[16..24].copy_from_slice(&number.to_le_bytes());
    h[24..32].copy_from_slice(&created_unix_ns.to_le_bytes());
    h
}

/// The file number a file header names, after checking its magic and versions.
pub(crate) fn read_file_header(bytes: &[u8], store_version: u32) -> Result<u64, String> {
    if bytes.len() < FILE_HEADER_LEN || &bytes[..8] != RECORDING_FILE_MAGIC {
        return Err("not a Yggdrasil recording file (bad magic)".into());
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != RECORDING_VERSION {
        return Err(format!(
            "recording format version {version}, this build reads {RECORDING_VERSION}"
        ));
    }
    let store = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes"));
    if store != store_version {
        return Err(format!(
            "segments archived with store format {store}, this build reads {store_version}"
        ));
    }
    Ok(u64::from_le_bytes(
        bytes[16..24].try_into().expect("8 bytes"),
    ))
}

impl RecordHeader {
    /// The header's 64 bytes for `payload`, its CRC included.
    pub(crate) fn encode(&self, payload: &[u8]) -> [u8; RECORD_HEADER_LEN] {
        let mut h = [0u8; RECORD_HEADER_LEN];
        h[..4].copy_from_slice(&RECORD_MAGIC.to_le_bytes());
        h[4..8].copy_from_slice(&(self.kind as u32).to_le_bytes());
        h[8..16].copy_from_slice(&self.len.to_le_bytes());
        for (i, w) in self.words.iter().enumerate() {
            h[16 + 8 * i..24 + 8 * i].copy_from_slice(&w.to_le_bytes());
        }
        let crc = crc(&h[..56], payload);
        h[56..60].copy_from_slice(&crc.to_le_bytes());
        h
    }

    /// The record at `at` of `file`, its payload's range checked against the file and its
    /// CRC against the bytes.
    pub(crate) fn decode(
        file: &[u8],
        at: usize,
    ) -> Result<(RecordHeader, std::ops::Range<usize>), RecordDefect> {
        let Some(h) = file.get(at..at + RECORD_HEADER_LEN) else {
            return Err(RecordDefect::Truncated);
        };
        let word32 = |i: usize| u32::from_le_bytes(h[i..i + 4].try_into().expect("4 bytes"));
        let word64 = |i: usize| u64::from_le_bytes(h[i..i + 8].try_into().expect("8 bytes"));
        if word32(0) != RECORD_MAGIC {
            // Zeros past the end of what was written (a preallocated or torn tail).
            return Err(if h.iter().all(|&b| b == 0) {
                RecordDefect::Truncated
            } else {
                RecordDefect::Corrupt("no record magic".into())
            });
        }
        let kind = match word32(4) {
            1 => RecordKind::Segment,
            2 => RecordKind::Cut,
            other => {
                return Err(RecordDefect::Corrupt(format!(
                    "unknown record kind {other}"
                )));
            }
        };
        let len = word64(8);
        let start = at + RECORD_HEADER_LEN;
        let end = usize::try_from(len)
            .ok()
            .and_then(|l| start.checked_add(l))
            .ok_or_else(|| RecordDefect::Corrupt(format!("record length {len} overflows")))?;
        let Some(payload) = file.get(start..end) else {
            return Err(RecordDefect::Truncated);
        };
        if crc(&h[..56], payload) != word32(56) {
            return Err(RecordDefect::Corrupt("CRC mismatch".into()));
        }
        if word32(60) != 0 {
            return Err(RecordDefect::Corrupt(
                "reserved header bytes not zero".into(),
            ));
        }
        let words = std::array::from_fn(|i| word64(16 + 8 * i));
        Ok((RecordHeader { kind, len, words }, start..end))
    }
}

/// CRC-32 (IEEE) of a header's first 56 bytes and a payload.
fn crc(header: &[u8], payload: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(header);
    h.update(payload);
    h.finalize()
}

/// One segment a cut names: its id, generation and the offset of its record in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CutEntry {
    pub segment: u64,
    pub generation: u64,
    pub record: u64,
}

/// A cut record's entry list: every segment (a checkpoint) or the segments set and
/// removed since the previous cut of the file.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct CutList {
    pub checkpoint: bool,
    pub set: Vec<CutEntry>,
    pub removed: Vec<u64>,
}

impl CutList {
    /// The list's bytes.
    pub(crate) fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&u32::from(self.checkpoint).to_le_bytes());
        out.extend_from_slice(&(self.set.len() as u32).to_le_bytes());
        out.extend_from_slice(&(self.removed.len() as u32).to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        for e in &self.set {
            out.extend_from_slice(&e.segment.to_le_bytes());
            out.extend_from_slice(&e.generation.to_le_bytes());
            out.extend_from_slice(&e.record.to_le_bytes());
        }
        for id in &self.removed {
            out.extend_from_slice(&id.to_le_bytes());
        }
    }

    /// Reads a list; its counts are checked against the bytes.
    pub(crate) fn decode(bytes: &[u8]) -> Result<CutList, String> {
        let Some(head) = bytes.get(..CUT_LIST_HEADER_LEN) else {
            return Err("cut record too short for its entry list".into());
        };
        let word = |i: usize| u32::from_le_bytes(head[i..i + 4].try_into().expect("4 bytes"));
        let flags = word(0);
        let (set, removed) = (word(4) as usize, word(8) as usize);
        let need = CUT_LIST_HEADER_LEN + set * CUT_ENTRY_LEN + removed * 8;
        if bytes.len() != need {
            return Err(format!(
                "cut entry list of {set} entries and {removed} removals needs {need} bytes, \
                 the record holds {}",
                bytes.len()
            ));
        }
        let u64_at = |i: usize| u64::from_le_bytes(bytes[i..i + 8].try_into().expect("8 bytes"));
        let set = (0..set)
            .map(|i| {
                let at = CUT_LIST_HEADER_LEN + i * CUT_ENTRY_LEN;
                CutEntry {
                    segment: u64_at(at),
                    generation: u64_at(at + 8),
                    record: u64_at(at + 16),
                }
            })
            .collect::<Vec<_>>();
        let removed_at = CUT_LIST_HEADER_LEN + set.len() * CUT_ENTRY_LEN;
        let removed = (0..removed).map(|i| u64_at(removed_at + 8 * i)).collect();
        Ok(CutList {
            checkpoint: flags & CUT_CHECKPOINT != 0,
            set,
            removed,
        })
    }
}

/// Where a cut record's entry list starts: after the manifest, 8-aligned.
pub(crate) fn cut_list_at(manifest_len: usize) -> usize {
    manifest_len.div_ceil(8) * 8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payloads_start_aligned() {
        assert_eq!((FIRST_RECORD_AT + RECORD_HEADER_LEN) % ARCHIVE_ALIGN, 0);
        for end in [200usize, 255, 256, 257, 1000, 4096] {
            let next = next_record_at(end);
            assert!(next >= end);
            assert_eq!((next + RECORD_HEADER_LEN) % ARCHIVE_ALIGN, 0);
        }
    }

    #[test]
    fn a_record_round_trips_and_any_flipped_byte_is_caught() {
        let payload = b"segment bytes".to_vec();
        let header = RecordHeader {
            kind: RecordKind::Segment,
            len: payload.len() as u64,
            words: [7, 3, 99, 0, 0],
        };
        let mut file = vec![0u8; 8];
        file.extend_from_slice(&header.encode(&payload));
        file.extend_from_slice(&payload);
        let (read, range) = RecordHeader::decode(&file, 8).expect("a whole record");
        assert_eq!(read, header);
        assert_eq!(&file[range], payload);
        for i in 8..file.len() {
            let mut bad = file.clone();
            bad[i] ^= 0x40;
            assert!(RecordHeader::decode(&bad, 8).is_err(), "byte {i} flipped");
        }
        assert_eq!(
            RecordHeader::decode(&file[..file.len() - 1], 8),
            Err(RecordDefect::Truncated)
        );
    }

    #[test]
    fn a_cut_list_round_trips_and_wrong_counts_are_refused() {
        let list = CutList {
            checkpoint: true,
            set: vec![CutEntry {
                segment: 5,
                generation: 9,
                record: 192,
            }],
            removed: vec![4, 6],
        };
        let mut bytes = Vec::new();
        list.encode(&mut bytes);
        assert_eq!(CutList::decode(&bytes), Ok(list));
        assert!(CutList::decode(&bytes[..bytes.len() - 8]).is_err());
    }
}
