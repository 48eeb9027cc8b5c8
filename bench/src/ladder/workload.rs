//! The paper's query workload: 64 reference points per room (fixed seed), Q1a, Q1b at
//! five radii, Q2 with random cones, Q3 for four label classes; and [`Answer`], what every
//! target returns for a query.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};
use ygg_dsg::objects::{ObjectQuery, cone_view};
use ygg_dsg::{DsgGraph, NodeKind};
use ygg_store::Point;
use ygg_store::query::{CheckedCone, within_radius};

/// Sorted object ids answering one query.
pub type Answer = Vec<u64>;

/// Radii of Q1b, metres.
pub const RADII: [f32; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];
/// Labels of Q3: frequent, median, rare, absent.
pub const LABELS: [&str; 4] = ["light", "shelf", "bulletin", "unicorn"];

/// One query of the workload.
#[derive(Clone, Debug, PartialEq)]
pub enum Query {
    /// Q1a: the object nearest `point` among the room's objects.
    Nearest { room: u64, point: Point },
    /// Q1b: the room's objects with a point within `radius` of `point`.
    Within {
        room: u64,
        point: Point,
        radius: f32,
    },
    /// Q2: the room's objects with a point inside the cone.
    Visible {
        room: u64,
        eye: Point,
        dir: Point,
        half_angle_deg: f32,
        range: f32,
    },
    /// Q3: objects carrying `label`.
    Label { label: String },
}

impl Query {
    /// The row name of the query's family ("Q1a", "Q1b@0.25", "Q2", "Q3:light").
    pub fn family(&self) -> String {
        match self {
            Query::Nearest { .. } => "Q1a".into(),
            Query::Within { radius, .. } => format!("Q1b@{radius}"),
            Query::Visible { .. } => "Q2".into(),
            Query::Label { label } => format!("Q3:{label}"),
        }
    }

    /// The room the query is asked in (`None` for Q3, which asks the whole scene).
    pub fn room(&self) -> Option<u64> {
        match self {
            Query::Nearest { room, .. }
            | Query::Within { room, .. }
            | Query::Visible { room, .. } => Some(*room),
            Query::Label { .. } => None,
        }
    }

    /// The query as the object-query contract ([`ObjectQuery`]) asks it, without the room.
    pub fn to_object_query(&self) -> ObjectQuery {
        match self {
            Query::Nearest { point, .. } => ObjectQuery::NearestObject { point: *point },
            Query::Within { point, radius, .. } => ObjectQuery::ObjectsWithin {
                point: *point,
                radius: *radius,
            },
            Query::Visible {
                eye,
                dir,
                half_angle_deg,
                range,
                ..
            } => ObjectQuery::VisibleObjects {
                eye: *eye,
                dir: *dir,
                half_angle_deg: *half_angle_deg,
                range: *range,
            },
            Query::Label { label } => ObjectQuery::ObjectsWithLabel {
                label: label.clone(),
            },
        }
    }

    fn to_json(&self, id: usize) -> Value {
        match self {
            Query::Nearest { room, point } => {
                json!({"id": id, "family": "Q1a", "room": room, "point": point})
            }
            Query::Within {
                room,
                point,
                radius,
            } => {
                json!({"id": id, "family": "Q1b", "room": room, "point": point, "radius": radius})
            }
            Query::Visible {
                room,
                eye,
                dir,
                half_angle_deg,
                range,
            } => json!({
                "id": id, "family": "Q2", "room": room, "eye": eye, "dir": dir,
                "half_angle_deg": half_angle_deg, "range": range
            }),
            Query::Label { label } => json!({"id": id, "family": "Q3", "label": label}),
        }
    }
}

/// The workload: queries plus the update used for "query after an update".
pub struct Workload {
    /// Every query, in a fixed order.
    pub queries: Vec<Query>,
    /// The object moved by the update.
    pub update_object: u64,
    /// How far it moves.
    pub update_translation: Point,
}

impl Workload {
    /// Draws the workload from a fixed seed: `per_room` reference points in each room's
    /// box (x, y inside the box, z between 0.2 m and 2.8 m).
    pub fn generate(dsg: &DsgGraph, seed: u64, per_room: usize) -> Workload {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut rooms: Vec<_> = dsg
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Room)
            .collect();
        rooms.sort_by_key(|r| r.id);
        let mut queries = Vec::new();
        for room in &rooms {
            let (lo, hi) = match room.bbox {
                Some(b) => (b.min, b.max),
                None => {
                    let p = room.position;
                    ([p[0] - 2.0, p[1] - 2.0, 0.0], [p[0] + 2.0, p[1] + 2.0, 3.0])
                }
            };
            for _ in 0..per_room {
                let point = [
                    rng.gen_range(lo[0]..=hi[0]),
                    rng.gen_range(lo[1]..=hi[1]),
                    rng.gen_range(0.2f32..=2.8),
                ];
                queries.push(Query::Nearest {
                    room: room.id,
                    point,
                });
                for radius in RADII {
                    queries.push(Query::Within {
                        room: room.id,
                        point,
                        radius,
                    });
                }
                let yaw: f32 = rng.gen_range(0.0..std::f32::consts::TAU);
                let pitch: f32 = rng.gen_range(-0.4f32..0.4);
                let dir = [
                    yaw.cos() * pitch.cos(),
                    yaw.sin() * pitch.cos(),
                    pitch.sin(),
                ];
                queries.push(Query::Visible {
                    room: room.id,
                    eye: point,
                    dir,
                    half_angle_deg: rng.gen_range(30.0..=70.0),
                    range: rng.gen_range(0.3..=8.0),
                });
            }
        }
        for label in LABELS {
            queries.push(Query::Label {
                label: label.into(),
            });
        }
        let mut objects: Vec<u64> = dsg
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Object && !n.mesh_connections.is_empty())
            .map(|n| n.id)
            .collect();
        objects.sort_unstable();
        let update_object = objects.get(objects.len() / 2).copied().unwrap_or(0);
        Workload {
            queries,
            update_object,
            update_translation: [0.05, -0.03, 0.0],
        }
    }

    /// The workload as the JSON the Spark-DSG anchor script reads.
    pub fn to_json(&self) -> Value {
        json!({
            "queries": self.queries.iter().enumerate().map(|(i, q)| q.to_json(i)).collect::<Vec<_>>(),
            "update": {"object": self.update_object, "translation": self.update_translation},
        })
    }
}

/// A brute-force answer to a spatial query (Q1a, Q1b, Q2), as the dsg and vanilla rungs
/// compute it: feed it every object of the query's room with its points
/// ([`Scan::object`]), then take [`Scan::answer`]. The tests are the store's: ties to
/// the smaller id, [`within_radius`], and the contract's cone ([`cone_view`]).
pub struct Scan<'q> {
    query: &'q Query,
    /// Q2's cone, checked once (`None` for an invalid cone, which sees nothing).
    cone: Option<CheckedCone>,
    /// Q1a: the closest point so far (squared distance) and its object.
    best: Option<(f32, u64)>,
    /// Q1b, Q2: the objects found.
    found: Answer,
}

impl<'q> Scan<'q> {
    /// A scan answering `query`.
    pub fn new(query: &'q Query) -> Self {
        let cone = match query {
            Query::Visible {
                eye,
                dir,
                half_angle_deg,
                range,
                ..
            } => cone_view(*eye, *dir, *half_angle_deg, *range)
                .ok()
                .and_then(|c| c.checked().ok()),
            _ => None,
        };
        Scan {
            query,
            cone,
            best: None,
            found: Vec::new(),
        }
    }

    /// Takes object `id` with (some of) its points into account; an object may come
    /// several times.
    pub fn object<'p>(&mut self, id: u64, points: impl IntoIterator<Item = &'p Point>) {
        let mut points = points.into_iter();
        let hit = match self.query {
            Query::Nearest { point, .. } => {
                for p in points {
                    let d = ygg_store::distance_squared(p, point);
                    if self
                        .best
                        .is_none_or(|(bd, bid)| d < bd || (d == bd && id < bid))
                    {
                        self.best = Some((d, id));
                    }
                }
                false
            }
            Query::Within { point, radius, .. } => points.any(|p| within_radius(p, point, *radius)),
            Query::Visible { .. } => self
                .cone
                .as_ref()
                .is_some_and(|cone| points.any(|p| cone.contains(p))),
            Query::Label { .. } => false,
        };
        if hit {
            self.found.push(id);
        }
    }

    /// The answer: object ids ascending.
    pub fn answer(self) -> Answer {
        let mut out: Answer = self.best.map(|(_, id)| id).into_iter().collect();
        out.extend(self.found);
        out.sort_unstable();
        out.dedup();
        out
    }
}
