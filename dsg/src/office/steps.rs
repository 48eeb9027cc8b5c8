//! [`Gen::run`]: the office in named steps, in the order they draw from the random
//! stream (changing that order changes every office).

use rand::distributions::{Distribution, WeightedIndex};
use rand::seq::SliceRandom;

use super::grid::Grid;
use super::mesh::block_order;
use super::objects::{add_partner_claims, stored_box};
use super::places::{edges_for, trajectory};
use super::plan::{
    CEILING, DOORS, LABELS, ROOMS, area, free_dist, full, label_names, office_labelspaces,
    office_layers, shell_patches,
};
use super::sampling::{Gen, alloc, f32x3, round_even};
use crate::model::{DsgAabb, DsgEdge, DsgGraph, DsgMesh, DsgNode, DsgVersion, LayerKey, NodeKind};
use crate::symbol::NodeSymbol;

/// Every count of one office, from the full-scale targets and the scale.
struct Counts {
    vertices: usize,
    faces: usize,
    unclaimed: usize,
    claimed: usize,
    /// Vertices claimed by more than one object.
    multi: usize,
    places: usize,
    mesh_places: usize,
    agents: usize,
    /// Objects of each label (same order as [`LABELS`]).
    per_label: Vec<usize>,
    objects: usize,
    wrong_boxes: usize,
}

/// The objects before the mesh: label (index into [`LABELS`]), room, centre and half
/// extents of each.
struct ObjectDraft {
    labels: Vec<usize>,
    rooms: Vec<usize>,
    centers: Vec<[f64; 3]>,
    halves: Vec<[f64; 3]>,
}

/// The mesh before the vertex reorder: points (already rounded to `f32`), faces, the
/// semantic label of each point, the vertex range each object's surface owns, and the
/// size of each range.
struct MeshDraft {
    points: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    labels: Vec<u32>,
    own_ranges: Vec<(usize, usize)>,
    own_counts: Vec<usize>,
}

/// Places and mesh places with the room of each.
struct PlaceDraft {
    places: Vec<[f64; 3]>,
    place_rooms: Vec<usize>,
    mesh_places: Vec<[f64; 3]>,
    mesh_place_rooms: Vec<usize>,
}

/// The node id of symbol `c`, index `i`.
fn sym(c: u8, i: usize) -> u64 {
    NodeSymbol::new(c, i as u64).id()
}

/// The semantic label of label `li` (index into [`LABELS`]): its rank in `names`.
fn semantic_label(names: &[&str], li: usize) -> u32 {
    names
        .iter()
        .position(|n| *n == LABELS[li].name)
        .unwrap_or(0) as u32
}

impl Gen {
    /// Builds the office: counts, agent trajectory, objects, mesh, claims, Hydra-like
    /// vertex order, stored boxes, places, parents, edges and nodes.
    pub(super) fn run(mut self) -> DsgGraph {
        let counts = self.counts();
        let areas: Vec<f64> = (0..ROOMS.len()).map(area).collect();
        let names = label_names();
        let (agent_pos, agent_t) = trajectory(counts.agents);
        let objects = self.draw_objects(&counts, &names, &areas);
        let mut mesh = self.draw_mesh(&counts, &objects, &names);
        self.drop_faces(&mut mesh.faces, counts.faces);
        let claims = self.draw_claims(&counts, &objects, &mesh);
        // Hydra-like vertex order: by 1.6 m voxel block, then stable.
        let (inv, claims) = reorder_vertices(&mut mesh, claims);
        let boxes = self.object_boxes(
            &claims,
            &mesh.points,
            &objects.centers,
            &objects.halves,
            counts.wrong_boxes,
        );
        let places = self.draw_places(&counts, &areas);
        let edges = self.office_edges(&counts, &places);
        let positions = object_positions(&objects, &mesh, &inv);
        let nodes = office_nodes(
            &objects,
            &positions,
            &claims,
            &boxes,
            &places,
            (&agent_pos, &agent_t),
            &names,
        );
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
                points: mesh.points.iter().map(|&p| f32x3(p)).collect(),
                faces: mesh.faces,
                labels: Some(mesh.labels),
            }),
            labelspaces: office_labelspaces(&names),
        }
    }

    fn counts(&self) -> Counts {
        let scale = self.scale;
        let vertices = self.count(full::VERTICES);
        let unclaimed = self.count(full::UNCLAIMED).min(vertices);
        let claimed = vertices - unclaimed;
        let obj_scale = scale.max(0.1);
        let per_label: Vec<usize> = LABELS
            .iter()
            .map(|l| {
                if scale == 1.0 {
                    l.freq as usize
                } else {
                    round_even(f64::from(l.freq) * obj_scale).max(1)
                }
            })
            .collect();
        let objects: usize = per_label.iter().sum();
        Counts {
            vertices,
            faces: self.count(full::FACES),
            unclaimed,
            claimed,
            multi: self.count(full::MULTI).min(claimed),
            places: self.count(full::PLACES).max(1),
            mesh_places: self.count(full::MESH_PLACES).max(1),
            agents: self.count(full::AGENTS).max(2),
            per_label,
            objects,
            wrong_boxes: round_even(full::WRONG_BOXES * objects as f64 / full::OBJECTS)
                .min(objects),
        }
    }

    /// Objects: labels shuffled, rooms drawn by area, then each placed in its room.
    fn draw_objects(&mut self, counts: &Counts, names: &[&str], areas: &[f64]) -> ObjectDraft {
        let n_obj = counts.objects;
        let mut labels: Vec<usize> = Vec::with_capacity(n_obj);
        for name in names {
            let li = LABELS.iter().position(|l| l.name == *name).unwrap_or(0);
            labels.extend(std::iter::repeat_n(li, counts.per_label[li]));
        }
        labels.shuffle(&mut self.rng);
        let room_dist = WeightedIndex::new(areas).ok();
        let rooms: Vec<usize> = (0..n_obj)
            .map(|_| room_dist.as_ref().map_or(0, |d| d.sample(&mut self.rng)))
            .collect();
        let mut centers = vec![[0.0; 3]; n_obj];
        let mut halves = vec![[0.0; 3]; n_obj];
        for o in 0..n_obj {
            let (c, h) = self.place_object(&LABELS[labels[o]], rooms[o]);
            centers[o] = c;
            halves[o] = h;
        }
        ObjectDraft {
            labels,
            rooms,
            centers,
            halves,
        }
    }

    /// The mesh: object surfaces (claimed, by surface area) then room shells
    /// (unclaimed, by area), with noise, rounded to `f32` as a file stores them.
    fn draw_mesh(&mut self, counts: &Counts, objects: &ObjectDraft, names: &[&str]) -> MeshDraft {
        let n_vert = counts.vertices;
        let sa: Vec<f64> = objects
            .halves
            .iter()
            .map(|h| 2.0 * (h[0] * h[1] + h[1] * h[2] + h[0] * h[2]) + 0.02)
            .collect();
        let own_counts = alloc(counts.claimed, &sa);
        let mut pts: Vec<[f64; 3]> = Vec::with_capacity(n_vert);
        let mut faces: Vec<[u32; 3]> = Vec::with_capacity(2 * n_vert);
        let mut labs: Vec<u32> = Vec::with_capacity(n_vert);
        let mut own_ranges = Vec::with_capacity(counts.objects);
        for (o, &n_own) in own_counts.iter().enumerate() {
            let (p, f) = self.box_surface(objects.centers[o], objects.halves[o], n_own);
            let off = pts.len();
            self.push_noisy(&mut pts, p, 0.003);
            faces.extend(f.iter().map(|t| t.map(|i| i + off as u32)));
            labs.extend(std::iter::repeat_n(
                semantic_label(names, objects.labels[o]),
                pts.len() - off,
            ));
            own_ranges.push((off, pts.len()));
        }
        let patches = shell_patches();
        let n_patch = alloc(
            counts.unclaimed,
            &patches.iter().map(|p| p.4).collect::<Vec<_>>(),
        );
        for (&(origin, u, v, label, _), &n) in patches.iter().zip(&n_patch) {
            let (p, f) = self.grid_patch(origin, u, v, n);
            let off = pts.len();
            self.push_noisy(&mut pts, p, 0.002);
            faces.extend(f.iter().map(|t| t.map(|i| i + off as u32)));
            labs.extend(std::iter::repeat_n(label, pts.len() - off));
        }
        // What a file stores: f32.
        let points: Vec<[f64; 3]> = pts.iter().map(|p| p.map(|x| f64::from(x as f32))).collect();
        MeshDraft {
            points,
            faces,
            labels: labs,
            own_ranges,
            own_counts,
        }
    }

    /// Appends `points` to `out`, each moved by normal noise of deviation `sigma` per axis.
    fn push_noisy(&mut self, out: &mut Vec<[f64; 3]>, points: Vec<[f64; 3]>, sigma: f64) {
        for q in points {
            let n = [self.normal(), self.normal(), self.normal()];
            out.push([
                q[0] + sigma * n[0],
                q[1] + sigma * n[1],
                q[2] + sigma * n[2],
            ]);
        }
    }

    /// Holes: drops faces at random down to `target`.
    fn drop_faces(&mut self, faces: &mut Vec<[u32; 3]>, target: usize) {
        if faces.len() <= target {
            return;
        }
        let mut drop = vec![false; faces.len()];
        for i in rand::seq::index::sample(&mut self.rng, faces.len(), faces.len() - target) {
            drop[i] = true;
        }
        let mut k = 0;
        faces.retain(|_| {
            k += 1;
            !drop[k - 1]
        });
    }

    /// Claims: each object's own vertices, plus part of them claimed by a partner (the
    /// nearest object of the same room, else any other).
    fn draw_claims(
        &mut self,
        counts: &Counts,
        objects: &ObjectDraft,
        mesh: &MeshDraft,
    ) -> Vec<Vec<usize>> {
        let mut claims: Vec<Vec<usize>> = mesh
            .own_ranges
            .iter()
            .map(|&(a, b)| (a..b).collect())
            .collect();
        let k_share = self.share_counts(counts.multi, &mesh.own_counts);
        let centers = &objects.centers;
        let obj_grid = Grid::new(centers, 2.0);
        let partner: Vec<usize> = (0..counts.objects)
            .map(|o| {
                obj_grid
                    .nearest(centers[o], centers, |j| {
                        j != o && objects.rooms[j] == objects.rooms[o]
                    })
                    .or_else(|| obj_grid.nearest(centers[o], centers, |j| j != o))
                    .unwrap_or(o)
            })
            .collect();
        add_partner_claims(
            &mut claims,
            &mesh.own_ranges,
            &k_share,
            &partner,
            centers,
            &mesh.points,
        );
        claims
    }

    /// Places and mesh places, uniform in each room by area.
    fn draw_places(&mut self, counts: &Counts, areas: &[f64]) -> PlaceDraft {
        let p_counts = alloc(counts.places, areas);
        let (places, place_rooms) = self.sample_in_rooms(&p_counts, 0.3, 0.6, 2.2);
        let m_counts = alloc(counts.mesh_places, areas);
        let (mut mesh_places, mesh_place_rooms) = self.sample_in_rooms(&m_counts, 0.2, 0.0, 0.0);
        for p in &mut mesh_places {
            p[2] = 0.02;
        }
        PlaceDraft {
            places,
            place_rooms,
            mesh_places,
            mesh_place_rooms,
        }
    }

    /// Intra-layer edges: odometry, doors, place–place and mesh-place–mesh-place.
    fn office_edges(&self, counts: &Counts, places: &PlaceDraft) -> Vec<DsgEdge> {
        let mut edges = Vec::new();
        for i in 0..counts.agents.saturating_sub(1) {
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
        let rad = 1.0 / self.scale.sqrt();
        let (place_pos, place_room) = (&places.places, &places.place_rooms);
        let pe = edges_for(
            place_pos,
            place_room,
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
            &places.mesh_places,
            &places.mesh_place_rooms,
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
        edges
    }
}

/// Reorders the mesh's vertices by [`block_order`] (points, labels, faces) and maps the
/// claims to the new order (sorted, deduplicated). Returns the old-to-new map and the
/// claims.
fn reorder_vertices(mesh: &mut MeshDraft, claims: Vec<Vec<usize>>) -> (Vec<u32>, Vec<Vec<u32>>) {
    let perm = block_order(&mesh.points, 1.6);
    let mut inv = vec![0u32; mesh.points.len()];
    for (new, &old) in perm.iter().enumerate() {
        inv[old] = new as u32;
    }
    mesh.points = perm.iter().map(|&i| mesh.points[i]).collect();
    mesh.labels = perm.iter().map(|&i| mesh.labels[i]).collect();
    for f in &mut mesh.faces {
        *f = f.map(|i| inv[i as usize]);
    }
    let claims = claims
        .into_iter()
        .map(|c| {
            let mut c: Vec<u32> = c.into_iter().map(|v| inv[v]).collect();
            c.sort_unstable();
            c.dedup();
            c
        })
        .collect();
    (inv, claims)
}

/// Each object's position: the mean of the vertices its surface owns (`inv`: old to
/// new vertex index), or its centre when it owns none.
fn object_positions(objects: &ObjectDraft, mesh: &MeshDraft, inv: &[u32]) -> Vec<[f64; 3]> {
    mesh.own_ranges
        .iter()
        .zip(&objects.centers)
        .map(|(&(a, b), &center)| {
            if b > a {
                let mut s = [0.0; 3];
                for &v in &inv[a..b] {
                    let p = mesh.points[v as usize];
                    for k in 0..3 {
                        s[k] += p[k];
                    }
                }
                s.map(|x| x / (b - a) as f64)
            } else {
                center
            }
        })
        .collect()
}

/// Every node, in Spark-DSG file order: objects, places, rooms, building, agent poses,
/// mesh places. Objects and agent poses get the nearest place as parent (objects: of
/// their room, if any), places and mesh places their room, rooms the building.
fn office_nodes(
    objects: &ObjectDraft,
    positions: &[[f64; 3]],
    claims: &[Vec<u32>],
    boxes: &[DsgAabb],
    places: &PlaceDraft,
    (agent_pos, agent_t): (&[[f64; 3]], &[u64]),
    names: &[&str],
) -> Vec<DsgNode> {
    let n_obj = objects.labels.len();
    let place_pos = &places.places;
    let place_grid = Grid::new(place_pos, 1.0);
    let obj_parent: Vec<usize> = (0..n_obj)
        .map(|o| {
            let c = objects.centers[o];
            place_grid
                .nearest(c, place_pos, |j| places.place_rooms[j] == objects.rooms[o])
                .or_else(|| place_grid.nearest(c, place_pos, |_| true))
                .unwrap_or(0)
        })
        .collect();
    let agent_parent: Vec<usize> = agent_pos
        .iter()
        .map(|&a| place_grid.nearest(a, place_pos, |_| true).unwrap_or(0))
        .collect();
    let mut nodes = Vec::with_capacity(
        n_obj + place_pos.len() + ROOMS.len() + 1 + agent_pos.len() + places.mesh_places.len(),
    );
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
        let position = positions[o];
        let name = LABELS[objects.labels[o]].name.to_owned();
        nodes.push(DsgNode {
            name: Some(name.clone()),
            label: Some(name),
            semantic_label: Some(semantic_label(names, objects.labels[o])),
            bbox: Some(boxes[o]),
            mesh_connections: claims[o].clone(),
            parent: Some(sym(b'p', obj_parent[o])),
            ..blank(sym(b'O', o), LayerKey::OBJECTS, NodeKind::Object, position)
        });
    }
    for (i, &p) in place_pos.iter().enumerate() {
        nodes.push(DsgNode {
            parent: Some(sym(b'R', places.place_rooms[i])),
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
    for (i, &p) in places.mesh_places.iter().enumerate() {
        nodes.push(DsgNode {
            parent: Some(sym(b'R', places.mesh_place_rooms[i])),
            ..blank(sym(b'Q', i), LayerKey::MESH_PLACES, NodeKind::Place2d, p)
        });
    }
    nodes
}
