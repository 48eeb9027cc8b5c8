//! Queries, each written once over [`crate::SceneView`] so that the live graph and
//! archived snapshots answer identically.
//!
//! Results that are node sets come back sorted by ascending [`crate::NodeId`]; ranked
//! results break distance ties by the smaller id.
//!
//! Spatial queries ([`nearest_nodes`], [`nodes_within_radius`], [`nearest_in_subtree`],
//! [`visible`]) use a spatial index when one covers their scope
//! ([`crate::SceneView::layer_index`], [`crate::SceneView::node_index`]) and scan
//! otherwise, pruning sub-trees by their bounding boxes; both paths return exactly the
//! same answer.

mod fov;
mod pattern;
mod spatial;
mod traverse;

#[doc(inline)]
pub use fov::{BoxSight, CheckedCone, ConeView, index_sees, visible};
#[doc(inline)]
pub use pattern::{
    edges_from, edges_matching, edges_to, nodes_having, nodes_matching, nodes_with_label,
};
#[doc(inline)]
pub use spatial::{
    SpatialQueryError, nearest_in_index, nearest_in_subtree, nearest_nodes, nodes_within_radius,
    radius_bound, within_index, within_radius,
};
pub(crate) use traverse::visit_subtree;
#[doc(inline)]
pub use traverse::{Direction, bfs, children, dfs, parent, shortest_path, subgraph, subtree};

use crate::{LayerId, SceneView};

/// Where a query looks: the whole graph or one layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Scope {
    /// Every layer.
    Graph,
    /// One layer.
    Layer(LayerId),
}

impl Scope {
    /// Whether `layer` is inside this scope.
    pub fn contains(&self, layer: LayerId) -> bool {
        match self {
            Scope::Graph => true,
            Scope::Layer(l) => *l == layer,
        }
    }

    /// The layers of `view` inside this scope.
    pub fn layers<V: SceneView>(&self, view: &V) -> Vec<LayerId> {
        self.iter(view).collect()
    }

    /// The layers of `view` inside this scope, ascending, without allocating: one
    /// lookup for a layer scope (no walk over the layer list).
    pub(crate) fn iter<'v, V: SceneView>(
        &self,
        view: &'v V,
    ) -> impl Iterator<Item = LayerId> + use<'v, V> {
        let (all, one) = match *self {
            Scope::Graph => (Some(view.layers()), None),
            Scope::Layer(l) => (None, view.layer_name(l).map(|_| l)),
        };
        all.into_iter().flatten().chain(one)
    }
}
