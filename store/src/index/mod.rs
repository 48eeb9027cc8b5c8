//! Spatial indexes: kd-trees over the points of one layer (a **layer index**) or of one
//! node's sub-tree (a **node index**), and the [`SpatialIndex`] trait that the spatial
//! queries in [`crate::query`] are written against.
//!
//! | index | type | kept by | items |
//! |---|---|---|---|
//! | live | [`LiveIndex`] over a [`LiveKdTree`] plus an overlay of nodes moved wholesale | [`crate::SceneGraph`], updated by every mutation | node handles |
//! | archived | [`ArchivedIndex`] over kiddo's archived `ImmutableKdTree` | the layer segment of a snapshot, queried zero-copy | rows / id-table positions |
//! | reader-built | [`KdIndex`]: kiddo's `ImmutableKdTree`, kept archived | a reader ([`build_layer_index`], [`build_subtree_index`], [`IndexCache`]) | id-table positions |
//!
//! kiddo builds the snapshot's and the readers' trees and answers their radius queries;
//! nearest-node search is one branch-and-bound pass over the same layout (see
//! [`SpatialIndex::nearest_visit`]). The live graph uses its own dynamic tree, because
//! kiddo's `MutableKdTree` refuses inserts once a full bucket's points share the
//! coordinate it must split on (a wall, a floor, duplicates).
//!
//! Every index reports distances computed exactly as [`crate::distance_squared`]
//! computes them (the same expression in the same order; for kiddo's scalar kernel a
//! test pins this), so an indexed query returns what brute force returns, bit for bit.
//!
//! # Memory
//! An index stores each point's coordinates (12 bytes) and item (4 bytes). Measured
//! totals per point: 16.5–16.8 bytes archived (kiddo's leaves, extents and stems), about
//! 19.2 bytes live (leaves are bulk-built 7/8 full so that inserts rarely split one).
//! The live indexes of a graph share one handle table besides (item to node id: 8 bytes
//! per indexed node, grown by an eighth; [`crate::SceneGraph::index_handle_bytes`]).

mod kdtree;
mod live;
mod maintain;
mod overlay;

pub use kdtree::{ArchivedIndex, ArchivedKdTree, KdIndex, KdTree};
pub(crate) use kdtree::{build_tree, check_tree};
pub use live::LiveKdTree;
pub(crate) use maintain::LiveIndexes;

use crate::query::visit_subtree;
use crate::{LayerId, NodeId, Point, SceneView};
use rustc_hash::FxHashMap;

/// Read access to one spatial index: a multiset of points, each tagged with an item that
/// names the node it belongs to.
///
/// Implemented by [`LiveIndex`] (live graph), [`ArchivedIndex`] (snapshot) and
/// [`KdIndex`] (built by a reader). The spatial queries use only these methods, so they
/// run unchanged on every kind of index.
pub trait SpatialIndex {
    /// Number of indexed points.
    fn len(&self) -> usize;

    /// Whether the index holds no point.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The node an item belongs to (`None` only for an item no point carries).
    fn node_of(&self, item: u32) -> Option<NodeId>;

    /// A hint that [`SpatialIndex::node_of`] will soon be asked about `item`: starts
    /// loading its entry of the id table into the cache, so that the (in a large index,
    /// cold) loads of many items overlap the search that finds them. Changes no result;
    /// the default does nothing.
    fn prefetch_node(&self, _item: u32) {}

    /// Branch-and-bound search from `c`, nearer cells first: calls `f(distance², item)`
    /// for every point whose squared distance is at most the current bound, and skips
    /// every cell whose points are all strictly farther than it. `f` returns the new bound
    /// (it starts at `+∞` and may only shrink). Points *at* the bound are still reported,
    /// so a caller can break ties exactly.
    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F);

    /// Calls `f(distance², item, point)` for every point with `distance² <= r2`.
    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, f: F);

    /// Bytes of memory (or of archive) the index occupies.
    fn memory_bytes(&self) -> usize;
}

/// Starts loading the cache line holding `p` into the cache (a hint: `p` may be any
/// address, even a dangling or wild one).
#[inline]
pub(crate) fn prefetch<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code, reason = "a prefetch hint")]
    // SAFETY: `_mm_prefetch` only hints the cache hierarchy: it never faults, whatever
    // the address, and changes no memory the program can observe. It needs SSE, which
    // every x86_64 CPU has (part of the target's baseline features).
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// The live graph's index over one layer or one sub-tree, as [`SceneView::layer_index`]
/// and [`SceneView::node_index`] return it for a [`crate::SceneGraph`].
#[derive(Clone, Copy, Debug)]
pub struct LiveIndex<'a> {
    tree: &'a overlay::OverlaidTree,
    ids: &'a [NodeId],
}

impl<'a> LiveIndex<'a> {
    pub(crate) fn new(tree: &'a overlay::OverlaidTree, ids: &'a [NodeId]) -> Self {
        LiveIndex { tree, ids }
    }
}

impl SpatialIndex for LiveIndex<'_> {
    fn len(&self) -> usize {
        self.tree.len()
    }

    fn node_of(&self, item: u32) -> Option<NodeId> {
        self.ids
            .get(item as usize)
            .copied()
            .filter(|&id| id != NodeId::NONE)
    }

    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, f: F) {
        self.tree.nearest_visit(c, f);
    }

    fn prefetch_node(&self, item: u32) {
        prefetch(self.ids.as_ptr().wrapping_add(item as usize));
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, mut f: F) {
        self.tree.within(c, r2, &mut f);
    }

    fn memory_bytes(&self) -> usize {
        self.tree.memory_bytes()
    }
}

/// A kd-tree index over every point of `layer` in `view`, built by a reader for a layer
/// the writer does not index.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::{build_layer_index, SpatialIndex}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let mesh = g.add_layer("mesh")?;
/// g.add_node(NodeId(1), mesh)?;
/// g.set_geometry(NodeId(1), vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])?;
/// let snapshot = g.to_snapshot();
/// let index = build_layer_index(&snapshot.view(), mesh);
/// assert_eq!(index.len(), 2);
/// # Ok(()) }
/// ```
pub fn build_layer_index<V: SceneView>(view: &V, layer: LayerId) -> KdIndex {
    let mut nodes: Vec<(NodeId, V::NodeRef<'_>)> = view
        .layer_nodes(layer)
        .map(|n| (view.node_id(n), n))
        .collect();
    nodes.sort_unstable_by_key(|n| n.0);
    let mut ids = Vec::new();
    let mut entries = Vec::new();
    for (id, n) in nodes {
        let points = view.points(n);
        if !points.is_empty() {
            let item = ids.len() as u32;
            ids.push(id);
            entries.extend(points.iter().map(|p| (item, *p)));
        }
    }
    KdIndex::new(&build_tree(&entries), ids)
}

/// A kd-tree index over every point in the sub-tree of `root` in `view` (empty for an
/// unknown root), built by a reader for a sub-tree the writer does not index.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::{build_subtree_index, SpatialIndex}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (rooms, objects) = (g.add_layer("rooms")?, g.add_layer("objects")?);
/// g.add_layer_edge(rooms, objects)?;
/// g.add_node(NodeId(1), rooms)?;
/// g.add_node(NodeId(2), objects)?;
/// g.set_geometry(NodeId(2), vec![[1.0, 2.0, 0.0]])?;
/// g.nest(NodeId(1), NodeId(2))?;
/// let index = build_subtree_index(&g.to_snapshot().view(), NodeId(1));
/// assert_eq!(index.len(), 1);
/// # Ok(()) }
/// ```
pub fn build_subtree_index<V: SceneView>(view: &V, root: NodeId) -> KdIndex {
    let mut members = Vec::new();
    visit_subtree(view, root, |id| members.push(id));
    members.sort_unstable();
    let mut ids = Vec::new();
    let mut entries = Vec::new();
    for id in members {
        let Some(n) = view.node(id) else { continue };
        let points = view.points(n);
        if !points.is_empty() {
            let item = ids.len() as u32;
            ids.push(id);
            entries.extend(points.iter().map(|p| (item, *p)));
        }
    }
    KdIndex::new(&build_tree(&entries), ids)
}

/// Indexes a reader built itself, kept for as long as the layers they cover are
/// unchanged.
///
/// A layer index is reused while its layer's generation is unchanged; a sub-tree index
/// while the generations of the root's layer and of every layer below it in the layer
/// DAG are unchanged. Generations come from [`SceneView::layer_generation`], so the same
/// cache serves successive snapshots of one scene.
///
/// # Examples
/// ```
/// # use ygg_store::{SceneGraph, NodeId, index::{IndexCache, SpatialIndex}};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut g = SceneGraph::new();
/// let (mesh, poses) = (g.add_layer("mesh")?, g.add_layer("poses")?);
/// g.add_node(NodeId(1), mesh)?;
/// g.set_geometry(NodeId(1), vec![[0.0, 0.0, 0.0]])?;
/// let mut cache = IndexCache::new();
/// assert_eq!(cache.layer(&g.to_snapshot().view(), mesh).len(), 1);
/// g.add_node(NodeId(2), poses)?; // another layer changes: the mesh index is kept
/// assert_eq!(cache.layer(&g.to_snapshot().view(), mesh).len(), 1);
/// assert_eq!(cache.builds(), 1);
/// # Ok(()) }
/// ```
#[derive(Debug, Default)]
pub struct IndexCache {
    layers: FxHashMap<LayerId, (u64, KdIndex)>,
    subtrees: FxHashMap<NodeId, (Vec<(LayerId, u64)>, KdIndex)>,
    builds: u64,
}

impl IndexCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The index of `layer` in `view`, rebuilt only if the layer changed since it was
    /// built (or was never built).
    pub fn layer<V: SceneView>(&mut self, view: &V, layer: LayerId) -> &KdIndex {
        let generation = view.layer_generation(layer).unwrap_or(u64::MAX);
        let fresh = self
            .layers
            .get(&layer)
            .is_some_and(|(g, _)| *g == generation);
        if !fresh {
            self.builds += 1;
            self.layers
                .insert(layer, (generation, build_layer_index(view, layer)));
        }
        &self.layers[&layer].1
    }

    /// The index of `root`'s sub-tree in `view`, rebuilt only if a layer it may cover
    /// changed since it was built.
    pub fn subtree<V: SceneView>(&mut self, view: &V, root: NodeId) -> &KdIndex {
        let stamp = subtree_stamp(view, root);
        let fresh = self.subtrees.get(&root).is_some_and(|(s, _)| *s == stamp);
        if !fresh {
            self.builds += 1;
            self.subtrees
                .insert(root, (stamp, build_subtree_index(view, root)));
        }
        &self.subtrees[&root].1
    }

    /// How many indexes this cache has built so far.
    pub fn builds(&self) -> u64 {
        self.builds
    }
}

/// The generations of the root's layer and of every layer below it in the DAG.
fn subtree_stamp<V: SceneView>(view: &V, root: NodeId) -> Vec<(LayerId, u64)> {
    let Some(n) = view.node(root) else {
        return Vec::new();
    };
    let mut stack = vec![view.node_layer(n)];
    let mut stamp = Vec::new();
    while let Some(l) = stack.pop() {
        if stamp.iter().any(|(x, _)| *x == l) {
            continue;
        }
        stamp.push((l, view.layer_generation(l).unwrap_or(u64::MAX)));
        stack.extend(view.layer_children(l));
    }
    stamp.sort_unstable();
    stamp
}
