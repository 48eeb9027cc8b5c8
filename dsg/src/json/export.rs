//! Spark-DSG JSON export: the inverse of [`parse_json`](crate::parse_json).
//!
//! See [`write_json`](crate::write_json) for the layout and what reads back.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use serde_json::ser::{CompactFormatter, Formatter};

use crate::model::{DsgAabb, DsgEdge, DsgGraph, DsgMesh, DsgNode, LayerKey, NodeKind};

/// Why a graph could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DsgExportError {
    /// The file could not be created or written.
    #[error("{file}: cannot write: {source}")]
    Io {
        /// File name.
        file: String,
        /// The I/O error.
        #[source]
        source: io::Error,
    },
    /// A value does not fit the binary format (see
    /// [`to_binary_bytes`](crate::to_binary_bytes)).
    #[error("cannot write as Spark-DSG binary: {what}")]
    Unrepresentable {
        /// What does not fit.
        what: String,
    },
}

/// Writes `graph` as a Spark-DSG v1.1.3 JSON file at `path` (created or truncated).
///
/// The output mirrors what spark_dsg 1.1.3 writes (`DynamicSceneGraph.save`, see
/// `office_tiny.json`): `SPARK_DSG_header`, `layer_keys`, `layer_names`, nodes with
/// their full attribute sets, edges, `metadata.labelspaces` and the mesh. Object
/// keys are written in sorted order, as nlohmann's JSON does.
///
/// # Layout, and what reads back
///
/// * Numbers: node ids and indices as integers; f32 values (positions, boxes, mesh
///   points) in the shortest form that reads back as the same f32 (checked once for
///   every finite f32 against the importer's parser). f64 edge weights are written in the
///   shortest form, or, where `serde_json`'s default (not `float_roundtrip`) parser
///   used by the importer would read that back wrong, in a nearby form it reads back
///   exactly. That parser cannot produce every f64, so a few weights read back one
///   ulp off (7 of the 3,042 weights of the full office); spark_dsg reads them all
///   exactly. NaN and infinities are written as `null`, as nlohmann does (the
///   importer then rejects the file, as it would Spark-DSG's own).
/// * Boxes: [`DsgAabb`] is stored as centre and dimensions with an identity
///   rotation. The centre and half extent are chosen so that the importer's f32
///   `centre ∓ dimensions / 2` gives back `min` and `max` exactly; this is always
///   possible for boxes that came from a v1.1 file or from the office generator.
///   Boxes of legacy files (stored as `min` / `max`) may come back one ulp off.
/// * Edges: [`DsgGraph::edges`] (with `weighted: true` when there is a weight),
///   then [`DsgGraph::sibling_edges`], then one edge per [`DsgNode::parent`]
///   (child as `source`, parent as `target`, like spark_dsg), then
///   [`DsgGraph::extra_parent_edges`]. That order makes the importer pick the same
///   parents.
/// * Fields the graph does not keep get spark_dsg's defaults: colors are black,
///   `last_update_time_ns` is 0 (the timestamp for agent poses), orientations are
///   the identity, place distances are 0, and the mesh has no colors or stamps.
///
/// Importing the output with [`parse_json`](crate::parse_json) gives back an equal
/// graph, except for [`DsgGraph::source`], a legacy [`DsgGraph::version`] (always
/// written as 1.1.3), the one-ulp cases above, and these corner cases of hand-built
/// graphs:
/// * a node with a [`DsgNode::label`] but no [`DsgNode::name`] whose label the
///   labelspace does not give is written with the label as its `name`;
/// * a node whose `name` is not a symbol but differs from its label reads back
///   with the name as its label when the labelspace does not name it;
/// * an agent pose without a timestamp is written with timestamp 0;
/// * an empty mesh label list reads back as no labels.
///
/// # Errors
/// [`DsgExportError::Io`] if the file cannot be created or written. A failed write
/// may leave a partial file behind.
///
/// # Examples
/// ```no_run
/// use ygg_dsg::{self as dsg, office::{generate, OfficeParams}};
/// let g = generate(OfficeParams { seed: 7, scale: 0.02 });
/// dsg::write_json(&g, "office.json")?;
/// assert_eq!(dsg::read_file("office.json")?.nodes, g.nodes);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_json(graph: &DsgGraph, path: impl AsRef<Path>) -> Result<(), DsgExportError> {
    let path = path.as_ref();
    let io_err = |source| DsgExportError::Io {
        file: path.display().to_string(),
        source,
    };
    let file = File::create(path).map_err(io_err)?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    write_json_to(graph, &mut w).map_err(io_err)?;
    w.into_inner()
        .map_err(|e| io_err(e.into_error()))?
        .sync_all()
        .map_err(io_err)
}

/// The Spark-DSG v1.1.3 JSON text of `graph` (see [`write_json`]).
///
/// # Examples
/// ```
/// use ygg_dsg::{self as dsg, office::{generate, OfficeParams}};
/// let g = generate(OfficeParams { seed: 7, scale: 0.02 });
/// let bytes = dsg::to_json_bytes(&g);
/// let back = dsg::parse_json(&bytes, "office.json")?;
/// assert_eq!(back.nodes, g.nodes);
/// assert_eq!(back.counts(), g.counts());
/// # Ok::<(), ygg_dsg::DsgImportError>(())
/// ```
pub fn to_json_bytes(graph: &DsgGraph) -> Vec<u8> {
    let mut out = Vec::with_capacity(estimate_len(graph));
    // Writing into a Vec cannot fail.
    let _ = write_json_to(graph, &mut out);
    out
}

/// Writes the Spark-DSG v1.1.3 JSON text of `graph` to `w` (see [`write_json`]).
/// Pass a buffered writer: the text is written in many small pieces.
///
/// # Errors
/// Any error of `w`.
pub fn write_json_to<W: Write>(graph: &DsgGraph, w: W) -> io::Result<()> {
    Out::new(w).graph(graph)
}

/// A rough output size, to size the buffer of [`to_json_bytes`].
fn estimate_len(g: &DsgGraph) -> usize {
    let claims: usize = g.nodes.iter().map(|n| n.mesh_connections.len()).sum();
    let edges = g.edges.len() + g.sibling_edges.len() + g.nodes.len() + g.extra_parent_edges.len();
    let mesh = g
        .mesh
        .as_ref()
        .map_or(0, |m| m.points.len() * 40 + m.faces.len() * 22);
    4096 + g.nodes.len() * 700 + edges * 140 + claims * 7 + mesh
}

const HEADER: &[u8] = br#"{"project_name":"main","version":{"major":1,"minor":1,"patch":3}}"#;
const IDENTITY: &[u8] = br#"{"w":1.0,"x":0.0,"y":0.0,"z":0.0}"#;
const BLACK: &[u8] = br#"{"a":255,"b":0,"g":0,"r":0}"#;
const NO_FEATURE: &[u8] = br#"{"cols":0,"data":null,"rows":0}"#;
const INVALID_BOX: &[u8] = br#"{"dimensions":[0.0,0.0,0.0],"type":"INVALID","world_P_center":[0.0,0.0,0.0],"world_R_center":{"w":1.0,"x":0.0,"y":0.0,"z":0.0}}"#;

/// A JSON writer over `W` with the few primitives the layout needs.
struct Out<W: Write> {
    w: W,
    fmt: CompactFormatter,
    /// Scratch space for number checks.
    tmp: Vec<u8>,
}

impl<W: Write> Out<W> {
    fn new(w: W) -> Self {
        Self {
            w,
            fmt: CompactFormatter,
            tmp: Vec::with_capacity(64),
        }
    }

    #[inline]
    fn raw(&mut self, b: &[u8]) -> io::Result<()> {
        self.w.write_all(b)
    }

    #[inline]
    fn u64(&mut self, v: u64) -> io::Result<()> {
        self.fmt.write_u64(&mut self.w, v)
    }

    #[inline]
    fn u32(&mut self, v: u32) -> io::Result<()> {
        self.fmt.write_u32(&mut self.w, v)
    }

    /// Shortest text that reads back (through f64) as the same f32; `null` when not
    /// finite.
    #[inline]
    fn f32(&mut self, v: f32) -> io::Result<()> {
        if v.is_finite() {
            self.fmt.write_f32(&mut self.w, v)
        } else {
            self.raw(b"null")
        }
    }

    /// Text that serde_json's default parser reads back as exactly `v`; `null` when
    /// not finite.
    fn f64(&mut self, v: f64) -> io::Result<()> {
        if !v.is_finite() {
            return self.raw(b"null");
        }
        f64_text(v, &mut self.tmp);
        self.w.write_all(&self.tmp)
    }

    fn str(&mut self, s: &str) -> io::Result<()> {
        serde_json::to_writer(&mut self.w, s).map_err(io::Error::from)
    }

    fn vec3(&mut self, v: [f32; 3]) -> io::Result<()> {
        self.raw(b"[")?;
        self.f32(v[0])?;
        self.raw(b",")?;
        self.f32(v[1])?;
        self.raw(b",")?;
        self.f32(v[2])?;
        self.raw(b"]")
    }

    fn u32_list(&mut self, v: &[u32]) -> io::Result<()> {
        self.raw(b"[")?;
        for (i, &x) in v.iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.u32(x)?;
        }
        self.raw(b"]")
    }

    fn layer_key(&mut self, k: LayerKey) -> io::Result<()> {
        self.raw(br#"{"layer":"#)?;
        self.u32(k.layer)?;
        self.raw(br#","partition":"#)?;
        self.u32(k.partition)?;
        self.raw(b"}")
    }

    fn graph(mut self, g: &DsgGraph) -> io::Result<()> {
        self.raw(br#"{"SPARK_DSG_header":"#)?;
        self.raw(HEADER)?;
        self.raw(br#","directed":false,"edges":["#)?;
        self.edges(g)?;
        self.raw(br#"],"layer_keys":["#)?;
        let keys = layer_keys(g);
        for (i, &k) in keys.iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.layer_key(k)?;
        }
        self.raw(br#"],"layer_names":{"#)?;
        for (i, (name, &k)) in layer_names(g).iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.str(name)?;
            self.raw(b":")?;
            self.layer_key(k)?;
        }
        self.raw(b"}")?;
        if let Some(m) = &g.mesh {
            self.raw(br#","mesh":"#)?;
            self.mesh(m)?;
        }
        self.raw(br#","metadata":{"labelspaces":{"#)?;
        for (i, (key, space)) in g.labelspaces.iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.str(key)?;
            self.raw(b":[")?;
            for (j, (&id, name)) in space.iter().enumerate() {
                if j > 0 {
                    self.raw(b",")?;
                }
                self.raw(b"[")?;
                self.u32(id)?;
                self.raw(b",")?;
                self.str(name)?;
                self.raw(b"]")?;
            }
            self.raw(b"]")?;
        }
        self.raw(br#"}},"multigraph":false,"nodes":["#)?;
        for (i, n) in g.nodes.iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.node(g, n)?;
        }
        self.raw(b"]}")?;
        self.w.flush()
    }

    fn edges(&mut self, g: &DsgGraph) -> io::Result<()> {
        let mut first = true;
        let intra = g.edges.iter().chain(&g.sibling_edges).copied();
        let parents = g.nodes.iter().filter_map(|n| {
            n.parent.map(|p| DsgEdge {
                source: n.id,
                target: p,
                weight: None,
            })
        });
        let extra = g.extra_parent_edges.iter().map(|e| DsgEdge {
            source: e.child,
            target: e.parent,
            weight: None,
        });
        for e in intra.chain(parents).chain(extra) {
            if !first {
                self.raw(b",")?;
            }
            first = false;
            self.raw(br#"{"info":{"metadata":{},"type":"EdgeAttributes","weight":"#)?;
            match e.weight {
                Some(w) => {
                    self.f64(w)?;
                    self.raw(br#","weighted":true},"source":"#)?;
                }
                None => self.raw(br#"1.0,"weighted":false},"source":"#)?,
            }
            self.u64(e.source)?;
            self.raw(br#","target":"#)?;
            self.u64(e.target)?;
            self.raw(b"}")?;
        }
        Ok(())
    }

    fn bbox(&mut self, b: Option<&DsgAabb>) -> io::Result<()> {
        let Some(b) = b else {
            return self.raw(INVALID_BOX);
        };
        let mut dims = [0f32; 3];
        let mut ctr = [0f32; 3];
        for k in 0..3 {
            let (c, h) = box_axis(b.min[k], b.max[k]);
            ctr[k] = c;
            dims[k] = h * 2.0;
        }
        self.raw(br#"{"dimensions":"#)?;
        self.vec3(dims)?;
        self.raw(br#","type":"AABB","world_P_center":"#)?;
        self.vec3(ctr)?;
        self.raw(br#","world_R_center":"#)?;
        self.raw(IDENTITY)?;
        self.raw(b"}")
    }

    /// Common fields of `SemanticNodeAttributes` and its subtypes, up to (not
    /// including) `is_active`.
    fn semantic_head(&mut self, n: &DsgNode) -> io::Result<()> {
        self.raw(br#""bounding_box":"#)?;
        self.bbox(n.bbox.as_ref())?;
        self.raw(br#","color":"#)?;
        self.raw(BLACK)
    }

    fn node(&mut self, g: &DsgGraph, n: &DsgNode) -> io::Result<()> {
        self.raw(br#"{"attributes":{"#)?;
        let name = name_to_write(g, n);
        let time = n.timestamp_ns.unwrap_or(0);
        match n.kind {
            NodeKind::Agent => {
                self.raw(br#""dbow_ids":null,"dbow_values":null,"external_key":"#)?;
                self.u64(n.id)?;
                self.raw(br#","is_active":false,"is_predicted":false,"last_update_time_ns":"#)?;
                self.u64(time)?;
                self.raw(br#","metadata":{},"position":"#)?;
                self.vec3(n.position)?;
                self.raw(br#","timestamp":"#)?;
                self.u64(time)?;
                self.raw(br#","type":"AgentNodeAttributes","world_R_body":"#)?;
                self.raw(IDENTITY)?;
                // Not part of AgentNodeAttributes; kept so that nothing is lost.
                if let Some(name) = name {
                    self.raw(br#","name":"#)?;
                    self.str(name)?;
                }
                if let Some(l) = n.semantic_label {
                    self.raw(br#","semantic_label":"#)?;
                    self.u32(l)?;
                }
                if n.bbox.is_some() {
                    self.raw(br#","bounding_box":"#)?;
                    self.bbox(n.bbox.as_ref())?;
                }
            }
            kind => {
                if kind == NodeKind::Place {
                    self.raw(br#""active_frontier":false,"anti_frontier":false,"#)?;
                }
                self.semantic_head(n)?;
                match kind {
                    NodeKind::Place => self.raw(
                        br#","deformation_connections":[],"distance":0.0,"frontier_scale":[0.0,0.0,0.0]"#,
                    )?,
                    NodeKind::Place2d => {
                        self.raw(br#","boundary":[],"deformation_connections":[],"ellipse_centroid":"#)?;
                        self.vec3(n.position)?;
                        self.raw(
                            br#","ellipse_matrix_compress":[1.0,0.0,0.0,1.0],"ellipse_matrix_expand":[1.0,0.0,0.0,1.0],"has_active_mesh_indices":false"#,
                        )?;
                    }
                    _ => {}
                }
                self.raw(br#","is_active":false,"is_predicted":false,"last_update_time_ns":0"#)?;
                if kind == NodeKind::Object || !n.mesh_connections.is_empty() {
                    self.raw(br#","mesh_connections":"#)?;
                    self.u32_list(&n.mesh_connections)?;
                }
                if matches!(kind, NodeKind::Place | NodeKind::Place2d) {
                    self.raw(br#","mesh_vertex_labels":[]"#)?;
                }
                self.raw(br#","metadata":{},"name":"#)?;
                self.str(name.unwrap_or(""))?;
                match kind {
                    NodeKind::Place => self.raw(
                        br#","need_cleanup":false,"num_basis_points":0,"num_frontier_voxels":0,"orientation":{"w":1.0,"x":0.0,"y":0.0,"z":0.0},"pcl_mesh_connections":[]"#,
                    )?,
                    NodeKind::Place2d => self.raw(
                        br#","need_cleanup_splitting":false,"pcl_boundary_connections":[],"pcl_mesh_connections":[]"#,
                    )?,
                    _ => {}
                }
                self.raw(br#","position":"#)?;
                self.vec3(n.position)?;
                match kind {
                    NodeKind::Place => self.raw(br#","real_place":true"#)?,
                    NodeKind::Object => self.raw(br#","registered":false"#)?,
                    NodeKind::Room => self.raw(br#","semantic_class_probabilities":{}"#)?,
                    _ => {}
                }
                self.raw(br#","semantic_feature":"#)?;
                self.raw(NO_FEATURE)?;
                self.raw(br#","semantic_label":"#)?;
                self.u32(n.semantic_label.unwrap_or(u32::MAX))?;
                if let Some(t) = n.timestamp_ns {
                    // Not part of these attribute types; kept so that nothing is lost.
                    self.raw(br#","timestamp":"#)?;
                    self.u64(t)?;
                }
                self.raw(br#","type":""#)?;
                self.raw(kind.attribute_type().as_bytes())?;
                self.raw(b"\"")?;
                match kind {
                    NodeKind::Place | NodeKind::Place2d => {
                        self.raw(br#","voxblox_mesh_connections":[]"#)?;
                    }
                    NodeKind::Object => {
                        self.raw(br#","world_R_object":"#)?;
                        self.raw(IDENTITY)?;
                    }
                    _ => {}
                }
            }
        }
        self.raw(br#"},"id":"#)?;
        self.u64(n.id)?;
        self.raw(br#","layer":"#)?;
        self.u32(n.layer.layer)?;
        self.raw(br#","partition":"#)?;
        self.u32(n.layer.partition)?;
        self.raw(b"}")
    }

    fn mesh(&mut self, m: &DsgMesh) -> io::Result<()> {
        self.raw(br#"{"colors":[],"faces":["#)?;
        for (i, f) in m.faces.iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.raw(b"[")?;
            self.u32(f[0])?;
            self.raw(b",")?;
            self.u32(f[1])?;
            self.raw(b",")?;
            self.u32(f[2])?;
            self.raw(b"]")?;
        }
        self.raw(br#"],"first_seen_stamps":[],"has_colors":false,"has_first_seen_stamps":false,"has_labels":"#)?;
        let labels = m.labels.as_deref().unwrap_or(&[]);
        self.raw(if labels.is_empty() { b"false" } else { b"true" })?;
        self.raw(br#","has_timestamps":false,"header":"#)?;
        self.raw(HEADER)?;
        self.raw(br#","labels":"#)?;
        self.u32_list(labels)?;
        self.raw(br#","points":["#)?;
        for (i, &p) in m.points.iter().enumerate() {
            if i > 0 {
                self.raw(b",")?;
            }
            self.vec3(p)?;
        }
        self.raw(br#"],"stamps":[]}"#)
    }
}

/// The declared layers plus any layer a node uses (sorted, no duplicates).
pub(crate) fn layer_keys(g: &DsgGraph) -> Vec<LayerKey> {
    let mut keys: Vec<LayerKey> = g.layers.iter().map(|l| l.key).collect();
    keys.extend(g.nodes.iter().map(|n| n.layer));
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// `layer_names`: every alias of every layer (the first layer claiming a name
/// wins). A layer without aliases is left out; the importer then gives it its
/// conventional name again.
pub(crate) fn layer_names(g: &DsgGraph) -> BTreeMap<&str, LayerKey> {
    let mut names = BTreeMap::new();
    for l in &g.layers {
        for a in &l.aliases {
            names.entry(a.as_str()).or_insert(l.key);
        }
    }
    names
}

/// The `name` attribute: the node's name, or else its label when the importer
/// could not get the label back from the labelspace.
pub(crate) fn name_to_write<'g>(g: &'g DsgGraph, n: &'g DsgNode) -> Option<&'g str> {
    if let Some(name) = &n.name {
        return Some(name);
    }
    let label = n.label.as_deref()?;
    let from_space = n.semantic_label.and_then(|l| {
        g.labelspaces
            .get(&format!("_l{}p{}", n.layer.layer, n.layer.partition))
            .and_then(|space| space.get(&l))
    });
    if from_space.map(String::as_str) == Some(label) {
        None
    } else {
        Some(label)
    }
}

/// Centre `c` and half extent `h` (f32) for which the importer's f32 arithmetic
/// `c - h` and `c + h` gives exactly `lo` and `hi`. Falls back to the rounded exact
/// midpoint and half width when no nearby pair does (the box may then read back
/// one ulp off).
pub(crate) fn box_axis(lo: f32, hi: f32) -> (f32, f32) {
    let exact = |c: f32, h: f32| {
        (c - h).to_bits() == lo.to_bits() && (c + h).to_bits() == hi.to_bits() && h >= 0.0
    };
    let (l, u) = (f64::from(lo), f64::from(hi));
    let c0 = f32::midpoint(lo, hi);
    let h0 = ((u - l) / 2.0) as f32;
    if exact(c0, h0) || !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return (c0, h0);
    }
    // Reals that round to lo (resp. hi), as an interval [a, b] in f64.
    let mid = |a: f32, b: f32| f64::from(a).midpoint(f64::from(b));
    let (lo_a, lo_b) = (mid(lo.next_down(), lo), mid(lo, lo.next_up()));
    let (hi_a, hi_b) = (mid(hi.next_down(), hi), mid(hi, hi.next_up()));
    for dc in NUDGES {
        let c = nudge(c0, dc);
        let cd = f64::from(c);
        // c + h must round to hi and c - h to lo.
        let a = (hi_a - cd).max(cd - lo_b);
        let b = (hi_b - cd).min(cd - lo_a);
        if a > b {
            continue;
        }
        let hm = a.midpoint(b) as f32;
        for dh in NUDGES {
            let h = nudge(hm, dh);
            if exact(c, h) {
                return (c, h);
            }
        }
    }
    (c0, h0)
}

/// Ulp offsets tried around a first guess, nearest first.
const NUDGES: [i32; 9] = [0, 1, -1, 2, -2, 3, -3, 4, -4];

/// `x` moved by `n` ulps (down when negative).
fn nudge(mut x: f32, n: i32) -> f32 {
    for _ in 0..n.unsigned_abs() {
        x = if n > 0 { x.next_up() } else { x.next_down() };
    }
    x
}

/// Writes into `out` a decimal text for the finite `v` that serde_json's default
/// parser (used by the importer) reads back as exactly `v`.
///
/// That parser is not correctly rounding: it reads `<N>e<-k>` as the f64 `N`
/// divided by the f64 nearest `10^k`. The shortest round-trip text usually works;
/// when it does not, this tries integers `N` (up to 1e19) that are f64 values near
/// `|v| * 10^k`, for the few `k` that give `N` 16 to 19 digits, and keeps the first
/// text that reads back as `v`. If none does (not seen in practice; possible for
/// magnitudes beyond 1e±290), the shortest text is kept and reads back within an ulp
/// or so.
fn f64_text(v: f64, out: &mut Vec<u8>) {
    out.clear();
    // Writing into a Vec cannot fail.
    let _ = CompactFormatter.write_f64(out, v);
    if reads_back(out, v) {
        return;
    }
    let shortest = out.clone();
    let sign = if v.is_sign_negative() { "-" } else { "" };
    let a = v.abs();
    let e10 = a.log10().floor() as i32;
    for k in (15 - e10)..=(19 - e10) {
        // serde_json's POW10 table holds the correctly rounded powers of ten.
        let Ok(p) = format!("1e{}", k.unsigned_abs()).parse::<f64>() else {
            continue;
        };
        if k.unsigned_abs() > 308 {
            continue;
        }
        let n0 = if k >= 0 { a * p } else { a / p };
        if !(1.0..=1e19).contains(&n0) {
            continue;
        }
        let base = n0.round();
        for j in [0i32, 1, -1, 2, -2, 3, -3, 4, -4] {
            let n = if base < 9_007_199_254_740_992.0 {
                base + f64::from(j)
            } else {
                nudge64(base, j)
            };
            if !(1.0..=1e19).contains(&n) {
                continue;
            }
            out.clear();
            // `n` is an integer below 1e19, so the cast is exact.
            let _ = write!(out, "{sign}{}e{}", n as u64, -k);
            if reads_back(out, v) {
                return;
            }
        }
    }
    out.clear();
    out.extend_from_slice(&shortest);
}

/// `x` moved by `n` ulps (down when negative).
fn nudge64(mut x: f64, n: i32) -> f64 {
    for _ in 0..n.unsigned_abs() {
        x = if n > 0 { x.next_up() } else { x.next_down() };
    }
    x
}

fn reads_back(text: &[u8], v: f64) -> bool {
    serde_json::from_slice::<f64>(text).is_ok_and(|x| x.to_bits() == v.to_bits())
}
