//! Seeded synthetic office: a uHumans2-like Spark-DSG scene graph built in Rust.
//!
//! [`generate`] ports `tools/gen_office_dsg.py` (the generator of the data files):
//! the same floor plan, label table, object placement rules, mesh construction,
//! claim overlaps, wrong boxes and edge recipe, with the same count targets. It
//! uses its own random stream (ChaCha8), so the output is not the Python file's
//! bytes but the same kind of office with the same counts.
//!
//! # Counts at `scale = 1`
//!
//! | what | count |
//! |---|---|
//! | building / rooms | 1 / 9 (R(0) corridor x 0–40, y 11–14; R(1)–R(4) south, R(5)–R(8) north; 3 m ceiling) |
//! | places / mesh places / agent poses / objects | 1,130 / 1,472 / 705 / 215 (27 labels, light ×40 … bulletin ×1) |
//! | nodes / edges | 3,532 / 11,012 (3,531 parents, 704 odometry, 12 doors, 3,030 place–place, 3,735 mesh-place) |
//! | mesh vertices / faces | 354,885 / 677,884 |
//! | unclaimed / claimed by >1 object | 313,522 (88.3 %) / 28,000 (7.89 %) |
//! | object boxes missing some claimed vertex | 126 of 215 |
//!
//! # Scaling
//!
//! `scale` multiplies the vertex, face, place, mesh-place, agent, edge and overlap
//! counts (rounded half to even, as Python does). The building and the 9 rooms stay.
//! Away from scale 1 each label frequency becomes `max(1, round(f · max(scale,
//! 0.1)))`, so all 27 labels stay present, and the number of wrong boxes follows
//! the object count. Below scale 1 the face and edge targets may be out of reach
//! (small patches, few candidate pairs); the graph then has fewer. Candidate
//! neighbourhoods for place edges shrink with `1/sqrt(scale)` above scale 1 (the
//! Python tool keeps them fixed there) so the expected degree stays constant.
//!
//! # Determinism
//!
//! The output is a pure function of `(seed, scale)` on a given platform. Across
//! platforms it may differ in the last bits of a few coordinates, since it uses the
//! platform's `sin`, `cos`, `ln` and `sqrt`.

use std::collections::BTreeMap;
use std::f64::consts::PI;

use rand::distributions::{Distribution, WeightedIndex};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::model::{
    DsgAabb, DsgEdge, DsgGraph, DsgLayer, DsgMesh, DsgNode, DsgVersion, LayerKey, NodeKind,
};
use crate::symbol::NodeSymbol;

/// Parameters of [`generate`].
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

/// Full-scale targets (uHumans2 office, as in the paper).
mod full {
    pub const PLACES: f64 = 1130.0;
    pub const MESH_PLACES: f64 = 1472.0;
    pub const AGENTS: f64 = 705.0;
    pub const VERTICES: f64 = 354_885.0;
    pub const FACES: f64 = 677_884.0;
    pub const UNCLAIMED: f64 = 313_522.0;
    pub const MULTI: f64 = 28_000.0;
    pub const WRONG_BOXES: f64 = 126.0;
    pub const OBJECTS: f64 = 215.0;
    pub const PLACE_EDGES: f64 = 3030.0;
    pub const MESH_PLACE_EDGES: f64 = 3735.0;
}

/// Ceiling height in metres.
pub const CEILING: f64 = 3.0;

/// Floor plan: `[xmin, xmax, ymin, ymax]` of R(0) (the corridor) to R(8).
pub const ROOMS: [[f64; 4]; 9] = [
    [0.0, 40.0, 11.0, 14.0],
    [0.0, 10.0, 0.0, 11.0],
    [10.0, 20.0, 0.0, 11.0],
    [20.0, 30.0, 0.0, 11.0],
    [30.0, 40.0, 0.0, 11.0],
    [0.0, 12.0, 14.0, 25.0],
    [12.0, 22.0, 14.0, 25.0],
    [22.0, 32.0, 14.0, 25.0],
    [32.0, 40.0, 14.0, 25.0],
];

/// Doors: the two rooms and the door centre (x, y).
pub const DOORS: [(usize, usize, [f64; 2]); 12] = [
    (0, 1, [5.0, 11.0]),
    (0, 2, [15.0, 11.0]),
    (0, 3, [25.0, 11.0]),
    (0, 4, [35.0, 11.0]),
    (0, 5, [6.0, 14.0]),
    (0, 6, [17.0, 14.0]),
    (0, 7, [27.0, 14.0]),
    (0, 8, [36.0, 14.0]),
    (1, 2, [10.0, 5.5]),
    (3, 4, [30.0, 5.5]),
    (5, 6, [12.0, 19.5]),
    (7, 8, [32.0, 19.5]),
];

#[derive(Clone, Copy, PartialEq)]
enum Placement {
    Floor,
    Ceiling,
    Wall,
    Surface,
}

struct LabelSpec {
    name: &'static str,
    freq: u32,
    size: [f64; 3],
    place: Placement,
    base: f64,
}

const fn spec(
    name: &'static str,
    freq: u32,
    size: [f64; 3],
    place: Placement,
    base: f64,
) -> LabelSpec {
    LabelSpec {
        name,
        freq,
        size,
        place,
        base,
    }
}

use Placement::{Ceiling, Floor, Surface, Wall};

/// Object labels: full-scale frequency, nominal size (m), placement, base height.
const LABELS: [LabelSpec; 27] = [
    spec("light", 40, [0.6, 0.6, 0.08], Ceiling, 0.0),
    spec("chair", 30, [0.5, 0.5, 0.9], Floor, 0.0),
    spec("desk", 22, [1.4, 0.7, 0.75], Floor, 0.0),
    spec("monitor", 18, [0.55, 0.2, 0.4], Surface, 0.75),
    spec("plant", 14, [0.4, 0.4, 1.0], Floor, 0.0),
    spec("cabinet", 12, [0.5, 0.6, 1.2], Floor, 0.0),
    spec("table", 10, [1.2, 0.8, 0.75], Floor, 0.0),
    spec("trashcan", 9, [0.3, 0.3, 0.4], Floor, 0.0),
    spec("keyboard", 8, [0.45, 0.15, 0.03], Surface, 0.75),
    spec("window", 7, [1.5, 0.05, 1.2], Wall, 0.9),
    spec("door", 6, [0.9, 0.05, 2.1], Wall, 0.0),
    spec("computer", 6, [0.2, 0.45, 0.45], Floor, 0.0),
    spec("sofa", 5, [2.0, 0.9, 0.8], Floor, 0.0),
    spec("shelf", 5, [1.0, 0.4, 2.0], Floor, 0.0),
    spec("whiteboard", 4, [1.8, 0.03, 1.2], Wall, 0.9),
    spec("printer", 3, [0.5, 0.5, 0.4], Floor, 0.0),
    spec("lamp", 2, [0.3, 0.3, 1.6], Floor, 0.0),
    spec("clock", 2, [0.3, 0.05, 0.3], Wall, 2.0),
    spec("picture", 2, [0.6, 0.03, 0.5], Wall, 1.4),
    spec("fridge", 2, [0.7, 0.7, 1.8], Floor, 0.0),
    spec("microwave", 2, [0.5, 0.35, 0.3], Surface, 0.9),
    spec("sink", 1, [0.6, 0.5, 0.2], Surface, 0.85),
    spec("coat_rack", 1, [0.5, 0.5, 1.8], Floor, 0.0),
    spec("fire_extinguisher", 1, [0.2, 0.2, 0.6], Floor, 0.0),
    spec("projector", 1, [0.35, 0.3, 0.15], Ceiling, 0.0),
    spec("water_dispenser", 1, [0.35, 0.35, 1.2], Floor, 0.0),
    spec("bulletin", 1, [1.2, 0.03, 0.9], Wall, 1.2),
];

/// Mesh labels of the room shells (after the 27 object labels).
const MESH_WALL: u32 = 27;
const MESH_FLOOR: u32 = 28;
const MESH_CEILING: u32 = 29;

const T0_NS: u64 = 1_000_000_000;
const DT_NS: u64 = 200_000_000;

/// The 27 object label names in semantic-label order (alphabetical, as in the
/// `_l2p0` labelspace of the data files).
pub fn label_names() -> Vec<&'static str> {
    let mut names: Vec<&'static str> = LABELS.iter().map(|l| l.name).collect();
    names.sort_unstable();
    names
}

/// Builds the synthetic office for `params`.
///
/// Nodes come in Spark-DSG's file order (objects, places, rooms, building, agent
/// poses, mesh places), each kind by index; ids are [`NodeSymbol`]s `O(i)`, `p(i)`,
/// `R(i)`, `B(0)`, `a(i)`, `Q(i)`. Every object lies inside its room, every node but
/// the building has a parent, and the layers and labelspaces are those of the data
/// files, so the result matches what [`parse_json`](super::parse_json) gives for a
/// file written by `gen_office_dsg.py`.
///
/// # Examples
/// ```
/// use ygg_dsg::office::{generate, OfficeParams};
/// let g = generate(OfficeParams { seed: 7, scale: 0.02 });
/// let c = g.counts();
/// assert_eq!((c.nodes, c.mesh_vertices), (110, 7_098));
/// assert_eq!(g, generate(OfficeParams { seed: 7, scale: 0.02 }));
/// ```
pub fn generate(params: OfficeParams) -> DsgGraph {
    Gen::new(params).run()
}

fn round_even(x: f64) -> usize {
    let r = x.round_ties_even();
    if r.is_finite() && r > 0.0 {
        r as usize
    } else {
        0
    }
}

/// Largest-remainder split of `total` proportional to `weights` (ties to the lower
/// index). Zero or invalid weights split evenly.
fn alloc(total: usize, weights: &[f64]) -> Vec<usize> {
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

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn area(r: usize) -> f64 {
    let [x0, x1, y0, y1] = ROOMS[r];
    (x1 - x0) * (y1 - y0)
}

/// The room (index into [`ROOMS`]) containing floor point `(x, y)`: the first one
/// whose box holds it, bounds inclusive, so the corridor R(0) wins on shared walls.
pub fn room_at(x: f64, y: f64) -> Option<usize> {
    ROOMS
        .iter()
        .position(|&[x0, x1, y0, y1]| x0 <= x && x <= x1 && y0 <= y && y <= y1)
}

fn free_dist(p: [f64; 3], r: usize) -> f64 {
    let [x0, x1, y0, y1] = ROOMS[r];
    (p[0] - x0)
        .min(x1 - p[0])
        .min(p[1] - y0)
        .min(y1 - p[1])
        .min(p[2])
        .min(CEILING - p[2])
}

fn f32x3(p: [f64; 3]) -> [f32; 3] {
    p.map(|x| x as f32)
}

struct Gen {
    rng: ChaCha8Rng,
    params: OfficeParams,
    scale: f64,
    spare_normal: Option<f64>,
}

/// Points and triangles of one surface patch.
type Patch = (Vec<[f64; 3]>, Vec<[u32; 3]>);

impl Gen {
    fn new(params: OfficeParams) -> Self {
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

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.rng.r#gen::<f64>()
    }

    /// Standard normal sample (Box–Muller, both outputs used).
    fn normal(&mut self) -> f64 {
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

    fn count(&self, full: f64) -> usize {
        round_even(full * self.scale)
    }

    fn run(mut self) -> DsgGraph {
        let scale = self.scale;
        let n_vert = self.count(full::VERTICES);
        let n_faces_target = self.count(full::FACES);
        let n_unclaimed = self.count(full::UNCLAIMED).min(n_vert);
        let n_claimed = n_vert - n_unclaimed;
        let n_multi = self.count(full::MULTI).min(n_claimed);
        let n_places = self.count(full::PLACES).max(1);
        let n_mplaces = self.count(full::MESH_PLACES).max(1);
        let n_agents = self.count(full::AGENTS).max(2);
        let obj_scale = scale.max(0.1);
        let freq: Vec<usize> = LABELS
            .iter()
            .map(|l| {
                if scale == 1.0 {
                    l.freq as usize
                } else {
                    round_even(f64::from(l.freq) * obj_scale).max(1)
                }
            })
            .collect();
        let n_obj: usize = freq.iter().sum();
        let n_wrong = round_even(full::WRONG_BOXES * n_obj as f64 / full::OBJECTS).min(n_obj);
        let areas: Vec<f64> = (0..ROOMS.len()).map(area).collect();
        let names = label_names();

        // ---- agent trajectory
        let (agent_pos, agent_t) = trajectory(n_agents);

        // ---- objects: labels, rooms, boxes
        let mut obj_labels: Vec<usize> = Vec::with_capacity(n_obj); // index into LABELS
        for name in &names {
            let li = LABELS.iter().position(|l| l.name == *name).unwrap_or(0);
            obj_labels.extend(std::iter::repeat_n(li, freq[li]));
        }
        obj_labels.shuffle(&mut self.rng);
        let room_dist = WeightedIndex::new(&areas).ok();
        let obj_room: Vec<usize> = (0..n_obj)
            .map(|_| room_dist.as_ref().map_or(0, |d| d.sample(&mut self.rng)))
            .collect();
        let mut obj_center = vec![[0.0; 3]; n_obj];
        let mut obj_half = vec![[0.0; 3]; n_obj];
        for o in 0..n_obj {
            let (c, h) = self.place_object(&LABELS[obj_labels[o]], obj_room[o]);
            obj_center[o] = c;
            obj_half[o] = h;
        }
        let sem_of = |li: usize| {
            names
                .iter()
                .position(|n| *n == LABELS[li].name)
                .unwrap_or(0) as u32
        };

        // ---- mesh: object surfaces (claimed) then room shells (unclaimed)
        let sa: Vec<f64> = obj_half
            .iter()
            .map(|h| 2.0 * (h[0] * h[1] + h[1] * h[2] + h[0] * h[2]) + 0.02)
            .collect();
        let n_own = alloc(n_claimed, &sa);
        let mut pts: Vec<[f64; 3]> = Vec::with_capacity(n_vert);
        let mut faces: Vec<[u32; 3]> = Vec::with_capacity(2 * n_vert);
        let mut labs: Vec<u32> = Vec::with_capacity(n_vert);
        let mut own_ranges = Vec::with_capacity(n_obj);
        for o in 0..n_obj {
            let (p, f) = self.box_surface(obj_center[o], obj_half[o], n_own[o]);
            let off = pts.len();
            for q in p {
                let n = [self.normal(), self.normal(), self.normal()];
                pts.push([
                    q[0] + 0.003 * n[0],
                    q[1] + 0.003 * n[1],
                    q[2] + 0.003 * n[2],
                ]);
            }
            faces.extend(f.iter().map(|t| t.map(|i| i + off as u32)));
            labs.extend(std::iter::repeat_n(sem_of(obj_labels[o]), pts.len() - off));
            own_ranges.push((off, pts.len()));
        }
        let patches = shell_patches();
        let n_patch = alloc(
            n_unclaimed,
            &patches.iter().map(|p| p.4).collect::<Vec<_>>(),
        );
        for (&(origin, u, v, label, _), &n) in patches.iter().zip(&n_patch) {
            let (p, f) = self.grid_patch(origin, u, v, n);
            let off = pts.len();
            for q in p {
                let n = [self.normal(), self.normal(), self.normal()];
                pts.push([
                    q[0] + 0.002 * n[0],
                    q[1] + 0.002 * n[1],
                    q[2] + 0.002 * n[2],
                ]);
            }
            faces.extend(f.iter().map(|t| t.map(|i| i + off as u32)));
            labs.extend(std::iter::repeat_n(label, pts.len() - off));
        }
        // What a file stores: f32.
        let pts: Vec<[f64; 3]> = pts.iter().map(|p| p.map(|x| f64::from(x as f32))).collect();

        // Holes: drop faces at random down to the target.
        if faces.len() > n_faces_target {
            let mut drop = vec![false; faces.len()];
            for i in
                rand::seq::index::sample(&mut self.rng, faces.len(), faces.len() - n_faces_target)
            {
                drop[i] = true;
            }
            let mut k = 0;
            faces.retain(|_| {
                k += 1;
                !drop[k - 1]
            });
        }

        // ---- claims: own vertices, plus a partner claiming part of them
        let mut claims: Vec<Vec<usize>> =
            own_ranges.iter().map(|&(a, b)| (a..b).collect()).collect();
        let k_share = self.share_counts(n_multi, &n_own);
        let obj_grid = Grid::new(&obj_center, 2.0);
        let partner: Vec<usize> = (0..n_obj)
            .map(|o| {
                obj_grid
                    .nearest(obj_center[o], &obj_center, |j| {
                        j != o && obj_room[j] == obj_room[o]
                    })
                    .or_else(|| obj_grid.nearest(obj_center[o], &obj_center, |j| j != o))
                    .unwrap_or(o)
            })
            .collect();
        add_partner_claims(
            &mut claims,
            &own_ranges,
            &k_share,
            &partner,
            &obj_center,
            &pts,
        );

        // ---- Hydra-like vertex order: by 1.6 m voxel block, then stable
        let perm = block_order(&pts, 1.6);
        let mut inv = vec![0u32; n_vert];
        for (new, &old) in perm.iter().enumerate() {
            inv[old] = new as u32;
        }
        let pts: Vec<[f64; 3]> = perm.iter().map(|&i| pts[i]).collect();
        let labs: Vec<u32> = perm.iter().map(|&i| labs[i]).collect();
        for f in &mut faces {
            *f = f.map(|i| inv[i as usize]);
        }
        let claims: Vec<Vec<u32>> = claims
            .into_iter()
            .map(|c| {
                let mut c: Vec<u32> = c.into_iter().map(|v| inv[v]).collect();
                c.sort_unstable();
                c.dedup();
                c
            })
            .collect();

        // ---- stored boxes: correct (claims + 1 cm) or wrong (shrunk, shifted)
        let boxes = self.object_boxes(&claims, &pts, &obj_center, &obj_half, n_wrong);

        // ---- places and mesh places
        let p_counts = alloc(n_places, &areas);
        let (place_pos, place_room) = self.sample_in_rooms(&p_counts, 0.3, 0.6, 2.2);
        let m_counts = alloc(n_mplaces, &areas);
        let (mut mp_pos, mp_room) = self.sample_in_rooms(&m_counts, 0.2, 0.0, 0.0);
        for p in &mut mp_pos {
            p[2] = 0.02;
        }

        // ---- parents needing a search
        let place_grid = Grid::new(&place_pos, 1.0);
        let obj_parent: Vec<usize> = (0..n_obj)
            .map(|o| {
                place_grid
                    .nearest(obj_center[o], &place_pos, |j| place_room[j] == obj_room[o])
                    .or_else(|| place_grid.nearest(obj_center[o], &place_pos, |_| true))
                    .unwrap_or(0)
            })
            .collect();
        let agent_parent: Vec<usize> = agent_pos
            .iter()
            .map(|&a| place_grid.nearest(a, &place_pos, |_| true).unwrap_or(0))
            .collect();

        // ---- intra-layer edges
        let sym = |c: u8, i: usize| NodeSymbol::new(c, i as u64).id();
        let mut edges = Vec::new();
        for i in 0..n_agents.saturating_sub(1) {
            edges.push(DsgEdge {
                source: sym(b'a', i),
                target: sym(b'a', i + 1),
                weight: None,
            });
        }
        for &(a, b, _) in &DOORS {
            edges.push(DsgEdge {
                source: sym(b'R', a),
                target: sym(b'R', b),
                weight: Some(1.0),
            });
        }
        let rad = 1.0 / scale.sqrt();
        let pe = edges_for(
            &place_pos,
            &place_room,
            3.0 * rad,
            1.5 * rad,
            self.count(full::PLACE_EDGES),
        );
        for (a, b) in pe {
            let w =
                free_dist(place_pos[a], place_room[a]).min(free_dist(place_pos[b], place_room[b]));
            edges.push(DsgEdge {
                source: sym(b'p', a),
                target: sym(b'p', b),
                weight: Some(w),
            });
        }
        let me = edges_for(
            &mp_pos,
            &mp_room,
            2.5 * rad,
            1.5 * rad,
            self.count(full::MESH_PLACE_EDGES),
        );
        for (a, b) in me {
            edges.push(DsgEdge {
                source: sym(b'Q', a),
                target: sym(b'Q', b),
                weight: None,
            });
        }

        // ---- nodes, in Spark-DSG file order
        let mut nodes =
            Vec::with_capacity(n_obj + n_places + ROOMS.len() + 1 + n_agents + n_mplaces);
        let blank = |id: u64, layer: LayerKey, kind: NodeKind, position: [f64; 3]| DsgNode {
            id,
            layer,
            kind,
            position: f32x3(position),
            name: None,
            label: None,
            semantic_label: None,
            bbox: None,
            mesh_connections: Vec::new(),
            timestamp_ns: None,
            parent: None,
        };
        for o in 0..n_obj {
            let (a, b) = own_ranges[o];
            let position = if b > a {
                let mut s = [0.0; 3];
                for v in a..b {
                    let p = pts[inv[v] as usize];
                    for k in 0..3 {
                        s[k] += p[k];
                    }
                }
                s.map(|x| x / (b - a) as f64)
            } else {
                obj_center[o]
            };
            let name = LABELS[obj_labels[o]].name.to_owned();
            nodes.push(DsgNode {
                name: Some(name.clone()),
                label: Some(name),
                semantic_label: Some(sem_of(obj_labels[o])),
                bbox: Some(boxes[o]),
                mesh_connections: claims[o].clone(),
                parent: Some(sym(b'p', obj_parent[o])),
                ..blank(sym(b'O', o), LayerKey::OBJECTS, NodeKind::Object, position)
            });
        }
        for (i, &p) in place_pos.iter().enumerate() {
            nodes.push(DsgNode {
                parent: Some(sym(b'R', place_room[i])),
                ..blank(sym(b'p', i), LayerKey::PLACES, NodeKind::Place, p)
            });
        }
        for (r, &[x0, x1, y0, y1]) in ROOMS.iter().enumerate() {
            let c = [(x0 + x1) / 2.0, (y0 + y1) / 2.0, CEILING / 2.0];
            nodes.push(DsgNode {
                name: Some(format!("R({r})")),
                bbox: Some(stored_box([x1 - x0, y1 - y0, CEILING], c)),
                parent: Some(sym(b'B', 0)),
                ..blank(sym(b'R', r), LayerKey::ROOMS, NodeKind::Room, c)
            });
        }
        let c = [20.0, 12.5, CEILING / 2.0];
        nodes.push(DsgNode {
            name: Some("B(0)".to_owned()),
            bbox: Some(stored_box([40.0, 25.0, CEILING], c)),
            ..blank(sym(b'B', 0), LayerKey::BUILDINGS, NodeKind::Building, c)
        });
        for (i, &p) in agent_pos.iter().enumerate() {
            nodes.push(DsgNode {
                timestamp_ns: Some(agent_t[i]),
                parent: Some(sym(b'p', agent_parent[i])),
                ..blank(sym(b'a', i), LayerKey::AGENTS, NodeKind::Agent, p)
            });
        }
        for (i, &p) in mp_pos.iter().enumerate() {
            nodes.push(DsgNode {
                parent: Some(sym(b'R', mp_room[i])),
                ..blank(sym(b'Q', i), LayerKey::MESH_PLACES, NodeKind::Place2d, p)
            });
        }

        let labelspaces = office_labelspaces(&names);

        DsgGraph {
            source: format!(
                "office(seed={}, scale={})",
                self.params.seed, self.params.scale
            ),
            version: DsgVersion::V1_1_3,
            layers: office_layers(),
            nodes,
            edges,
            sibling_edges: Vec::new(),
            extra_parent_edges: Vec::new(),
            mesh: Some(DsgMesh {
                points: pts.iter().map(|&p| f32x3(p)).collect(),
                faces,
                labels: Some(labs),
            }),
            labelspaces,
        }
    }

    /// How many of each object's vertices its partner claims too: `n_multi` split
    /// in proportion to `n_own · U(0.3, 1)`, capped at `n_own` (the excess is
    /// redistributed to objects with room left).
    fn share_counts(&mut self, n_multi: usize, n_own: &[usize]) -> Vec<usize> {
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
    fn object_boxes(
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

    /// Centre and half extents of one object of `label` in room `r`.
    fn place_object(&mut self, label: &LabelSpec, r: usize) -> ([f64; 3], [f64; 3]) {
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

    /// A closed box-shaped surface of exactly `n` vertices: a UV sphere projected
    /// onto the box (random directions below 6 vertices, without faces).
    fn box_surface(&mut self, center: [f64; 3], half: [f64; 3], n: usize) -> Patch {
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
    fn grid_patch(&mut self, origin: [f64; 3], u: [f64; 3], v: [f64; 3], n: usize) -> Patch {
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

    /// `counts[r]` uniform points per room, `margin` from the walls, z in `[zlo, zhi)`.
    fn sample_in_rooms(
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
fn trajectory(n: usize) -> (Vec<[f64; 3]>, Vec<u64>) {
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

/// Vertex order of Hydra-like meshes: by `block`-sized voxel block (x, then y,
/// then z block index), stable within a block. A counting sort: O(n + blocks).
fn block_order(pts: &[[f64; 3]], block: f64) -> Vec<usize> {
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

/// A floor, ceiling or wall patch: origin, the two edge vectors, mesh label, area.
type Shell = ([f64; 3], [f64; 3], [f64; 3], u32, f64);

/// The floor, ceiling and four walls of every room.
fn shell_patches() -> Vec<Shell> {
    let mut patches = Vec::with_capacity(6 * ROOMS.len());
    for &[x0, x1, y0, y1] in &ROOMS {
        let (lx, ly) = (x1 - x0, y1 - y0);
        let (ux, uy, up) = ([lx, 0.0, 0.0], [0.0, ly, 0.0], [0.0, 0.0, CEILING]);
        patches.extend([
            ([x0, y0, 0.0], ux, uy, MESH_FLOOR, lx * ly),
            ([x0, y0, CEILING], ux, uy, MESH_CEILING, lx * ly),
            ([x0, y0, 0.0], ux, up, MESH_WALL, lx * CEILING),
            ([x0, y1, 0.0], ux, up, MESH_WALL, lx * CEILING),
            ([x0, y0, 0.0], uy, up, MESH_WALL, ly * CEILING),
            ([x1, y0, 0.0], uy, up, MESH_WALL, ly * CEILING),
        ]);
    }
    patches
}

/// The `_l2p0` (objects) and `mesh` labelspaces of the data files.
fn office_labelspaces(names: &[&str]) -> BTreeMap<String, BTreeMap<u32, String>> {
    let objects: BTreeMap<u32, String> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (i as u32, (*n).to_owned()))
        .collect();
    let mut mesh = objects.clone();
    mesh.insert(MESH_WALL, "wall".to_owned());
    mesh.insert(MESH_FLOOR, "floor".to_owned());
    mesh.insert(MESH_CEILING, "ceiling".to_owned());
    BTreeMap::from([("_l2p0".to_owned(), objects), ("mesh".to_owned(), mesh)])
}

/// Partner claims: each object `o` hands its `k_share[o]` vertices closest to
/// `partner[o]`'s centre to `partner[o]` as well (ties to the lower vertex index).
fn add_partner_claims(
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
fn stored_box(dims: [f64; 3], ctr: [f64; 3]) -> DsgAabb {
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

fn office_layers() -> Vec<DsgLayer> {
    let layer = |key: LayerKey, name: &str, aliases: &[&str]| DsgLayer {
        key,
        name: name.to_owned(),
        aliases: aliases.iter().map(|s| (*s).to_owned()).collect(),
    };
    vec![
        layer(LayerKey::OBJECTS, "OBJECTS", &["AGENTS", "OBJECTS"]),
        layer(LayerKey::AGENTS, "AGENTS", &[]),
        layer(LayerKey::PLACES, "PLACES", &["PLACES"]),
        layer(LayerKey::MESH_PLACES, "MESH_PLACES", &["MESH_PLACES"]),
        layer(LayerKey::ROOMS, "ROOMS", &["ROOMS"]),
        layer(LayerKey::BUILDINGS, "BUILDINGS", &["BUILDINGS"]),
    ]
}

/// Place edges: [`kruskal_plus`] over [`candidate_pairs`]. When those candidates
/// cannot reach `target` (sparse places at small scales), every pair across a door
/// becomes a candidate, whatever its distance to the door.
fn edges_for(
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

/// A uniform grid over the xy extent of a point set, for radius and nearest
/// searches.
struct Grid {
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
    fn new(pos: &[[f64; 3]], cell: f64) -> Self {
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
    fn for_each_near(&self, p: [f64; 3], mut f: impl FnMut(usize)) {
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
    fn nearest(
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

    use crate::ClaimStats;

    fn prefix_pair(g: &DsgGraph) -> BTreeMap<(u8, u8), usize> {
        let mut m = BTreeMap::new();
        let p = |id: u64| NodeSymbol::from_id(id).prefix();
        for e in &g.edges {
            *m.entry((p(e.source), p(e.target))).or_default() += 1;
        }
        for n in &g.nodes {
            if let Some(par) = n.parent {
                *m.entry((p(n.id), p(par))).or_default() += 1;
            }
        }
        m
    }

    #[test]
    fn full_scale_office_has_the_paper_counts() {
        let g = generate(OfficeParams {
            seed: 7,
            scale: 1.0,
        });
        let c = g.counts();
        assert_eq!(c.nodes, 3_532);
        assert_eq!(c.kind(NodeKind::Building), 1);
        assert_eq!(c.kind(NodeKind::Room), 9);
        assert_eq!(c.kind(NodeKind::Place), 1_130);
        assert_eq!(c.kind(NodeKind::Place2d), 1_472);
        assert_eq!(c.kind(NodeKind::Agent), 705);
        assert_eq!(c.kind(NodeKind::Object), 215);
        assert_eq!(c.edges, 11_012);
        assert_eq!(c.parent_edges, 3_531);
        let e = prefix_pair(&g);
        assert_eq!(e[&(b'a', b'a')], 704);
        assert_eq!(e[&(b'R', b'R')], 12);
        assert_eq!(e[&(b'p', b'p')], 3_030);
        assert_eq!(e[&(b'Q', b'Q')], 3_735);
        assert_eq!(e[&(b'O', b'p')], 215);
        assert_eq!(e[&(b'a', b'p')], 705);
        assert_eq!(e[&(b'p', b'R')], 1_130);
        assert_eq!(e[&(b'Q', b'R')], 1_472);
        assert_eq!(e[&(b'R', b'B')], 9);
        assert_eq!(c.mesh_vertices, 354_885);
        assert_eq!(c.mesh_faces, 677_884);

        let s = g.claim_stats().expect("mesh");
        assert_eq!(
            s,
            ClaimStats {
                vertices: 354_885,
                objects: 215,
                unclaimed: 313_522,
                claimed: 41_363,
                multi_claimed: 28_000,
                total_claims: 69_363,
                wrong_boxes: 126,
                objects_without_box: 0,
            }
        );
        let pct = |n: usize| (10_000.0 * n as f64 / s.vertices as f64).round() / 100.0;
        assert_eq!(pct(s.unclaimed), 88.34);
        assert_eq!(pct(s.multi_claimed), 7.89);

        let h = g.object_label_histogram();
        assert_eq!(h.len(), 27);
        for l in &LABELS {
            assert_eq!(h[l.name], l.freq as usize, "{}", l.name);
        }
        let mut f: Vec<usize> = h.values().copied().collect();
        f.sort_unstable();
        assert_eq!(f[f.len() / 2], 5, "median frequency");
        check_structure(&g);
    }

    /// Invariants every generated office has.
    fn check_structure(g: &DsgGraph) {
        let index = g.node_index();
        let mesh = g.mesh.as_ref().expect("mesh");
        let nv = mesh.points.len();
        assert_eq!(mesh.labels.as_ref().map(Vec::len), Some(nv));
        assert!(mesh.faces.iter().flatten().all(|&i| (i as usize) < nv));
        let mut ids: Vec<u64> = g.nodes.iter().map(|n| n.id).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), g.nodes.len(), "unique ids");
        for n in &g.nodes {
            assert!(g.layer(n.layer).is_some());
            match n.parent {
                None => assert_eq!(n.kind, NodeKind::Building),
                Some(p) => {
                    let parent = &g.nodes[index[&p]];
                    assert!(parent.layer.is_parent_of(n.layer));
                }
            }
            assert!(n.mesh_connections.iter().all(|&v| (v as usize) < nv));
            assert!(n.mesh_connections.windows(2).all(|w| w[0] < w[1]));
        }
        // Every object lies in a room, and (when every room has places, i.e. above
        // degenerate scales) in the room of its place.
        let places_everywhere = (0..ROOMS.len()).all(|r| {
            g.nodes.iter().any(|n| {
                n.kind == NodeKind::Place && n.parent == Some(NodeSymbol::new(b'R', r as u64).id())
            })
        });
        for o in g.nodes.iter().filter(|n| n.kind == NodeKind::Object) {
            let [x, y, z] = o.position.map(f64::from);
            let r = room_at(x, y).expect("object in a room");
            assert!((-0.05..CEILING + 0.05).contains(&z), "{z}");
            let place = &g.nodes[index[&o.parent.expect("object parent")]];
            let room = &g.nodes[index[&place.parent.expect("place parent")]];
            if places_everywhere {
                let b = room.bbox.expect("room box");
                assert!(b.contains(o.position), "{:?} outside {:?}", o.position, b);
                let rr = NodeSymbol::from_id(room.id).index() as usize;
                let [x0, x1, y0, y1] = ROOMS[rr];
                assert!(r == rr || (x0 <= x && x <= x1 && y0 <= y && y <= y1));
            }
            assert_eq!(o.label, o.name);
        }
        for e in &g.edges {
            let (a, b) = (&g.nodes[index[&e.source]], &g.nodes[index[&e.target]]);
            assert_eq!(a.layer, b.layer);
            assert_ne!(a.id, b.id);
        }
    }

    #[test]
    fn tiny_office_matches_the_tiny_fixture_counts() {
        let g = generate(OfficeParams {
            seed: 7,
            scale: 0.02,
        });
        let c = g.counts();
        assert_eq!(c.nodes, 110);
        assert_eq!(c.kind(NodeKind::Object), 34);
        assert_eq!(c.kind(NodeKind::Place), 23);
        assert_eq!(c.kind(NodeKind::Place2d), 29);
        assert_eq!(c.kind(NodeKind::Agent), 14);
        assert_eq!(c.edges, 270);
        assert_eq!(c.mesh_vertices, 7_098);
        let s = g.claim_stats().expect("mesh");
        assert_eq!(
            (s.unclaimed, s.multi_claimed, s.claimed, s.total_claims),
            (6_270, 560, 828, 1_388)
        );
        assert_eq!(s.wrong_boxes, 20);
        let h = g.object_label_histogram();
        assert_eq!(h.len(), 27);
        assert_eq!(
            (h["light"], h["chair"], h["desk"], h["monitor"], h["shelf"]),
            (4, 3, 2, 2, 1)
        );
        check_structure(&g);
    }

    #[test]
    fn generation_is_deterministic_per_seed() {
        let a = generate(OfficeParams {
            seed: 11,
            scale: 0.05,
        });
        let b = generate(OfficeParams {
            seed: 11,
            scale: 0.05,
        });
        assert_eq!(a, b);
        let c = generate(OfficeParams {
            seed: 12,
            scale: 0.05,
        });
        assert_ne!(a.nodes, c.nodes);
        // Counts do not depend on the seed, except the face count below scale 1
        // (the natural face count of small patches is under the target).
        let (mut ca, mut cc) = (a.counts(), c.counts());
        (ca.mesh_faces, cc.mesh_faces) = (0, 0);
        assert_eq!(ca, cc);
        assert_eq!(
            a.claim_stats().map(|s| s.unclaimed),
            c.claim_stats().map(|s| s.unclaimed)
        );
        assert_eq!(
            a.claim_stats().map(|s| s.wrong_boxes),
            c.claim_stats().map(|s| s.wrong_boxes)
        );
    }

    #[test]
    fn degenerate_scales_still_give_a_valid_office() {
        for scale in [0.0, -1.0, f64::NAN, 1e-6, 0.003] {
            let g = generate(OfficeParams { seed: 1, scale });
            let c = g.counts();
            assert_eq!(c.kind(NodeKind::Room), 9);
            assert_eq!(c.kind(NodeKind::Object), 34);
            assert!(c.kind(NodeKind::Agent) >= 2);
            check_structure(&g);
        }
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
    fn alloc_splits_exactly_by_largest_remainder() {
        assert_eq!(alloc(10, &[1.0, 1.0, 1.0]), vec![4, 3, 3]);
        assert_eq!(alloc(7, &[0.0, 0.0]), vec![4, 3]);
        assert_eq!(alloc(5, &[3.0, 1.0]).iter().sum::<usize>(), 5);
        assert!(alloc(3, &[]).is_empty());
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
