//! Byte view of a loaned, not yet initialised sample.
//!
//! The only unsafe code of the writer: it lets the store serialize straight into shared memory
//! (DESIGN.md §8: exact-size serialization into a loaned sample avoids a copy).
#![expect(
    unsafe_code,
    reason = "viewing a loaned shared-memory payload as bytes avoids zeroing or copying it"
)]

use core::mem::MaybeUninit;

use crate::protocol::{BLOCK_SIZE, Block128, Ipc, SegmentHeader};
use iceoryx2::sample_mut::SampleMut;
use iceoryx2::sample_mut_uninit::SampleMutUninit;

/// An uninitialised loaned sample of blocks.
pub type UninitSample = SampleMutUninit<Ipc, [MaybeUninit<Block128>], SegmentHeader>;

/// An initialised loaned sample of blocks, ready to send.
pub type InitSample = SampleMut<Ipc, [Block128], SegmentHeader>;

/// Lets `fill` write the first `len` bytes of the sample's payload, zeroes the rest of the
/// last block, and returns the sample as initialised.
///
/// # Errors
///
/// Whatever `fill` returns; the sample is then dropped (returned to the pool) unsent.
pub fn fill_sample<E>(
    mut sample: UninitSample,
    len: usize,
    fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
) -> Result<InitSample, E> {
    let blocks = sample.payload_mut();
    let total = blocks.len() * BLOCK_SIZE;
    assert!(len <= total, "loaned sample is smaller than requested");
    // SAFETY: `blocks` is `blocks.len()` contiguous `MaybeUninit<Block128>`; a `Block128` is
    // `[u8; 128]` with no padding, so the region is exactly `total` bytes, valid for writes and
    // exclusively borrowed through `sample` for the lifetime of `bytes`. The memory is a
    // shared-memory mapping (mmap), never compiler-tracked uninitialised memory: every byte holds
    // either the kernel's zero fill or a byte written by an earlier sample, and every bit pattern
    // is a valid `u8`.
    let bytes: &mut [u8] =
        unsafe { core::slice::from_raw_parts_mut(blocks.as_mut_ptr().cast::<u8>(), total) };
    let (payload, tail) = bytes.split_at_mut(len);
    fill(payload)?;
    tail.fill(0);
    // SAFETY: every byte of every block was initialised above (see the SAFETY comment of
    // `bytes`; the tail was zeroed explicitly) and any byte pattern is a valid `Block128`.
    Ok(unsafe { sample.assume_init() })
}
