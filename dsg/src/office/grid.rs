//! [`Grid`]: nearest and radius searches over the generator's point sets.

use super::sampling::dist;

/// A uniform grid over the xy extent of a point set, for radius and nearest
/// searches.
pub(super) struct Grid {
    x0: f64,
    y0: f64,
    cell: f64,
    nx: usize,
    ny: usize,
    /// CSR: cell `c` holds `items[start[c]..start[c + 1]]`, in ascending index.
    start: Vec<usize>,
    items: Vec<usize>,
}

impl Grid {
    pub(super) fn new(pos: &[[f64; 3]], cell: f64) -> Self {
        let cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        let (mut x0, mut y0, mut x1, mut y1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for p in pos {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
        if pos.is_empty() {
            (x0, y0, x1, y1) = (0.0, 0.0, 0.0, 0.0);
        }
        // Cap the cell count: never more cells than about 4x the points.
        let mut cell = cell;
        let cap = (4 * pos.len()).max(1) as f64;
        while ((x1 - x0) / cell + 1.0) * ((y1 - y0) / cell + 1.0) > cap {
            cell *= 1.5;
        }
        let nx = ((x1 - x0) / cell) as usize + 1;
        let ny = ((y1 - y0) / cell) as usize + 1;
        let mut g = Self {
            x0,
            y0,
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            items: vec![0; pos.len()],
        };
        let cells: Vec<usize> = pos.iter().map(|p| g.cell_of(*p)).collect();
        for &c in &cells {
            g.start[c + 1] += 1;
        }
        for c in 0..nx * ny {
            g.start[c + 1] += g.start[c];
        }
        let mut fill = g.start.clone();
        for (i, &c) in cells.iter().enumerate() {
            g.items[fill[c]] = i;
            fill[c] += 1;
        }
        g
    }

    fn coords(&self, p: [f64; 3]) -> (usize, usize) {
        let cx = ((p[0] - self.x0) / self.cell)
            .floor()
            .clamp(0.0, (self.nx - 1) as f64) as usize;
        let cy = ((p[1] - self.y0) / self.cell)
            .floor()
            .clamp(0.0, (self.ny - 1) as f64) as usize;
        (cx, cy)
    }

    fn cell_of(&self, p: [f64; 3]) -> usize {
        let (cx, cy) = self.coords(p);
        cy * self.nx + cx
    }

    fn cell_items(&self, cx: usize, cy: usize) -> &[usize] {
        let c = cy * self.nx + cx;
        &self.items[self.start[c]..self.start[c + 1]]
    }

    /// Calls `f` for every point in the 3x3 cells around `p` (a superset of the
    /// points within one `cell` of `p`, since the cell size never shrinks).
    pub(super) fn for_each_near(&self, p: [f64; 3], mut f: impl FnMut(usize)) {
        let (cx, cy) = self.coords(p);
        for y in cy.saturating_sub(1)..=(cy + 1).min(self.ny - 1) {
            for x in cx.saturating_sub(1)..=(cx + 1).min(self.nx - 1) {
                for &i in self.cell_items(x, y) {
                    f(i);
                }
            }
        }
    }

    /// The accepted point nearest to `q` (3D distance; ties to the smaller index).
    pub(super) fn nearest(
        &self,
        q: [f64; 3],
        pos: &[[f64; 3]],
        accept: impl Fn(usize) -> bool,
    ) -> Option<usize> {
        let (cx, cy) = self.coords(q);
        let mut best: Option<(f64, usize)> = None;
        for ring in 0.. {
            let (lo_x, hi_x) = (cx.saturating_sub(ring), (cx + ring).min(self.nx - 1));
            let (lo_y, hi_y) = (cy.saturating_sub(ring), (cy + ring).min(self.ny - 1));
            for y in lo_y..=hi_y {
                for x in lo_x..=hi_x {
                    // Only the cells on this ring (Chebyshev distance == ring).
                    if x.abs_diff(cx).max(y.abs_diff(cy)) != ring {
                        continue;
                    }
                    for &i in self.cell_items(x, y) {
                        if accept(i) {
                            let d = dist(q, pos[i]);
                            if best.is_none_or(|(bd, bi)| d < bd || (d == bd && i < bi)) {
                                best = Some((d, i));
                            }
                        }
                    }
                }
            }
            // Lower bound (xy) on the distance to any cell not visited yet: the
            // distance from q to the nearest side of the visited square beyond which
            // cells remain.
            let mut bound = f64::INFINITY;
            if cx > ring {
                bound = bound.min(q[0] - (self.x0 + (cx - ring) as f64 * self.cell));
            }
            if cx + ring + 1 < self.nx {
                bound = bound.min(self.x0 + (cx + ring + 1) as f64 * self.cell - q[0]);
            }
            if cy > ring {
                bound = bound.min(q[1] - (self.y0 + (cy - ring) as f64 * self.cell));
            }
            if cy + ring + 1 < self.ny {
                bound = bound.min(self.y0 + (cy + ring + 1) as f64 * self.cell - q[1]);
            }
            if bound == f64::INFINITY || best.is_some_and(|(bd, _)| bd < bound) {
                break;
            }
        }
        best.map(|(_, i)| i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute_nearest(
        q: [f64; 3],
        pos: &[[f64; 3]],
        accept: impl Fn(usize) -> bool,
    ) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        for (i, &p) in pos.iter().enumerate() {
            if accept(i) {
                let d = dist(q, p);
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, i));
                }
            }
        }
        best.map(|(_, i)| i)
    }

    #[test]
    fn grid_nearest_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pos: Vec<[f64; 3]> = (0..500)
            .map(|_| {
                [
                    rng.gen_range(0.0..40.0),
                    rng.gen_range(0.0..25.0),
                    rng.gen_range(0.0..3.0),
                ]
            })
            .collect();
        let g = Grid::new(&pos, 1.0);
        for _ in 0..300 {
            let q = [
                rng.gen_range(-5.0..45.0),
                rng.gen_range(-5.0..30.0),
                rng.gen_range(0.0..3.0),
            ];
            assert_eq!(
                g.nearest(q, &pos, |_| true),
                brute_nearest(q, &pos, |_| true)
            );
            assert_eq!(
                g.nearest(q, &pos, |i| i % 7 == 0),
                brute_nearest(q, &pos, |i| i % 7 == 0)
            );
        }
        assert_eq!(g.nearest([1.0; 3], &pos, |_| false), None);
    }
}
