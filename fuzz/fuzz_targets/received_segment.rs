//! What a reader receives from shared memory: a segment header and its payload. The
//! transport's header and manifest-prefix checks, then the store's validation of the
//! segment its id names (a part, a point or tree chunk, the structure) or of the
//! manifest, as `SceneReader` runs them.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ygg_store::snapshot::{
    SegmentBytes, is_chunk_segment_id, is_structure_segment_id, is_tree_chunk_segment_id,
    validate_chunk, validate_layer, validate_manifest, validate_structure, validate_tree_chunk,
};
use ygg_transport::protocol::{
    SegmentHeader, SegmentKind, check_segment_header, decode_manifest_prefix,
};

/// Bytes of the fixed header fields, in `SegmentHeader` order.
const HEADER_LEN: usize = 56;

fuzz_target!(|data: &[u8]| {
    let Some((head, payload)) = data.split_at_checked(HEADER_LEN) else {
        return;
    };
    let u16_at = |i: usize| u16::from_le_bytes([head[i], head[i + 1]]);
    let u32_at = |i: usize| u32::from_le_bytes(head[i..i + 4].try_into().unwrap());
    let u64_at = |i: usize| u64::from_le_bytes(head[i..i + 8].try_into().unwrap());
    let header = SegmentHeader {
        magic: u32_at(0),
        version: u16_at(4),
        kind: u16_at(6),
        flags: u32_at(8),
        reserved: u32_at(12),
        layer_id: u64_at(16),
        session: u64_at(24),
        generation: u64_at(32),
        len: u64_at(40),
        published_unix_ns: u64_at(48),
    };
    // Payloads arrive 128-byte aligned, in whole blocks.
    let mut aligned = SegmentBytes::with_capacity(payload.len());
    aligned.extend_from_slice(payload);
    let is_manifest = header.kind == SegmentKind::Manifest as u16;
    let kind = if is_manifest {
        SegmentKind::Manifest
    } else {
        SegmentKind::Layer
    };
    let layer = (!is_manifest).then_some(header.layer_id);
    let Ok(len) = check_segment_header(&header, kind, layer, aligned.len()) else {
        return;
    };
    let bytes = &aligned[..len];
    if is_manifest {
        if let Ok((_, offset)) = decode_manifest_prefix(bytes) {
            let _ = validate_manifest(&bytes[offset..], "fuzz manifest");
        }
    } else if is_structure_segment_id(header.layer_id) {
        let _ = validate_structure(bytes, "fuzz structure");
    } else if is_tree_chunk_segment_id(header.layer_id) {
        let _ = validate_tree_chunk(bytes, "fuzz tree chunk");
    } else if is_chunk_segment_id(header.layer_id) {
        let _ = validate_chunk(bytes, "fuzz point chunk");
    } else {
        let _ = validate_layer(bytes, "fuzz layer");
    }
});
