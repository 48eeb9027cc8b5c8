//! Byte view of a loaned, not yet initialised sample, and the pages a chunk gives back.
//!
//! The only unsafe code of the writer: it lets the store serialize straight into shared memory
//! (DESIGN.md §8: exact-size serialization into a loaned sample avoids a copy), and releases the
//! shared-memory pages of a loaned chunk that the new segment does not use.
//!
//! Why pages are released: every chunk of iceoryx2's pool has the size of the largest segment
//! (rounded up to a power of two), and freed chunks are reused last-in first-out by whatever
//! segment comes next. Without the release, every chunk that ever held a large segment keeps
//! its tmpfs pages: a writer serving the office touched ~1 MB per chunk in use, and its
//! resident shared memory grew by ~100 MB a minute under reader churn (`ygg-soak`). With
//! it, the pages written into the pool stay near a budget of four times the newest segments
//! (at least 16 MiB; [`ChunkPages`]).
#![expect(
    unsafe_code,
    reason = "viewing a loaned shared-memory payload as bytes avoids zeroing or copying it; \
              releasing a loaned chunk's unused pages needs madvise on its address range \
              and the page size from sysconf"
)]

use core::mem::MaybeUninit;
use std::collections::HashMap;

use crate::protocol::{BLOCK_SIZE, Block128, SegmentHeader};
use crate::service::Ipc;
use iceoryx2::sample_mut::SampleMut;
use iceoryx2::sample_mut_uninit::SampleMutUninit;

/// An uninitialised loaned sample of blocks.
pub type UninitSample = SampleMutUninit<Ipc, [MaybeUninit<Block128>], SegmentHeader>;

/// An initialised loaned sample of blocks, ready to send.
pub type InitSample = SampleMut<Ipc, [Block128], SegmentHeader>;

/// Pages the pool may hold without any being released: at least this many bytes...
const RESIDENT_FLOOR: usize = 16 << 20;
/// ... or this many times the bytes of the newest segment of every id (about the snapshot).
const RESIDENT_FACTOR: usize = 4;

/// What one publisher wrote into its pool's chunks, so that it can give back the pages a chunk
/// no longer needs when it is loaned again for a smaller segment.
///
/// Every loan asks for the largest slice loaned so far ([`ChunkPages::loan_blocks`]): iceoryx2
/// sizes every chunk of the current pool for it, so the whole loaned range, and every page a
/// previous segment of this publisher wrote into the chunk, belongs to the loan. Pages are only
/// ever released inside the range of the sample the publisher holds on loan.
///
/// Releasing has a price: the next larger segment written into the chunk faults its pages in
/// afresh, in the writer and in every reader (republishing the whole office every time went
/// from 4.8 to 23 ms when every loan released). So pages are released only while the pages
/// written into the pool exceed a budget: [`RESIDENT_FACTOR`] times the newest segment of each
/// id, at least [`RESIDENT_FLOOR`].
#[derive(Debug)]
pub struct ChunkPages {
    /// Slice length (blocks) of every loan: the largest asked for so far.
    loan_blocks: usize,
    /// Per chunk (the address of its payload), the end (bytes from the payload start) of what
    /// was written into it since its pages were last released.
    written: HashMap<usize, usize>,
    /// The sum of `written`.
    resident: usize,
    /// Per chunk of the current pool, the bytes from its payload start whose tmpfs pages are
    /// known to exist (written by this publisher and not released since): a segment that fits
    /// in them needs no new shared memory. Cleared whenever the loans grow, since iceoryx2 may
    /// then map a new pool whose chunks reuse old addresses.
    backed: HashMap<usize, usize>,
    /// Bytes of the newest segment of each id, and their sum.
    newest: HashMap<u64, usize>,
    newest_total: usize,
    /// Resident bytes below which nothing is released ([`RESIDENT_FLOOR`]) and the multiple
    /// of `newest_total` likewise ([`RESIDENT_FACTOR`]).
    floor: usize,
    factor: usize,
    page: usize,
}

impl ChunkPages {
    /// Starts with loans of `initial_blocks` (the pool's initial slice length).
    pub fn new(initial_blocks: usize) -> Self {
        let mut pages = Self {
            loan_blocks: initial_blocks.max(1),
            written: HashMap::new(),
            resident: 0,
            backed: HashMap::new(),
            newest: HashMap::new(),
            newest_total: 0,
            floor: RESIDENT_FLOOR,
            factor: RESIDENT_FACTOR,
            page: 4096,
        };
        match page_size() {
            Some(page) => pages.page = page,
            // Without the page size nothing can be released safely: never release.
            None => pages.floor = usize::MAX,
        }
        pages
    }

    /// The slice length to loan for a segment of `blocks` blocks: the largest loaned so far.
    pub fn loan_blocks(&mut self, blocks: usize) -> usize {
        if blocks > self.loan_blocks {
            self.loan_blocks = blocks;
            self.backed.clear();
        }
        self.loan_blocks
    }

    /// Whether a segment of `blocks` blocks is loaned from the current pool (no larger loan,
    /// so iceoryx2 maps no new pool for it).
    pub fn fits_current_pool(&self, blocks: usize) -> bool {
        blocks <= self.loan_blocks
    }

    /// Bytes from the start of the chunk whose payload starts at address `payload` whose
    /// pages are known to exist in the current pool (0 for a chunk not written since): the
    /// bytes written there, up to the end of the page the last of them is in.
    pub fn backed(&self, payload: usize) -> usize {
        match self.backed.get(&payload) {
            Some(&written) if written > 0 => {
                (payload + written).next_multiple_of(self.page) - payload
            }
            _ => 0,
        }
    }

    /// Records that the chunk whose loaned payload starts at address `payload` (`total` bytes
    /// on loan) now holds `len` bytes of segment `id`, and, while the pool holds more than its
    /// budget, returns the whole pages past them that still hold bytes of an earlier segment:
    /// `(start address, length)`, inside the loaned range.
    fn stale_range(
        &mut self,
        payload: usize,
        total: usize,
        id: u64,
        len: usize,
    ) -> Option<(usize, usize)> {
        let old_len = self.newest.insert(id, len).unwrap_or(0);
        self.newest_total = self.newest_total + len - old_len;
        let page = self.page;
        let old_written = self.written.get(&payload).copied().unwrap_or(0);
        let dirty = old_written.min(total);
        let start = (payload + len).next_multiple_of(page);
        let end = (payload + dirty)
            .next_multiple_of(page)
            .min((payload + total) / page * page);
        let budget = self.floor.max(self.factor * self.newest_total);
        let (written, release) = if end > start && self.resident > budget {
            // The page `len` ends in keeps its older bytes past `len`.
            (start - payload, Some((start, end - start)))
        } else {
            (dirty.max(len), None)
        };
        self.written.insert(payload, written);
        // What was known to be backed in this pool, plus what was just written; a release
        // leaves the pages up to `start`.
        let backed = match release {
            Some((start, _)) => start - payload,
            None => self.backed.get(&payload).copied().unwrap_or(0).max(len),
        };
        self.backed.insert(payload, backed);
        self.resident = self.resident + written - old_written;
        release
    }
}

/// The size of a memory page, from `sysconf` (rustix's `page_size` reads the auxiliary
/// vector in a way that crashes under Valgrind).
fn page_size() -> Option<usize> {
    // SAFETY: sysconf(3) takes no pointers and only reads a constant of the system.
    let size = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    usize::try_from(size).ok().filter(|&s| s.is_power_of_two())
}

/// Lets `fill` write the first `len` bytes of the sample's payload, zeroes the rest of the
/// block `len` ends in, releases the pages of the chunk that held bytes of an earlier, larger
/// segment past that (they read as zeros again), and returns the sample as initialised.
///
/// # Errors
///
/// Whatever `fill` returns; the sample is then dropped (returned to the pool) unsent.
pub fn fill_sample<E>(
    mut sample: UninitSample,
    len: usize,
    pages: &mut ChunkPages,
    fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
) -> Result<InitSample, E> {
    let blocks = sample.payload_mut();
    let total = blocks.len() * BLOCK_SIZE;
    assert!(len <= total, "loaned sample is smaller than requested");
    let payload = blocks.as_mut_ptr().cast::<u8>();
    // SAFETY: `blocks` is `blocks.len()` contiguous `MaybeUninit<Block128>`; a `Block128` is
    // `[u8; 128]` with no padding, so the region is exactly `total` bytes, valid for writes and
    // exclusively borrowed through `sample` for the lifetime of `bytes`. The memory is a
    // shared-memory mapping (mmap), never compiler-tracked uninitialised memory: every byte holds
    // either the kernel's zero fill or a byte written by an earlier sample, and every bit pattern
    // is a valid `u8`.
    let bytes: &mut [u8] = unsafe { core::slice::from_raw_parts_mut(payload, total) };
    let (content, tail) = bytes.split_at_mut(len);
    fill(content)?;
    let block_end = len.next_multiple_of(BLOCK_SIZE).min(total);
    tail[..block_end - len].fill(0);
    let id = sample.user_header().layer_id;
    if let Some((start, range_len)) = pages.stale_range(payload.addr(), total, id, len) {
        // SAFETY: `start..start + range_len` lies inside `payload..payload + total` (the range
        // `stale_range` returns is clamped to `total` and starts after `len`), which is the
        // payload of the sample this function holds on loan: no other process reads or writes
        // it until the sample is sent, and no Rust reference into it is used after this call
        // (`bytes` is not touched again). The range is page aligned and mapped shared and
        // writable, so MADV_REMOVE frees its tmpfs pages, which then read as zeros. A failure
        // (another kernel, another file system) only means the pages stay: it is ignored.
        let _ = unsafe {
            rustix::mm::madvise(
                start as *mut core::ffi::c_void,
                range_len,
                rustix::mm::Advice::LinuxRemove,
            )
        };
    }
    // SAFETY: every byte of every block was initialised above (see the SAFETY comment of
    // `bytes`; the rest of the last written block was zeroed explicitly, released pages read as
    // zeros) and any byte pattern is a valid `Block128`.
    Ok(unsafe { sample.assume_init() })
}

#[cfg(test)]
mod tests {
    use super::ChunkPages;

    /// Pages that release whenever a chunk holds stale whole pages (no budget).
    fn always_releasing() -> ChunkPages {
        let mut pages = ChunkPages::new(4);
        pages.floor = 0;
        pages.factor = 0;
        pages
    }

    #[test]
    fn releases_only_pages_a_larger_segment_left_behind() {
        let mut pages = always_releasing();
        let page = pages.page;
        let base = 64 * page;
        let total = 16 * page;
        assert_eq!(pages.stale_range(base, total, 1, 10 * page + 5), None);
        // Smaller now: pages 3..=10 held bytes of the earlier segment.
        assert_eq!(
            pages.stale_range(base, total, 1, 3 * page),
            Some((base + 3 * page, 8 * page))
        );
        assert_eq!(
            pages.stale_range(base, total, 1, page),
            Some((base + page, 2 * page))
        );
        // Growing or equal: nothing to release.
        assert_eq!(pages.stale_range(base, total, 1, 2 * page), None);
        assert_eq!(pages.stale_range(base, total, 1, 2 * page), None);
        // Another chunk is tracked on its own.
        assert_eq!(pages.stale_range(base + total, total, 2, 1), None);
        assert_eq!(pages.resident, 2 * page + 1);
    }

    #[test]
    fn keeps_partial_pages_at_both_ends() {
        let mut pages = always_releasing();
        let page = pages.page;
        // A payload that starts 256 bytes into a page, with 4 pages on loan.
        let payload = 64 * page + 256;
        let total = 4 * page;
        assert_eq!(pages.stale_range(payload, total, 1, 3 * page), None);
        // The page holding byte 100 stays; the last page of the loan is not whole: stays.
        assert_eq!(
            pages.stale_range(payload, total, 1, 100),
            Some((65 * page, 3 * page))
        );
        // The page the payload starts in also holds the chunk's headers: never released.
        assert_eq!(pages.stale_range(payload, total, 1, 0), None);
    }

    #[test]
    fn never_reaches_past_the_loaned_range() {
        let mut pages = always_releasing();
        let page = pages.page;
        let base = 8 * page;
        assert_eq!(pages.stale_range(base, 8 * page, 1, 8 * page), None);
        // The same address loaned with a smaller slice (a new pool): clamped to it.
        assert_eq!(
            pages.stale_range(base, 2 * page, 1, 0),
            Some((base, 2 * page))
        );
    }

    #[test]
    fn releases_only_while_the_pool_holds_more_than_its_budget() {
        let mut pages = ChunkPages::new(4);
        let page = pages.page;
        pages.floor = 10 * page;
        let total = 16 * page;
        // Two chunks written with 8 pages each: 16 pages resident, budget 4 x 8 pages.
        assert_eq!(pages.stale_range(0, total, 1, 8 * page), None);
        assert_eq!(pages.stale_range(total, total, 2, 8 * page), None);
        // Segment 1 shrinks to a page; the pool is within 4 x 9 pages: kept.
        assert_eq!(pages.stale_range(0, total, 1, page), None);
        // Segment 2 shrinks too: the budget is the floor (10 pages), 16 are resident.
        assert_eq!(
            pages.stale_range(total, total, 2, page),
            Some((total + page, 7 * page))
        );
        assert_eq!(pages.resident, 9 * page);
    }

    #[test]
    fn knows_which_pages_a_chunk_holds_until_the_pool_may_change() {
        let mut pages = always_releasing();
        let page = pages.page;
        let total = 16 * page;
        assert_eq!(pages.backed(0), 0);
        pages.stale_range(0, total, 1, 5 * page + 1);
        // The page holding the last byte is whole.
        assert_eq!(pages.backed(0), 6 * page);
        // Smaller: the pages past the page it ends in are released.
        pages.stale_range(0, total, 1, page + 1);
        assert_eq!(pages.backed(0), 2 * page);
        // A larger loan may map a new pool at the same addresses: nothing is known.
        assert!(pages.fits_current_pool(4));
        assert!(!pages.fits_current_pool(5));
        pages.loan_blocks(5);
        assert_eq!(pages.backed(0), 0);
        // The chunk's earlier bytes are not taken as backed in the new pool.
        pages.floor = usize::MAX;
        pages.stale_range(0, total, 1, page);
        assert_eq!(pages.backed(0), page);
    }

    #[test]
    fn loans_the_largest_slice_asked_for() {
        let mut pages = ChunkPages::new(4);
        assert_eq!(pages.loan_blocks(2), 4);
        assert_eq!(pages.loan_blocks(9), 9);
        assert_eq!(pages.loan_blocks(3), 9);
    }
}
