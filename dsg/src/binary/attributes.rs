//! Node and edge attribute blocks of spark_dsg 1.1.3, with the version branches of its
//! reader back to 1.0.2 (`src/node_attributes.cpp`, `src/edge_attributes.cpp`,
//! `attribute_serialization.h`, `binary_conversions.{h,cpp}`).
//!
//! A block is `u8 type index` (into the file's list of type names), the attribute's
//! metadata as a JSON string (from 1.0.6), then the fields of `serialization_info()`
//! in order, with **no length prefix**: a block can only be skipped by decoding it, so
//! every layout is implemented here, including those the model does not hold
//! (`NodeAttributes`, `KhronosObjectAttributes`, `TraversabilityNodeAttributes`).
//! Their fields are checked and dropped; the import then rejects such nodes with
//! [`DsgImportError::UnknownNodeType`](crate::DsgImportError::UnknownNodeType),
//! exactly as the JSON importer does.
//!
//! Writing mirrors reading for the six kinds of [`NodeKind`], with spark_dsg's
//! defaults for every field the model does not keep.

use std::borrow::Cow;

use super::mesh;
use super::reader::{Cursor, DecodeError, Decoded, Scalar, Tag, u64_as_u32_at};
use super::writer::Writer;
use crate::model::{DsgVersion, NodeKind};
use crate::raw::{Num, RawAttrs, RawBox, RawEdgeInfo, RawQuat};

/// A node attribute layout: the registered names of spark_dsg 1.1.3, in its
/// registration order (the order it writes the type-name list in).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum NodeLayout {
    Node,
    Semantic,
    Object,
    Room,
    Place,
    Place2d,
    Agent,
    KhronosObject,
    Traversability,
}

impl NodeLayout {
    /// Every layout, in spark_dsg's registration order.
    pub(super) const ALL: [NodeLayout; 9] = [
        NodeLayout::Node,
        NodeLayout::Semantic,
        NodeLayout::Object,
        NodeLayout::Room,
        NodeLayout::Place,
        NodeLayout::Place2d,
        NodeLayout::Agent,
        NodeLayout::KhronosObject,
        NodeLayout::Traversability,
    ];

    /// The registered type name.
    pub(super) fn name(self) -> &'static str {
        match self {
            NodeLayout::Node => "NodeAttributes",
            NodeLayout::Semantic => "SemanticNodeAttributes",
            NodeLayout::Object => "ObjectNodeAttributes",
            NodeLayout::Room => "RoomNodeAttributes",
            NodeLayout::Place => "PlaceNodeAttributes",
            NodeLayout::Place2d => "Place2dNodeAttributes",
            NodeLayout::Agent => "AgentNodeAttributes",
            NodeLayout::KhronosObject => "KhronosObjectAttributes",
            NodeLayout::Traversability => "TraversabilityNodeAttributes",
        }
    }

    /// The layout registered under `name`.
    pub(super) fn from_name(name: &[u8]) -> Option<Self> {
        Self::ALL.into_iter().find(|l| l.name().as_bytes() == name)
    }

    /// The layout of a model kind.
    pub(super) fn of(kind: NodeKind) -> Self {
        match kind {
            NodeKind::Object => NodeLayout::Object,
            NodeKind::Place => NodeLayout::Place,
            NodeKind::Place2d => NodeLayout::Place2d,
            NodeKind::Room => NodeLayout::Room,
            NodeKind::Building => NodeLayout::Semantic,
            NodeKind::Agent => NodeLayout::Agent,
        }
    }

    /// Index in [`NodeLayout::ALL`] (the type index this crate writes).
    pub(super) fn index(self) -> u8 {
        self as u8
    }
}

/// The only edge attribute type of spark_dsg 1.1.3.
pub(super) const EDGE_ATTRIBUTES: &str = "EdgeAttributes";

/// The attribute type table of a file: type index to layout (`None` for a name this
/// crate does not know; a block using it cannot be decoded).
pub(super) struct TypeTable<T> {
    pub names: Vec<String>,
    pub layouts: Vec<Option<T>>,
}

impl<T: Copy> TypeTable<T> {
    /// The layout of the block at `c`, reading the type index.
    fn layout(&self, c: &mut Cursor<'_>, kind: &str) -> Decoded<T> {
        let at = c.offset();
        let idx = c.u8("attributes.type")?;
        match self.layouts.get(usize::from(idx)) {
            Some(Some(l)) => Ok(*l),
            Some(None) => Err(DecodeError::new(
                at,
                "attributes.type",
                format!(
                    "{kind} attribute type `{}` (index {idx}) is not a spark_dsg 1.1.3 type; \
                     blocks have no length prefix, so the rest cannot be read, not even by a \
                     lenient import",
                    self.names[usize::from(idx)]
                ),
            )),
            None => Err(DecodeError::new(
                at,
                "attributes.type",
                format!(
                    "{kind} attribute type index {idx} is outside the file's {} type names",
                    self.names.len()
                ),
            )),
        }
    }
}

/// Version tests of the reader's branches.
#[derive(Clone, Copy)]
pub(super) struct Ver(pub DsgVersion);

impl Ver {
    pub(super) fn before(self, major: u32, minor: u32, patch: u32) -> bool {
        self.0 < DsgVersion::new(major, minor, patch)
    }
}

/// The attribute metadata string (from 1.0.6): must be JSON, as spark_dsg parses it.
fn metadata(c: &mut Cursor<'_>, v: Ver) -> Decoded<()> {
    if v.before(1, 0, 6) {
        return Ok(());
    }
    let at = c.offset();
    let text = c.bytes("attributes.metadata")?;
    serde_json::from_slice::<serde::de::IgnoredAny>(text)
        .map(drop)
        .map_err(|e| DecodeError::new(at, "attributes.metadata", format!("not JSON: {e}")))
}

/// Reads one node attribute block into the JSON importer's raw form.
pub(super) fn read_node<'a>(
    c: &mut Cursor<'a>,
    types: &TypeTable<NodeLayout>,
    v: Ver,
) -> Decoded<RawAttrs<'a>> {
    let layout = types.layout(c, "node")?;
    metadata(c, v)?;
    let position = c.vec3_f64("attributes.position")?.map(Num);
    let mut a = RawAttrs {
        type_name: Cow::Borrowed(layout.name()),
        position,
        name: None,
        semantic_label: None,
        bounding_box: None,
        mesh_connections: None,
        timestamp: None,
    };
    c.u64("attributes.last_update_time_ns")?;
    c.bool("attributes.is_active")?;
    if !v.before(1, 0, 4) {
        c.bool("attributes.is_predicted")?;
    }
    match layout {
        NodeLayout::Node => {}
        NodeLayout::Agent => agent(c, v, &mut a)?,
        NodeLayout::Traversability => traversability(c)?,
        _ => {
            semantic(c, v, &mut a)?;
            match layout {
                NodeLayout::Object => object(c, &mut a)?,
                NodeLayout::KhronosObject => {
                    object(c, &mut a)?;
                    khronos(c)?;
                }
                NodeLayout::Room => {
                    map(c, "attributes.semantic_class_probabilities", |c| {
                        c.skip_scalar(Scalar::F64, "")
                    })?;
                }
                NodeLayout::Place => place(c, v)?,
                NodeLayout::Place2d => place2d(c, v)?,
                _ => {}
            }
        }
    }
    Ok(a)
}

/// `SemanticNodeAttributes` after the base fields.
fn semantic<'a>(c: &mut Cursor<'a>, v: Ver, a: &mut RawAttrs<'a>) -> Decoded<()> {
    a.name = Some(c.string("attributes.name")?);
    let color = if v.before(1, 0, 3) { 3 } else { 4 };
    for _ in 0..color {
        c.u8("attributes.color")?;
    }
    a.bounding_box = bounding_box(c, v).map_err(|e| e.within("attributes.bounding_box"))?;
    a.semantic_label = Some(c.u32("attributes.semantic_label")?);
    let feature = if v.before(1, 0, 5) {
        Scalar::F64
    } else {
        Scalar::F32
    };
    matrix(c, feature, Shape::Any).map_err(|e| e.within("attributes.semantic_feature"))?;
    Ok(())
}

/// `BoundingBox`: `[i32 type, dimensions, center, rotation]`, or before 1.0.3
/// `[i32 type, min, max, center, rotation]`. `None` for the INVALID type.
fn bounding_box<'a>(c: &mut Cursor<'a>, v: Ver) -> Decoded<Option<RawBox<'a>>> {
    let legacy = v.before(1, 0, 3);
    c.fixed(if legacy { 5 } else { 4 }, "")?;
    let at = c.offset();
    let type_name = match c.i32("type")? {
        0 => "INVALID",
        1 => "AABB",
        2 => "OBB",
        3 => "RAABB",
        t => {
            return Err(DecodeError::new(
                at,
                "type",
                format!("unknown box type {t}"),
            ));
        }
    };
    let dimensions = if legacy {
        let lo = c.vec3_f32("min")?;
        let hi = c.vec3_f32("max")?;
        [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]
    } else {
        c.vec3_f32("dimensions")?
    };
    let center = c.vec3_f32("world_P_center")?;
    let r = rotation3(c).map_err(|e| e.within("world_R_center"))?;
    if type_name == "INVALID" {
        return Ok(None);
    }
    let q = quaternion_of(r);
    let num = |x: f32| Num(f64::from(x));
    Ok(Some(RawBox {
        type_name: Some(Cow::Borrowed(type_name)),
        dimensions: Some(dimensions.map(num)),
        center: Some(center.map(num)),
        rotation: Some(RawQuat {
            w: num(q[0]),
            x: num(q[1]),
            y: num(q[2]),
            z: num(q[3]),
        }),
        min: None,
        max: None,
    }))
}

/// A 3x3 FLOAT32 matrix, row-major.
fn rotation3(c: &mut Cursor<'_>) -> Decoded<[[f32; 3]; 3]> {
    c.fixed(11, "")?;
    expect_dim(c, 3, "rows")?;
    expect_dim(c, 3, "cols")?;
    let mut m = [[0f32; 3]; 3];
    for row in &mut m {
        for x in row.iter_mut() {
            *x = c.f32("")?;
        }
    }
    Ok(m)
}

fn expect_dim(c: &mut Cursor<'_>, want: i64, field: &str) -> Decoded<()> {
    let at = c.offset();
    let got = c.i64(field)?;
    if got != want {
        return Err(DecodeError::new(
            at,
            field,
            format!("expected {want}, found {got}"),
        ));
    }
    Ok(())
}

/// Eigen's `Quaternionf(const Matrix3f&)` (Shepperd's method, in f32 like Eigen), so
/// that a box read here gets the quaternion spark_dsg writes to JSON for it.
fn quaternion_of(m: [[f32; 3]; 3]) -> [f32; 4] {
    let t = m[0][0] + m[1][1] + m[2][2];
    if t > 0.0 {
        let s = (t + 1.0).sqrt();
        let w = 0.5 * s;
        let s = 0.5 / s;
        return [
            w,
            (m[2][1] - m[1][2]) * s,
            (m[0][2] - m[2][0]) * s,
            (m[1][0] - m[0][1]) * s,
        ];
    }
    let mut i = 0;
    if m[1][1] > m[0][0] {
        i = 1;
    }
    if m[2][2] > m[i][i] {
        i = 2;
    }
    let j = (i + 1) % 3;
    let k = (j + 1) % 3;
    let s = (m[i][i] - m[j][j] - m[k][k] + 1.0).sqrt();
    let mut q = [0f32; 4];
    q[1 + i] = 0.5 * s;
    let s = 0.5 / s;
    q[0] = (m[k][j] - m[j][k]) * s;
    q[1 + j] = (m[j][i] + m[i][j]) * s;
    q[1 + k] = (m[k][i] + m[i][k]) * s;
    q
}

/// `ObjectNodeAttributes` after the semantic fields.
fn object(c: &mut Cursor<'_>, a: &mut RawAttrs<'_>) -> Decoded<()> {
    let field = "attributes.mesh_connections";
    let n = c.array_len(Scalar::U64.encoded(), field)?;
    let mut conn = Vec::with_capacity(n);
    c.records(n, &mut conn, |r: &[u8; 9]| u64_as_u32_at(r, 0));
    for i in conn.len()..n {
        let at = c.offset();
        let v = c.u64(field).map_err(|e| e.within(format!("[{i}]")))?;
        let v = u32::try_from(v).map_err(|_| {
            DecodeError::new(
                at,
                &format!("{field}[{i}]"),
                format!("vertex {v} does not fit u32"),
            )
        })?;
        conn.push(v);
    }
    a.mesh_connections = Some(conn);
    c.bool("attributes.registered")?;
    quaternion(c, "attributes.world_R_object")
}

/// `PlaceNodeAttributes` after the semantic fields.
fn place(c: &mut Cursor<'_>, v: Ver) -> Decoded<()> {
    c.f64("attributes.distance")?;
    c.u32("attributes.num_basis_points")?;
    list(c, "attributes.voxblox_mesh_connections", 1, nearest_vertex)?;
    scalars(c, Scalar::U64, "attributes.pcl_mesh_connections")?;
    scalars(c, Scalar::U8, "attributes.mesh_vertex_labels")?;
    scalars(c, Scalar::U64, "attributes.deformation_connections")?;
    c.bool("attributes.real_place")?;
    c.bool("attributes.active_frontier")?;
    c.vec3_f64("attributes.frontier_scale")?;
    quaternion(c, "attributes.orientation")?;
    c.bool("attributes.need_cleanup")?;
    c.u64("attributes.num_frontier_voxels")?;
    if !v.before(1, 1, 3) {
        c.bool("attributes.anti_frontier")?;
    }
    Ok(())
}

/// `Place2dNodeAttributes` after the semantic fields: spark_dsg 1.1.4 (its `develop`
/// branch, `node_attributes.cpp`) dropped the voxblox and deformation fields, renamed
/// the mesh fields and moved them first, and added the mesh index range; bodies before
/// 1.1.4 keep 1.1.3's layout.
fn place2d(c: &mut Cursor<'_>, v: Ver) -> Decoded<()> {
    let boundary = |c: &mut Cursor<'_>| {
        list(c, "attributes.boundary", 3 * Scalar::F64.encoded(), |c| {
            c.vec3_f64("").map(drop)
        })
    };
    let ellipse = |c: &mut Cursor<'_>| -> Decoded<()> {
        c.vec3_f64("attributes.ellipse_centroid")?;
        matrix(c, Scalar::F64, Shape::Exact(2, 2))
            .map_err(|e| e.within("attributes.ellipse_matrix_compress"))?;
        matrix(c, Scalar::F64, Shape::Exact(2, 2))
            .map_err(|e| e.within("attributes.ellipse_matrix_expand"))
    };
    if v.before(1, 1, 4) {
        boundary(c)?;
        ellipse(c)?;
        scalars(c, Scalar::U64, "attributes.pcl_boundary_connections")?;
        list(c, "attributes.voxblox_mesh_connections", 1, nearest_vertex)?;
        scalars(c, Scalar::U64, "attributes.pcl_mesh_connections")?;
        scalars(c, Scalar::U8, "attributes.mesh_vertex_labels")?;
        scalars(c, Scalar::U64, "attributes.deformation_connections")?;
        c.bool("attributes.need_cleanup_splitting")?;
    } else {
        scalars(c, Scalar::U64, "attributes.mesh_connections")?;
        scalars(c, Scalar::U64, "attributes.boundary_connections")?;
        boundary(c)?;
        ellipse(c)?;
        c.u64("attributes.min_mesh_index")?;
        c.u64("attributes.max_mesh_index")?;
        c.bool("attributes.need_finish_merge")?;
    }
    c.bool("attributes.has_active_mesh_indices")?;
    Ok(())
}

/// `AgentNodeAttributes` after the base fields.
fn agent(c: &mut Cursor<'_>, v: Ver, a: &mut RawAttrs<'_>) -> Decoded<()> {
    if !v.before(1, 1, 0) {
        let at = c.offset();
        let t = c.i64("attributes.timestamp")?;
        a.timestamp = Some(u64::try_from(t).map_err(|_| {
            DecodeError::new(
                at,
                "attributes.timestamp",
                format!("negative timestamp {t}"),
            )
        })?);
    }
    quaternion(c, "attributes.world_R_body")?;
    c.u64("attributes.external_key")?;
    matrix(c, Scalar::U32, Shape::Column).map_err(|e| e.within("attributes.dbow_ids"))?;
    matrix(c, Scalar::F32, Shape::Column).map_err(|e| e.within("attributes.dbow_values"))?;
    Ok(())
}

/// `KhronosObjectAttributes` after the object fields.
fn khronos(c: &mut Cursor<'_>) -> Decoded<()> {
    scalars(c, Scalar::U64, "attributes.first_observed_ns")?;
    scalars(c, Scalar::U64, "attributes.last_observed_ns")?;
    list(
        c,
        "attributes.trajectory_positions",
        3 * Scalar::F32.encoded(),
        |c| c.vec3_f32("").map(drop),
    )?;
    scalars(c, Scalar::U64, "attributes.trajectory_timestamps")?;
    list(c, "attributes.dynamic_object_points", 5, |c| {
        list(c, "", 3 * Scalar::F32.encoded(), |c| {
            c.vec3_f32("").map(drop)
        })
    })?;
    map(c, "attributes.details", |c| scalars(c, Scalar::U64, ""))?;
    mesh::read(c)
        .map(drop)
        .map_err(|e| e.within("attributes.mesh"))
}

/// `TraversabilityNodeAttributes` after the base fields.
fn traversability(c: &mut Cursor<'_>) -> Decoded<()> {
    c.u64("attributes.first_observed_ns")?;
    c.u64("attributes.last_observed_ns")?;
    c.f64("attributes.distance")?;
    matrix(c, Scalar::F64, Shape::Exact(2, 1)).map_err(|e| e.within("attributes.min"))?;
    matrix(c, Scalar::F64, Shape::Exact(2, 1)).map_err(|e| e.within("attributes.max"))?;
    for field in [
        "attributes.states_0",
        "attributes.states_1",
        "attributes.states_2",
        "attributes.states_3",
    ] {
        scalars(c, Scalar::U8, field)?;
    }
    Ok(())
}

/// `NearestVertexInfo`: `[[i32; 3], [f64; 3], u64 vertex, optional u32 label]`.
fn nearest_vertex(c: &mut Cursor<'_>) -> Decoded<()> {
    c.fixed(4, "")?;
    c.fixed(3, "block")?;
    for _ in 0..3 {
        c.i32("block")?;
    }
    c.fixed(3, "voxel_pos")?;
    for _ in 0..3 {
        c.f64("voxel_pos")?;
    }
    c.u64("vertex")?;
    c.opt_u32("label")?;
    Ok(())
}

/// `Eigen::Quaterniond`: `ARR32(4)` of w, x, y, z.
fn quaternion(c: &mut Cursor<'_>, field: &str) -> Decoded<()> {
    c.fixed(4, field)?;
    for _ in 0..4 {
        c.f64(field)?;
    }
    Ok(())
}

/// `std::vector` of one scalar type, skipped.
fn scalars(c: &mut Cursor<'_>, s: Scalar, field: &str) -> Decoded<()> {
    let n = c.array_len(s.encoded(), field)?;
    let fast = match s {
        Scalar::U8 => c.records(n, &mut Vec::new(), |r: &[u8; 2]| {
            (r[0] == Tag::U8 as u8).then_some(())
        }),
        Scalar::U64 => c.records(n, &mut Vec::new(), |r: &[u8; 9]| {
            (r[0] == Tag::U64 as u8).then_some(())
        }),
        _ => false,
    };
    if fast {
        return Ok(());
    }
    for i in 0..n {
        c.skip_scalar(s, "")
            .map_err(|e| e.within(format!("{field}[{i}]")))?;
    }
    Ok(())
}

/// A `std::vector` / `std::list` whose elements take at least `min` bytes each.
fn list(
    c: &mut Cursor<'_>,
    field: &str,
    min: usize,
    mut element: impl FnMut(&mut Cursor<'_>) -> Decoded<()>,
) -> Decoded<()> {
    let n = c.array_len(min, field)?;
    for i in 0..n {
        element(c).map_err(|e| e.within(format!("{field}[{i}]")))?;
    }
    Ok(())
}

/// A `std::map<std::string, V>`: `ARR32(n)`, then n times key, value (no pair array).
fn map(
    c: &mut Cursor<'_>,
    field: &str,
    mut value: impl FnMut(&mut Cursor<'_>) -> Decoded<()>,
) -> Decoded<()> {
    let n = c.array_len(6, field)?;
    for i in 0..n {
        c.bytes("key")
            .map_err(|e| e.within(format!("{field}[{i}]")))?;
        value(c).map_err(|e| e.within(format!("{field}[{i}]")))?;
    }
    Ok(())
}

/// Shapes a matrix field may have.
#[derive(Clone, Copy)]
enum Shape {
    /// `Eigen::MatrixX*`: any size.
    Any,
    /// A dynamic column vector: any rows, one column.
    Column,
    /// A fixed-size matrix.
    Exact(i64, i64),
}

/// An Eigen matrix: `ARR32(rows * cols + 2)`, INT64 rows, INT64 cols, the values row by
/// row. Skipped.
fn matrix(c: &mut Cursor<'_>, s: Scalar, shape: Shape) -> Decoded<()> {
    let at = c.offset();
    let len = c.array_len(1, "")?;
    if len < 2 {
        return Err(DecodeError::new(at, "", "matrix without dimensions"));
    }
    let rows = c.i64("rows")?;
    let cols = c.i64("cols")?;
    let count = rows
        .checked_mul(cols)
        .filter(|&n| rows >= 0 && cols >= 0 && usize::try_from(n).is_ok_and(|n| n == len - 2));
    let Some(count) = count else {
        return Err(DecodeError::new(
            at,
            "",
            format!("{rows} x {cols} matrix in an array of {len}"),
        ));
    };
    let ok = match shape {
        Shape::Any => true,
        Shape::Column => cols == 1,
        Shape::Exact(r, k) => rows == r && cols == k,
    };
    if !ok {
        return Err(DecodeError::new(
            at,
            "",
            format!("unexpected {rows} x {cols} matrix"),
        ));
    }
    for _ in 0..count {
        c.skip_scalar(s, "")?;
    }
    Ok(())
}

/// Reads one edge attribute block.
pub(super) fn read_edge(
    c: &mut Cursor<'_>,
    types: &TypeTable<&'static str>,
    v: Ver,
) -> Decoded<RawEdgeInfo> {
    types.layout(c, "edge")?;
    metadata(c, v)?;
    let weighted = c.bool("info.weighted")?;
    let weight = c.f64("info.weight")?;
    Ok(RawEdgeInfo {
        weight: Num(weight),
        weighted: Some(weighted),
    })
}

/// What the writer needs of one node's attributes.
pub(super) struct NodeOut<'g> {
    pub kind: NodeKind,
    pub position: [f32; 3],
    pub last_update_time_ns: u64,
    pub name: &'g str,
    /// `(dimensions, center)`, or `None` for an INVALID box.
    pub bbox: Option<([f32; 3], [f32; 3])>,
    pub semantic_label: u32,
    pub mesh_connections: &'g [u32],
    /// For agents.
    pub timestamp: i64,
    /// For agents.
    pub external_key: u64,
    /// For mesh places: `ellipse_centroid`.
    pub centroid: [f64; 3],
    /// For mesh places: spark_dsg 1.1.4's layout (else 1.1.3's).
    pub place2d_1_1_4: bool,
}

const IDENTITY_Q: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

/// Writes one node attribute block (type index, metadata `{}`, the fields).
pub(super) fn write_node(w: &mut Writer, n: &NodeOut<'_>) {
    let layout = NodeLayout::of(n.kind);
    w.u8(layout.index());
    w.str("{}");
    w.vec3_f64(n.position.map(f64::from));
    w.u64(n.last_update_time_ns);
    w.bool(false); // is_active
    w.bool(false); // is_predicted
    if layout == NodeLayout::Agent {
        w.i64(n.timestamp);
        w.quaternion(IDENTITY_Q);
        w.u64(n.external_key);
        w.matrix_header(0, 1); // dbow_ids
        w.matrix_header(0, 1); // dbow_values
        return;
    }
    w.str(n.name);
    for x in [0, 0, 0, 255] {
        w.u8(x);
    }
    write_box(w, n.bbox);
    w.u32(n.semantic_label);
    w.matrix_header(0, 0); // semantic_feature
    match layout {
        NodeLayout::Object => {
            w.array(n.mesh_connections.len());
            for &v in n.mesh_connections {
                w.u64(u64::from(v));
            }
            w.bool(false); // registered
            w.quaternion(IDENTITY_Q);
        }
        NodeLayout::Room => w.array(0),
        NodeLayout::Place => {
            w.f64(0.0); // distance
            w.u32(0); // num_basis_points
            for _ in 0..4 {
                w.array(0); // voxblox, pcl, vertex labels, deformation
            }
            w.bool(true); // real_place
            w.bool(false); // active_frontier
            w.vec3_f64([0.0; 3]);
            w.quaternion(IDENTITY_Q);
            w.bool(false); // need_cleanup
            w.u64(0); // num_frontier_voxels
            w.bool(false); // anti_frontier
        }
        NodeLayout::Place2d => {
            let ellipse = |w: &mut Writer| {
                w.vec3_f64(n.centroid);
                for _ in 0..2 {
                    w.matrix_header(2, 2);
                    for x in [1.0, 0.0, 0.0, 1.0] {
                        w.f64(x);
                    }
                }
            };
            if n.place2d_1_1_4 {
                w.array(0); // mesh_connections
                w.array(0); // boundary_connections
                w.array(0); // boundary
                ellipse(w);
                w.u64(0); // min_mesh_index
                w.u64(0); // max_mesh_index
                w.bool(false); // need_finish_merge
            } else {
                w.array(0); // boundary
                ellipse(w);
                for _ in 0..5 {
                    w.array(0); // boundary conns, voxblox, pcl, vertex labels, deformation
                }
                w.bool(false); // need_cleanup_splitting
            }
            w.bool(false); // has_active_mesh_indices
        }
        _ => {}
    }
}

fn write_box(w: &mut Writer, b: Option<([f32; 3], [f32; 3])>) {
    w.array(4);
    let (t, dims, center) = match b {
        Some((d, c)) => (1, d, c),
        None => (0, [0.0; 3], [0.0; 3]),
    };
    w.i32(t);
    w.vec3_f32(dims);
    w.vec3_f32(center);
    w.matrix_header(3, 3);
    for r in 0..3 {
        for k in 0..3 {
            w.f32(if r == k { 1.0 } else { 0.0 });
        }
    }
}

/// Writes one edge attribute block.
pub(super) fn write_edge(w: &mut Writer, weight: Option<f64>) {
    w.u8(0);
    w.str("{}");
    w.bool(weight.is_some());
    w.f64(weight.unwrap_or(1.0));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternion_of_rotations() {
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(quaternion_of(id), [1.0, 0.0, 0.0, 0.0]);
        // 180 degrees about z: trace -1, the i = 0 / 1 branch.
        let rz = [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(quaternion_of(rz), [0.0, 0.0, 0.0, 1.0]);
    }
}
