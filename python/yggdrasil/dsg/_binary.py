"""spark_dsg 1.1.3's binary encoding of a graph, written from the facade's objects (the
layout ``ygg_dsg``'s binary reader and writer document: tagged little-endian scalars,
``ARR32`` arrays and strings, dynamic arrays for the nodes and the edges)."""
from __future__ import annotations

import json
import struct
from typing import TYPE_CHECKING, Any, Iterable, List, Mapping

import numpy as np

from ._types import (
    AgentNodeAttributes,
    BoundingBox,
    NodeAttributes,
    ObjectNodeAttributes,
    Place2dNodeAttributes,
    PlaceNodeAttributes,
    Quaternion,
    RoomNodeAttributes,
    SemanticNodeAttributes,
)

if TYPE_CHECKING:
    from ._graph import DynamicSceneGraph
    from ._mesh import Mesh

# The registered node attribute types, in spark_dsg 1.1.3's order (a node's type index).
_NODE_TYPES = (
    "NodeAttributes",
    "SemanticNodeAttributes",
    "ObjectNodeAttributes",
    "RoomNodeAttributes",
    "PlaceNodeAttributes",
    "Place2dNodeAttributes",
    "AgentNodeAttributes",
    "KhronosObjectAttributes",
    "TraversabilityNodeAttributes",
)
_TYPE_INDEX = {name: i for i, name in enumerate(_NODE_TYPES)}

_NIL, _FALSE, _TRUE = b"\xc0", b"\xc2", b"\xc3"
_F32, _F64, _U8, _U32, _U64, _I32, _I64, _ARR = (struct.Struct(f) for f in ("<Bf", "<Bd", "<BB", "<BI", "<BQ", "<Bi", "<Bq", "<BI"))
_ARR_START, _ARR_END = b"\x00", b"\x01"


class _Out:
    """Appends encoded values to a list of byte strings."""

    def __init__(self):
        self.parts: List[bytes] = []

    def f32(self, v: float) -> None:
        self.parts.append(_F32.pack(0xCA, v))

    def f64(self, v: float) -> None:
        self.parts.append(_F64.pack(0xCB, v))

    def u8(self, v: int) -> None:
        self.parts.append(_U8.pack(0xCC, v))

    def u32(self, v: int) -> None:
        self.parts.append(_U32.pack(0xCE, v))

    def u64(self, v: int) -> None:
        self.parts.append(_U64.pack(0xCF, v))

    def i32(self, v: int) -> None:
        self.parts.append(_I32.pack(0xD2, v))

    def i64(self, v: int) -> None:
        self.parts.append(_I64.pack(0xD3, v))

    def bool(self, v: bool) -> None:
        self.parts.append(_TRUE if v else _FALSE)

    def array(self, n: int) -> None:
        if n >= 2**32:
            raise ValueError(f"an array of {n} elements does not fit spark_dsg's binary encoding (at most 2**32 - 1)")
        self.parts.append(_ARR.pack(0xDD, n))

    def str(self, s: str) -> None:
        data = s.encode()
        self.array(len(data))
        self.parts.append(data)

    def vec3_f64(self, v: Iterable[float]) -> None:
        for x in v:
            self.f64(float(x))

    def vec3_f32(self, v: Iterable[float]) -> None:
        for x in v:
            self.f32(float(x))

    def quaternion(self, q: Quaternion) -> None:
        self.array(4)
        for x in (q.w, q.x, q.y, q.z):
            self.f64(x)

    def matrix(self, a: np.ndarray, scalar) -> None:
        a = np.asarray(a)
        if a.ndim == 1:
            a = a.reshape(-1, 1)
        rows, cols = a.shape
        self.array(rows * cols + 2)
        self.i64(rows)
        self.i64(cols)
        for x in a.reshape(-1).tolist():  # row by row
            scalar(x)

    def bytes(self) -> bytes:
        return b"".join(self.parts)


def _layer_key(w: _Out, key) -> None:
    w.array(2)
    w.i64(key[0])
    w.u32(key[1])


def _box(w: _Out, box: BoundingBox) -> None:
    w.array(4)
    w.i32(int(box.type))
    w.vec3_f32(box.dimensions.tolist())
    w.vec3_f32(box.world_P_center.tolist())
    w.array(11)
    w.i64(3)
    w.i64(3)
    for x in box.world_R_center.reshape(-1).tolist():  # row-major
        w.f32(x)


def _nearest_vertex(w: _Out, info: Mapping[str, Any]) -> None:
    w.array(4)
    w.array(3)
    for x in info.get("block", (0, 0, 0)):
        w.i32(int(x))
    w.array(3)
    for x in info.get("voxel_pos", (0.0, 0.0, 0.0)):
        w.f64(float(x))
    w.u64(int(info.get("vertex", 0)))
    label = info.get("label")
    if label is None:
        w.parts.append(_NIL)
    else:
        w.u32(int(label))


def _scalars(w: _Out, values, scalar) -> None:
    values = list(values)
    w.array(len(values))
    for v in values:
        scalar(int(v))


def _node(w: _Out, a: NodeAttributes) -> None:
    a._complete()
    w.u8(_TYPE_INDEX[a._TYPE])
    w.str(json.dumps(a._metadata._data if a._metadata is not None else {}))
    w.vec3_f64(a._position.tolist())
    w.u64(a.last_update_time_ns)
    w.bool(a.is_active)
    w.bool(a.is_predicted)
    if isinstance(a, AgentNodeAttributes):
        t = a.timestamp
        w.i64((t.days * 86400 + t.seconds) * 10**9 + t.microseconds * 1000)
        w.quaternion(a._world_R_body)
        w.u64(a.external_key)
        w.matrix(a._dbow_ids, w.u32)
        w.matrix(a._dbow_values, w.f32)
        return
    if not isinstance(a, SemanticNodeAttributes):
        return
    w.str(a._name)
    for x in a._color.tolist() + [255]:
        w.u8(x)
    _box(w, a.bounding_box)
    w.u32(a._semantic_label)
    w.matrix(a._semantic_feature, w.f32)
    if isinstance(a, ObjectNodeAttributes):
        _scalars(w, a._mesh_connections, w.u64)
        w.bool(a.registered)
        w.quaternion(a._world_R_object)
    elif isinstance(a, RoomNodeAttributes):
        probabilities = a._semantic_class_probabilities
        w.array(len(probabilities))
        for k, v in probabilities.items():
            w.str(str(k))
            w.f64(float(v))
    elif isinstance(a, PlaceNodeAttributes):
        w.f64(a.distance)
        w.u32(a.num_basis_points)
        w.array(len(a._voxblox_mesh_connections))
        for info in a._voxblox_mesh_connections:
            _nearest_vertex(w, info)
        _scalars(w, a._pcl_mesh_connections, w.u64)
        _scalars(w, a._mesh_vertex_labels, w.u8)
        _scalars(w, a._deformation_connections, w.u64)
        w.bool(a.real_place)
        w.bool(a.active_frontier)
        w.vec3_f64(a._frontier_scale.tolist())
        w.quaternion(a._orientation)
        w.bool(a.need_cleanup)
        w.u64(a.num_frontier_voxels)
        w.bool(a.anti_frontier)
    elif isinstance(a, Place2dNodeAttributes):
        w.array(len(a._boundary))
        for p in a._boundary:
            w.vec3_f64(p)
        w.vec3_f64(a._ellipse_centroid.tolist())
        w.matrix(a._ellipse_matrix_compress, w.f64)
        w.matrix(a._ellipse_matrix_expand, w.f64)
        _scalars(w, a._pcl_boundary_connections, w.u64)
        w.array(len(a._voxblox_mesh_connections))
        for info in a._voxblox_mesh_connections:
            _nearest_vertex(w, info)
        _scalars(w, a._pcl_mesh_connections, w.u64)
        _scalars(w, a._mesh_vertex_labels, w.u8)
        _scalars(w, a._deformation_connections, w.u64)
        w.bool(False)  # need_cleanup_splitting
        w.bool(False)  # has_active_mesh_indices


def _mesh(w: _Out, m: "Mesh") -> None:
    for flag in (m.has_colors, m.has_timestamps, m.has_labels, m.has_first_seen_stamps):
        w.bool(flag)
    w.array(m.num_vertices())
    for p in m._points.tolist():
        w.vec3_f32(p)
    colors = m._colors.tolist() if m.has_colors else []
    w.array(len(colors))
    for c in colors:
        for x in c:
            w.u8(x)
    _scalars(w, m._stamps.tolist() if m.has_timestamps else [], w.u64)
    _scalars(w, m._labels.tolist() if m.has_labels else [], w.u32)
    _scalars(w, m._first_seen.tolist() if m.has_first_seen_stamps else [], w.u64)
    w.array(m.num_faces())
    for f in m._faces.tolist():
        w.array(3)
        for x in f:
            w.u64(x)


def graph_bytes(G: "DynamicSceneGraph", include_mesh: bool, header: bool) -> bytes:
    """The graph in spark_dsg 1.1.3's binary encoding (with the file header when
    ``header``, else the body alone, as spark_dsg's ``to_binary`` gives it)."""
    w = _Out()
    if header:
        w.str("SPARK_DSG")
        w.str("main")
        for v in (1, 1, 3):
            w.u8(v)
    keys = sorted(G._layers)
    w.array(len(keys))
    for k in keys:
        _layer_key(w, k)
    w.array(len(_NODE_TYPES))
    for name in _NODE_TYPES:
        w.str(name)
    w.array(1)
    w.str("EdgeAttributes")
    names = sorted(G._names.items())
    w.array(len(names))
    for name, k in names:
        w.str(name)
        _layer_key(w, k)
    w.str(json.dumps(G._file_metadata()))
    w.parts.append(_ARR_START)
    for k in keys:
        for nid, node in G._layers[k].nodes.items():
            w.array(4)
            w.i64(k[0])
            w.u64(nid)
            w.u32(k[1])
            _node(w, node.attributes)
    w.parts.append(_ARR_END)
    w.parts.append(_ARR_START)
    for e in G.edges:
        w.array(3)
        w.u64(e.source)
        w.u64(e.target)
        info = e.info
        w.u8(0)
        w.str(json.dumps(info._metadata._data if info._metadata is not None else {}))
        w.bool(info.weighted)
        w.f64(info.weight)
    w.parts.append(_ARR_END)
    mesh = G.mesh if include_mesh else None
    w.bool(mesh is not None)
    if mesh is not None:
        _mesh(w, mesh)
    return w.bytes()
