//! The synthetic segment content of `ygg-test-writer`, and its check.
//!
//! A synthetic layer segment is `YGGT`, the low 32 bits of the segment id (u32 LE), the
//! generation (u64 LE), then
//! one byte repeated. Readers use it to verify that a snapshot pairs every layer with the
//! generation its manifest names. It is a transport test aid, not part of the protocol.

use ygg_transport::protocol::ManifestEntry;

/// Magic at the start of a synthetic segment.
pub const MAGIC: &[u8; 4] = b"YGGT";

/// Smallest synthetic segment.
pub const MIN_LEN: usize = 16;

/// The byte repeated after the 16-byte head.
pub fn fill_byte(layer_id: u64, generation: u64) -> u8 {
    // Truncation intended: any byte that depends on both values.
    (layer_id.wrapping_mul(31) ^ generation) as u8
}

/// Writes the synthetic segment of `layer_id` / `generation` into `buf`.
///
/// # Panics
///
/// If `buf` is shorter than [`MIN_LEN`].
pub fn write(buf: &mut [u8], layer_id: u64, generation: u64) {
    let (head, rest) = buf.split_at_mut(MIN_LEN);
    head[0..4].copy_from_slice(MAGIC);
    // Truncation intended: test segment ids are small.
    head[4..8].copy_from_slice(&(layer_id as u32).to_le_bytes());
    head[8..16].copy_from_slice(&generation.to_le_bytes());
    rest.fill(fill_byte(u64::from(layer_id as u32), generation));
}

/// Whether `bytes` look like a synthetic segment at all.
pub fn is_synthetic(bytes: &[u8]) -> bool {
    bytes.len() >= MIN_LEN && bytes[..4] == MAGIC[..]
}

/// Checks that `bytes` is the synthetic segment that `entry` names (the head, and the fill
/// byte every 4 KiB and at the end).
///
/// # Errors
///
/// A description of the first mismatch.
pub fn check(bytes: &[u8], entry: ManifestEntry) -> Result<(), String> {
    if !is_synthetic(bytes) {
        return Err(format!("layer {}: not a synthetic segment", entry.layer_id));
    }
    let mut id = [0; 4];
    id.copy_from_slice(&bytes[4..8]);
    let mut generation = [0; 8];
    generation.copy_from_slice(&bytes[8..16]);
    let (id, generation) = (
        u64::from(u32::from_le_bytes(id)),
        u64::from_le_bytes(generation),
    );
    // Truncation intended: the head holds the id's low 32 bits.
    if (id, generation) != (u64::from(entry.layer_id as u32), entry.generation) {
        return Err(format!(
            "layer {} generation {} holds layer {id} generation {generation}",
            entry.layer_id, entry.generation
        ));
    }
    let expected = fill_byte(id, generation);
    let rest = &bytes[MIN_LEN..];
    let probes = (0..rest.len())
        .step_by(4096)
        .chain(rest.len().checked_sub(1));
    for at in probes {
        if rest[at] != expected {
            return Err(format!(
                "layer {id} generation {generation}: byte {} is {:#04x}, expected {expected:#04x}",
                at + MIN_LEN,
                rest[at]
            ));
        }
    }
    Ok(())
}
