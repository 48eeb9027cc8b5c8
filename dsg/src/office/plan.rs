//! The fixed office: count targets at full scale, floor plan, doors, label table,
//! room shells, layers and labelspaces.

use std::collections::BTreeMap;

use crate::model::{DsgLayer, LayerKey};

/// Full-scale targets (uHumans2 office, as in the paper).
pub(super) mod full {
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

/// Where an object of a label stands.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Placement {
    /// On the floor.
    Floor,
    /// Under the ceiling.
    Ceiling,
    /// Against a wall.
    Wall,
    /// On a desk or table top.
    Surface,
}

/// One row of [`LABELS`].
pub(super) struct LabelSpec {
    pub(super) name: &'static str,
    pub(super) freq: u32,
    pub(super) size: [f64; 3],
    pub(super) place: Placement,
    pub(super) base: f64,
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
pub(super) const LABELS: [LabelSpec; 27] = [
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
pub(super) const MESH_WALL: u32 = 27;
pub(super) const MESH_FLOOR: u32 = 28;
pub(super) const MESH_CEILING: u32 = 29;

/// Time of the first agent pose and between poses, ns.
pub(super) const T0_NS: u64 = 1_000_000_000;
pub(super) const DT_NS: u64 = 200_000_000;

/// The 27 object label names in semantic-label order (alphabetical, as in the
/// `_l2p0` labelspace of the data files).
pub fn label_names() -> Vec<&'static str> {
    let mut names: Vec<&'static str> = LABELS.iter().map(|l| l.name).collect();
    names.sort_unstable();
    names
}

/// Floor area of room `r`.
pub(super) fn area(r: usize) -> f64 {
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

/// Distance from `p` to the nearest wall, floor or ceiling of room `r`.
pub(super) fn free_dist(p: [f64; 3], r: usize) -> f64 {
    let [x0, x1, y0, y1] = ROOMS[r];
    (p[0] - x0)
        .min(x1 - p[0])
        .min(p[1] - y0)
        .min(y1 - p[1])
        .min(p[2])
        .min(CEILING - p[2])
}

/// A floor, ceiling or wall patch: origin, the two edge vectors, mesh label, area.
pub(super) type Shell = ([f64; 3], [f64; 3], [f64; 3], u32, f64);

/// The floor, ceiling and four walls of every room.
pub(super) fn shell_patches() -> Vec<Shell> {
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

/// The layers of the data files, with their aliases.
pub(super) fn office_layers() -> Vec<DsgLayer> {
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

/// The `_l2p0` (objects) and `mesh` labelspaces of the data files.
pub(super) fn office_labelspaces(names: &[&str]) -> BTreeMap<String, BTreeMap<u32, String>> {
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
