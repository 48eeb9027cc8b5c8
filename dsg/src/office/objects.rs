//! Objects: placement in their rooms, shared claims and stored boxes.

use rand::Rng;

use super::plan::{CEILING, LabelSpec, Placement, ROOMS};
use super::sampling::{Gen, alloc, dist, f32x3};
use crate::model::DsgAabb;

impl Gen {
    /// Centre and half extents of one object of `label` in room `r`.
    pub(super) fn place_object(&mut self, label: &LabelSpec, r: usize) -> ([f64; 3], [f64; 3]) {
        let [x0, x1, y0, y1] = ROOMS[r];
        let mut size = label.size;
        for s in &mut size {
            *s *= self.uniform(0.85, 1.15);
        }
        let (cx, cy, cz);
        if label.place == Placement::Wall {
            let wall = self.rng.gen_range(0..4);
            if wall < 2 {
                size.swap(0, 1); // west / east wall: thin along x
                cx = if wall == 0 {
                    x0 + size[0] / 2.0 + 0.02
                } else {
                    x1 - size[0] / 2.0 - 0.02
                };
                cy = self.uniform(y0 + size[1] / 2.0 + 0.1, y1 - size[1] / 2.0 - 0.1);
            } else {
                cy = if wall == 2 {
                    y0 + size[1] / 2.0 + 0.02
                } else {
                    y1 - size[1] / 2.0 - 0.02
                };
                cx = self.uniform(x0 + size[0] / 2.0 + 0.1, x1 - size[0] / 2.0 - 0.1);
            }
            cz = label.base + size[2] / 2.0;
        } else {
            if self.rng.r#gen::<f64>() < 0.5 {
                size.swap(0, 1);
            }
            let (mx, my) = (size[0] / 2.0 + 0.1, size[1] / 2.0 + 0.1);
            cx = self.uniform(x0 + mx, x1 - mx);
            cy = self.uniform(y0 + my, y1 - my);
            cz = if label.name == "light" {
                CEILING - 0.02 - size[2] / 2.0
            } else if label.place == Placement::Ceiling {
                CEILING - 0.2 - size[2] / 2.0
            } else {
                label.base + size[2] / 2.0
            };
        }
        ([cx, cy, cz], size.map(|s| s / 2.0))
    }

    /// How many of each object's vertices its partner claims too: `n_multi` split
    /// in proportion to `n_own · U(0.3, 1)`, capped at `n_own` (the excess is
    /// redistributed to objects with room left).
    pub(super) fn share_counts(&mut self, n_multi: usize, n_own: &[usize]) -> Vec<usize> {
        let share_w: Vec<f64> = n_own
            .iter()
            .map(|&n| n as f64 * self.uniform(0.3, 1.0))
            .collect();
        let mut k_share = alloc(n_multi, &share_w);
        for _ in 0..100 {
            let over: usize = k_share
                .iter()
                .zip(n_own)
                .map(|(k, n)| k.saturating_sub(*n))
                .sum();
            if over == 0 {
                break;
            }
            for (k, n) in k_share.iter_mut().zip(n_own) {
                *k = (*k).min(*n);
            }
            let spare: Vec<usize> = (0..n_own.len())
                .filter(|&o| k_share[o] < n_own[o])
                .collect();
            let room: Vec<f64> = spare
                .iter()
                .map(|&o| (n_own[o] - k_share[o]) as f64)
                .collect();
            for (&o, add) in spare.iter().zip(alloc(over, &room)) {
                k_share[o] += add;
            }
        }
        k_share
    }

    /// Stored object boxes: `n_wrong` random objects get a box shrunk to 60–90 %
    /// and shifted by up to 10 % of their claimed extent (so it misses claimed
    /// vertices); the others the claimed extent plus 1 cm on every side.
    pub(super) fn object_boxes(
        &mut self,
        claims: &[Vec<u32>],
        pts: &[[f64; 3]],
        centers: &[[f64; 3]],
        halves: &[[f64; 3]],
        n_wrong: usize,
    ) -> Vec<DsgAabb> {
        let n_obj = claims.len();
        let mut wrong = vec![false; n_obj];
        for i in rand::seq::index::sample(&mut self.rng, n_obj, n_wrong) {
            wrong[i] = true;
        }
        let mut boxes = Vec::with_capacity(n_obj);
        for o in 0..n_obj {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &v in &claims[o] {
                for k in 0..3 {
                    lo[k] = lo[k].min(pts[v as usize][k]);
                    hi[k] = hi[k].max(pts[v as usize][k]);
                }
            }
            if claims[o].is_empty() {
                let (c, h) = (centers[o], halves[o]);
                lo = [c[0] - h[0], c[1] - h[1], c[2] - h[2]];
                hi = [c[0] + h[0], c[1] + h[1], c[2] + h[2]];
            }
            let mut dims = [0.0; 3];
            let mut ctr = [0.0; 3];
            if wrong[o] {
                for k in 0..3 {
                    dims[k] = (hi[k] - lo[k]) * self.uniform(0.6, 0.9);
                }
                for k in 0..3 {
                    ctr[k] = 0.5 * (lo[k] + hi[k]) + (hi[k] - lo[k]) * self.uniform(-0.1, 0.1);
                }
            } else {
                for k in 0..3 {
                    dims[k] = hi[k] - lo[k] + 0.02;
                    ctr[k] = 0.5 * (lo[k] + hi[k]);
                }
            }
            boxes.push(stored_box(dims, ctr));
        }
        boxes
    }
}

/// Partner claims: each object `o` hands its `k_share[o]` vertices closest to
/// `partner[o]`'s centre to `partner[o]` as well (ties to the lower vertex index).
pub(super) fn add_partner_claims(
    claims: &mut [Vec<usize>],
    own_ranges: &[(usize, usize)],
    k_share: &[usize],
    partner: &[usize],
    centers: &[[f64; 3]],
    pts: &[[f64; 3]],
) {
    for (o, &(a, b)) in own_ranges.iter().enumerate() {
        let (k, p) = (k_share[o], partner[o]);
        if k == 0 || p == o {
            continue;
        }
        let mut idx: Vec<(f64, usize)> = (a..b).map(|v| (dist(pts[v], centers[p]), v)).collect();
        idx.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        claims[p].extend(idx.iter().take(k).map(|&(_, v)| v));
    }
}

/// The box a file would store (f32 dimensions and centre), as the importer reads it.
pub(super) fn stored_box(dims: [f64; 3], ctr: [f64; 3]) -> DsgAabb {
    let d = f32x3(dims);
    let c = f32x3(ctr);
    let mut b = DsgAabb {
        min: [0.0; 3],
        max: [0.0; 3],
    };
    for k in 0..3 {
        b.min[k] = c[k] - d[k] / 2.0;
        b.max[k] = c[k] + d[k] / 2.0;
    }
    b
}
