"""spark_dsg 1.1.3's graph classes over a Yggdrasil scene graph.

A ``DynamicSceneGraph`` keeps spark_dsg's structure (layers by key, nodes with their
attribute objects, parents, children, siblings, edges with their attributes) as Python
objects, and every write logs its edits of a ``yggdrasil.SceneGraph``; the log is
applied before that graph is read (``G.scene``, a snapshot on which every Yggdrasil
query answers, ``G.scene_graph``, ``save``). A graph loaded from a file starts from the
file's ``Scene``: on first use its nodes, their kept fields (position, name, semantic
label, box), nesting and layer edges are read from the scene, one pass per layer; the
attribute fields a scene does not keep (``color``, ``world_R_object``, ...) and the edge
weights are read from the file the first time one of them is asked for (Spark-DSG JSON,
parsed whole; from a binary file or a ``.ygg`` they take spark_dsg's defaults).
"""
from __future__ import annotations

import gc
import gzip
import json
import os
from typing import AbstractSet, Any, Dict, Iterator, List, Optional, Set, Tuple, Union

import numpy as np

from .. import _yggdrasil
from . import _binary
from ._mesh import Mesh
from ._types import (
    ATTRIBUTE_TYPES,
    NO_SEMANTIC_LABEL,
    AgentNodeAttributes,
    BoundingBox,
    EdgeAttributes,
    LayerKey,
    Labelspace,
    Metadata,
    NodeAttributes,
    NodeSymbol,
    ObjectNodeAttributes,
    Place2dNodeAttributes,
    PlaceNodeAttributes,
    RoomNodeAttributes,
    SemanticNodeAttributes,
    _partition,
    node_id,
)

_Key = Tuple[int, int]
_new = object.__new__
_OBJECTS: _Key = (2, 0)
_MESH: _Key = (1, 0)
_MESH_LAYER = "MESH"  # (ygg_dsg's name for layer 1, which holds the objects' geometry)
_GEOMETRY_PREFIX = 0xF5 << 56  # the geometry nodes of objects added here (ygg_dsg's layouts use 0xF0-0xF4)
_LOW56 = (1 << 56) - 1
_EMPTY: AbstractSet[int] = frozenset()


def _add(node: "SceneGraphNode", slot: str, value: int) -> None:
    """Adds ``value`` to one of a node's neighbour sets (made on first use)."""
    members = getattr(node, slot)
    if members is _EMPTY:
        members = set()
        setattr(node, slot, members)
    members.add(value)


def _discard(node: "SceneGraphNode", slot: str, value: int) -> None:
    """Removes ``value`` from one of a node's neighbour sets."""
    members = getattr(node, slot)
    if members is not _EMPTY:
        members.discard(value)
_DEFAULT_NAMES: Dict[str, _Key] = {"AGENTS": (2, 0), "BUILDINGS": (5, 0), "OBJECTS": (2, 0), "PLACES": (3, 0), "ROOMS": (4, 0)}
_CONVENTIONAL: Dict[_Key, str] = {(2, 0): "OBJECTS", (2, 97): "AGENTS", (3, 0): "PLACES", (3, 1): "MESH_PLACES", (4, 0): "ROOMS", (5, 0): "BUILDINGS"}
_STORE_KEYS = {name: key for key, name in _CONVENTIONAL.items()}
_ROOM_PREFIX = "room:"
_CLAIMED_OBJECTS = "/claimed-object"
_HEADER = {"project_name": "main", "version": {"major": 1, "minor": 1, "patch": 3}}


def _store_name(key: _Key) -> str:
    """The Yggdrasil layer name of a Spark-DSG layer key (as ``ygg_dsg`` names them)."""
    if key == _MESH:
        return _MESH_LAYER
    if key in _CONVENTIONAL:
        return _CONVENTIONAL[key]
    layer, p = key
    if layer == 2:
        c = chr(p) if p < 128 and chr(p).isalnum() else str(p)
        return f"AGENTS_{c}"
    return f"LAYER_{layer}_{p}"


def _key_of_store(name: str) -> Optional[_Key]:
    """The Spark-DSG layer key a Yggdrasil layer holds (``None`` for the layouts' own)."""
    if name in _STORE_KEYS:
        return _STORE_KEYS[name]
    if name.startswith(_ROOM_PREFIX) and name.endswith(_CLAIMED_OBJECTS):
        return (2, 0)
    if name.startswith("AGENTS_"):
        rest = name[7:]
        return (2, ord(rest) if len(rest) == 1 and not rest.isdigit() else int(rest))
    if name.startswith("LAYER_"):
        parts = name.split("_")
        if len(parts) == 3 and parts[1].isdigit() and parts[2].isdigit():
            return (int(parts[1]), int(parts[2]))
    return None


def _default_attributes(key: _Key) -> type:
    layer, partition = key
    if layer == 2:
        return ObjectNodeAttributes if partition == 0 else AgentNodeAttributes
    if layer == 3:
        return PlaceNodeAttributes if partition == 0 else Place2dNodeAttributes
    if layer == 4:
        return RoomNodeAttributes
    return SemanticNodeAttributes


class SceneGraphEdge:
    """An edge: ``source``, ``target`` (ids) and ``info`` (``EdgeAttributes``)."""

    __slots__ = ("source", "target", "_info", "_graph")

    def __init__(self, source: int, target: int, info: Optional[EdgeAttributes] = None, graph: Optional["DynamicSceneGraph"] = None):
        self.source = source
        self.target = target
        self._info = info
        self._graph = graph

    @property
    def info(self) -> EdgeAttributes:
        """The edge's attributes (weight, weighted, metadata)."""
        if self._info is None:
            # an edge read from a file asks the file; an inserted one has the defaults
            self._info = self._graph._edge_info(self.source, self.target) if self._graph is not None else EdgeAttributes()
        return self._info

    @info.setter
    def info(self, value: EdgeAttributes) -> None:
        self._info = value

    def __repr__(self) -> str:
        return f"Edge<source={NodeSymbol(self.source)}, target={NodeSymbol(self.target)}>"


class SceneGraphNode:
    """One node: ``id`` (``NodeSymbol``), ``layer`` (``LayerKey``), ``attributes``;
    ``get_parent()``, ``parents()``, ``children()``, ``siblings()``, ``connections()``."""

    __slots__ = ("id", "layer", "attributes", "_parents", "_children", "_siblings", "_graph", "_labels")

    def __init__(self, nid: int, layer: LayerKey, attributes: NodeAttributes, graph):
        self.id = symbol = _new(NodeSymbol)
        symbol.value = nid
        self.layer = layer
        self.attributes = attributes
        # empty until the first edge: a shared frozenset (see _add)
        self._parents: AbstractSet[int] = _EMPTY
        self._children: AbstractSet[int] = _EMPTY
        self._siblings: AbstractSet[int] = _EMPTY
        self._graph = graph
        # the labels given to Yggdrasil (None: those of the scene it was read from)
        self._labels: Optional[Tuple[str, ...]] = ()

    def get_parent(self) -> Optional[int]:
        """The parent's id when the node has exactly one parent, else ``None``."""
        p = self._parents
        if len(p) == 1:
            for x in p:
                return x
        return None

    def has_parent(self) -> bool:
        """Whether the node has a parent."""
        return bool(self._parents)

    def parents(self) -> Set[int]:
        """Every parent's id."""
        return set(self._parents)

    def children(self) -> Set[int]:
        """The children's ids."""
        return set(self._children)

    def has_children(self) -> bool:
        """Whether the node has children."""
        return bool(self._children)

    def siblings(self) -> Set[int]:
        """Ids of the nodes joined to this one in its layer (or another partition of it)."""
        return set(self._siblings)

    def has_siblings(self) -> bool:
        """Whether ``siblings()`` is not empty."""
        return bool(self._siblings)

    def connections(self) -> List[int]:
        """Every neighbour: siblings, parents and children."""
        return sorted(self._siblings | self._parents | self._children)

    # attribute setters tell the graph (Yggdrasil's copy follows)
    def _moved(self, attrs: NodeAttributes) -> None:
        if self._graph is not None:
            self._graph._mirror_position(self, attrs)

    def _relabelled(self, attrs: NodeAttributes) -> None:
        if self._graph is not None:
            self._graph._mirror_labels(self, attrs)

    def __repr__(self) -> str:
        return f"Node<id={self.id}, layer={self.layer}>"


class _Layer:
    __slots__ = ("key", "lkey", "nodes", "edges")

    def __init__(self, key: _Key):
        self.key = key
        self.lkey = LayerKey(*key)
        self.nodes: Dict[int, SceneGraphNode] = {}
        self.edges: Dict[_Key, SceneGraphEdge] = {}


def _edge_key(a: int, b: int) -> _Key:
    return (a, b) if a < b else (b, a)


class _LayerReads:
    """The read API a layer view and a stand-alone layer share."""

    _layer: _Layer

    @property
    def id(self) -> int:
        """The layer id."""
        return self._layer.key[0]

    @property
    def partition(self) -> int:
        """The partition."""
        return self._layer.key[1]

    @property
    def key(self) -> LayerKey:
        """The layer key."""
        return self._layer.lkey

    @property
    def nodes(self) -> Iterator[SceneGraphNode]:
        """The layer's nodes."""
        return iter(list(self._layer.nodes.values()))

    @property
    def edges(self) -> Iterator[SceneGraphEdge]:
        """The layer's edges."""
        return iter(list(self._layer.edges.values()))

    def num_nodes(self) -> int:
        """Number of nodes."""
        return len(self._layer.nodes)

    def num_edges(self) -> int:
        """Number of edges."""
        return len(self._layer.edges)

    def has_node(self, nid) -> bool:
        """Whether the layer holds the node."""
        return node_id(nid) in self._layer.nodes

    def find_node(self, nid) -> Optional[SceneGraphNode]:
        """The node, or ``None``."""
        return self._layer.nodes.get(node_id(nid))

    def get_node(self, nid) -> SceneGraphNode:
        """The node; raises ``IndexError`` naming it if the layer does not hold it."""
        n = self._layer.nodes.get(node_id(nid))
        if n is None:
            raise IndexError(f"layer {self._layer.lkey} has no node {NodeSymbol(node_id(nid))}")
        return n

    def has_edge(self, source, target) -> bool:
        """Whether the layer holds the edge."""
        return _edge_key(node_id(source), node_id(target)) in self._layer.edges

    def find_edge(self, source, target) -> Optional[SceneGraphEdge]:
        """The edge, or ``None``."""
        return self._layer.edges.get(_edge_key(node_id(source), node_id(target)))

    def get_edge(self, source, target) -> SceneGraphEdge:
        """The edge; raises ``IndexError`` if absent."""
        e = self.find_edge(source, target)
        if e is None:
            raise IndexError(f"layer {self._layer.lkey} has no edge {NodeSymbol(node_id(source))} -> {NodeSymbol(node_id(target))}")
        return e

    def get_position(self, nid) -> np.ndarray:
        """The node's position."""
        return self.get_node(nid).attributes.position

    def __repr__(self) -> str:
        return f"Layer<{self._layer.lkey}, nodes={len(self._layer.nodes)}>"


class LayerView(_LayerReads):
    """A layer of a ``DynamicSceneGraph`` (``G.get_layer(...)``, ``G.layers``)."""

    def __init__(self, layer: _Layer):
        self._layer = layer


class SceneGraphLayer(_LayerReads):
    """A stand-alone layer (``SceneGraphLayer(layer_id)`` or by ``DsgLayers`` name)."""

    def __init__(self, layer: Union[int, str], partition: Union[int, str] = 0):
        if isinstance(layer, str):
            if layer not in _DEFAULT_NAMES and layer not in _STORE_KEYS:
                raise ValueError(f"unknown layer name {layer!r}")
            key = _DEFAULT_NAMES.get(layer) or _STORE_KEYS[layer]
        else:
            key = (int(layer), _partition(partition))
        self._layer = _Layer(key)

    def add_node(self, nid, attrs: NodeAttributes) -> bool:
        """Adds a node (a copy of ``attrs``); ``False`` if the id is taken."""
        i = node_id(nid)
        if i in self._layer.nodes:
            return False
        self._layer.nodes[i] = SceneGraphNode(i, self._layer.lkey, attrs._clone(), None)
        return True

    def insert_edge(self, source, target, info: Optional[EdgeAttributes] = None) -> bool:
        """Joins two nodes of the layer; ``False`` if one is missing or the edge exists."""
        s, t = node_id(source), node_id(target)
        nodes = self._layer.nodes
        k = _edge_key(s, t)
        if s == t or s not in nodes or t not in nodes or k in self._layer.edges:
            return False
        self._layer.edges[k] = SceneGraphEdge(s, t, info._clone() if info is not None else EdgeAttributes())
        _add(nodes[s], "_siblings", t)
        _add(nodes[t], "_siblings", s)
        return True

    def remove_edge(self, source, target) -> bool:
        """Removes an edge; ``False`` if absent."""
        s, t = node_id(source), node_id(target)
        if self._layer.edges.pop(_edge_key(s, t), None) is None:
            return False
        _discard(self._layer.nodes[s], "_siblings", t)
        _discard(self._layer.nodes[t], "_siblings", s)
        return True

    def to_binary(self) -> bytes:
        """The layer as bytes (the facade's own encoding: UTF-8 Spark-DSG-style JSON)."""
        return json.dumps(
            {
                "layer": list(self._layer.key),
                "nodes": [{"id": i, "attributes": n.attributes._to_json()} for i, n in self._layer.nodes.items()],
                "edges": [{"source": e.source, "target": e.target, "info": e.info._to_json()} for e in self._layer.edges.values()],
            }
        ).encode()

    @staticmethod
    def from_binary(data: Union[bytes, bytearray, memoryview]) -> "SceneGraphLayer":
        """A layer from ``to_binary``'s bytes; raises ``ValueError`` if they are not that."""
        try:
            d = json.loads(bytes(data))
            out = SceneGraphLayer(*d["layer"])
            for n in d["nodes"]:
                cls = ATTRIBUTE_TYPES[n["attributes"]["type"]]
                out.add_node(n["id"], cls._from_json(n["attributes"]))
            for e in d["edges"]:
                out.insert_edge(e["source"], e["target"], EdgeAttributes._from_json(e["info"]))
        except (ValueError, KeyError, TypeError) as err:
            raise ValueError(f"not a layer written by SceneGraphLayer.to_binary: {err}") from err
        return out


class _FileExtras:
    """What a Yggdrasil scene does not keep, read from a Spark-DSG JSON file once: each
    node's attributes and each edge's info as JSON text (parsed when that node or edge
    asks), the metadata, and the mesh (parsed when asked for)."""

    def __init__(self, path: Optional[str]):
        self._nodes: Dict[int, Any] = {}
        self._edges: Dict[_Key, Any] = {}
        self.metadata: Dict[str, Any] = {}
        self._mesh: Any = None
        if path is None:
            return
        if path.endswith(".gz"):
            with gzip.open(path, "rt") as f:
                d = json.load(f)
            nodes = [(n["id"], n.get("attributes")) for n in d.get("nodes") or []]
            edges = [(e["source"], e["target"], e.get("info")) for e in d.get("edges") or []]
            metadata, self._mesh = d.get("metadata"), d.get("mesh")
        else:
            nodes, edges, metadata, self._mesh = _yggdrasil.spark_dsg_json_parts(path)
            metadata = json.loads(metadata) if metadata is not None else None
        self._nodes = dict(nodes)
        self._edges = {_edge_key(s, t): info for s, t, info in edges}
        self.metadata = dict(metadata or {})

    @staticmethod
    def _parsed(v: Any) -> Optional[Dict[str, Any]]:
        return json.loads(v) if isinstance(v, str) else v

    def node(self, nid: int) -> Optional[Dict[str, Any]]:
        """The node's attributes object, or ``None``."""
        return self._parsed(self._nodes.get(nid))

    def edge(self, key: _Key) -> Optional[Dict[str, Any]]:
        """The edge's info object, or ``None``."""
        return self._parsed(self._edges.get(key))

    def mesh_source(self) -> Any:
        """The mesh object as JSON text or parsed, or ``None``."""
        return self._mesh


class DynamicSceneGraph:
    """``spark_dsg.DynamicSceneGraph`` over a ``yggdrasil.SceneGraph`` (see the module)."""

    def __init__(self, empty: Any = False, layer_names: Optional[Dict[str, LayerKey]] = None):
        self._layers: Dict[_Key, _Layer] = {}
        self._names: Dict[str, _Key] = {}
        self._nodes: Dict[int, SceneGraphNode] = {}
        self._inter: Dict[_Key, SceneGraphEdge] = {}
        self._metadata = Metadata()
        self._labelspaces: Dict[_Key, Labelspace] = {}
        self._mesh: Optional[Mesh] = None
        self._extras: Optional[_FileExtras] = None
        self._extras_path: Optional[str] = None
        self._pending_file = False
        self._pending_mesh = False
        # the Yggdrasil side: a SceneGraph mirroring every write, its snapshot
        self._g: Optional[_yggdrasil.SceneGraph] = _yggdrasil.SceneGraph()
        self._scene: Optional[_yggdrasil.Scene] = None
        self._base: Optional[_yggdrasil.Scene] = None
        self._log: List[tuple] = []
        self._store_layers: Dict[_Key, str] = {}
        self._layer_edges: Set[Tuple[str, str]] = set()
        self._nested: Dict[int, int] = {}
        # a node's Yggdrasil layer when it is not its key's (a per-room layout's objects)
        self._node_store: Dict[int, str] = {}
        # objects added here: their geometry node, and those whose geometry changed
        self._geometry_nodes: Dict[int, int] = {}
        self._moved_objects: Set[int] = set()
        if not isinstance(empty, (bool, list, tuple)):
            raise TypeError(
                f"DynamicSceneGraph(empty: bool) or (layer_keys, layer_names), not {type(empty).__name__}"
                " (a yggdrasil.Scene: DynamicSceneGraph.from_scene)"
            )
        if isinstance(empty, (list, tuple)):
            for k in empty:
                self._layer((k.layer, k.partition))
            for name, k in (layer_names or {}).items():
                self._names[name] = (k.layer, k.partition)
        elif not empty:
            for name, key in _DEFAULT_NAMES.items():
                self._layer(key)
                self._names[name] = key

    # ------------------------------------------------------------ loading
    @staticmethod
    def load(path: Union[str, os.PathLike]) -> "DynamicSceneGraph":
        """Loads a Spark-DSG file (JSON, ``.json.gz`` or binary) or a ``.ygg`` snapshot;
        raises ``yggdrasil.FileError`` naming the file and what is wrong."""
        path = os.fspath(path)
        if isinstance(path, bytes):
            path = path.decode()
        if path.endswith(".ygg"):
            return DynamicSceneGraph.from_scene(_yggdrasil.open(path))
        graph = _yggdrasil.SceneGraph.import_spark_dsg(path, layout="vanilla")
        G = DynamicSceneGraph.from_scene(graph.snapshot())
        G._g = graph
        if path.endswith((".json", ".json.gz")):
            G._extras_path = path
        return G

    @staticmethod
    def from_scene(scene: "_yggdrasil.Scene") -> "DynamicSceneGraph":
        """The graph of a ``yggdrasil.Scene`` (a mapped ``.ygg``, a live reader's snapshot,
        ``SceneGraph.snapshot()``), read in place; the first write copies it into an
        editable graph (``scene.subgraph``), the scene itself never changes."""
        if not isinstance(scene, _yggdrasil.Scene):
            raise TypeError(f"from_scene takes a yggdrasil.Scene, not {type(scene).__name__}")
        G = DynamicSceneGraph(empty=True)
        G._g = None
        G._scene = G._base = scene
        G._pending_file = G._pending_mesh = True
        # nodes are built from the scene when first asked for (see __getattr__)
        del G._layers, G._nodes, G._inter, G._names
        return G

    def __getattr__(self, name: str):
        # a loaded graph builds its nodes, layers and edges on first use
        if name in ("_layers", "_nodes", "_inter", "_names") and self.__dict__.get("_base") is not None:
            self._read_scene(self.__dict__["_base"])
            return self.__dict__[name]
        raise AttributeError(f"'DynamicSceneGraph' object has no attribute {name!r}")

    def _read_scene(self, scene) -> None:
        """Builds every node of the Spark-DSG layers from ``scene``, one pass per layer
        (the collector paused: the objects built here all live as long as the graph)."""
        collecting = gc.isenabled()
        gc.disable()
        try:
            self._build_from(scene)
        finally:
            if collecting:
                gc.enable()

    def _build_from(self, scene) -> None:
        layers: Dict[_Key, _Layer] = {}
        nodes: Dict[int, SceneGraphNode] = {}
        inter: Dict[_Key, SceneGraphEdge] = {}
        self._layers, self._nodes, self._inter = layers, nodes, inter
        self._names = dict(_DEFAULT_NAMES)
        pending = self._fill_from_file
        parents: List[Tuple[int, Optional[int]]] = []
        edges: List[Tuple[int, int]] = []
        visible: Set[str] = set()
        new = object.__new__
        for store in scene.layers:
            key = _key_of_store(store)
            if key is None:
                continue
            visible.add(store)
            per_room = store.startswith(_ROOM_PREFIX)  # one of many Yggdrasil layers of the key
            layer = self._layer(key, None if per_room else store)
            if key in _CONVENTIONAL and key != (2, 97):
                self._names.setdefault(_CONVENTIONAL[key], key)
            cls = _default_attributes(key)
            semantic = issubclass(cls, SemanticNodeAttributes)
            lkey, members = layer.lkey, layer.nodes
            ids, positions, names, labels, boxes, parent_ids, layer_edges = scene.layer(store).spark_dsg_columns()
            positions.flags.writeable = False  # each node's position is a read-only row of it
            for nid, position, name, label, box in zip(ids, positions, names, labels, boxes):
                attrs = new(cls)
                attrs._metadata = None
                attrs._pending = pending
                attrs._position = position
                if semantic:
                    attrs._name = name
                    attrs._semantic_label = label
                    if box is not None:
                        attrs.bounding_box = BoundingBox.from_corners(box[:3], box[3:])
                node = new(SceneGraphNode)
                node.id = symbol = new(NodeSymbol)
                symbol.value = nid
                node.layer, node.attributes, node._graph, node._labels = lkey, attrs, self, None
                node._parents = node._children = node._siblings = _EMPTY
                attrs._owner = node
                members[nid] = node
                nodes[nid] = node
                if per_room:
                    self._node_store[nid] = store
            parents.extend(zip(ids, parent_ids))
            edges.extend(layer_edges)
        children: Dict[int, Set[int]] = {}
        for nid, parent in parents:
            while parent is not None and parent not in nodes and scene.has_node(parent) and scene.node(parent).layer not in visible:
                parent = scene.parent(parent)  # through a layout's own group nodes
            if parent is not None and parent in nodes:
                self._nested[nid] = parent
                nodes[nid]._parents = {parent}
                kids = children.get(parent)
                if kids is None:
                    kids = children[parent] = set()
                kids.add(nid)
                edge = new(SceneGraphEdge)
                edge.source, edge.target, edge._info, edge._graph = parent, nid, None, self
                inter[(nid, parent) if nid < parent else (parent, nid)] = edge
        for parent, kids in children.items():
            nodes[parent]._children = kids
        siblings: Dict[int, Set[int]] = {}
        for s, t in edges:
            a, b = nodes.get(s), nodes.get(t)
            if a is None or b is None:
                continue
            k = (s, t) if s < t else (t, s)
            found = layers[(a.layer.layer, a.layer.partition)].edges
            if k not in found:
                edge = new(SceneGraphEdge)
                edge.source, edge.target, edge._info, edge._graph = s, t, None, self
                found[k] = edge
                for x, y in ((s, t), (t, s)):
                    near = siblings.get(x)
                    if near is None:
                        near = siblings[x] = set()
                    near.add(y)
        for nid, near in siblings.items():
            nodes[nid]._siblings = near

    def _file(self) -> _FileExtras:
        if self._extras is None:
            self._extras = _FileExtras(self._extras_path)
        return self._extras

    def _fill_from_file(self, attrs: NodeAttributes) -> None:
        attrs._fill(self._file().node(attrs._owner.id.value))

    def _edge_info(self, source: int, target: int) -> EdgeAttributes:
        return EdgeAttributes._from_json(self._file().edge(_edge_key(source, target)))

    def _graph_extras(self) -> None:
        """Reads the graph's metadata and labelspaces from the file, once."""
        if not self._pending_file:
            return
        self._pending_file = False
        x = self._file()
        data = dict(x.metadata)
        for name, entries in (data.get("labelspaces") or {}).items():
            key = _labelspace_key(name)
            if key is not None:
                self._labelspaces[key] = Labelspace({int(i): str(n) for i, n in entries})
        self._metadata = Metadata(data)

    def _mesh_extras(self) -> None:
        """Reads the mesh from the file, once."""
        if not self._pending_mesh:
            return
        self._pending_mesh = False
        mesh = self._file().mesh_source()
        if isinstance(mesh, str):  # the text of a mesh object
            self._mesh = Mesh._from_arrays(_yggdrasil.spark_dsg_json_mesh(mesh))
        elif mesh is not None:  # a parsed mesh object (a .json.gz)
            self._mesh = Mesh._from_json(mesh)

    # ------------------------------------------------------------ the Yggdrasil side
    #
    # Every write appends its Yggdrasil edits to a log (a list append, so a write costs
    # what spark_dsg's does); the log is applied to the SceneGraph, in order, before
    # anything reads it: ``scene``, ``scene_graph``, ``save``.
    @property
    def scene(self) -> "_yggdrasil.Scene":
        """The graph as a ``yggdrasil.Scene`` (a snapshot taken after the last write),
        for Yggdrasil's queries: ``G.scene.objects.nearest(p)``, ``G.scene.nearest_nodes``, ..."""
        if self._log or self._moved_objects:
            self._flush()
        if self._scene is None:
            self._scene = self._g.snapshot()
        return self._scene

    @property
    def scene_graph(self) -> "_yggdrasil.SceneGraph":
        """The ``yggdrasil.SceneGraph`` the writes go to, brought up to date (ask again
        after more writes, e.g. before ``yggdrasil.Writer.publish()``)."""
        self._flush()
        return self._g

    def _edit(self, *op) -> None:
        if self._g is None:
            # a mapped .ygg: the first write copies it into an editable graph
            base = self._base
            self._g = base.subgraph([i for name in base.layers for i in base.layer(name).nodes])
        self._log.extend(op + (None,) * (4 - len(op)))
        self._scene = None

    def _flush(self) -> None:
        if self._g is None:
            self._edit("noop")
        g, log = self._g, self._log
        self._log = []
        for at in range(0, len(log), 4):
            kind, a, b, c = log[at : at + 4]
            if kind == "layer":
                if a not in g.layers:
                    g.add_layer(a)
            elif kind == "layer_edge":
                try:
                    g.add_layer_edge(a, b)
                except _yggdrasil.MutationError:
                    if (a, b) not in _layer_edges(g):
                        raise
            elif kind == "unlink":
                g.remove_edge(a, b)
                try:  # a file's undirected edge may be stored both ways
                    g.remove_edge(b, a)
                except _yggdrasil.MutationError:
                    pass
            elif kind == "set_geometry":
                g.set_geometry(a, (b,))
            elif kind == "set_feature":
                g.set_feature(a, b, c)
            elif kind != "noop":
                getattr(g, kind)(*(x for x in (a, b) if x is not None))
        moved, self._moved_objects = self._moved_objects, set()
        for nid in moved:
            if nid in self._geometry_nodes:
                g.set_geometry(self._geometry_nodes[nid], self._object_points(nid))

    def _store_layer(self, key: _Key) -> str:
        name = self._store_layers.get(key)
        if name is None:
            name = self._store_layers[key] = _store_name(key)
            self._edit("layer", name)
        return name

    def _store_of(self, node: SceneGraphNode) -> str:
        """The Yggdrasil layer holding ``node``."""
        nid = node.id.value
        if nid in self._node_store:
            return self._node_store[nid]
        return self._store_layer((node.layer.layer, node.layer.partition))

    def _mirror_add(self, node: SceneGraphNode, key: _Key) -> None:
        # the hottest write: its edits appended inline (as _edit and _mirror_labels would)
        if self._g is None:
            self._edit("noop")
        nid = node.id.value
        attrs = node.attributes
        layer = self._store_layers.get(key) or self._store_layer(key)
        log = self._log
        log.extend(("add_node", nid, layer, None))
        self._scene = None
        if key == _OBJECTS:
            self._add_object_geometry(node, layer)
        else:
            log.extend(("set_geometry", nid, attrs._position, None))
        if isinstance(attrs, SemanticNodeAttributes):
            name, label = attrs._name, attrs._semantic_label
            if name and not (name[-1] == ")" and name == node.id.str()):
                node._labels = (name,)
                log.extend(("add_label", nid, name, None))
            if name:
                log.extend(("set_feature", nid, "name", name))
            if label != NO_SEMANTIC_LABEL:
                node._labels += (str(label),)
                log.extend(("add_label", nid, str(label), None))
                log.extend(("set_feature", nid, "semantic_label", label))

    def _mirror_position(self, node: SceneGraphNode, attrs: NodeAttributes) -> None:
        if node.layer.layer == 2 and node.layer.partition == 0:
            # (an object loaded from a file keeps the geometry node it was loaded with)
            self._object_moved(node.id.value, attrs)
        else:
            self._edit("set_geometry", node.id.value, attrs._position)

    # Objects as Yggdrasil's object queries see them (as ygg_dsg's vanilla layout builds
    # them): the position in features, the geometry in a nested MESH node holding the
    # mesh vertices the object claims (``mesh_connections`` into ``G.mesh``), or its
    # position when it claims none. The geometry is worked out when the log is applied.
    def _add_object_geometry(self, node: SceneGraphNode, layer: str) -> None:
        nid = node.id.value
        mid = _GEOMETRY_PREFIX | (nid & _LOW56)
        taken = set(self._geometry_nodes.values())
        while mid in taken or (self._base is not None and self._base.has_node(mid)):
            mid = _GEOMETRY_PREFIX | ((mid + 1) & _LOW56)
        self._geometry_nodes[nid] = mid
        self._store_layer(_MESH)
        if (layer, _MESH_LAYER) not in self._layer_edges:
            self._edit("layer_edge", layer, _MESH_LAYER)
            self._layer_edges.add((layer, _MESH_LAYER))
        self._edit("add_node", mid, _MESH_LAYER)
        self._edit("nest", nid, mid)
        self._object_moved(nid, node.attributes)

    def _object_moved(self, nid: int, attrs: NodeAttributes) -> None:
        x, y, z = attrs._position.tolist()
        self._edit("set_feature", nid, "position_x", x)
        self._edit("set_feature", nid, "position_y", y)
        self._edit("set_feature", nid, "position_z", z)
        if nid in self._geometry_nodes:
            self._moved_objects.add(nid)

    def _object_points(self, nid: int) -> np.ndarray:
        attrs = self._nodes[nid].attributes
        claimed = attrs._mesh_connections
        mesh = self.mesh if claimed else None  # (a loaded file's mesh is read on first use)
        if mesh is not None:
            index = np.unique(np.asarray(claimed, dtype=np.int64))
            index = index[(index >= 0) & (index < mesh.num_vertices())]
            if len(index):
                return mesh._points[index]
        return attrs._position.reshape(1, 3)

    def _mirror_labels(self, node: SceneGraphNode, attrs: SemanticNodeAttributes) -> None:
        nid = node.id.value
        name, label = attrs._name, attrs._semantic_label
        labels: Tuple[str, ...] = ()
        if name and name != node.id.str():  # Hydra names nodes after their symbol: no label
            labels = (name,)
        if label != NO_SEMANTIC_LABEL:
            labels += (str(label),)
        current = node._labels
        if current is None:  # a node read from a scene: the labels the scene gave it
            base = self._base
            current = tuple(base.node(nid).labels) if base is not None and base.has_node(nid) else ()
        for old in current:
            if old not in labels:
                self._edit("remove_label", nid, old)
        for new in labels:
            if new not in current:
                self._edit("add_label", nid, new)
        node._labels = labels
        if name:
            self._edit("set_feature", nid, "name", name)
        if label != NO_SEMANTIC_LABEL:
            self._edit("set_feature", nid, "semantic_label", label)

    def _mirror_nest(self, parent: SceneGraphNode, child: SceneGraphNode) -> None:
        cid = child.id.value
        if cid in self._nested:
            return  # Yggdrasil nests a node under one parent; spark_dsg's others stay here
        pl, cl = self._store_of(parent), self._store_of(child)
        if (pl, cl) not in self._layer_edges:
            self._edit("layer_edge", pl, cl)
            self._layer_edges.add((pl, cl))
        self._edit("nest", parent.id.value, cid)
        self._nested[cid] = parent.id.value

    # ------------------------------------------------------------ layers
    def _layer(self, key: _Key, store: Optional[str] = None) -> _Layer:
        layer = self._layers.get(key)
        if layer is None:
            layer = self._layers[key] = _Layer(key)
            if store is not None:
                self._store_layers[key] = store
        return layer

    def _key(self, layer, partition=0) -> Optional[_Key]:
        if isinstance(layer, str):
            if partition:
                raise TypeError("a layer given by name takes no partition")
            return self._names.get(layer)
        if isinstance(layer, LayerKey):
            return (layer.layer, layer.partition)
        return (int(layer), _partition(partition))

    def add_layer(self, layer: int, partition: Union[int, str] = 0, name: str = "") -> LayerView:
        """Adds a layer (and names it, unless the name is taken); returns its view."""
        key = (int(layer), _partition(partition))
        view = LayerView(self._layer(key))
        if name:
            self._names.setdefault(name, key)
        return view

    def remove_layer(self, layer: int, partition: Union[int, str] = 0) -> None:
        """Removes a layer with its nodes."""
        key = (int(layer), _partition(partition))
        if key not in self._layers:
            return
        for nid in list(self._layers[key].nodes):
            self.remove_node(nid)
        del self._layers[key]
        self._names = {n: k for n, k in self._names.items() if k != key}

    def has_layer(self, layer, partition: Union[int, str] = 0) -> bool:
        """Whether the layer (by id and partition, or by name) exists."""
        return self._key(layer, partition) in self._layers

    def get_layer(self, layer, partition: Union[int, str] = 0) -> LayerView:
        """The layer by id and partition, or by name; raises ``IndexError`` naming it."""
        key = self._key(layer, partition)
        if key not in self._layers:
            what = repr(layer) if isinstance(layer, str) else str(LayerKey(*key))
            raise IndexError(f"missing layer {what}")
        return LayerView(self._layers[key])

    def get_layer_key(self, name: str) -> Optional[LayerKey]:
        """The key of the layer called ``name``, or ``None``."""
        key = self._names.get(name)
        return LayerKey(*key) if key is not None else None

    @property
    def layers(self) -> Iterator[LayerView]:
        """The layers (partition 0), by layer id."""
        return iter([LayerView(self._layers[k]) for k in sorted(self._layers) if k[1] == 0])

    @property
    def layer_partitions(self) -> Iterator[LayerView]:
        """The partitions (partition != 0), by key."""
        return iter([LayerView(self._layers[k]) for k in sorted(self._layers) if k[1] != 0])

    @property
    def layer_keys(self) -> List[LayerKey]:
        """Every layer key, sorted."""
        return [LayerKey(*k) for k in sorted(self._layers)]

    @property
    def layer_ids(self) -> List[int]:
        """The layer ids of the partition-0 layers."""
        return [k[0] for k in sorted(self._layers) if k[1] == 0]

    @property
    def layer_names(self) -> Dict[str, LayerKey]:
        """Layer name -> key."""
        return {n: LayerKey(*k) for n, k in sorted(self._names.items())}

    def num_layers(self) -> int:
        """Number of partition-0 layers."""
        return sum(1 for k in self._layers if k[1] == 0)

    # ------------------------------------------------------------ nodes
    def add_node(self, layer, nid, attrs: NodeAttributes, partition: Union[int, str] = 0) -> bool:
        """Adds a node (a copy of ``attrs``) to a layer (name, ``LayerKey`` or id with
        partition); ``False`` if the id is taken or the layer name is unknown."""
        key = self._key(layer, partition)
        if key is None:
            return False
        i = node_id(nid)
        if i in self._nodes:
            return False
        if not isinstance(attrs, NodeAttributes):
            raise TypeError(f"node attributes are a NodeAttributes, not {type(attrs).__name__}")
        target = self._layers.get(key) or self._layer(key)
        attrs = attrs._clone()
        node = SceneGraphNode(i, target.lkey, attrs, self)
        attrs._owner = node
        self._mirror_add(node, key)
        target.nodes[i] = node
        self._nodes[i] = node
        return True

    def has_node(self, nid) -> bool:
        """Whether the node exists."""
        return node_id(nid) in self._nodes

    def find_node(self, nid) -> Optional[SceneGraphNode]:
        """The node, or ``None``."""
        return self._nodes.get(node_id(nid))

    def get_node(self, nid) -> SceneGraphNode:
        """The node; raises ``IndexError`` naming it if absent."""
        try:
            return self._nodes[nid if type(nid) is int else node_id(nid)]
        except KeyError:
            raise IndexError(f"missing node {NodeSymbol(node_id(nid))}") from None

    def get_position(self, nid) -> np.ndarray:
        """The node's position."""
        return self.get_node(nid).attributes.position

    def remove_node(self, nid) -> bool:
        """Removes a node with its edges; ``False`` if absent."""
        i = node_id(nid)
        node = self._nodes.get(i)
        if node is None:
            return False
        for other in list(node._siblings | node._parents | node._children):
            self._drop_edge(i, other)
        del self._layers[(node.layer.layer, node.layer.partition)].nodes[i]
        del self._nodes[i]
        self._edit("remove_node", i)
        if i in self._geometry_nodes:
            self._edit("remove_node", self._geometry_nodes.pop(i))
            self._moved_objects.discard(i)
        self._nested.pop(i, None)
        node._graph = None
        node.attributes._owner = None
        return True

    @property
    def nodes(self) -> Iterator[SceneGraphNode]:
        """Every node (partitions included), layer by layer."""
        return iter([n for k in sorted(self._layers) for n in self._layers[k].nodes.values()])

    @property
    def unpartitioned_nodes(self) -> Iterator[SceneGraphNode]:
        """The nodes of the partition-0 layers."""
        return iter([n for k in sorted(self._layers) if k[1] == 0 for n in self._layers[k].nodes.values()])

    def num_nodes(self, include_partitions: bool = True) -> int:
        """Number of nodes."""
        return sum(len(L.nodes) for k, L in self._layers.items() if include_partitions or k[1] == 0)

    # ------------------------------------------------------------ edges
    def insert_edge(self, source, target, info: Optional[EdgeAttributes] = None, enforce_single_parent: bool = False) -> bool:
        """Joins two nodes: in one layer an edge between siblings, across layer ids the
        higher one becomes a parent (with ``enforce_single_parent``, the child's only
        one); ``False`` if a node is missing, the edge exists or ``source == target``."""
        if isinstance(info, bool):
            info, enforce_single_parent = None, info
        s, t = node_id(source), node_id(target)
        a, b = self._nodes.get(s), self._nodes.get(t)
        if a is None or b is None or s == t:
            return False
        k = (s, t) if s < t else (t, s)
        info = info._clone() if info is not None else None  # None: the defaults, made when asked for
        la, lb = a.layer, b.layer
        if la.layer == lb.layer and la.partition == lb.partition:
            layer = self._layers[(la.layer, la.partition)]
            if k in layer.edges:
                return False
            layer.edges[k] = SceneGraphEdge(s, t, info)
            _add(a, "_siblings", t)
            _add(b, "_siblings", s)
            if not self._node_store or self._store_of(a) == self._store_of(b):
                self._edit("add_edge", s, t)  # (two rooms' objects in a per-room layout: not mirrored)
            return True
        if k in self._inter:
            return False
        if la.layer == lb.layer:
            if enforce_single_parent:  # as spark_dsg: neither is the parent, the source is the child
                for old in list(a._parents):
                    self._drop_edge(s, old)
            _add(a, "_siblings", t)
            _add(b, "_siblings", s)
        else:
            parent, child = (a, b) if la.layer > lb.layer else (b, a)
            if enforce_single_parent:
                for old in list(child._parents):
                    self._drop_edge(child.id.value, old)
            _add(parent, "_children", child.id.value)
            _add(child, "_parents", parent.id.value)
            self._mirror_nest(parent, child)
        self._inter[k] = SceneGraphEdge(s, t, info)
        return True

    def _drop_edge(self, s: int, t: int) -> bool:
        k = (s, t) if s < t else (t, s)
        a, b = self._nodes[s], self._nodes[t]
        la, lb = a.layer, b.layer
        if la.layer == lb.layer and la.partition == lb.partition:
            edge = self._layers[(la.layer, la.partition)].edges.pop(k, None)
            if edge is None:
                return False
            _discard(a, "_siblings", t)
            _discard(b, "_siblings", s)
            if not self._node_store or self._store_of(a) == self._store_of(b):
                self._edit("unlink", edge.source, edge.target)
            return True
        if self._inter.pop(k, None) is None:
            return False
        if la.layer == lb.layer:
            _discard(a, "_siblings", t)
            _discard(b, "_siblings", s)
            return True
        parent, child = (a, b) if la.layer > lb.layer else (b, a)
        _discard(parent, "_children", child.id.value)
        _discard(child, "_parents", parent.id.value)
        cid = child.id.value
        if self._nested.get(cid) == parent.id.value:
            self._edit("unnest", cid)
            del self._nested[cid]
            for other in sorted(child._parents):
                self._mirror_nest(self._nodes[other], child)
                break
        return True

    def remove_edge(self, source, target) -> bool:
        """Removes an edge; ``False`` if absent."""
        s, t = node_id(source), node_id(target)
        if s not in self._nodes or t not in self._nodes:
            return False
        return self._drop_edge(s, t)

    def has_edge(self, source, target) -> bool:
        """Whether the edge exists."""
        return self.find_edge(source, target) is not None

    def find_edge(self, source, target) -> Optional[SceneGraphEdge]:
        """The edge, or ``None``."""
        s, t = node_id(source), node_id(target)
        a = self._nodes.get(s)
        if a is None or t not in self._nodes:
            return None
        k = _edge_key(s, t)
        key = (a.layer.layer, a.layer.partition)
        return self._layers[key].edges.get(k) or self._inter.get(k)

    def get_edge(self, source, target) -> SceneGraphEdge:
        """The edge; raises ``IndexError`` if absent."""
        e = self.find_edge(source, target)
        if e is None:
            raise IndexError(f"missing edge {NodeSymbol(node_id(source))} -> {NodeSymbol(node_id(target))}")
        return e

    @property
    def edges(self) -> Iterator[SceneGraphEdge]:
        """Every edge: each layer's, then the edges between layers."""
        out = [e for k in sorted(self._layers) for e in self._layers[k].edges.values()]
        out.extend(self._inter.values())
        return iter(out)

    @property
    def interlayer_edges(self) -> Iterator[SceneGraphEdge]:
        """The edges between layers (or partitions)."""
        return iter(list(self._inter.values()))

    def _in_partition(self, nid: int) -> bool:
        return self._nodes[nid].layer.partition != 0

    def num_edges(self, include_partitions: bool = True) -> int:
        """Number of edges."""
        n = sum(len(L.edges) for k, L in self._layers.items() if include_partitions or k[1] == 0)
        if include_partitions:
            return n + len(self._inter)
        return n + sum(1 for s, t in self._inter if not self._in_partition(s) and not self._in_partition(t))

    # ------------------------------------------------------------ metadata, labelspaces, mesh
    @property
    def metadata(self) -> Metadata:
        """The graph's JSON metadata."""
        self._graph_extras()
        return self._metadata

    def set_labelspace(self, labelspace: Labelspace, layer, partition: int = 0) -> None:
        """Sets the labelspace of a layer (id and partition, or name)."""
        self._graph_extras()
        key = self._key(layer, partition)
        if key is None:
            raise IndexError(f"missing layer {layer!r}")
        self._labelspaces[key] = Labelspace(labelspace.labels_to_names)

    def get_labelspace(self, layer, partition: int = 0) -> Labelspace:
        """The labelspace of a layer (empty if none was set)."""
        self._graph_extras()
        key = self._key(layer, partition)
        return Labelspace(self._labelspaces[key].labels_to_names) if key in self._labelspaces else Labelspace()

    def has_mesh(self) -> bool:
        """Whether the graph has a mesh."""
        self._mesh_extras()
        return self._mesh is not None

    @property
    def mesh(self) -> Optional[Mesh]:
        """The scene mesh (``None`` if there is none)."""
        self._mesh_extras()
        return self._mesh

    @mesh.setter
    def mesh(self, mesh: Optional[Mesh]) -> None:
        self._pending_mesh = False
        self._mesh = mesh
        self._moved_objects.update(self._geometry_nodes)  # their claimed vertices moved
        self._scene = None

    def set_mesh(self, mesh: Optional[Mesh]) -> None:
        """Sets the scene mesh."""
        self.mesh = mesh

    # ------------------------------------------------------------ saving
    def save(self, path: Union[str, os.PathLike], include_mesh: bool = True) -> None:
        """Writes the graph: ``.ygg`` (Yggdrasil's snapshot of it), Spark-DSG JSON
        (``.json``), or, for any other extension (as spark_dsg decides), spark_dsg
        1.1.3's binary encoding; spark_dsg 1.1.3 loads both Spark-DSG files."""
        path = os.fspath(path)
        if path.endswith(".ygg"):
            self.scene_graph.save(path)
        elif path.endswith(".json"):
            with open(path, "w") as f:
                json.dump(self._to_json(include_mesh), f)
        else:
            data = _binary.graph_bytes(self, include_mesh, header=True)
            with open(path, "wb") as f:
                f.write(data)

    def _file_metadata(self) -> Dict[str, Any]:
        """The metadata a file gets: the graph's, with the labelspaces under ``labelspaces``."""
        self._graph_extras()
        metadata = json.loads(json.dumps(self._metadata._data))
        if self._labelspaces:
            spaces = metadata.setdefault("labelspaces", {})
            for key, space in self._labelspaces.items():
                spaces[_labelspace_name(key)] = [[k, v] for k, v in sorted(space.labels_to_names.items())]
        return metadata

    def to_binary(self, include_mesh: bool = False) -> bytes:
        """The graph in spark_dsg 1.1.3's binary encoding, without the file header (what
        spark_dsg's ``to_binary`` gives)."""
        return _binary.graph_bytes(self, include_mesh, header=False)

    def _to_json(self, include_mesh: bool) -> Dict[str, Any]:
        metadata = self._file_metadata()
        nodes = [
            {"attributes": n.attributes._to_json(), "id": i, "layer": k[0], "partition": k[1]}
            for k in sorted(self._layers)
            for i, n in self._layers[k].nodes.items()
        ]
        edges = [{"info": e.info._to_json(), "source": e.source, "target": e.target} for e in self.edges]
        out = {
            "SPARK_DSG_header": _HEADER,
            "directed": False,
            "edges": edges,
            "layer_keys": [{"layer": k[0], "partition": k[1]} for k in sorted(self._layers)],
            "layer_names": {n: {"layer": k[0], "partition": k[1]} for n, k in sorted(self._names.items())},
            "metadata": metadata,
            "multigraph": False,
            "nodes": nodes,
        }
        mesh = self.mesh if include_mesh else None
        if mesh is not None:
            out["mesh"] = mesh._to_json()
        return out

    def clone(self) -> "DynamicSceneGraph":
        """A deep copy (a new Yggdrasil graph too)."""
        G = DynamicSceneGraph(empty=True)
        for k in self._layers:
            G._layer(k)
        G._names = dict(self._names)
        for k in sorted(self._layers):
            for i, n in self._layers[k].nodes.items():
                G.add_node(LayerKey(*k), i, n.attributes)
        for e in self.edges:
            G.insert_edge(e.source, e.target, e.info)
        G._metadata = Metadata(json.loads(json.dumps(self.metadata._data)))
        G._labelspaces = {k: Labelspace(v.labels_to_names) for k, v in self._labelspaces.items()}
        G._mesh = self.mesh.clone() if self.mesh is not None else None
        return G

    def __repr__(self) -> str:
        return f"DynamicSceneGraph<nodes={self.num_nodes()}, edges={self.num_edges()}, layers={self.layer_keys}>"


def _layer_edges(g) -> Set[Tuple[str, str]]:
    """The layer DAG edges of a SceneGraph, by name."""
    scene = g.snapshot()
    return {(name, child) for name in scene.layers for child in scene.layer(name).children}


def _labelspace_name(key: _Key) -> str:
    return f"_l{key[0]}p{key[1]}"


def _labelspace_key(name: str) -> Optional[_Key]:
    if name.startswith("_l") and "p" in name:
        layer, _, partition = name[2:].partition("p")
        if layer.isdigit() and partition.isdigit():
            return (int(layer), int(partition))
    return None


def load(path: Union[str, os.PathLike]) -> DynamicSceneGraph:
    """``DynamicSceneGraph.load(path)``."""
    return DynamicSceneGraph.load(path)


def compute_ancestor_bounding_box(G: DynamicSceneGraph, nid, depth: int = 1, bbox_type=None) -> BoundingBox:
    """The axis-aligned box of the positions of the node's descendants ``depth`` layers
    down (invalid if there are none)."""
    frontier = {node_id(nid)}
    for _ in range(depth):
        frontier = {c for n in frontier for c in G._nodes[n]._children}
    if not frontier:
        return BoundingBox()
    pts = np.array([G._nodes[n].attributes._position for n in frontier])
    return BoundingBox.from_corners(pts.min(axis=0), pts.max(axis=0))


def add_bounding_boxes_to_layer(G: DynamicSceneGraph, layer_id, child_layer: str = "PLACES", bbox_type=None) -> None:
    """Sets every node's ``bounding_box`` of a layer from its descendants in ``child_layer``."""
    depth = G.get_layer_key(layer_id).layer - G.get_layer_key(child_layer).layer if isinstance(layer_id, str) else int(layer_id) - G.get_layer_key(child_layer).layer
    if depth <= 0:
        raise ValueError(f"layer {layer_id!r} is not above {child_layer!r}")
    for node in G.get_layer(layer_id).nodes:
        node.attributes.bounding_box = compute_ancestor_bounding_box(G, node.id.value, depth=depth)
