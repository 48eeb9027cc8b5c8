//! [`YggNodeList`]: the node-id lists queries return, owned by the caller until
//! `ygg_node_list_free`.

use crate::args::Out;
use crate::errors::{FfiResult, YggStatus, guard};
use ygg_store::NodeId;

/// A list of node ids returned by a query, ascending by id, or ranked (nearest first)
/// with `distances`.
///
/// Ownership: the library allocates `ids` and `distances`; the caller owns the list and
/// frees it once with `ygg_node_list_free` (which empties it, so freeing twice is
/// harmless). The list does not borrow the snapshot it came from. An empty list has
/// null pointers. Thread-safety: plain memory, no locking.
#[repr(C)]
#[derive(Debug)]
pub struct YggNodeList {
    /// `len` node ids, or null when `len == 0`.
    pub ids: *mut u64,
    /// `len` distances (metres) for ranked queries (`nearest_*`); null otherwise.
    pub distances: *mut f32,
    /// Number of ids.
    pub len: usize,
}

impl YggNodeList {
    /// The empty list.
    pub(crate) const EMPTY: YggNodeList = YggNodeList {
        ids: std::ptr::null_mut(),
        distances: std::ptr::null_mut(),
        len: 0,
    };

    /// A list of ids.
    pub(crate) fn of_ids(ids: Vec<NodeId>) -> Self {
        Self::build(ids.into_iter().map(|n| n.0).collect(), None)
    }

    /// A ranked list of `(id, distance)`.
    pub(crate) fn of_ranked(ranked: Vec<(NodeId, f32)>) -> Self {
        let (ids, distances) = ranked.into_iter().map(|(n, d)| (n.0, d)).unzip();
        Self::build(ids, Some(distances))
    }

    fn build(ids: Vec<u64>, distances: Option<Vec<f32>>) -> Self {
        if ids.is_empty() {
            return Self::EMPTY;
        }
        let len = ids.len();
        YggNodeList {
            ids: Box::into_raw(ids.into_boxed_slice()).cast(),
            distances: distances.map_or(std::ptr::null_mut(), |d| {
                Box::into_raw(d.into_boxed_slice()).cast()
            }),
            len,
        }
    }
}

/// Frees a list returned by a query and sets it to the empty list. A null `list`, or an
/// empty or already freed list, is accepted and left empty.
///
/// # Safety
/// `list` is null or points to a list filled by this library and not modified since.
/// Thread-safety: do not free one list from two threads.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_node_list_free(list: *mut YggNodeList) -> YggStatus {
    guard("ygg_node_list_free", || {
        if list.is_null() {
            return Ok(());
        }
        // SAFETY: non-null, and a list this library filled by the caller's contract.
        let list = unsafe { &mut *list };
        let taken = std::mem::replace(list, YggNodeList::EMPTY);
        if !taken.ids.is_null() {
            let ids = std::ptr::slice_from_raw_parts_mut(taken.ids, taken.len);
            // SAFETY: `ids` came from `Box<[u64]>::into_raw` with this length in `build`,
            // and the list was not modified (caller's contract); `replace` above makes
            // this the only free.
            drop(unsafe { Box::from_raw(ids) });
        }
        if !taken.distances.is_null() {
            let distances = std::ptr::slice_from_raw_parts_mut(taken.distances, taken.len);
            // SAFETY: as for `ids`: a `Box<[f32]>` of the same length made by `build`.
            drop(unsafe { Box::from_raw(distances) });
        }
        Ok(())
    })
}

/// Writes ids (or the empty list on error) to `out` and passes the error on.
pub(crate) fn deliver_ids(found: FfiResult<Vec<NodeId>>, out: Out<YggNodeList>) -> FfiResult {
    match found {
        Ok(ids) => {
            out.write(YggNodeList::of_ids(ids));
            Ok(())
        }
        Err(e) => {
            out.write(YggNodeList::EMPTY);
            Err(e)
        }
    }
}

/// Writes ranked ids (or the empty list on error) to `out`.
pub(crate) fn deliver_ranked(
    found: FfiResult<Vec<(NodeId, f32)>>,
    out: Out<YggNodeList>,
) -> FfiResult {
    match found {
        Ok(ranked) => {
            out.write(YggNodeList::of_ranked(ranked));
            Ok(())
        }
        Err(e) => {
            out.write(YggNodeList::EMPTY);
            Err(e)
        }
    }
}
