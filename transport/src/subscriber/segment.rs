//! A received segment held in shared memory: the reader's mapping module.
//!
//! The only unsafe code of the reader. A [`HeldSegment`] owns an iceoryx2 sample (so the
//! writer cannot reuse the chunk) and caches the validated byte range of its payload.
#![expect(
    unsafe_code,
    reason = "caches a validated view into a held shared-memory sample and shares it across threads"
)]

use iceoryx2::sample::Sample;

use crate::protocol::{
    BLOCK_SIZE, Block128, SEGMENT_ALIGN, SegmentError, SegmentHeader, SegmentKind,
    check_stream_header,
};
use crate::service::Ipc;

/// A received iceoryx2 sample of segment blocks.
pub(crate) type SegmentSample = Sample<Ipc, [Block128], SegmentHeader>;

/// A received, header-checked segment. Keeps its shared-memory chunk alive until dropped.
pub(crate) struct HeldSegment {
    ptr: *const u8,
    len: usize,
    kind: SegmentKind,
    header: SegmentHeader,
    _sample: SegmentSample,
}

// SAFETY: `SegmentSample` of the thread-safe service is `Send`; the raw pointer points into the
// sample's chunk, which stays mapped and owned by this value wherever it moves.
unsafe impl Send for HeldSegment {}
// SAFETY: shared access only reads `ptr..ptr+len` (immutable once sent: the writer never writes
// a chunk that a subscriber holds) and plain copied fields. The sample itself is only touched
// on drop, which needs exclusive access.
unsafe impl Sync for HeldSegment {}

impl HeldSegment {
    /// Checks the sample's header (kind, id, length against the payload size), copying the
    /// header once so that later changes in shared memory cannot invalidate the check.
    pub(crate) fn new(sample: SegmentSample) -> Result<Self, SegmentError> {
        let header = *sample.user_header();
        let blocks: &[Block128] = sample.payload();
        let ptr = blocks.as_ptr().cast::<u8>();
        let payload_bytes = blocks.len() * BLOCK_SIZE;
        let (kind, len) = check_stream_header(&header, payload_bytes)?;
        // `Block128` is 128-aligned, so a misaligned payload would be an iceoryx2 bug; checked
        // anyway because the archives inside rely on it.
        if !ptr.addr().is_multiple_of(SEGMENT_ALIGN) {
            return Err(SegmentError::Misaligned {
                address: ptr.addr(),
            });
        }
        Ok(Self {
            ptr,
            len,
            kind,
            header,
            _sample: sample,
        })
    }

    /// The meaningful bytes of the payload (128-byte aligned start).
    pub(crate) fn bytes(&self) -> &[u8] {
        // SAFETY: `ptr` is the start of the sample's payload, which holds at least `len` bytes
        // (checked in `new` against the payload size iceoryx2 reports) and stays mapped while
        // `self._sample` lives, i.e. at least as long as the returned borrow of `self`. Any byte
        // is a valid `u8`; the writer does not write a chunk while a subscriber holds it.
        unsafe { core::slice::from_raw_parts(self.ptr, self.len) }
    }

    /// The header as received.
    pub(crate) fn header(&self) -> &SegmentHeader {
        &self.header
    }

    /// What the segment carries.
    pub(crate) fn kind(&self) -> SegmentKind {
        self.kind
    }

    /// `(session, generation)`: which publish of its segment id this is.
    pub(crate) fn version(&self) -> (u64, u64) {
        (self.header.session, self.header.generation)
    }
}

impl std::fmt::Debug for HeldSegment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HeldSegment")
            .field("header", &self.header)
            .field("len", &self.len)
            .finish_non_exhaustive()
    }
}
