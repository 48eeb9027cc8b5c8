//! Visibility: [`Objects::visible_objects`] and the contract's cone, [`cone_view`].

use super::{ObjectQueryError, Objects};
use ygg_store::query::{self, BoxSight, ConeView};
use ygg_store::{Aabb, NodeId, Point, SceneView};

impl<V: SceneView> Objects<'_, V> {
    /// Every object with a vertex `v` such that `|v - eye| <= range` and the angle
    /// between `v - eye` and `dir` is at most `half_angle_deg` degrees, ascending.
    ///
    /// # Errors
    /// [`SpatialQueryError::NonFinitePoint`] (eye), [`SpatialQueryError::InvalidDirection`]
    /// (zero or non-finite `dir`), [`SpatialQueryError::InvalidRange`], and
    /// [`ObjectQueryError::InvalidHalfAngleDeg`] outside `[0, 180]`.
    ///
    /// [`SpatialQueryError::NonFinitePoint`]: ygg_store::query::SpatialQueryError::NonFinitePoint
    /// [`SpatialQueryError::InvalidDirection`]: ygg_store::query::SpatialQueryError::InvalidDirection
    /// [`SpatialQueryError::InvalidRange`]: ygg_store::query::SpatialQueryError::InvalidRange
    ///
    /// # Complexity
    /// Classifies each object's box, then its up to eight part boxes (computed by the
    /// first call, one pass over the claimed vertices), against the cone with margins far above rounding: a box
    /// clearly outside rules its vertices out, a non-empty box clearly inside answers
    /// yes. Only an object that neither settles is searched: for an object of many mesh
    /// nodes whose node index holds exactly its vertices (saffron), one radius search of
    /// that index over a ball around the cone, testing points against the cone until the
    /// first one inside; otherwise [`ygg_store::query::visible`] from the object (a scan of
    /// its vertices that stops at the first visible one).
    pub fn visible_objects(
        &self,
        eye: Point,
        dir: Point,
        half_angle_deg: f32,
        range: f32,
    ) -> Result<Vec<NodeId>, ObjectQueryError> {
        let cone = cone_view(eye, dir, half_angle_deg, range)?;
        let checked = cone.checked()?;
        let claimants = self.claimants();
        let parts = self.parts.get_or_init(|| {
            claimants
                .iter()
                .map(|c| match (&c.bbox, c.mesh.is_empty()) {
                    (Some(around), false) => {
                        let sets: Vec<&[Point]> = c
                            .mesh
                            .iter()
                            .flat_map(|&m| self.view.points(m).runs())
                            .collect();
                        octant_boxes(&sets, around)
                    }
                    _ => Vec::new(),
                })
                .collect()
        });
        let mut out = Vec::new();
        for (c, parts) in claimants.iter().zip(parts) {
            match c.bbox.map(|b| checked.classify(&b)) {
                Some(BoxSight::Outside) => continue,
                // The box holds the object's claimed vertices, and lies inside the cone.
                Some(BoxSight::Inside) => {
                    out.push(c.id);
                    continue;
                }
                Some(BoxSight::Maybe) | None => {}
            }
            // The same with the part boxes: one inside proves a visible vertex (each
            // holds one), all outside prove none.
            if !parts.is_empty() {
                let (mut inside, mut outside) = (false, true);
                for p in parts {
                    match checked.classify(p) {
                        BoxSight::Inside => {
                            inside = true;
                            break;
                        }
                        BoxSight::Maybe => outside = false,
                        BoxSight::Outside => {}
                    }
                }
                if inside {
                    out.push(c.id);
                }
                if inside || outside {
                    continue;
                }
            }
            // An object of many mesh nodes (no part boxes: saffron's one per vertex) whose
            // node index holds exactly its vertices: a yes or no from the index, without
            // a node lookup per vertex found.
            if c.indexed_mesh
                && c.mesh.is_empty()
                && let Some(index) = self.view.node_index(c.id)
            {
                if query::index_sees(&index, &cone)? {
                    out.push(c.id);
                }
                continue;
            }
            let seen = query::visible(self.view, c.id, &cone)?;
            if seen.iter().any(|&m| self.is_mesh_node(m)) {
                out.push(c.id);
            }
        }
        Ok(out)
    }
}

/// The store's view cone for a half-angle in degrees, checked.
///
/// The half-angle is converted with `f32::to_radians` (and clamped to `π`, which
/// 180° may round just above), so every caller builds the very same cone.
///
/// # Errors
/// As [`Objects::visible_objects`].
pub fn cone_view(
    eye: Point,
    dir: Point,
    half_angle_deg: f32,
    range: f32,
) -> Result<ConeView, ObjectQueryError> {
    if !(half_angle_deg.is_finite() && (0.0..=180.0).contains(&half_angle_deg)) {
        return Err(ObjectQueryError::InvalidHalfAngleDeg(half_angle_deg));
    }
    let cone = ConeView {
        eye,
        dir,
        half_angle: half_angle_deg.to_radians().min(std::f32::consts::PI),
        range,
    };
    cone.contains(&eye)?; // checks eye, direction, half-angle and range
    Ok(cone)
}

/// The points of `sets` split into the octants around the centre of `around` (a box
/// holding them all), as the boxes of the non-empty octants: each holds its points
/// exactly, so each holds at least one point and together they hold all.
fn octant_boxes(sets: &[&[Point]], around: &Aabb) -> Vec<Aabb> {
    let centre = [0, 1, 2].map(|a| around.min[a] + (around.max[a] - around.min[a]) / 2.0);
    let mut parts = [Aabb {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    }; 8];
    for p in sets.iter().flat_map(|s| s.iter()) {
        let octant = usize::from(p[0] > centre[0])
            | usize::from(p[1] > centre[1]) << 1
            | usize::from(p[2] > centre[2]) << 2;
        let b = &mut parts[octant];
        for ((lo, hi), &c) in b.min.iter_mut().zip(&mut b.max).zip(p) {
            if c < *lo {
                *lo = c;
            }
            if c > *hi {
                *hi = c;
            }
        }
    }
    parts.into_iter().filter(|b| b.min[0] <= b.max[0]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_angles_in_degrees_are_checked() {
        let ok = |a: f32| cone_view([0.0; 3], [1.0, 0.0, 0.0], a, 1.0).is_ok();
        assert!(ok(0.0) && ok(45.0) && ok(180.0));
        assert!(!ok(-1.0) && !ok(180.5) && !ok(f32::NAN) && !ok(f32::INFINITY));
        assert!(cone_view([0.0; 3], [0.0; 3], 30.0, 1.0).is_err());
        assert!(cone_view([0.0; 3], [1.0, 0.0, 0.0], 30.0, -1.0).is_err());
    }
}
