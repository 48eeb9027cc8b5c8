//! The generator's random stream and count arithmetic: [`Gen`], rounding and
//! largest-remainder splits.

use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::params::OfficeParams;

/// The generator: parameters and one random stream, drawn in a fixed order.
pub(super) struct Gen {
    pub(super) rng: ChaCha8Rng,
    pub(super) params: OfficeParams,
    /// `params.scale`, or the smallest positive scale when that is not a positive number.
    pub(super) scale: f64,
    /// The second output of the last Box–Muller draw.
    spare_normal: Option<f64>,
}

/// Points and triangles of one surface patch.
pub(super) type Patch = (Vec<[f64; 3]>, Vec<[u32; 3]>);

impl Gen {
    pub(super) fn new(params: OfficeParams) -> Self {
        let scale = if params.scale.is_finite() && params.scale > 0.0 {
            params.scale
        } else {
            f64::MIN_POSITIVE
        };
        Self {
            rng: ChaCha8Rng::seed_from_u64(params.seed),
            params,
            scale,
            spare_normal: None,
        }
    }

    /// A uniform sample in `[lo, hi)`.
    pub(super) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.rng.r#gen::<f64>()
    }

    /// Standard normal sample (Box–Muller, both outputs used).
    pub(super) fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        let u1 = 1.0 - self.rng.r#gen::<f64>(); // (0, 1]
        let u2 = self.rng.r#gen::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * PI * u2).sin_cos();
        self.spare_normal = Some(r * s);
        r * c
    }

    /// A full-scale count scaled, rounded half to even.
    pub(super) fn count(&self, full: f64) -> usize {
        round_even(full * self.scale)
    }
}

/// `x` rounded half to even, as Python rounds (0 for anything not positive).
pub(super) fn round_even(x: f64) -> usize {
    let r = x.round_ties_even();
    if r.is_finite() && r > 0.0 {
        r as usize
    } else {
        0
    }
}

/// Largest-remainder split of `total` proportional to `weights` (ties to the lower
/// index). Zero or invalid weights split evenly.
pub(super) fn alloc(total: usize, weights: &[f64]) -> Vec<usize> {
    if weights.is_empty() {
        return Vec::new();
    }
    let sum: f64 = weights.iter().filter(|w| w.is_finite() && **w > 0.0).sum();
    let w: Vec<f64> = if sum > 0.0 {
        weights
            .iter()
            .map(|&w| {
                if w.is_finite() && w > 0.0 {
                    w / sum
                } else {
                    0.0
                }
            })
            .collect()
    } else {
        vec![1.0 / weights.len() as f64; weights.len()]
    };
    let raw: Vec<f64> = w.iter().map(|w| total as f64 * w).collect();
    let mut base: Vec<usize> = raw.iter().map(|r| r.floor() as usize).collect();
    let assigned: usize = base.iter().sum();
    let rem = total.saturating_sub(assigned);
    let mut order: Vec<usize> = (0..w.len()).collect();
    order.sort_by(|&a, &b| {
        let fa = raw[a] - base[a] as f64;
        let fb = raw[b] - base[b] as f64;
        fb.total_cmp(&fa).then(a.cmp(&b))
    });
    for &i in order.iter().cycle().take(rem) {
        base[i] += 1;
    }
    base
}

/// Euclidean distance.
pub(super) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// A point as a file stores it.
pub(super) fn f32x3(p: [f64; 3]) -> [f32; 3] {
    p.map(|x| x as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alloc_splits_exactly_by_largest_remainder() {
        assert_eq!(alloc(10, &[1.0, 1.0, 1.0]), vec![4, 3, 3]);
        assert_eq!(alloc(7, &[0.0, 0.0]), vec![4, 3]);
        assert_eq!(alloc(5, &[3.0, 1.0]).iter().sum::<usize>(), 5);
        assert!(alloc(3, &[]).is_empty());
    }
}
