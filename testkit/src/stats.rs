//! Latency statistics: median and p99 by nearest rank, the one definition every test,
//! bench and demo report uses.
//!
//! The q-quantile of n samples is the ⌈q·n⌉-th smallest (1-based; at least the first):
//! the median of an even count is the lower middle, and the p99 of fewer than 100
//! samples is the maximum. `NaN` samples are ignored.
//!
//! ```
//! use ygg_testkit::stats;
//! let ns: Vec<f64> = (1..=100).map(f64::from).collect();
//! assert_eq!(stats::median_p99(&ns), Some((50.0, 99.0)));
//! assert_eq!(stats::median(&[3.0, 1.0, 2.0, 4.0]), Some(2.0));
//! assert_eq!(stats::median_p99(&[]), None);
//! ```

/// The `q`-quantile (`0 < q <= 1`) of `sorted` (ascending) by nearest rank; `None` when
/// empty.
pub fn nearest_rank<T: Copy>(sorted: &[T], q: f64) -> Option<T> {
    let n = sorted.len();
    if n == 0 {
        return None;
    }
    let rank = ((n as f64 * q).ceil() as usize).clamp(1, n);
    Some(sorted[rank - 1])
}

/// The samples without `NaN`, ascending.
fn sorted(samples: &[f64]) -> Vec<f64> {
    let mut v: Vec<f64> = samples.iter().copied().filter(|x| !x.is_nan()).collect();
    v.sort_unstable_by(f64::total_cmp);
    v
}

/// Median and 99th percentile of `samples` (any order) by nearest rank; `None` when
/// there are none.
pub fn median_p99(samples: &[f64]) -> Option<(f64, f64)> {
    let v = sorted(samples);
    Some((nearest_rank(&v, 0.5)?, nearest_rank(&v, 0.99)?))
}

/// [`median_p99`] of nanosecond samples, in microseconds; `NaN` when there are none (the
/// form report tables print).
pub fn median_p99_us(samples_ns: &[f64]) -> (f64, f64) {
    median_p99(samples_ns).map_or((f64::NAN, f64::NAN), |(m, p)| (m / 1e3, p / 1e3))
}

/// Median of `samples` (any order) by nearest rank; `None` when there are none.
pub fn median(samples: &[f64]) -> Option<f64> {
    nearest_rank(&sorted(samples), 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_takes_the_lower_middle_and_the_maximum_of_small_samples() {
        assert_eq!(median(&[1.0, 2.0]), Some(1.0));
        assert_eq!(median_p99(&[7.0]), Some((7.0, 7.0)));
        assert_eq!(median_p99(&[5.0, 1.0, 9.0]), Some((5.0, 9.0)));
        assert_eq!(median(&[f64::NAN, 2.0]), Some(2.0));
        assert_eq!(median(&[f64::NAN]), None);
        assert_eq!(nearest_rank(&[1u32, 2, 3, 4], 0.75), Some(3));
    }
}
