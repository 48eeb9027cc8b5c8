//! The intermediate representation shared by the importer and the office generator.

use std::collections::BTreeMap;
use std::fmt;

use rustc_hash::FxHashMap;

use super::symbol::NodeSymbol;

/// A Spark-DSG layer key: layer id plus partition.
///
/// Layer ids: 1 mesh / segments, 2 objects and agents, 3 places, 4 rooms, 5 buildings.
/// Partition 0 is the main layer of an id. Agent poses live in layer 2 with the
/// partition equal to their prefix character (`97` = `'a'`); mesh places live in
/// layer 3 partition 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct LayerKey {
    /// Layer id (`2` objects/agents, `3` places, `4` rooms, `5` buildings).
    pub layer: u32,
    /// Partition inside the layer (`0` is the main partition).
    pub partition: u32,
}

impl LayerKey {
    /// Objects, layer 2 partition 0.
    pub const OBJECTS: Self = Self::new(2, 0);
    /// Agent poses of agent `'a'`, layer 2 partition 97.
    pub const AGENTS: Self = Self::new(2, b'a' as u32);
    /// Places, layer 3 partition 0.
    pub const PLACES: Self = Self::new(3, 0);
    /// Mesh places (2D places), layer 3 partition 1.
    pub const MESH_PLACES: Self = Self::new(3, 1);
    /// Rooms, layer 4 partition 0.
    pub const ROOMS: Self = Self::new(4, 0);
    /// Buildings, layer 5 partition 0.
    pub const BUILDINGS: Self = Self::new(5, 0);

    /// A key from layer id and partition.
    pub const fn new(layer: u32, partition: u32) -> Self {
        Self { layer, partition }
    }

    /// Spark-DSG's rule for inter-layer edges: a node in a layer with a higher layer
    /// id is the parent. Two partitions of one layer id are neither parent nor child.
    pub fn is_parent_of(self, other: LayerKey) -> bool {
        self.layer > other.layer
    }
}

impl fmt::Display for LayerKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "layer {} partition {}", self.layer, self.partition)
    }
}

/// A layer of the imported graph.
#[derive(Clone, Debug, PartialEq)]
pub struct DsgLayer {
    /// The layer key.
    pub key: LayerKey,
    /// Unique layer name, e.g. `OBJECTS`, `AGENTS`, `PLACES`, `MESH_PLACES`, `ROOMS`,
    /// `BUILDINGS`.
    ///
    /// Taken from the file's `layer_names` when exactly one name maps to the key (or
    /// when one of several is the conventional name for it); otherwise the
    /// conventional name (see [`DsgLayer::default_name`]).
    pub name: String,
    /// Every name the file's `layer_names` gives this key (sorted), including `name`
    /// when it came from the file. Spark-DSG maps both `OBJECTS` and `AGENTS` to
    /// layer 2 partition 0, so `AGENTS` shows up here as an alias of `OBJECTS`.
    pub aliases: Vec<String>,
}

impl DsgLayer {
    /// The conventional name of a layer key: `OBJECTS` (2,0), `PLACES` (3,0),
    /// `MESH_PLACES` (3,1), `ROOMS` (4,0), `BUILDINGS` (5,0), `MESH` (1,0),
    /// `AGENTS` for layer 2 partition `'a'` and `AGENTS_<c>` for any other layer-2
    /// partition `c`, and `LAYER_<l>_<p>` otherwise.
    pub fn default_name(key: LayerKey) -> String {
        match (key.layer, key.partition) {
            (1, 0) => "MESH".to_owned(),
            (2, 0) => "OBJECTS".to_owned(),
            (2, 97) => "AGENTS".to_owned(),
            (2, p) => match char::from_u32(p).filter(char::is_ascii_alphanumeric) {
                Some(c) => format!("AGENTS_{c}"),
                None => format!("AGENTS_{p}"),
            },
            (3, 0) => "PLACES".to_owned(),
            (3, 1) => "MESH_PLACES".to_owned(),
            (4, 0) => "ROOMS".to_owned(),
            (5, 0) => "BUILDINGS".to_owned(),
            (l, p) => format!("LAYER_{l}_{p}"),
        }
    }
}

/// What kind of node this is, from the Spark-DSG attribute type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum NodeKind {
    /// `ObjectNodeAttributes`.
    Object,
    /// `PlaceNodeAttributes` (3D places).
    Place,
    /// `Place2dNodeAttributes` (mesh places).
    Place2d,
    /// `RoomNodeAttributes`.
    Room,
    /// `SemanticNodeAttributes`; Spark-DSG and Hydra use this type for buildings.
    Building,
    /// `AgentNodeAttributes` (agent poses).
    Agent,
}

impl NodeKind {
    /// All kinds, in declaration order.
    pub const ALL: [NodeKind; 6] = [
        NodeKind::Object,
        NodeKind::Place,
        NodeKind::Place2d,
        NodeKind::Room,
        NodeKind::Building,
        NodeKind::Agent,
    ];

    /// The Spark-DSG attribute type name (`attributes.type`).
    pub fn attribute_type(self) -> &'static str {
        match self {
            NodeKind::Object => "ObjectNodeAttributes",
            NodeKind::Place => "PlaceNodeAttributes",
            NodeKind::Place2d => "Place2dNodeAttributes",
            NodeKind::Room => "RoomNodeAttributes",
            NodeKind::Building => "SemanticNodeAttributes",
            NodeKind::Agent => "AgentNodeAttributes",
        }
    }

    /// The kind for a Spark-DSG attribute type name, if it is one this importer knows.
    pub fn from_attribute_type(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.attribute_type() == name)
    }
}

/// An axis-aligned bounding box in world coordinates (`min <= max` on every axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DsgAabb {
    /// Smallest corner.
    pub min: [f32; 3],
    /// Largest corner.
    pub max: [f32; 3],
}

impl DsgAabb {
    /// Whether `p` lies inside the box (bounds inclusive).
    pub fn contains(&self, p: [f32; 3]) -> bool {
        (0..3).all(|i| self.min[i] <= p[i] && p[i] <= self.max[i])
    }
}

/// One node of the imported graph.
#[derive(Clone, Debug, PartialEq)]
pub struct DsgNode {
    /// The Spark-DSG node id, kept as is (a [`NodeSymbol`] for Hydra and office data).
    pub id: u64,
    /// Layer and partition of the node.
    pub layer: LayerKey,
    /// Node kind, from `attributes.type`.
    pub kind: NodeKind,
    /// `attributes.position`, converted from f64 to f32.
    pub position: [f32; 3],
    /// The raw `attributes.name`, when present and not empty (`"R(0)"`, `"desk"`, ...).
    pub name: Option<String>,
    /// The semantic label name: the labelspace entry `_l{layer}p{partition}` for
    /// `semantic_label` if the file has one; otherwise `name`, unless `name` only
    /// spells the node's symbol (like Hydra's `"O(0)"` or `"R(3)"`).
    pub label: Option<String>,
    /// `attributes.semantic_label`; `None` when absent or `4294967295` (Spark-DSG's
    /// "no label").
    pub semantic_label: Option<u32>,
    /// The stored bounding box (`None` for Spark-DSG's `INVALID` box or when absent).
    /// Rotated boxes become the axis-aligned box around them. Stored boxes are not
    /// guaranteed to contain the node's geometry (see [`ClaimStats::wrong_boxes`]).
    pub bbox: Option<DsgAabb>,
    /// `attributes.mesh_connections` of objects: indices into [`DsgMesh::points`]
    /// claimed by this object, as stored (sorted in practice, duplicates kept). Empty
    /// for other kinds.
    pub mesh_connections: Vec<u32>,
    /// Timestamp in nanoseconds, as agent poses carry it (`attributes.timestamp` in
    /// v1.1, the node-level `timestamp` in legacy files). `None` when absent, which
    /// is the case for every other kind in Spark-DSG output.
    pub timestamp_ns: Option<u64>,
    /// The parent node: the higher-layer end of the first inter-layer edge touching
    /// this node, in file order. Later inter-layer edges that would give the node a
    /// second parent are kept in [`DsgGraph::extra_parent_edges`].
    pub parent: Option<u64>,
}

impl DsgNode {
    /// The labels a scene built from this node carries: [`DsgNode::label`] (its
    /// labelspace name, or its `name`) when there is one, and the decimal
    /// [`DsgNode::semantic_label`] (`"5"`) when there is one, in that order, without
    /// repeats.
    ///
    /// # Examples
    /// ```
    /// # let json = br#"{"layer_ids":[{"layer":2}],"nodes":[{"id":5692549928996306944,"layer":2,
    /// #   "attributes":{"type":"ObjectNodeAttributes","position":[0,0,0],"name":"O(0)","semantic_label":5}}],"edges":[]}"#;
    /// let g = ygg_dsg::parse_json(json, "hydra.json")?;
    /// // Hydra names objects after their symbol, which is no label; the id always is one.
    /// assert_eq!(g.nodes[0].labels().collect::<Vec<_>>(), ["5"]);
    /// # Ok::<(), ygg_dsg::DsgImportError>(())
    /// ```
    pub fn labels(&self) -> impl Iterator<Item = String> + '_ {
        let id = self
            .semantic_label
            .map(|l| l.to_string())
            .filter(|l| self.label.as_deref() != Some(l.as_str()));
        self.label.iter().cloned().chain(id)
    }

    /// The id as a Spark-DSG node symbol (`O(3)`, `a(0)`, ...).
    pub fn symbol(&self) -> NodeSymbol {
        NodeSymbol::from_id(self.id)
    }
}

/// An undirected edge between two nodes (Spark-DSG edges are undirected; `source`
/// and `target` are as stored in the file).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DsgEdge {
    /// First node id.
    pub source: u64,
    /// Second node id.
    pub target: u64,
    /// The edge weight, when `info.weighted` is true (always finite: the importer
    /// rejects non-finite weights). Only intra-layer edges keep a weight.
    pub weight: Option<f64>,
}

/// A nesting relation that was not used as a node's parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DsgParentEdge {
    /// The higher-layer node.
    pub parent: u64,
    /// The lower-layer node (which already had another parent).
    pub child: u64,
}

/// The scene mesh: one array of vertices that objects index into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DsgMesh {
    /// Vertex positions.
    pub points: Vec<[f32; 3]>,
    /// Triangles as vertex indices (every index `< points.len()`).
    pub faces: Vec<[u32; 3]>,
    /// Per-vertex semantic label (same length as `points`), when the file has labels.
    /// Names are in the `mesh` labelspace ([`DsgGraph::labelspaces`]).
    pub labels: Option<Vec<u32>>,
}

/// Version of the file format (from `SPARK_DSG_header`; legacy files are 1.0.0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct DsgVersion {
    /// Major version.
    pub major: u32,
    /// Minor version.
    pub minor: u32,
    /// Patch version.
    pub patch: u32,
}

impl DsgVersion {
    /// Files without a header: Spark-DSG treats them as 1.0.0.
    pub const LEGACY: Self = Self::new(1, 0, 0);
    /// The version the office generator and `gen_office_dsg.py` produce.
    pub const V1_1_3: Self = Self::new(1, 1, 3);
    /// spark_dsg's next version (its `develop` branch): a new `Place2dNodeAttributes`
    /// layout, nothing else in the binary encoding changes.
    pub const V1_1_4: Self = Self::new(1, 1, 4);

    /// A version from its parts.
    pub const fn new(major: u32, minor: u32, patch: u32) -> Self {
        Self {
            major,
            minor,
            patch,
        }
    }

    /// Whether this is the pre-1.1 encoding (no partitions, legacy colors and boxes).
    pub fn is_legacy(self) -> bool {
        self < Self::new(1, 1, 0)
    }
}

impl std::str::FromStr for DsgVersion {
    type Err = String;

    /// `major.minor.patch`, e.g. `1.1.4`.
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<u32> = s
            .split('.')
            .map(|p| p.parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("{s:?} is not a version like 1.1.4"))?;
        match parts[..] {
            [major, minor, patch] => Ok(Self::new(major, minor, patch)),
            _ => Err(format!("{s:?} is not a version like 1.1.4")),
        }
    }
}

impl fmt::Display for DsgVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}.{}", self.major, self.minor, self.patch)
    }
}

/// A Spark-DSG scene graph as plain data: the common output of
/// [`parse_json`](super::parse_json) and [`office::generate`](super::office::generate).
///
/// Invariants (checked by the importer, upheld by the generator):
/// - node ids are unique; every node's layer is in `layers`;
/// - every edge end and every `parent` names a node of `nodes`;
/// - `edges` join two nodes of the same layer key, `sibling_edges` two nodes of
///   different partitions of one layer id, and a `parent` lies in a higher layer id
///   than its child;
/// - no edge joins a node to itself and no unordered pair appears twice across
///   `edges`, `sibling_edges`, parents and `extra_parent_edges`;
/// - when `mesh` is present, every `mesh_connections` entry and face index is a valid
///   vertex index, and every coordinate is finite.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DsgGraph {
    /// Where the graph came from (file name, or `office(seed=..,scale=..)`).
    pub source: String,
    /// File format version.
    pub version: DsgVersion,
    /// Layers, sorted by key. Includes declared layers that hold no node.
    pub layers: Vec<DsgLayer>,
    /// Nodes, in file order.
    pub nodes: Vec<DsgNode>,
    /// Intra-layer edges (both ends in the same layer and partition), in file order.
    pub edges: Vec<DsgEdge>,
    /// Edges between two partitions of the same layer id (Spark-DSG "siblings",
    /// e.g. object to agent); they imply no nesting.
    pub sibling_edges: Vec<DsgEdge>,
    /// Inter-layer edges not used as a parent because the child already had one
    /// (the first inter-layer edge in file order wins).
    pub extra_parent_edges: Vec<DsgParentEdge>,
    /// The mesh, if the file carries one.
    pub mesh: Option<DsgMesh>,
    /// Labelspaces from `metadata.labelspaces`: key (`_l2p0`, `mesh`, ...) to
    /// label id to name.
    pub labelspaces: BTreeMap<String, BTreeMap<u32, String>>,
}

impl Default for DsgVersion {
    fn default() -> Self {
        Self::V1_1_3
    }
}

/// Node and edge counts of a [`DsgGraph`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DsgCounts {
    /// Total number of nodes.
    pub nodes: usize,
    /// Nodes per kind, in [`NodeKind::ALL`] order.
    pub by_kind: BTreeMap<NodeKind, usize>,
    /// Nodes per layer key.
    pub by_layer: BTreeMap<LayerKey, usize>,
    /// Intra-layer edges.
    pub intra_edges: usize,
    /// Sibling (cross-partition) edges.
    pub sibling_edges: usize,
    /// Parent relations (nodes with a parent).
    pub parent_edges: usize,
    /// Inter-layer edges that were not used as parents.
    pub extra_parent_edges: usize,
    /// All edges as Spark-DSG counts them: the sum of the four above.
    pub edges: usize,
    /// Mesh vertices (0 without a mesh).
    pub mesh_vertices: usize,
    /// Mesh faces (0 without a mesh).
    pub mesh_faces: usize,
}

impl DsgCounts {
    /// Number of nodes of one kind.
    pub fn kind(&self, kind: NodeKind) -> usize {
        self.by_kind.get(&kind).copied().unwrap_or(0)
    }
}

/// One object label of a graph and how many objects carry it
/// ([`DsgGraph::object_labels`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelCount {
    /// The label id (`semantic_label`), if the objects have one.
    pub semantic_label: Option<u32>,
    /// The label name ([`DsgNode::label`]), if any.
    pub name: Option<String>,
    /// Objects with this label id and name.
    pub objects: usize,
}

/// How objects claim mesh vertices, and whether their stored boxes hold their claims.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ClaimStats {
    /// Mesh vertices.
    pub vertices: usize,
    /// Object nodes.
    pub objects: usize,
    /// Vertices claimed by no object.
    pub unclaimed: usize,
    /// Vertices claimed by at least one object.
    pub claimed: usize,
    /// Vertices claimed by more than one object.
    pub multi_claimed: usize,
    /// Sum over objects of their distinct claimed vertices.
    pub total_claims: usize,
    /// Objects with a stored box that misses at least one claimed vertex.
    pub wrong_boxes: usize,
    /// Objects with at least one claimed vertex and no stored box.
    pub objects_without_box: usize,
}

impl DsgGraph {
    /// Index from node id to position in [`DsgGraph::nodes`].
    pub fn node_index(&self) -> FxHashMap<u64, usize> {
        self.nodes
            .iter()
            .enumerate()
            .map(|(i, n)| (n.id, i))
            .collect()
    }

    /// The layer with this key, if declared.
    pub fn layer(&self, key: LayerKey) -> Option<&DsgLayer> {
        self.layers.iter().find(|l| l.key == key)
    }

    /// The layer with this name, if any.
    pub fn layer_by_name(&self, name: &str) -> Option<&DsgLayer> {
        self.layers.iter().find(|l| l.name == name)
    }

    /// Iterator over the nodes of one kind.
    pub fn nodes_of_kind(&self, kind: NodeKind) -> impl Iterator<Item = &DsgNode> + '_ {
        self.nodes.iter().filter(move |n| n.kind == kind)
    }

    /// Node and edge counts.
    pub fn counts(&self) -> DsgCounts {
        let mut c = DsgCounts {
            nodes: self.nodes.len(),
            intra_edges: self.edges.len(),
            sibling_edges: self.sibling_edges.len(),
            extra_parent_edges: self.extra_parent_edges.len(),
            ..DsgCounts::default()
        };
        for n in &self.nodes {
            *c.by_kind.entry(n.kind).or_default() += 1;
            *c.by_layer.entry(n.layer).or_default() += 1;
            c.parent_edges += usize::from(n.parent.is_some());
        }
        c.edges = c.intra_edges + c.sibling_edges + c.parent_edges + c.extra_parent_edges;
        if let Some(m) = &self.mesh {
            c.mesh_vertices = m.points.len();
            c.mesh_faces = m.faces.len();
        }
        c
    }

    /// Object label histogram: label name (or `#<semantic_label>` when the object
    /// has no name, `?` when it has neither) to object count.
    pub fn object_label_histogram(&self) -> BTreeMap<String, usize> {
        let mut h = BTreeMap::new();
        for n in self.nodes_of_kind(NodeKind::Object) {
            let key = match (&n.label, n.semantic_label) {
                (Some(l), _) => l.clone(),
                (None, Some(s)) => format!("#{s}"),
                (None, None) => "?".to_owned(),
            };
            *h.entry(key).or_default() += 1;
        }
        h
    }

    /// The object labels with their counts: one entry per distinct pair of
    /// [`DsgNode::semantic_label`] and [`DsgNode::label`] among the objects, most
    /// frequent first, ties by label id then name. An object is found by
    /// `objects_with_label` under each of [`DsgNode::labels`].
    ///
    /// # Examples
    /// ```
    /// let office = ygg_dsg::office::generate(ygg_dsg::office::OfficeParams { seed: 7, scale: 1.0 });
    /// let labels = office.object_labels();
    /// assert_eq!(labels[0].name.as_deref(), Some("light"));
    /// assert_eq!(labels[0].objects, 40);
    /// ```
    pub fn object_labels(&self) -> Vec<LabelCount> {
        let mut counts: BTreeMap<(Option<u32>, Option<&str>), usize> = BTreeMap::new();
        for n in self.nodes_of_kind(NodeKind::Object) {
            *counts
                .entry((n.semantic_label, n.label.as_deref()))
                .or_default() += 1;
        }
        let mut out: Vec<LabelCount> = counts
            .into_iter()
            .map(|((semantic_label, name), objects)| LabelCount {
                semantic_label,
                name: name.map(str::to_owned),
                objects,
            })
            .collect();
        out.sort_by_key(|l| std::cmp::Reverse(l.objects));
        out
    }

    /// Claim statistics of the mesh, or `None` without a mesh. Each object counts a
    /// vertex once even if its `mesh_connections` repeats it; out-of-range indices
    /// (impossible after import) are skipped.
    pub fn claim_stats(&self) -> Option<ClaimStats> {
        let mesh = self.mesh.as_ref()?;
        let nv = mesh.points.len();
        let mut mult = vec![0u32; nv];
        let mut last_owner = vec![usize::MAX; nv];
        let mut s = ClaimStats {
            vertices: nv,
            ..ClaimStats::default()
        };
        for (oi, n) in self.nodes.iter().enumerate() {
            if n.kind != NodeKind::Object {
                continue;
            }
            s.objects += 1;
            let mut wrong = false;
            let mut any = false;
            for &v in &n.mesh_connections {
                let v = v as usize;
                if v >= nv || last_owner[v] == oi {
                    continue;
                }
                last_owner[v] = oi;
                mult[v] += 1;
                s.total_claims += 1;
                any = true;
                if let Some(b) = &n.bbox {
                    wrong |= !b.contains(mesh.points[v]);
                }
            }
            s.wrong_boxes += usize::from(wrong);
            s.objects_without_box += usize::from(any && n.bbox.is_none());
        }
        for &m in &mult {
            match m {
                0 => s.unclaimed += 1,
                1 => s.claimed += 1,
                _ => {
                    s.claimed += 1;
                    s.multi_claimed += 1;
                }
            }
        }
        Some(s)
    }
}
