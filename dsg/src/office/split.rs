//! The same office as a building of more, smaller rooms ([`split_rooms`]).

use crate::model::{DsgAabb, DsgEdge, DsgGraph, DsgNode, NodeKind};
use crate::symbol::NodeSymbol;

/// Why [`split_rooms`] refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SplitRoomsError {
    /// Fewer rooms were asked for than the graph has.
    #[error("cannot split {have} rooms into {wanted}: ask for at least {have}")]
    TooFew {
        /// Rooms in the graph.
        have: usize,
        /// Rooms asked for.
        wanted: usize,
    },
    /// A room has no stored box to split.
    #[error("room {id:#x} has no bounding box to split")]
    NoBox {
        /// The room's node id.
        id: u64,
    },
}

/// `g` with its rooms split into `rooms` rooms in all: each room is cut across its longer side
/// into strips of equal width, the number of strips per room proportional to its floor area
/// (largest remainders, at least one each). The new rooms are `R(0)`..`R(rooms-1)`, room by
/// room; each node nested directly in a room moves to the strip holding its position (objects
/// and agents follow their place), consecutive strips of a room are joined by an edge, and a
/// door between two rooms joins their first strips. Everything else is unchanged, so
/// `split_rooms(&generate(p), 9)` renumbers nothing and equals `generate(p)` but for the
/// [`DsgGraph::source`] string.
///
/// For the many-layer scenes of the transport benchmark: the office in a per-room layout with
/// 103 rooms has 418 layers.
///
/// # Errors
///
/// [`SplitRoomsError::TooFew`] if `rooms` is below the graph's room count,
/// [`SplitRoomsError::NoBox`] if a room has no stored box.
pub fn split_rooms(g: &DsgGraph, rooms: usize) -> Result<DsgGraph, SplitRoomsError> {
    let old: Vec<&DsgNode> = g
        .nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Room)
        .collect();
    if rooms < old.len() {
        return Err(SplitRoomsError::TooFew {
            have: old.len(),
            wanted: rooms,
        });
    }
    let boxes = old
        .iter()
        .map(|r| r.bbox.ok_or(SplitRoomsError::NoBox { id: r.id }))
        .collect::<Result<Vec<_>, _>>()?;
    let counts = strips_per_room(&boxes, rooms);
    let mut plans = Vec::with_capacity(old.len());
    let mut next = 0;
    for (room, (bbox, &count)) in old.iter().zip(boxes.iter().zip(&counts)) {
        plans.push(Strips::new(room.id, *bbox, count, next));
        next += count;
    }
    let plan_of = |id: u64| plans.iter().find(|p| p.old == id);

    let mut out = g.clone();
    out.source = format!("{} rooms={rooms}", g.source);
    let mut nodes = Vec::with_capacity(g.nodes.len() + rooms - old.len());
    for n in &g.nodes {
        if let Some(plan) = plan_of(n.id) {
            nodes.extend((0..plan.count).map(|i| plan.room_node(n, i)));
            continue;
        }
        let mut n = n.clone();
        if let Some(plan) = n.parent.and_then(plan_of) {
            n.parent = Some(plan.id_at(n.position));
        }
        nodes.push(n);
    }
    out.nodes = nodes;
    let mut edges = Vec::with_capacity(g.edges.len() + rooms);
    for e in &g.edges {
        match (plan_of(e.source), plan_of(e.target)) {
            (Some(a), Some(b)) => edges.push(DsgEdge {
                source: a.id(0),
                target: b.id(0),
                weight: e.weight,
            }),
            _ => edges.push(*e),
        }
    }
    for plan in &plans {
        edges.extend((1..plan.count).map(|i| DsgEdge {
            source: plan.id(i - 1),
            target: plan.id(i),
            weight: None,
        }));
    }
    out.edges = edges;
    for e in &mut out.extra_parent_edges {
        if let Some(plan) = plan_of(e.parent) {
            e.parent = plan.id(0);
        }
    }
    Ok(out)
}

/// Strips per room: proportional to floor area, at least one each, `total` in all.
fn strips_per_room(boxes: &[DsgAabb], total: usize) -> Vec<usize> {
    let area = |b: &DsgAabb| f64::from((b.max[0] - b.min[0]) * (b.max[1] - b.min[1])).max(0.0);
    let sum: f64 = boxes.iter().map(area).sum();
    let extra = total - boxes.len();
    let shares: Vec<f64> = boxes
        .iter()
        .map(|b| {
            if sum > 0.0 {
                extra as f64 * area(b) / sum
            } else {
                extra as f64 / boxes.len() as f64
            }
        })
        .collect();
    let mut counts: Vec<usize> = shares.iter().map(|s| 1 + s.floor() as usize).collect();
    let mut order: Vec<usize> = (0..boxes.len()).collect();
    order.sort_by(|&a, &b| {
        let frac = |i: usize| shares[i] - shares[i].floor();
        frac(b).total_cmp(&frac(a)).then(a.cmp(&b))
    });
    let missing = total - counts.iter().sum::<usize>();
    for &i in order.iter().take(missing) {
        counts[i] += 1;
    }
    counts
}

/// How one room is cut.
struct Strips {
    old: u64,
    bbox: DsgAabb,
    count: usize,
    /// Index of the first strip's `R(i)`.
    first: usize,
    /// The axis cut across (0: x, 1: y): the longer side.
    axis: usize,
}

impl Strips {
    fn new(old: u64, bbox: DsgAabb, count: usize, first: usize) -> Self {
        let axis = usize::from(bbox.max[1] - bbox.min[1] > bbox.max[0] - bbox.min[0]);
        Self {
            old,
            bbox,
            count,
            first,
            axis,
        }
    }

    fn id(&self, i: usize) -> u64 {
        NodeSymbol::new(b'R', (self.first + i) as u64).id()
    }

    fn width(&self) -> f32 {
        (self.bbox.max[self.axis] - self.bbox.min[self.axis]) / self.count as f32
    }

    /// The strip holding `p` (points outside go to the nearest end).
    fn id_at(&self, p: [f32; 3]) -> u64 {
        let t = (p[self.axis] - self.bbox.min[self.axis]) / self.width();
        // Saturating float-to-int cast; clamped to the strips.
        self.id((t.max(0.0) as usize).min(self.count - 1))
    }

    fn room_node(&self, old: &DsgNode, i: usize) -> DsgNode {
        if self.count == 1 && old.id == self.id(0) {
            return old.clone();
        }
        let mut bbox = self.bbox;
        bbox.min[self.axis] = self.bbox.min[self.axis] + self.width() * i as f32;
        if i + 1 < self.count {
            bbox.max[self.axis] = bbox.min[self.axis] + self.width();
        }
        let centre = std::array::from_fn(|k| (bbox.min[k] + bbox.max[k]) / 2.0);
        DsgNode {
            id: self.id(i),
            name: Some(format!("R({})", self.first + i)),
            position: centre,
            bbox: Some(bbox),
            ..old.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::office::{OfficeParams, generate};

    #[test]
    fn splitting_into_as_many_rooms_changes_nothing_but_the_source() {
        let g = generate(OfficeParams {
            seed: 7,
            scale: 0.02,
        });
        let mut same = split_rooms(&g, 9).expect("split");
        assert_ne!(same.source, g.source);
        same.source.clone_from(&g.source);
        assert_eq!(same, g);
    }

    #[test]
    fn rooms_are_split_and_every_child_lies_in_its_room() {
        let g = generate(OfficeParams {
            seed: 7,
            scale: 0.02,
        });
        let split = split_rooms(&g, 103).expect("split");
        let rooms: Vec<&DsgNode> = split
            .nodes
            .iter()
            .filter(|n| n.kind == NodeKind::Room)
            .collect();
        assert_eq!(rooms.len(), 103);
        assert_eq!(split.nodes.len(), g.nodes.len() + 103 - 9);
        for n in &split.nodes {
            let Some(room) = rooms.iter().find(|r| Some(r.id) == n.parent) else {
                continue;
            };
            let b = room.bbox.expect("box");
            // Only points beyond the room's own box may land in an end strip.
            let inside = (0..2)
                .all(|k| n.position[k] >= b.min[k] - 1e-3 && n.position[k] <= b.max[k] + 1e-3);
            let original_inside = g
                .nodes
                .iter()
                .find(|o| o.id == n.id)
                .and_then(|o| o.parent)
                .and_then(|p| g.nodes.iter().find(|r| r.id == p))
                .and_then(|r| r.bbox)
                .is_some_and(|ob| {
                    (0..2).all(|k| n.position[k] >= ob.min[k] && n.position[k] <= ob.max[k])
                });
            assert!(
                inside || !original_inside,
                "node {:#x} outside its room",
                n.id
            );
        }
        assert!(matches!(
            split_rooms(&g, 3),
            Err(SplitRoomsError::TooFew { have: 9, wanted: 3 })
        ));
    }
}
