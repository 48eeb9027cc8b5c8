//! The mesh: object surfaces, room-shell patches and the Hydra-like vertex order.

use std::f64::consts::PI;

use rand::Rng;

use super::sampling::{Gen, Patch, round_even};

impl Gen {
    /// A closed box-shaped surface of exactly `n` vertices: a UV sphere projected
    /// onto the box (random directions below 6 vertices, without faces).
    pub(super) fn box_surface(&mut self, center: [f64; 3], half: [f64; 3], n: usize) -> Patch {
        let project = |d: [f64; 3]| {
            let m = (0..3).map(|k| d[k].abs() / half[k]).fold(0.0, f64::max);
            let t = if m > 0.0 { 1.0 / m } else { 0.0 };
            [
                center[0] + d[0] * t,
                center[1] + d[1] * t,
                center[2] + d[2] * t,
            ]
        };
        if n < 6 {
            let pts = (0..n)
                .map(|_| project([self.normal(), self.normal(), self.normal()]))
                .collect();
            return (pts, Vec::new());
        }
        let c = round_even((2.0 * (n - 2) as f64).sqrt()).max(3);
        let r = ((n - 2) / c).max(1);
        let extra = n - 2 - r * c;
        let phase = self.rng.r#gen::<f64>() * 2.0 * PI / c as f64;
        let mut pts = Vec::with_capacity(n);
        pts.push(project([0.0, 0.0, 1.0]));
        for k in 0..r {
            let th = PI * (k + 1) as f64 / (r + 1) as f64;
            for j in 0..c {
                let ph = 2.0 * PI * j as f64 / c as f64 + phase;
                pts.push(project([
                    th.sin() * ph.cos(),
                    th.sin() * ph.sin(),
                    th.cos(),
                ]));
            }
        }
        pts.push(project([0.0, 0.0, -1.0]));
        for _ in 0..extra {
            pts.push(project([self.normal(), self.normal(), self.normal()]));
        }
        let (c32, top, bot) = (c as u32, 0u32, (1 + r * c) as u32);
        let mut faces = Vec::with_capacity(2 * r * c);
        for j in 0..c32 {
            faces.push([top, 1 + j, 1 + (j + 1) % c32]);
        }
        for k in 0..(r as u32).saturating_sub(1) {
            for j in 0..c32 {
                let a = 1 + k * c32 + j;
                let b = 1 + k * c32 + (j + 1) % c32;
                faces.push([a, a + c32, b]);
                faces.push([b, a + c32, b + c32]);
            }
        }
        let last = (r as u32 - 1) * c32;
        for j in 0..c32 {
            faces.push([1 + last + j, bot, 1 + last + (j + 1) % c32]);
        }
        (pts, faces)
    }

    /// A triangulated grid of exactly `n` vertices on `origin + s·u + t·v`.
    pub(super) fn grid_patch(
        &mut self,
        origin: [f64; 3],
        u: [f64; 3],
        v: [f64; 3],
        n: usize,
    ) -> Patch {
        let at = |s: f64, t: f64| {
            [
                origin[0] + s * u[0] + t * v[0],
                origin[1] + s * u[1] + t * v[1],
                origin[2] + s * u[2] + t * v[2],
            ]
        };
        if n < 4 {
            let pts = (0..n)
                .map(|_| {
                    let (s, t) = (self.rng.r#gen::<f64>(), self.rng.r#gen::<f64>());
                    at(s, t)
                })
                .collect();
            return (pts, Vec::new());
        }
        let norm = |w: [f64; 3]| (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        let (lu, lv) = (norm(u), norm(v));
        let c = round_even((n as f64 * lu / lv).sqrt()).min(n / 2).max(2);
        let (rows, rem) = (n / c, n % c);
        let nrows = rows + usize::from(rem > 0);
        let pts = (0..n)
            .map(|idx| {
                let (i, j) = (idx / c, idx % c);
                at(
                    j as f64 / (c - 1) as f64,
                    i as f64 / (nrows.max(2) - 1) as f64,
                )
            })
            .collect();
        let c32 = c as u32;
        let mut faces = Vec::with_capacity(2 * n);
        let mut second = Vec::with_capacity(n);
        for ii in 0..(rows as u32).saturating_sub(1) {
            for jj in 0..c32 - 1 {
                let a = ii * c32 + jj;
                faces.push([a, a + 1, a + c32 + 1]);
                second.push([a, a + c32 + 1, a + c32]);
            }
        }
        faces.append(&mut second);
        if rem >= 2 {
            for jj in 0..rem as u32 - 1 {
                let a = (rows as u32 - 1) * c32 + jj;
                let b = rows as u32 * c32 + jj;
                faces.push([a, a + 1, b + 1]);
                faces.push([a, b + 1, b]);
            }
        }
        (pts, faces)
    }
}

/// Vertex order of Hydra-like meshes: by `block`-sized voxel block (x, then y,
/// then z block index), stable within a block. A counting sort: O(n + blocks).
pub(super) fn block_order(pts: &[[f64; 3]], block: f64) -> Vec<usize> {
    let keys: Vec<[i64; 3]> = pts
        .iter()
        .map(|p| p.map(|x| (x / block).floor() as i64))
        .collect();
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for k in &keys {
        for a in 0..3 {
            lo[a] = lo[a].min(k[a]);
            hi[a] = hi[a].max(k[a]);
        }
    }
    let span = |a: usize| {
        if keys.is_empty() {
            1
        } else {
            (hi[a] - lo[a] + 1) as usize
        }
    };
    let (sy, sz) = (span(1), span(2));
    let nb = span(0) * sy * sz;
    let id = |k: &[i64; 3]| {
        ((k[0] - lo[0]) as usize * sy + (k[1] - lo[1]) as usize) * sz + (k[2] - lo[2]) as usize
    };
    let mut start = vec![0usize; nb + 1];
    for k in &keys {
        start[id(k) + 1] += 1;
    }
    for b in 0..nb {
        start[b + 1] += start[b];
    }
    let mut perm = vec![0usize; keys.len()];
    for (i, k) in keys.iter().enumerate() {
        let b = id(k);
        perm[start[b]] = i;
        start[b] += 1;
    }
    perm
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::office::OfficeParams;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn block_order_is_a_stable_sort_by_block() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let pts: Vec<[f64; 3]> = (0..2000)
            .map(|_| {
                [
                    rng.gen_range(-3.0..40.0),
                    rng.gen_range(0.0..25.0),
                    rng.gen_range(-0.1..3.1),
                ]
            })
            .collect();
        let mut expected: Vec<usize> = (0..pts.len()).collect();
        expected.sort_by_key(|&i| (pts[i].map(|x| (x / 1.6).floor() as i64), i));
        assert_eq!(block_order(&pts, 1.6), expected);
        assert!(block_order(&[], 1.6).is_empty());
    }

    #[test]
    fn surfaces_have_exactly_n_vertices_and_valid_faces() {
        let mut g = Gen::new(OfficeParams::default());
        for n in [0, 1, 5, 6, 7, 50, 333] {
            let (p, f) = g.box_surface([1.0, 1.0, 1.0], [0.5, 0.2, 0.3], n);
            assert_eq!(p.len(), n);
            assert!(f.iter().flatten().all(|&i| (i as usize) < n));
            let (p, f) = g.grid_patch([0.0; 3], [4.0, 0.0, 0.0], [0.0, 0.0, 3.0], n);
            assert_eq!(p.len(), n);
            assert!(f.iter().flatten().all(|&i| (i as usize) < n));
        }
    }
}
