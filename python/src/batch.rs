//! Running one query per input row, spread over the machine's cores (the caller has
//! released the GIL).

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
