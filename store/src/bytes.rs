//! Aligned bytes for archived data: [`SegmentBytes`] and [`archive`], at the bottom of
//! the crate (the snapshot layout and the reader-built indexes both archive into them).

/// Alignment an archived segment needs to be accessed in place (kd-tree leaves in archived
/// indexes need 128 bytes). Whatever carries segments (a `.ygg` file, the shared-memory
/// transport) must start each one at a multiple of it.
pub const ARCHIVE_ALIGN: usize = 128;

/// Bytes aligned for archived segments.
pub type SegmentBytes = rkyv::util::AlignedVec<ARCHIVE_ALIGN>;

/// Archives any serializable value into 128-aligned bytes.
pub fn archive<T>(value: &T) -> SegmentBytes
where
    T: for<'a> rkyv::Serialize<
            rkyv::api::high::HighSerializer<
                SegmentBytes,
                rkyv::ser::allocator::ArenaHandle<'a>,
                rkyv::rancor::Error,
            >,
        >,
{
    rkyv::api::high::to_bytes_in::<_, rkyv::rancor::Error>(value, SegmentBytes::new())
        .expect("serializing into memory cannot fail")
}
