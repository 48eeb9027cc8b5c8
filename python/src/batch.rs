//! Running one query per input row, spread over the machine's cores (the caller has
//! released the GIL), and the ids batch answers hold.

use numpy::IntoPyArray;
use pyo3::prelude::*;
use ygg_store::NodeId;

use crate::errors::QueryError;

/// The id a batch answer of object ids holds for "no object": -1, in an `int64` array.
/// Every Spark-DSG object id is below 2**63 (its symbol byte is ASCII), so no id takes it.
pub const NO_NODE: i64 = -1;

/// Batch answers as `int64` ids, [`NO_NODE`] for none (object ids).
///
/// Raises `QueryError` for an id of 2**63 or more, which an `int64` cannot hold.
pub fn signed_ids(found: impl IntoIterator<Item = Option<NodeId>>) -> PyResult<Vec<i64>> {
    found
        .into_iter()
        .map(|n| match n {
            None => Ok(NO_NODE),
            Some(n) => i64::try_from(n.0).map_err(|_| {
                QueryError::new_err(format!(
                    "node id {} does not fit a batch answer's int64 (ids must be below 2**63)",
                    n.0
                ))
            }),
        })
        .collect()
}

/// Batch answers as a `numpy.ma` masked `uint64` array, masked for none (node ids, which
/// use all 64 bits: the layouts' mesh nodes are above 2**63).
pub fn masked_ids<'py>(py: Python<'py>, found: &[Option<NodeId>]) -> PyResult<Bound<'py, PyAny>> {
    let ids: Vec<u64> = found.iter().map(|n| n.map_or(0, |n| n.0)).collect();
    let mask: Vec<bool> = found.iter().map(Option::is_none).collect();
    py.import("numpy.ma")?.call_method1(
        "masked_array",
        (ids.into_pyarray(py), mask.into_pyarray(py)),
    )
}

/// Inputs per thread below which a batch runs on the calling thread alone.
const MIN_PER_THREAD: usize = 4096;

/// `f` applied to every element of `inputs`, in order; the first error (in input order)
/// wins. Large batches are cut into one contiguous chunk per core.
pub fn map<I, T, E, F>(inputs: &[I], f: F) -> Result<Vec<T>, E>
where
    I: Sync,
    T: Send,
    E: Send,
    F: Fn(&I) -> Result<T, E> + Sync,
{
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(inputs.len() / MIN_PER_THREAD)
        .max(1);
    if threads == 1 {
        return inputs.iter().map(&f).collect();
    }
    let chunk = inputs.len().div_ceil(threads);
    let f = &f;
    std::thread::scope(|s| {
        let handles: Vec<_> = inputs
            .chunks(chunk)
            .map(|part| s.spawn(move || part.iter().map(f).collect::<Result<Vec<T>, E>>()))
            .collect();
        let mut out = Vec::with_capacity(inputs.len());
        for h in handles {
            match h.join() {
                Ok(part) => out.extend(part?),
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
        Ok(out)
    })
}
