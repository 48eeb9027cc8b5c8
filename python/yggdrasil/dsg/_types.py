"""spark_dsg 1.1.3's value types: node symbols, layer keys, boxes, quaternions, metadata,
labelspaces and the node and edge attribute classes, in plain Python."""
from __future__ import annotations

import copy
import datetime
import enum
import json
import types
from typing import Any, Dict, Iterable, Mapping, Optional, Tuple, Union

import numpy as np

NO_SEMANTIC_LABEL = 2**32 - 1
_LOW56 = (1 << 56) - 1


class DsgLayers:
    """Spark-DSG's layer names (as ``spark_dsg.DsgLayers``)."""

    SEGMENTS = "SEGMENTS"
    OBJECTS = "OBJECTS"
    AGENTS = "AGENTS"
    PLACES = "PLACES"
    MESH_PLACES = "MESH_PLACES"
    TRAVERSABILITY = "TRAVERSABILITY"
    ROOMS = "ROOMS"
    BUILDINGS = "BUILDINGS"


def _partition(p: Union[int, str]) -> int:
    """A partition id from an int or a one-character prefix (``"a"`` is 97)."""
    if isinstance(p, str):
        if len(p) != 1:
            raise ValueError(f"a partition is an int or one character, not {p!r}")
        return ord(p)
    return int(p)


class NodeSymbol:
    """A Spark-DSG node id: ``NodeSymbol("O", 3)`` or ``NodeSymbol(value)``; ``value`` is
    the u64, ``category`` its prefix character, ``category_id`` the low 56 bits."""

    __slots__ = ("value",)

    def __init__(self, key: Union[int, str, "NodeSymbol"], index: Optional[int] = None):
        if index is None:
            self.value = int(key)
        else:
            if not isinstance(key, str) or len(key) != 1:
                raise ValueError(f"a node symbol's category is one character, not {key!r}")
            if not 0 <= int(index) <= _LOW56:
                raise ValueError(f"a node symbol's index must be in [0, 2**56), not {index}")
            self.value = (ord(key) << 56) | int(index)

    @property
    def category(self) -> str:
        """The prefix character (the top byte)."""
        return chr(self.value >> 56)

    @property
    def category_id(self) -> int:
        """The index below the prefix (the low 56 bits)."""
        return self.value & _LOW56

    def str(self, literal: bool = True) -> str:
        """``"O(12)"``, as Spark-DSG prints symbols."""
        return f"{self.category}({self.category_id})"

    def __str__(self) -> str:
        return self.str()

    def __repr__(self) -> str:
        return self.str()

    def __eq__(self, other) -> bool:
        if isinstance(other, NodeSymbol):
            return self.value == other.value
        if isinstance(other, int):
            return self.value == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self.value)

    def __int__(self) -> int:
        return self.value

    __index__ = __int__


def node_id(x) -> int:
    """The u64 of a node id given as an int or a ``NodeSymbol``."""
    if type(x) is int:
        return x
    if isinstance(x, (NodeSymbol, int, np.integer)):
        return int(x)
    raise TypeError(f"a node id is an int or a NodeSymbol, not {type(x).__name__}")


class LayerKey:
    """A Spark-DSG layer key: ``layer`` (the layer id) and ``partition`` (an int, or a
    one-character prefix such as ``"a"``)."""

    __slots__ = ("layer", "partition")

    def __init__(self, layer: int, partition: Union[int, str] = 0):
        self.layer = int(layer)
        self.partition = _partition(partition)

    def __eq__(self, other) -> bool:
        return isinstance(other, LayerKey) and self.layer == other.layer and self.partition == other.partition

    def __hash__(self) -> int:
        return hash((self.layer, self.partition))

    def __lt__(self, other: "LayerKey") -> bool:
        return (self.layer, self.partition) < (other.layer, other.partition)

    def __repr__(self) -> str:
        return f"{self.layer}" if self.partition == 0 else f"{self.layer}[{self.partition}]"

    __str__ = __repr__


class BoundingBoxType(enum.IntEnum):
    """``spark_dsg.BoundingBoxType``."""

    INVALID = 0
    AABB = 1
    OBB = 2
    RAABB = 3


class Quaternion:
    """A rotation ``w, x, y, z`` (identity by default)."""

    __slots__ = ("w", "x", "y", "z")

    def __init__(self, w: float = 1.0, x: float = 0.0, y: float = 0.0, z: float = 0.0):
        self.w, self.x, self.y, self.z = float(w), float(x), float(y), float(z)

    def _copy(self) -> "Quaternion":
        q = object.__new__(Quaternion)
        q.w, q.x, q.y, q.z = self.w, self.x, self.y, self.z
        return q

    def __eq__(self, other) -> bool:
        return isinstance(other, Quaternion) and (self.w, self.x, self.y, self.z) == (other.w, other.x, other.y, other.z)

    def __repr__(self) -> str:
        return f"Quaternion<w={self.w:g}, x={self.x:g}, y={self.y:g}, z={self.z:g}>"

    def to_json(self) -> Dict[str, float]:
        return {"w": self.w, "x": self.x, "y": self.y, "z": self.z}

    @classmethod
    def from_json(cls, d: Optional[Mapping[str, float]]) -> "Quaternion":
        if not d:
            return cls()
        return cls(d.get("w", 1.0), d.get("x", 0.0), d.get("y", 0.0), d.get("z", 0.0))

    def matrix(self) -> np.ndarray:
        """The 3x3 rotation matrix."""
        w, x, y, z = self.w, self.x, self.y, self.z
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )


_IDENTITY = Quaternion()


class BoundingBox:
    """``spark_dsg.BoundingBox``: ``BoundingBox()`` is invalid, ``BoundingBox(dimensions,
    world_P_center)`` axis-aligned; ``type``, ``dimensions``, ``world_P_center`` (float32),
    ``world_R_center`` (3x3), ``min``, ``max``."""

    __slots__ = ("type", "dimensions", "world_P_center", "_rotation")

    def __init__(self, *args):
        self._rotation = _IDENTITY
        if not args:
            self.type = BoundingBoxType.INVALID
            self.dimensions = np.zeros(3, dtype=np.float32)
            self.world_P_center = np.zeros(3, dtype=np.float32)
        elif len(args) == 2:
            self.type = BoundingBoxType.AABB
            self.dimensions = np.asarray(args[0], dtype=np.float32).reshape(3)
            self.world_P_center = np.asarray(args[1], dtype=np.float32).reshape(3)
        else:
            raise TypeError("BoundingBox() or BoundingBox(dimensions, world_P_center)")

    @classmethod
    def from_corners(cls, lo, hi) -> "BoundingBox":
        """The axis-aligned box from its smallest to its largest corner."""
        lo, hi = np.asarray(lo, dtype=np.float32), np.asarray(hi, dtype=np.float32)
        return cls(hi - lo, (hi + lo) / 2)

    @classmethod
    def _make(cls, kind: BoundingBoxType, dims, center, rotation: Quaternion) -> "BoundingBox":
        box = cls()
        box.type = BoundingBoxType(kind)
        box.dimensions = np.asarray(dims, dtype=np.float32).reshape(3)
        box.world_P_center = np.asarray(center, dtype=np.float32).reshape(3)
        box._rotation = rotation
        return box

    def _copy(self) -> "BoundingBox":
        box = object.__new__(BoundingBox)
        box.type = self.type
        box.dimensions = self.dimensions.copy()
        box.world_P_center = self.world_P_center.copy()
        box._rotation = self._rotation  # never changed in place: shared
        return box

    @property
    def min(self) -> np.ndarray:
        """The smallest corner (axis-aligned part)."""
        return (self.world_P_center - self.dimensions / 2).astype(np.float32)

    @property
    def max(self) -> np.ndarray:
        """The largest corner (axis-aligned part)."""
        return (self.world_P_center + self.dimensions / 2).astype(np.float32)

    @property
    def world_R_center(self) -> np.ndarray:
        """The box's rotation as a 3x3 matrix."""
        return self._rotation.matrix().astype(np.float32)

    def has_rotation(self) -> bool:
        """Whether the box is oriented (``OBB`` or ``RAABB``)."""
        return self.type in (BoundingBoxType.OBB, BoundingBoxType.RAABB)

    def is_valid(self) -> bool:
        """Whether the type is not ``INVALID``."""
        return self.type != BoundingBoxType.INVALID

    def volume(self) -> float:
        """The product of the dimensions."""
        return float(np.prod(self.dimensions))

    def contains(self, point) -> bool:
        """Whether ``point`` lies inside (axis-aligned boxes)."""
        p = np.asarray(point, dtype=np.float32)
        return bool(self.is_valid() and np.all(self.min <= p) and np.all(p <= self.max))

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, BoundingBox)
            and self.type == other.type
            and np.array_equal(self.dimensions, other.dimensions)
            and np.array_equal(self.world_P_center, other.world_P_center)
            and self._rotation == other._rotation
        )

    def __repr__(self) -> str:
        if not self.is_valid():
            return "invalid"
        return f"{{pos: {self.world_P_center.tolist()}, dim: {self.dimensions.tolist()}}}"

    def to_json(self) -> Dict[str, Any]:
        return {
            "dimensions": self.dimensions.tolist(),
            "type": self.type.name,
            "world_P_center": self.world_P_center.tolist(),
            "world_R_center": self._rotation.to_json(),
        }

    @classmethod
    def from_json(cls, d: Optional[Mapping[str, Any]]) -> "BoundingBox":
        if not d:
            return cls()
        kind = BoundingBoxType[d.get("type", "INVALID")]
        rotation = Quaternion.from_json(d.get("world_R_center"))
        if "dimensions" in d:
            return cls._make(kind, d["dimensions"], d["world_P_center"], rotation)
        lo, hi = np.asarray(d["min"], dtype=np.float32), np.asarray(d["max"], dtype=np.float32)
        return cls._make(kind, hi - lo, d.get("world_P_center", (lo + hi) / 2), rotation)


def _merge(into: Dict[str, Any], new: Mapping[str, Any]) -> None:
    for k, v in new.items():
        if isinstance(v, Mapping) and isinstance(into.get(k), dict):
            _merge(into[k], v)
        else:
            into[k] = copy.deepcopy(v)


class Metadata:
    """JSON metadata (``get()``, ``set(obj)``, ``add(obj)``: a recursive merge)."""

    __slots__ = ("_data",)

    def __init__(self, data: Optional[Dict[str, Any]] = None):
        self._data: Dict[str, Any] = data if data is not None else {}

    def get(self) -> Mapping[str, Any]:
        """A read-only view of the metadata."""
        return types.MappingProxyType(self._data)

    def set(self, obj: Mapping[str, Any]) -> None:
        """Replaces the metadata (a JSON-serialisable mapping)."""
        self._data = copy.deepcopy(dict(_json_checked(obj)))

    def add(self, obj: Mapping[str, Any]) -> None:
        """Merges ``obj`` in, key by key (nested mappings merge too)."""
        _merge(self._data, _json_checked(obj))


def _json_checked(obj: Mapping[str, Any]) -> Mapping[str, Any]:
    if not isinstance(obj, Mapping):
        raise TypeError(f"metadata is a mapping, not {type(obj).__name__}")
    json.dumps(obj)  # raises TypeError naming what is not serialisable
    return obj


class Labelspace:
    """Semantic label id -> category name (``spark_dsg.Labelspace``)."""

    def __init__(self, labels_to_names: Optional[Mapping[int, str]] = None):
        self.labels_to_names: Dict[int, str] = {int(k): str(v) for k, v in (labels_to_names or {}).items()}

    @property
    def names_to_labels(self) -> Dict[str, int]:
        """Category name -> label id."""
        return {v: k for k, v in self.labels_to_names.items()}

    def get_category(self, label: int) -> Optional[str]:
        """The name of ``label``, or ``None``."""
        return self.labels_to_names.get(int(label))

    def get_label(self, name: str) -> Optional[int]:
        """The label id of ``name``, or ``None``."""
        return self.names_to_labels.get(name)

    def get_node_category(self, node) -> Optional[str]:
        """The name of a node's ``semantic_label``, or ``None``."""
        return self.get_category(node.attributes.semantic_label)

    def __bool__(self) -> bool:
        return bool(self.labels_to_names)

    def __repr__(self) -> str:
        return f"Labelspace({self.labels_to_names})"


# ---------------------------------------------------------------- attributes
#
# Each class lists its fields with a default factory and a JSON codec. A node loaded
# from a file has the fields its Scene keeps (position, name, semantic label, box) set
# at once; the others are filled from the file on first use (``_pending``).


def _f64x3(v) -> np.ndarray:
    a = np.array(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,):
        raise ValueError(f"a position is 3 numbers, not shape {a.shape}")
    return a


def _u8x3(v) -> np.ndarray:
    if isinstance(v, Mapping):
        v = (v.get("r", 0), v.get("g", 0), v.get("b", 0))
    a = np.array(v, dtype=np.uint8).reshape(-1)[:3]
    if a.shape != (3,):
        raise ValueError(f"a color is 3 numbers, not shape {a.shape}")
    return a


def _feature(d) -> np.ndarray:
    if not d or not d.get("rows") or not d.get("cols"):
        return np.zeros((0, 0), dtype=np.float32)
    return np.asarray(d["data"], dtype=np.float32).reshape((d["rows"], d["cols"]))  # row by row


def _feature_json(a: np.ndarray) -> Dict[str, Any]:
    a = np.asarray(a, dtype=np.float32)
    if a.size == 0:
        return {"cols": 0, "data": None, "rows": 0}
    return {"cols": int(a.shape[1]), "data": a.reshape(-1).tolist(), "rows": int(a.shape[0])}


def _timedelta(v) -> datetime.timedelta:
    if isinstance(v, datetime.timedelta):
        return v
    return datetime.timedelta(microseconds=int(v) / 1000)


def _ns(v: datetime.timedelta) -> int:
    return (v.days * 86400 + v.seconds) * 10**9 + v.microseconds * 1000


# name: (default factory, from-json, to-json)
_Field = Tuple[Any, Any, Any]

_BASE_FIELDS: Dict[str, _Field] = {
    "position": (lambda: np.zeros(3), _f64x3, lambda v: v.tolist()),
    "last_update_time_ns": (lambda: 0, int, int),
    "is_active": (lambda: False, bool, bool),
    "is_predicted": (lambda: False, bool, bool),
}
_SEMANTIC_FIELDS: Dict[str, _Field] = {
    **_BASE_FIELDS,
    "name": (lambda: "", str, str),
    "color": (lambda: np.zeros(3, dtype=np.uint8), _u8x3, lambda v: {"a": 255, "b": int(v[2]), "g": int(v[1]), "r": int(v[0])}),
    "bounding_box": (BoundingBox, BoundingBox.from_json, lambda v: v.to_json()),
    "semantic_label": (lambda: NO_SEMANTIC_LABEL, int, int),
    "semantic_feature": (lambda: np.zeros((0, 0), dtype=np.float32), _feature, _feature_json),
}
_LIST = (tuple, lambda v: tuple(v or ()), list)
_OBJECT_FIELDS: Dict[str, _Field] = {
    **_SEMANTIC_FIELDS,
    "registered": (lambda: False, bool, bool),
    "world_R_object": (Quaternion, Quaternion.from_json, lambda v: v.to_json()),
    "mesh_connections": _LIST,
}
_PLACE_FIELDS: Dict[str, _Field] = {
    **_SEMANTIC_FIELDS,
    "distance": (lambda: 0.0, float, float),
    "num_basis_points": (lambda: 0, int, int),
    "voxblox_mesh_connections": _LIST,
    "pcl_mesh_connections": _LIST,
    "mesh_vertex_labels": _LIST,
    "deformation_connections": _LIST,
    "real_place": (lambda: True, bool, bool),
    "need_cleanup": (lambda: False, bool, bool),
    "active_frontier": (lambda: False, bool, bool),
    "frontier_scale": (lambda: np.zeros(3), _f64x3, lambda v: v.tolist()),
    "orientation": (Quaternion, Quaternion.from_json, lambda v: v.to_json()),
    "num_frontier_voxels": (lambda: 0, int, int),
    "anti_frontier": (lambda: False, bool, bool),
}
_PLACE2D_FIELDS: Dict[str, _Field] = {
    **_SEMANTIC_FIELDS,
    "boundary": _LIST,
    "ellipse_matrix_compress": (lambda: np.zeros((2, 2)), lambda v: np.asarray(v, dtype=np.float64).reshape(2, 2), lambda v: v.tolist()),
    "ellipse_matrix_expand": (lambda: np.zeros((2, 2)), lambda v: np.asarray(v, dtype=np.float64).reshape(2, 2), lambda v: v.tolist()),
    "ellipse_centroid": (lambda: np.zeros(3), _f64x3, lambda v: v.tolist()),
    "pcl_boundary_connections": _LIST,
    "voxblox_mesh_connections": _LIST,
    "pcl_mesh_connections": _LIST,
    "mesh_vertex_labels": _LIST,
    "deformation_connections": _LIST,
}
_ROOM_FIELDS: Dict[str, _Field] = {
    **_SEMANTIC_FIELDS,
    "semantic_class_probabilities": (dict, lambda v: dict(v or {}), dict),
}
_AGENT_FIELDS: Dict[str, _Field] = {
    **_BASE_FIELDS,
    "timestamp": (datetime.timedelta, _timedelta, _ns),
    "world_R_body": (Quaternion, Quaternion.from_json, lambda v: v.to_json()),
    "external_key": (lambda: 0, int, int),
    "dbow_ids": (lambda: np.zeros(0, dtype=np.uint32), lambda v: np.asarray(v or [], dtype=np.uint32), lambda v: v.tolist() or None),
    "dbow_values": (lambda: np.zeros(0, dtype=np.float32), lambda v: np.asarray(v or [], dtype=np.float32), lambda v: v.tolist() or None),
}


# fields behind a property (the setter tells the graph): their slot names
def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def _quaternion(q) -> "Quaternion":
    if not isinstance(q, Quaternion):
        raise TypeError(f"a rotation is a Quaternion, not {type(q).__name__}")
    return q._copy()


def _frozen_as(coerce):
    return lambda v: _frozen(coerce(v))


# Value fields: kept in a form no one changes in place (read-only arrays, tuples, dicts
# only replaced), so that copies of the attributes share them, and handed out as new
# copies, as spark_dsg hands out its Eigen and STL fields. name -> (store, hand out).
_VALUE_FIELDS: Dict[str, Tuple[Any, Any]] = {
    **{
        name: (_frozen_as(coerce), np.copy)
        for name, coerce in {
            "position": _f64x3,
            "color": _u8x3,
            "semantic_feature": lambda v: np.array(v, dtype=np.float32, ndmin=2),
            "frontier_scale": _f64x3,
            "ellipse_matrix_compress": lambda v: np.array(v, dtype=np.float64).reshape(2, 2),
            "ellipse_matrix_expand": lambda v: np.array(v, dtype=np.float64).reshape(2, 2),
            "ellipse_centroid": _f64x3,
            "dbow_ids": lambda v: np.array(v, dtype=np.uint32).reshape(-1),
            "dbow_values": lambda v: np.array(v, dtype=np.float32).reshape(-1),
        }.items()
    },
    **{
        name: (tuple, list)
        for name in (
            "mesh_connections", "voxblox_mesh_connections", "pcl_mesh_connections", "mesh_vertex_labels",
            "deformation_connections", "boundary", "pcl_boundary_connections",
        )
    },
    "semantic_class_probabilities": (dict, dict),
    **{name: (_quaternion, Quaternion._copy) for name in ("world_R_object", "orientation", "world_R_body")},
}
_SLOT = {"name": "_name", "semantic_label": "_semantic_label", **{n: "_" + n for n in _VALUE_FIELDS}}


def _slots(fields: Iterable[str]) -> Tuple[str, ...]:
    return tuple(_SLOT.get(k, k) for k in fields)


def _value_property(name: str) -> property:
    slot, (store, hand_out) = "_" + name, _VALUE_FIELDS[name]

    def get(self):
        return hand_out(getattr(self, slot))

    def set(self, value):
        setattr(self, slot, store(value))
        if name == "mesh_connections" and self._owner is not None:
            self._owner._moved(self)  # an object's geometry is the vertices it claims

    return property(get, set, doc=f"``{name}`` (a copy; assign a new value to change it).")


class NodeAttributes:
    """``spark_dsg.NodeAttributes``: ``position`` (float64, 3), ``last_update_time_ns``,
    ``is_active``, ``is_predicted`` and ``metadata``. Setting ``position`` on a node of a
    graph moves it in the graph's Yggdrasil scene too."""

    _FIELDS: Dict[str, _Field] = _BASE_FIELDS
    _TYPE = "NodeAttributes"
    __slots__ = ("_position", "last_update_time_ns", "is_active", "is_predicted", "_metadata", "_owner", "_pending")

    def __init__(self):
        self._owner = None
        self._pending = None
        self._metadata: Optional[Metadata] = None  # made when first asked for
        for name, (default, _, _) in self._FIELDS.items():
            v = default()
            object.__setattr__(self, _SLOT.get(name, name), _VALUE_FIELDS[name][0](v) if name in _VALUE_FIELDS else v)

    @property
    def metadata(self) -> Metadata:
        """The node's JSON metadata."""
        if self._pending is not None:
            self._complete()
        if self._metadata is None:
            self._metadata = Metadata()
        return self._metadata

    @property
    def position(self) -> np.ndarray:
        """The position (a float64 copy)."""
        return self._position.copy()

    @position.setter
    def position(self, value) -> None:
        self._position = _frozen(_f64x3(value))  # (as _VALUE_FIELDS stores it)
        if self._owner is not None:
            self._owner._moved(self)

    def __getattr__(self, name: str):
        # a field of a node loaded from a file, not read yet: fill every such field
        pending = object.__getattribute__(self, "_pending")
        if pending is not None and name in type(self)._FIELDS:
            self._pending = None
            pending(self)
            return object.__getattribute__(self, name)
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")

    def _fill(self, raw: Optional[Mapping[str, Any]]) -> None:
        """Sets every field not set yet from ``raw`` (a Spark-DSG JSON attributes object)."""
        raw = raw or {}
        for name, (default, decode, _) in self._FIELDS.items():
            slot = _SLOT.get(name, name)
            try:
                object.__getattribute__(self, slot)
                continue
            except AttributeError:
                pass
            v = raw.get(name)
            v = default() if v is None else decode(v)
            object.__setattr__(self, slot, _VALUE_FIELDS[name][0](v) if name in _VALUE_FIELDS else v)
        if raw.get("metadata") and (self._metadata is None or not self._metadata._data):
            self._metadata = Metadata(dict(raw["metadata"] or {}))

    def _complete(self) -> None:
        if self._pending is not None:
            pending, self._pending = self._pending, None
            pending(self)

    def _to_json(self) -> Dict[str, Any]:
        self._complete()
        out = {name: enc(getattr(self, name)) for name, (_, _, enc) in self._FIELDS.items()}
        out["metadata"] = copy.deepcopy(self._metadata._data) if self._metadata is not None else {}
        out["type"] = self._TYPE
        return out

    @classmethod
    def _from_json(cls, raw: Mapping[str, Any]) -> "NodeAttributes":
        attrs = cls.__new__(cls)
        attrs._owner = None
        attrs._pending = None
        attrs._metadata = None
        attrs._fill(raw)
        return attrs

    def __dir__(self) -> Iterable[str]:
        return sorted(set(self._FIELDS) | {"metadata"} | ({"NO_SEMANTIC_LABEL"} if "semantic_label" in self._FIELDS else set()))

    def __repr__(self) -> str:
        return f"{type(self).__name__}<position={self._position.tolist()}>"


class SemanticNodeAttributes(NodeAttributes):
    """Adds ``name``, ``color`` (uint8, 3), ``bounding_box``, ``semantic_label`` and
    ``semantic_feature``; setting ``name`` or ``semantic_label`` on a graph's node
    relabels it in the Yggdrasil scene."""

    NO_SEMANTIC_LABEL = NO_SEMANTIC_LABEL
    _FIELDS = _SEMANTIC_FIELDS
    _TYPE = "SemanticNodeAttributes"
    __slots__ = _slots(k for k in _SEMANTIC_FIELDS if k not in _BASE_FIELDS)

    @property
    def name(self) -> str:
        """The node's name."""
        return self._name

    @name.setter
    def name(self, value: str) -> None:
        self._name = str(value)
        if self._owner is not None:
            self._owner._relabelled(self)

    @property
    def semantic_label(self) -> int:
        """The semantic label (``NO_SEMANTIC_LABEL`` if none)."""
        return self._semantic_label

    @semantic_label.setter
    def semantic_label(self, value: int) -> None:
        value = int(value)
        if not 0 <= value <= NO_SEMANTIC_LABEL:
            raise ValueError(f"a semantic label is in [0, 2**32), not {value}")
        self._semantic_label = value
        if self._owner is not None:
            self._owner._relabelled(self)


class ObjectNodeAttributes(SemanticNodeAttributes):
    """Adds ``registered``, ``world_R_object`` and ``mesh_connections``."""

    _FIELDS = _OBJECT_FIELDS
    _TYPE = "ObjectNodeAttributes"
    __slots__ = _slots(("registered", "world_R_object", "mesh_connections"))


class PlaceNodeAttributes(SemanticNodeAttributes):
    """Adds ``distance``, ``num_basis_points``, the mesh connections and frontier fields."""

    _FIELDS = _PLACE_FIELDS
    _TYPE = "PlaceNodeAttributes"
    __slots__ = _slots(k for k in _PLACE_FIELDS if k not in _SEMANTIC_FIELDS)


class Place2dNodeAttributes(SemanticNodeAttributes):
    """Adds ``boundary``, the ellipse and the mesh connections."""

    _FIELDS = _PLACE2D_FIELDS
    _TYPE = "Place2dNodeAttributes"
    __slots__ = _slots(k for k in _PLACE2D_FIELDS if k not in _SEMANTIC_FIELDS)


class RoomNodeAttributes(SemanticNodeAttributes):
    """Adds ``semantic_class_probabilities``."""

    _FIELDS = _ROOM_FIELDS
    _TYPE = "RoomNodeAttributes"
    __slots__ = _slots(("semantic_class_probabilities",))


class AgentNodeAttributes(NodeAttributes):
    """Adds ``timestamp`` (a ``timedelta``), ``world_R_body``, ``external_key``,
    ``dbow_ids`` and ``dbow_values``."""

    _FIELDS = _AGENT_FIELDS
    _TYPE = "AgentNodeAttributes"
    __slots__ = _slots(k for k in _AGENT_FIELDS if k not in _BASE_FIELDS)


def _make_cloner(cls: type) -> None:
    """Gives ``cls`` a ``_clone`` that copies each field as its type needs, in straight-line
    code (a loop over the fields costs several times more per node added)."""
    body = [
        "def _clone(s):",
        "    if s._pending is not None:",
        "        s._complete()",
        "    o = _new(_cls)",
        "    o._owner = None",
        "    o._pending = None",
        "    m = s._metadata",
        "    o._metadata = _Metadata(_deepcopy(m._data)) if m is not None and m._data else None",
    ]
    for name, (default, _, _) in cls._FIELDS.items():
        slot = _SLOT.get(name, name)
        v = default()
        if name in _VALUE_FIELDS:
            body.append(f"    o.{slot} = s.{slot}")  # never changed in place: shared
        elif isinstance(v, (BoundingBox, Quaternion)):
            body.append(f"    o.{slot} = s.{slot}._copy()")
        else:
            body.append(f"    o.{slot} = s.{slot}")
    body.append("    return o")
    scope = {"_new": object.__new__, "_cls": cls, "_Metadata": Metadata, "_deepcopy": copy.deepcopy}
    exec("\n".join(body), scope)  # noqa: S102 - code built above from the class's own field names
    cls._clone = scope["_clone"]


ATTRIBUTE_TYPES = {
    cls._TYPE: cls
    for cls in (
        NodeAttributes,
        SemanticNodeAttributes,
        ObjectNodeAttributes,
        PlaceNodeAttributes,
        Place2dNodeAttributes,
        RoomNodeAttributes,
        AgentNodeAttributes,
    )
}
for _cls in ATTRIBUTE_TYPES.values():
    for _name in _cls._FIELDS:
        if _name in _VALUE_FIELDS and _name != "position" and not any(_name in vars(k) for k in _cls.__mro__):
            setattr(_cls, _name, _value_property(_name))
    _make_cloner(_cls)


class EdgeAttributes:
    """``spark_dsg.EdgeAttributes``: ``weight`` (1.0), ``weighted`` (False), ``metadata``."""

    __slots__ = ("weight", "weighted", "_metadata")

    def __init__(self, weight: float = 1.0, weighted: bool = False):
        self.weight = float(weight)
        self.weighted = bool(weighted)
        self._metadata: Optional[Metadata] = None  # made when first asked for

    @property
    def metadata(self) -> Metadata:
        """The edge's JSON metadata."""
        if self._metadata is None:
            self._metadata = Metadata()
        return self._metadata

    def _clone(self) -> "EdgeAttributes":
        other = EdgeAttributes(self.weight, self.weighted)
        if self._metadata is not None and self._metadata._data:
            other._metadata = Metadata(copy.deepcopy(self._metadata._data))
        return other

    def _to_json(self) -> Dict[str, Any]:
        data = copy.deepcopy(self._metadata._data) if self._metadata is not None else {}
        return {"metadata": data, "type": "EdgeAttributes", "weight": self.weight, "weighted": self.weighted}

    @classmethod
    def _from_json(cls, raw: Optional[Mapping[str, Any]]) -> "EdgeAttributes":
        raw = raw or {}
        out = cls(raw.get("weight", 1.0), raw.get("weighted", False))
        if raw.get("metadata"):
            out._metadata = Metadata(dict(raw["metadata"]))
        return out

    def __dir__(self) -> Iterable[str]:
        return ["metadata", "weight", "weighted"]

    def __repr__(self) -> str:
        return f"EdgeAttributes<weight={self.weight}, weighted={self.weighted}>"
