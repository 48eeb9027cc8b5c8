"""A spark_dsg-style read facade over Yggdrasil scenes.

Code that reads scene graphs with spark_dsg 1.1.3 ports by changing its import::

    import yggdrasil.dsg as dsg              # was: import spark_dsg as dsg
    G = dsg.load("office.json")              # Spark-DSG JSON or binary, or a .ygg file
    objects = G.get_layer(dsg.DsgLayers.OBJECTS)
    for node in objects.nodes:
        print(node.id.value, node.attributes.name, node.attributes.position)

Every call reads the underlying ``yggdrasil.Scene`` (``G.scene``) in place; for fast
spatial and label queries use ``G.scene`` directly (``G.scene.objects.nearest(p)``).

What is covered: ``load``, ``DynamicSceneGraph`` (``get_layer`` by ``DsgLayers`` name or
layer id, ``has_layer``, ``layers``, ``layer_names``, ``nodes``, ``edges``,
``get_node``, ``has_node``, ``find_node``, ``num_nodes``, ``num_edges``,
``get_position``), ``SceneGraphLayer`` (``id``, ``name``, ``nodes``, ``edges``,
``num_nodes``, ``num_edges``, ``get_node``, ``has_node``, ``find_node``),
``SceneGraphNode`` (``id`` as ``NodeSymbol`` with ``value``, ``category``,
``category_id``, ``str()``; ``layer`` with ``layer`` and ``partition``; ``attributes``
with ``position``, ``bounding_box`` (``min``, ``max``, ``dimensions``,
``world_P_center``, ``volume()``), ``semantic_label``, ``name``; ``get_parent()``,
``has_parent()``, ``children()``, ``has_children()``), ``SceneGraphEdge`` (``source``,
``target``) and ``graph_to_networkx``.

What is not: writing (``add_node``, ``insert_edge``, ``save``, ...: use
``yggdrasil.SceneGraph``), the mesh object (``G.mesh``: an object's vertices are
``G.scene.node(mesh_id).points``), labelspaces, metadata, partitions other than the
agents', dynamic layers' agent-specific attributes, edge weights (``edge.info`` is
absent), ``siblings``, ``to_torch``, ``transform`` and ``from_binary``.

On the per-room layouts (chocolate, mint, saffron), an object's parent is its room
(Spark-DSG's object -> place nesting is not kept by those layouts); on vanilla and on a
Spark-DSG file loaded here, parents are Spark-DSG's.
"""
from __future__ import annotations

import os
from typing import Dict, Iterator, List, Optional, Set, Union

import numpy as np

from . import _yggdrasil

__all__ = [
    "BoundingBox",
    "DsgLayers",
    "DynamicSceneGraph",
    "LayerKey",
    "NodeAttributes",
    "NodeSymbol",
    "SceneGraphEdge",
    "SceneGraphLayer",
    "SceneGraphNode",
    "graph_to_networkx",
    "load",
]


class DsgLayers:
    """Spark-DSG's layer names (as ``spark_dsg.DsgLayers``)."""

    OBJECTS = "OBJECTS"
    AGENTS = "AGENTS"
    PLACES = "PLACES"
    MESH_PLACES = "MESH_PLACES"
    ROOMS = "ROOMS"
    BUILDINGS = "BUILDINGS"


# Spark-DSG layer keys (layer id, partition) of the conventional layer names.
_LAYER_KEYS = {
    DsgLayers.OBJECTS: (2, 0),
    DsgLayers.AGENTS: (2, 97),  # partition "a", as Hydra writes agents
    DsgLayers.PLACES: (3, 0),
    DsgLayers.MESH_PLACES: (3, 1),
    DsgLayers.ROOMS: (4, 0),
    DsgLayers.BUILDINGS: (5, 0),
}
_NAME_OF_ID = {key[0]: name for name, key in _LAYER_KEYS.items() if key[1] == 0}
_ROOM_PREFIX = "room:"
_CLAIMED_OBJECT_SUFFIX = "/claimed-object"
_BOX_KEYS = ("bbox_min_x", "bbox_min_y", "bbox_min_z", "bbox_max_x", "bbox_max_y", "bbox_max_z")


def _spark_dsg_name(store_layer: str) -> Optional[str]:
    """The Spark-DSG layer a store layer belongs to (``None`` for the layouts' own layers)."""
    if store_layer in _LAYER_KEYS:
        return store_layer
    if store_layer.startswith(_ROOM_PREFIX) and store_layer.endswith(_CLAIMED_OBJECT_SUFFIX):
        return DsgLayers.OBJECTS
    return None


def load(path: Union[str, os.PathLike]) -> "DynamicSceneGraph":
    """Loads a scene graph: a ``.ygg`` snapshot (mapped, any layout) or a Spark-DSG file
    (JSON, ``.json.gz`` or binary; imported in the vanilla layout, Spark-DSG's own
    structure). Raises ``yggdrasil.FileError`` naming the file and what is wrong."""
    path = os.fspath(path)
    if path.endswith(".ygg"):
        return DynamicSceneGraph(_yggdrasil.open(path))
    graph = _yggdrasil.SceneGraph.import_spark_dsg(path, layout="vanilla")
    return DynamicSceneGraph(graph.snapshot())


class NodeSymbol:
    """A Spark-DSG node id: ``value`` (the u64), ``category`` (its prefix character) and
    ``category_id`` (the index below the prefix)."""

    __slots__ = ("value",)

    def __init__(self, value: int):
        self.value = int(value)

    @property
    def category(self) -> str:
        """The prefix character (the top byte)."""
        return chr(self.value >> 56)

    @property
    def category_id(self) -> int:
        """The index below the prefix (the low 56 bits)."""
        return self.value & ((1 << 56) - 1)

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
        return self.value == other

    def __hash__(self) -> int:
        return hash(self.value)

    def __int__(self) -> int:
        return self.value


class LayerKey:
    """A Spark-DSG layer key: ``layer`` (the layer id) and ``partition``."""

    __slots__ = ("layer", "partition")

    def __init__(self, layer: int, partition: int = 0):
        self.layer = layer
        self.partition = partition

    def __eq__(self, other) -> bool:
        return isinstance(other, LayerKey) and (self.layer, self.partition) == (other.layer, other.partition)

    def __hash__(self) -> int:
        return hash((self.layer, self.partition))

    def __repr__(self) -> str:
        return f"{self.layer}" if self.partition == 0 else f"{self.layer}[{self.partition}]"


class BoundingBox:
    """A stored Spark-DSG bounding box: ``min``, ``max``, ``dimensions`` and
    ``world_P_center`` as float32 numpy arrays."""

    __slots__ = ("min", "max")

    def __init__(self, lo, hi):
        self.min = np.asarray(lo, dtype=np.float32)
        self.max = np.asarray(hi, dtype=np.float32)

    @property
    def dimensions(self) -> np.ndarray:
        """``max - min``."""
        return self.max - self.min

    @property
    def world_P_center(self) -> np.ndarray:
        """The centre."""
        return (self.min + self.max) / 2

    def volume(self) -> float:
        """The product of the dimensions."""
        return float(np.prod(self.dimensions))

    def __repr__(self) -> str:
        return f"BoundingBox(min={self.min.tolist()}, max={self.max.tolist()})"


class NodeAttributes:
    """A node's attributes: ``position`` (float64 array of 3), ``name``,
    ``semantic_label``, ``bounding_box`` (``None`` when the file stored none), and
    ``labels`` (Yggdrasil's label set) and ``features`` (every stored feature)."""

    def __init__(self, node: "_yggdrasil.Node"):
        self._node = node
        self.features: Dict[str, object] = node.features

    @property
    def position(self) -> np.ndarray:
        """The node's position: its stored ``attributes.position`` for objects, else its one point."""
        f = self.features
        if "position_x" in f:
            return np.array([f["position_x"], f["position_y"], f["position_z"]], dtype=np.float64)
        points = self._node.points
        if len(points) == 0:
            return np.zeros(3, dtype=np.float64)
        return points[0].astype(np.float64)

    @property
    def name(self) -> str:
        """The node's name (empty if the file gave none)."""
        return str(self.features.get("name", ""))

    @property
    def semantic_label(self) -> int:
        """The semantic label (Spark-DSG's ``NO_SEMANTIC_LABEL``, 2**32 - 1, if none)."""
        return int(self.features.get("semantic_label", 2**32 - 1))

    @property
    def bounding_box(self) -> Optional[BoundingBox]:
        """The stored Spark-DSG bounding box, or ``None``."""
        f = self.features
        if not all(k in f for k in _BOX_KEYS):
            return None
        v = [f[k] for k in _BOX_KEYS]
        return BoundingBox(v[:3], v[3:])

    @property
    def labels(self) -> List[str]:
        """Yggdrasil's labels of the node (a set; Spark-DSG's one name among them)."""
        return self._node.labels


class SceneGraphNode:
    """One node, as ``spark_dsg.SceneGraphNode``."""

    def __init__(self, graph: "DynamicSceneGraph", node: "_yggdrasil.Node", layer: str):
        self._graph = graph
        self._node = node
        self._layer = layer
        self.id = NodeSymbol(node.id)
        self.attributes = NodeAttributes(node)

    @property
    def layer(self) -> LayerKey:
        """The node's Spark-DSG layer key."""
        return LayerKey(*_LAYER_KEYS[self._layer])

    def get_parent(self) -> Optional[int]:
        """The id of the nearest ancestor in a Spark-DSG layer, or ``None``."""
        return self._graph._visible_parent(self._node.id)

    def has_parent(self) -> bool:
        """Whether ``get_parent()`` is not ``None``."""
        return self.get_parent() is not None

    def children(self) -> Set[int]:
        """Ids of the nearest descendants in Spark-DSG layers."""
        return self._graph._visible_children(self._node.id)

    def has_children(self) -> bool:
        """Whether ``children()`` is not empty."""
        return bool(self.children())

    def __repr__(self) -> str:
        return f"Node<id={self.id}, layer={self.layer}>"


class SceneGraphEdge:
    """An intra-layer edge: ``source`` and ``target`` ids."""

    __slots__ = ("source", "target")

    def __init__(self, source: int, target: int):
        self.source = source
        self.target = target

    def __repr__(self) -> str:
        return f"Edge<source={NodeSymbol(self.source)}, target={NodeSymbol(self.target)}>"


class SceneGraphLayer:
    """One Spark-DSG layer (on per-room layouts, ``OBJECTS`` gathers every room's objects)."""

    def __init__(self, graph: "DynamicSceneGraph", name: str, store_layers: List[str]):
        self._graph = graph
        self.name = name
        self._store_layers = store_layers
        self.id = _LAYER_KEYS[name][0]

    def _ids(self) -> List[int]:
        scene = self._graph.scene
        ids: List[int] = []
        for layer in self._store_layers:
            ids.extend(scene.layer(layer).nodes)
        ids.sort()
        return ids

    @property
    def nodes(self) -> Iterator[SceneGraphNode]:
        """The layer's nodes, ascending by id."""
        return (self._graph._wrap(i, self.name) for i in self._ids())

    @property
    def edges(self) -> Iterator[SceneGraphEdge]:
        """The layer's edges (each undirected Spark-DSG edge once, as stored)."""
        scene = self._graph.scene
        for i in self._ids():
            for source, target, _ in scene.edges_from(i):
                yield SceneGraphEdge(source, target)

    def num_nodes(self) -> int:
        """Number of nodes."""
        scene = self._graph.scene
        return sum(len(scene.layer(layer)) for layer in self._store_layers)

    def num_edges(self) -> int:
        """Number of edges."""
        return sum(1 for _ in self.edges)

    def has_node(self, node_id: int) -> bool:
        """Whether the layer holds this node."""
        return self._graph._layer_of(int(node_id)) in self._store_layers

    def get_node(self, node_id: int) -> SceneGraphNode:
        """The node; raises ``IndexError`` if the layer does not hold it."""
        node = self.find_node(node_id)
        if node is None:
            raise IndexError(f"layer {self.name} has no node {NodeSymbol(int(node_id))}")
        return node

    def find_node(self, node_id: int) -> Optional[SceneGraphNode]:
        """The node, or ``None``."""
        if not self.has_node(node_id):
            return None
        return self._graph._wrap(int(node_id), self.name)

    def __repr__(self) -> str:
        return f"Layer<{self.name}, nodes={self.num_nodes()}>"


class DynamicSceneGraph:
    """A scene graph read the way spark_dsg reads one, over a ``yggdrasil.Scene``."""

    def __init__(self, scene: "_yggdrasil.Scene"):
        self.scene = scene
        groups: Dict[str, List[str]] = {}
        for layer in scene.layers:
            name = _spark_dsg_name(layer)
            if name is not None:
                groups.setdefault(name, []).append(layer)
        self._groups = groups
        self._visible = {layer for layers in groups.values() for layer in layers}
        self._names = {layer: name for name, layers in groups.items() for layer in layers}

    # ---- internals
    def _layer_of(self, node_id: int) -> Optional[str]:
        if not self.scene.has_node(node_id):
            return None
        return self.scene.node(node_id).layer

    def _wrap(self, node_id: int, name: str) -> SceneGraphNode:
        return SceneGraphNode(self, self.scene.node(node_id), name)

    def _visible_parent(self, node_id: int) -> Optional[int]:
        parent = self.scene.parent(node_id)
        while parent is not None and self.scene.node(parent).layer not in self._visible:
            parent = self.scene.parent(parent)
        return parent

    def _visible_children(self, node_id: int) -> Set[int]:
        out: Set[int] = set()
        stack = list(self.scene.children(node_id))
        while stack:
            child = stack.pop()
            layer = self.scene.node(child).layer
            if layer in self._visible:
                out.add(child)
            elif _spark_dsg_name(layer) is None and layer.startswith(_ROOM_PREFIX) and "/" not in layer:
                # a per-room layout's group node: look through it to the room's objects
                stack.extend(self.scene.children(child))
        return out

    # ---- spark_dsg's read API
    def get_layer(self, key: Union[str, int]) -> SceneGraphLayer:
        """The layer with this ``DsgLayers`` name or Spark-DSG layer id; raises ``IndexError``."""
        name = _NAME_OF_ID.get(key) if isinstance(key, int) else key
        if name not in self._groups:
            raise IndexError(f"missing layer {key!r}")
        return SceneGraphLayer(self, name, self._groups[name])

    def has_layer(self, key: Union[str, int]) -> bool:
        """Whether the layer exists."""
        name = _NAME_OF_ID.get(key) if isinstance(key, int) else key
        return name in self._groups

    @property
    def layers(self) -> List[SceneGraphLayer]:
        """Every Spark-DSG layer present, by layer key."""
        names = sorted(self._groups, key=lambda n: _LAYER_KEYS[n])
        return [SceneGraphLayer(self, n, self._groups[n]) for n in names]

    @property
    def layer_names(self) -> Dict[str, int]:
        """Layer name -> Spark-DSG layer id."""
        return {n: _LAYER_KEYS[n][0] for n in self._groups}

    @property
    def nodes(self) -> Iterator[SceneGraphNode]:
        """Every node of the Spark-DSG layers."""
        for layer in self.layers:
            yield from layer.nodes

    @property
    def edges(self) -> Iterator[SceneGraphEdge]:
        """Every intra-layer edge of the Spark-DSG layers."""
        for layer in self.layers:
            yield from layer.edges

    def num_nodes(self) -> int:
        """Number of nodes in the Spark-DSG layers."""
        return sum(layer.num_nodes() for layer in self.layers)

    def num_edges(self) -> int:
        """Number of intra-layer edges."""
        return sum(layer.num_edges() for layer in self.layers)

    def has_node(self, node_id: int) -> bool:
        """Whether a Spark-DSG layer holds this node."""
        return self._layer_of(int(node_id)) in self._visible

    def find_node(self, node_id: int) -> Optional[SceneGraphNode]:
        """The node, or ``None``."""
        layer = self._layer_of(int(node_id))
        if layer not in self._visible:
            return None
        return self._wrap(int(node_id), self._names[layer])

    def get_node(self, node_id: int) -> SceneGraphNode:
        """The node; raises ``IndexError`` if there is none."""
        node = self.find_node(node_id)
        if node is None:
            raise IndexError(f"missing node {NodeSymbol(int(node_id))}")
        return node

    def get_position(self, node_id: int) -> np.ndarray:
        """The node's position."""
        return self.get_node(node_id).attributes.position

    def __repr__(self) -> str:
        return f"DynamicSceneGraph<nodes={self.num_nodes()}, layers={list(self._groups)}>"


def _node_attributes(node: SceneGraphNode) -> Dict[str, object]:
    a = node.attributes
    out: Dict[str, object] = {
        "position": a.position,
        "name": a.name,
        "semantic_label": a.semantic_label,
        "layer": node.layer.layer,
        "partition": node.layer.partition,
    }
    if a.bounding_box is not None:
        out["bounding_box"] = a.bounding_box
    return out


def graph_to_networkx(G: DynamicSceneGraph, include_partitions: bool = True):
    """A ``networkx.Graph``: one node per Spark-DSG node (keyed by ``id.value``, with
    ``position``, ``name``, ``semantic_label``, ``layer``, ``partition`` and, when
    stored, ``bounding_box``), the intra-layer edges and the parent-child edges. With
    ``include_partitions=False`` the agents and mesh places (partitions) are left out."""
    import networkx as nx

    out = nx.Graph()
    for layer in G.layers:
        if not include_partitions and _LAYER_KEYS[layer.name][1] != 0:
            continue
        for node in layer.nodes:
            out.add_node(node.id.value, **_node_attributes(node))
        for edge in layer.edges:
            out.add_edge(edge.source, edge.target)
    for node_id in list(out.nodes):
        parent = G._visible_parent(node_id)
        if parent is not None and parent in out:
            out.add_edge(parent, node_id)
    return out
