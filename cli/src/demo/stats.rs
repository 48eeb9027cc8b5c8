//! Latency statistics of the roles' summaries: median and p99 by nearest rank (the
//! definition every Yggdrasil report uses).
//!
//! The q-quantile of n samples is the ⌈q·n⌉-th smallest (1-based; at least the first):
//! the median of an even count is the lower middle, and the p99 of fewer than 100
//! samples is the maximum. `NaN` samples are ignored.

/// Median and 99th percentile of `samples` (any order) by nearest rank; `None` when
/// there are none.
pub fn median_p99(samples: &[f64]) -> Option<(f64, f64)> {
    let mut v: Vec<f64> = samples.iter().copied().filter(|x| !x.is_nan()).collect();
    v.sort_unstable_by(f64::total_cmp);
    let rank = |q: f64| v[((v.len() as f64 * q).ceil() as usize).clamp(1, v.len()) - 1];
    (!v.is_empty()).then(|| (rank(0.5), rank(0.99)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_takes_the_lower_middle_and_the_maximum_of_small_samples() {
        assert_eq!(median_p99(&[1.0, 2.0]), Some((1.0, 2.0)));
        assert_eq!(median_p99(&[7.0]), Some((7.0, 7.0)));
        assert_eq!(median_p99(&[5.0, 1.0, 9.0]), Some((5.0, 9.0)));
        assert_eq!(median_p99(&[f64::NAN, 2.0]), Some((2.0, 2.0)));
        assert_eq!(median_p99(&[f64::NAN]), None);
        let ns: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(median_p99(&ns), Some((50.0, 99.0)));
    }
}
