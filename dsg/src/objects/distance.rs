//! Distance queries: [`Objects::nearest_object`] and [`Objects::objects_within`].

use super::{ObjectQueryError, Objects, check_point};
use ygg_store::index::SpatialIndex;
use ygg_store::query::{self, SpatialQueryError};
use ygg_store::{Aabb, LayerId, NodeId, Point, SceneView, Scope};

impl<V: SceneView> Objects<'_, V> {
    /// The object with the vertex closest to `point`; ties go to the smaller id.
    /// `None` when no object claims a vertex.
    ///
    /// # Errors
    /// [`SpatialQueryError::NonFinitePoint`] (as [`ObjectQueryError::Spatial`]).
    ///
    /// # Complexity
    /// One [`ygg_store::query::nearest_nodes`] (`m = 1`) per object-mesh layer whose box
    /// can hold a closer vertex (a kd-tree search where the layer has an index; repeated
    /// with a larger `m` only while mesh nodes without an object come first).
    pub fn nearest_object(&self, point: Point) -> Result<Option<NodeId>, ObjectQueryError> {
        check_point(&point)?;
        // Layers to search, nearest layer boxes first (one layer needs no boxes); a layer
        // whose box is farther than the best distance so far cannot hold a closer node
        // (nor a tie).
        let order: Vec<(f64, LayerId)> = match self.mesh_layers.as_slice() {
            [] => return Ok(None),
            &[only] => vec![(0.0, only)],
            layers => {
                let mut order: Vec<(f64, LayerId)> = layers
                    .iter()
                    .zip(self.layer_boxes())
                    .filter_map(|(&l, b)| Some((lower_bound(b.as_ref()?, &point), l)))
                    .collect();
                order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                order
            }
        };
        // The best (distance, owner) so far. Within a layer the store's nearest query
        // breaks distance ties by the smaller mesh node id, and the layouts number mesh
        // nodes in the order of their objects' ids, so the first owned node found is
        // the tie winner of its layer; across layers the smaller (distance, owner) wins.
        let mut best: Option<(f32, NodeId)> = None;
        for (bound, layer) in order {
            if best.is_some_and(|(d, _)| bound > f64::from(d)) {
                break;
            }
            let mut m = 1usize;
            let found = loop {
                let found = query::nearest_nodes(self.view, Scope::Layer(layer), point, m)?;
                let first = found
                    .iter()
                    .find_map(|&(mesh, d)| Some((d, self.owner(mesh)?)));
                match first {
                    Some(hit) => break Some(hit),
                    // Only mesh nodes without an object so far (vanilla's unclaimed
                    // vertices): look further.
                    None if found.len() == m => m = m.saturating_mul(4),
                    None => break None,
                }
            };
            if let Some((d, owner)) = found
                && best.is_none_or(|b| (d, owner) < b)
            {
                best = Some((d, owner));
            }
        }
        Ok(best.map(|(_, owner)| owner))
    }

    /// Every object with a vertex at distance `<= radius` from `point`, ascending.
    ///
    /// # Errors
    /// [`SpatialQueryError::NonFinitePoint`], [`SpatialQueryError::InvalidRadius`] (as
    /// [`ObjectQueryError::Spatial`]).
    ///
    /// # Complexity
    /// Where every object keeps a box and a node index over exactly its vertices (mint,
    /// saffron): one box test per object, and for an object whose box straddles the
    /// ball a kd-tree search of its node index that stops at the first vertex within
    /// `radius`. Elsewhere: one [`ygg_store::query::nodes_within_radius`] per object-mesh
    /// layer (a kd-tree range search where the layer has an index), then one parent
    /// lookup per mesh node found.
    pub fn objects_within(
        &self,
        point: Point,
        radius: f32,
    ) -> Result<Vec<NodeId>, ObjectQueryError> {
        check_point(&point)?;
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(SpatialQueryError::InvalidRadius(radius).into());
        }
        let mut out = Vec::new();
        let claimants = self.claimants();
        if !claimants.is_empty() && claimants.iter().all(|c| c.indexed_mesh) {
            let r2 = query::radius_bound(radius);
            for c in claimants {
                let Some(b) = c.bbox else { continue };
                // The box bounds the object's vertices: entirely beyond the ball, or
                // entirely inside it (and it holds at least one vertex).
                if b.distance_squared_to(&point) > r2 {
                    continue;
                }
                let within = farthest_distance2(&b, &point) <= r2
                    || match self.view.node_index(c.id) {
                        Some(index) => any_within(&index, &point, r2),
                        None => query::nearest_in_subtree(self.view, c.id, point, 1)?
                            .first()
                            .is_some_and(|&(_, d)| d <= radius),
                    };
                if within {
                    out.push(c.id); // claimants ascend by id
                }
            }
            return Ok(out);
        }
        for (&layer, b) in self.mesh_layers.iter().zip(self.layer_boxes()) {
            if b.is_none_or(|b| lower_bound(&b, &point) > f64::from(radius)) {
                continue;
            }
            let found = query::nodes_within_radius(self.view, Scope::Layer(layer), point, radius)?;
            out.extend(found.into_iter().filter_map(|m| self.owner(m)));
        }
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }
}

/// An upper bound of [`ygg_store::distance_squared`] from `c` to any point inside `b`: per
/// axis the farther face, evaluated in the same order (rounding is monotone, so no point
/// of the box is farther).
fn farthest_distance2(b: &Aabb, c: &Point) -> f32 {
    let v = [0, 1, 2].map(|a| {
        let (lo, hi) = (b.min[a] - c[a], b.max[a] - c[a]);
        (lo * lo).max(hi * hi)
    });
    v[0] + v[1] + v[2]
}

/// Whether `index` holds a point at squared distance `<= r2` from `c`: a nearest-point
/// search bounded by `r2` that drops its bound below zero at the first such point, so
/// that it prunes everything left.
fn any_within<I: SpatialIndex>(index: &I, c: &Point, r2: f32) -> bool {
    let mut hit = false;
    index.nearest_visit(c, |d2, _| {
        if d2 <= r2 {
            hit = true;
            -1.0
        } else {
            r2
        }
    });
    hit
}

/// A lower bound of the distance (as the spatial queries compute it in `f32`) from `c`
/// to any point inside `b`: the box distance (rounded like a point's, so never above
/// one) less a relative margin far above the rounding of `sqrt`.
fn lower_bound(b: &Aabb, c: &Point) -> f64 {
    f64::from(b.distance_squared_to(c)).sqrt() * (1.0 - 1e-5)
}
