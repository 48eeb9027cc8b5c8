//! Places, mesh places and agent poses: sampling in rooms, the trajectory, and the
//! place edges.

use super::grid::Grid;
use super::plan::{DOORS, DT_NS, ROOMS, T0_NS};
use super::sampling::{Gen, dist};

impl Gen {
    /// `counts[r]` uniform points per room, `margin` from the walls, z in `[zlo, zhi)`.
    pub(super) fn sample_in_rooms(
        &mut self,
        counts: &[usize],
        margin: f64,
        zlo: f64,
        zhi: f64,
    ) -> (Vec<[f64; 3]>, Vec<usize>) {
        let mut pos = Vec::new();
        let mut room = Vec::new();
        for (r, &n) in counts.iter().enumerate() {
            let [x0, x1, y0, y1] = ROOMS[r];
            for _ in 0..n {
                let x = self.uniform(x0 + margin, x1 - margin);
                let y = self.uniform(y0 + margin, y1 - margin);
                let z = self.uniform(zlo, zhi);
                pos.push([x, y, z]);
                room.push(r);
            }
        }
        (pos, room)
    }
}

/// Agent poses along a tour of every room, at 5 Hz keyframes.
pub(super) fn trajectory(n: usize) -> (Vec<[f64; 3]>, Vec<u64>) {
    let mut wps = vec![[1.0, 12.5]];
    for &(_, rb, [dx, dy]) in &DOORS[..8] {
        let [x0, x1, y0, y1] = ROOMS[rb];
        let cy = 0.5 * (y0 + y1);
        let inset = 2.0;
        wps.extend([
            [dx, 12.5],
            [dx, dy],
            [dx, cy],
            [x0 + inset, y0 + inset],
            [x1 - inset, y0 + inset],
            [x1 - inset, y1 - inset],
            [x0 + inset, y1 - inset],
            [dx, cy],
            [dx, dy],
            [dx, 12.5],
        ]);
    }
    wps.push([39.0, 12.5]);
    let mut cum = vec![0.0];
    for w in wps.windows(2) {
        let d = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
        cum.push(cum[cum.len() - 1] + d);
    }
    let total = cum[cum.len() - 1];
    let mut pos = Vec::with_capacity(n);
    let mut seg = 0;
    for i in 0..n {
        let s = if n > 1 {
            total * i as f64 / (n - 1) as f64
        } else {
            0.0
        };
        while seg + 2 < cum.len() && cum[seg + 1] < s {
            seg += 1;
        }
        let len = cum[seg + 1] - cum[seg];
        let t = if len > 0.0 {
            ((s - cum[seg]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (wps[seg], wps[seg + 1]);
        pos.push([
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            1.5 + 0.05 * (s / 3.0).sin(),
        ]);
    }
    let times = (0..n as u64).map(|i| T0_NS + DT_NS * i).collect();
    (pos, times)
}

/// Place edges: [`kruskal_plus`] over [`candidate_pairs`]. When those candidates
/// cannot reach `target` (sparse places at small scales), every pair across a door
/// becomes a candidate, whatever its distance to the door.
pub(super) fn edges_for(
    pos: &[[f64; 3]],
    room: &[usize],
    radius: f64,
    door_radius: f64,
    target: usize,
) -> Vec<(usize, usize)> {
    let pairs = candidate_pairs(pos, room, radius, door_radius);
    if pairs.len() >= target {
        return kruskal_plus(pos, &pairs, target);
    }
    kruskal_plus(
        pos,
        &candidate_pairs(pos, room, radius, f64::INFINITY),
        target,
    )
}

/// Candidate edges: same-room pairs within `radius` (3D), and pairs across a door
/// with both ends within `door_radius` (xy) of the door centre. Sorted `(i, j)`,
/// `i < j`.
fn candidate_pairs(
    pos: &[[f64; 3]],
    room: &[usize],
    radius: f64,
    door_radius: f64,
) -> Vec<(usize, usize)> {
    let grid = Grid::new(pos, radius);
    let mut pairs = Vec::new();
    for i in 0..pos.len() {
        grid.for_each_near(pos[i], |j| {
            if j > i && room[j] == room[i] && dist(pos[i], pos[j]) <= radius {
                pairs.push((i, j));
            }
        });
    }
    for &(ra, rb, [dx, dy]) in &DOORS {
        let near =
            |i: usize| ((pos[i][0] - dx).powi(2) + (pos[i][1] - dy).powi(2)).sqrt() <= door_radius;
        let a: Vec<usize> = (0..pos.len())
            .filter(|&i| room[i] == ra && near(i))
            .collect();
        let b: Vec<usize> = (0..pos.len())
            .filter(|&i| room[i] == rb && near(i))
            .collect();
        for &i in &a {
            for &j in &b {
                pairs.push((i.min(j), i.max(j)));
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// Spanning forest over the candidates (shortest first), plus the shortest of the
/// remaining candidates up to `target` edges; sorted by length.
fn kruskal_plus(
    points: &[[f64; 3]],
    pairs: &[(usize, usize)],
    target: usize,
) -> Vec<(usize, usize)> {
    let d: Vec<f64> = pairs
        .iter()
        .map(|&(a, b)| dist(points[a], points[b]))
        .collect();
    let mut order: Vec<usize> = (0..pairs.len()).collect();
    let key = |k: &usize| (d[*k], pairs[*k]);
    order.sort_by(|x, y| {
        let (dx, px) = key(x);
        let (dy, py) = key(y);
        dx.total_cmp(&dy).then(px.cmp(&py))
    });
    let mut parent: Vec<usize> = (0..points.len()).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let mut tree = Vec::new();
    let mut rest = Vec::new();
    for k in order {
        let (a, b) = pairs[k];
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra == rb {
            rest.push(k);
        } else {
            parent[ra] = rb;
            tree.push(k);
        }
    }
    let need = target.saturating_sub(tree.len());
    let mut chosen = tree;
    chosen.extend(rest.into_iter().take(need));
    chosen.sort_by(|x, y| {
        let (dx, px) = key(x);
        let (dy, py) = key(y);
        dx.total_cmp(&dy).then(px.cmp(&py))
    });
    chosen.into_iter().map(|k| pairs[k]).collect()
}
