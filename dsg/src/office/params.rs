//! [`OfficeParams`]: what the office generator is asked for.

/// Parameters of [`generate`](super::generate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OfficeParams {
    /// Random seed; equal seeds (and scales) give equal graphs.
    pub seed: u64,
    /// Size multiplier: `1.0` is the uHumans2 office (354,885 vertices), `0.02` a
    /// tiny fixture, `10` / `100` for scaling curves (100 needs about 2 GB).
    /// Non-finite or non-positive values are treated as the smallest scale (every
    /// count at its minimum).
    pub scale: f64,
}

impl Default for OfficeParams {
    /// Seed 7 (the data files' seed), scale 1.
    fn default() -> Self {
        Self {
            seed: 7,
            scale: 1.0,
        }
    }
}
