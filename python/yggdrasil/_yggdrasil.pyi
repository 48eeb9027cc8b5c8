"""Type stubs of the extension module ``yggdrasil._yggdrasil`` (PyO3)."""
from __future__ import annotations

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Point = Union[Sequence[float], npt.NDArray[Any]]
_Points = Union[Sequence[Sequence[float]], npt.NDArray[Any]]
_Path = Union[str, os.PathLike[str]]
_LayerArg = Union[str, int]
_FeatureValue = Union[str, int, float, bool]
_Edge = Tuple[int, int, str]
_Box = Tuple[Tuple[float, float, float], Tuple[float, float, float]]
_Ragged = Tuple[npt.NDArray[np.int64], npt.NDArray[np.uint64]]

NO_NODE: int
"""The id ``ObjectQueries.nearest_many`` (an ``int64`` array) holds for "no object": -1.
Every Spark-DSG object id is below 2**63, so no id takes it; a larger id raises
``QueryError``. ``Scene.nearest_nodes_many`` answers node ids, which use all 64 bits, as a
masked ``uint64`` array instead."""

def set_log_level(level: str) -> None:
    """Sets how much the shared-memory transport (iceoryx2) prints on stderr, process-wide:
    ``"trace"``, ``"debug"``, ``"info"``, ``"warn"``, ``"error"`` or ``"fatal"``. The package
    sets ``"error"`` when it loads unless the environment variable ``YGG_LOG`` names another
    level. Raises ``ValueError`` for an unknown name."""

class AgentPose:
    """The newest agent pose of a scene (``Scene.newest_pose()``)."""

    @property
    def node(self) -> int:
        """The pose node: the largest id of the ``AGENTS`` layer with a point."""
    @property
    def position(self) -> Tuple[float, float, float]:
        """Its position."""
    @property
    def previous(self) -> Tuple[float, float, float]:
        """The previous pose's position (1 m behind along -x when there is one pose)."""
    @property
    def heading(self) -> Tuple[float, float, float]:
        """The unit direction of travel (+x when ``previous == position``)."""

class RoomScope:
    """Where a room's objects live in a per-room layout (``Scene.room_scope(room)``)."""

    @property
    def mesh_layer(self) -> str:
        """The room's claimed-mesh layer (its objects' mesh nodes)."""
    @property
    def claimed(self) -> int:
        """The room's claimed group node: ``scene.objects_in(claimed)`` is the room's objects."""

class Error(Exception):
    """Base class of every Yggdrasil error."""

class FileError(Error):
    """A file could not be read, is not what it claims, or failed validation."""

class QueryError(Error):
    """A query was given bad input (non-finite point, negative radius, unknown node or layer, malformed query)."""

class MutationError(Error):
    """The graph refused a mutation; it is left unchanged."""

class TransportError(Error):
    """Shared memory failed: no writer, a rejected snapshot, a full /dev/shm, ..."""

class WriterGoneError(TransportError):
    """The scene's writer exited or died; the last snapshot stays usable."""

def open(path: _Path) -> Scene:
    """Maps a ``.ygg`` snapshot file and validates it once; raises ``FileError``."""

def open_recording(path: _Path) -> Recording:
    """Opens a recording folder (``ygg record`` / ``Recorder``); raises ``FileError``."""

def write_office(path: _Path, seed: int = 7, scale: float = 1.0) -> None:
    """Writes the built-in office as a Spark-DSG file (binary for ``.sparkdsg``, else JSON)."""

def office_graph(layout: str = "mint", seed: int = 7, scale: float = 1.0) -> SceneGraph:
    """The built-in office in one of the paper's layouts."""

def spark_dsg_json_parts(
    path: _Path,
) -> Tuple[List[Tuple[int, str]], List[Tuple[int, int, str]], Optional[str], Optional[str]]:
    """The parts of a Spark-DSG JSON file ``yggdrasil.dsg`` reads on demand, as JSON text
    (only their extent parsed, without the GIL): ``(nodes, edges, metadata, mesh)``, each
    node ``(id, attributes)``, each edge ``(source, target, info)``; raises ``FileError``."""

def spark_dsg_json_mesh(
    text: str,
) -> Tuple[
    Tuple[bool, bool, bool, bool],
    npt.NDArray[np.float32],
    npt.NDArray[np.uint8],
    npt.NDArray[np.uint64],
    npt.NDArray[np.uint32],
    npt.NDArray[np.uint64],
    npt.NDArray[np.uint64],
]:
    """A Spark-DSG JSON mesh object's text as numpy arrays: ``(flags, points (n, 3), colors
    (n, 4), stamps, labels, first_seen_stamps, faces (m, 3))``, the flags ``(has_colors,
    has_timestamps, has_labels, has_first_seen_stamps)``; raises ``FileError``."""

class Scene:
    """A validated snapshot, queried in place (from ``open``, ``Reader`` or ``SceneGraph.snapshot``)."""

    @property
    def generation(self) -> int:
        """The snapshot generation (0 for a file)."""
    @property
    def layers(self) -> List[str]:
        """Every layer's name, ascending by layer id."""
    @property
    def node_count(self) -> int:
        """Total number of nodes."""
    @property
    def objects(self) -> ObjectQueries:
        """The object contract of ``ygg query`` over the whole scene."""
    def layer(self, name: str) -> Layer:
        """The layer called ``name``; raises ``QueryError``."""
    def has_node(self, id: int) -> bool:
        """Whether the node exists."""
    def node(self, id: int) -> Node:
        """The node; raises ``QueryError`` if absent."""
    def objects_in(self, root: int) -> ObjectQueries:
        """The object queries restricted to ``root``'s sub-tree."""
    def query(self, q: Union[Mapping[str, Any], str]) -> Dict[str, List[int]]:
        """One query of the ``ygg query`` contract, a dict (read directly) or a JSON
        line: ``{"ids": [...]}``; raises ``QueryError`` with the CLI's message."""
    def nearest_nodes(self, point: _Point, m: int = 1, layer: Optional[str] = None) -> List[Tuple[int, float]]:
        """At most ``m`` ``(id, distance)`` pairs, nearest first."""
    def nodes_within_radius(self, point: _Point, radius: float, layer: Optional[str] = None) -> List[int]:
        """Nodes with a point at distance ``<= radius``, ascending."""
    def nearest_in_subtree(self, root: int, point: _Point, m: int = 1) -> List[Tuple[int, float]]:
        """Like ``nearest_nodes`` within ``root``'s sub-tree."""
    def visible(self, root: int, eye: _Point, dir: _Point, half_angle_deg: float, range: float) -> List[int]:
        """Nodes in ``root``'s sub-tree with a point in the cone (half-angle in degrees, ``[0, 180]``)."""
    def nodes_with_label(self, label: str, layer: Optional[str] = None) -> List[int]:
        """Nodes carrying ``label``, ascending."""
    def nodes_matching(self, features: Mapping[str, _FeatureValue], layer: Optional[str] = None) -> List[int]:
        """Nodes matching every ``key: value``, ascending."""
    def nodes_having(self, keys: Sequence[str], layer: Optional[str] = None) -> List[int]:
        """Nodes carrying every key, ascending."""
    def edges_from(self, node: int) -> List[_Edge]:
        """Edges leaving ``node``."""
    def edges_to(self, node: int) -> List[_Edge]:
        """Edges entering ``node``."""
    def edges_matching(self, description: str, layer: Optional[str] = None) -> List[_Edge]:
        """Edges with this description."""
    def parent(self, node: int) -> Optional[int]:
        """The parent, or ``None``."""
    def children(self, node: int) -> List[int]:
        """The children, ascending."""
    def subtree(self, root: int) -> List[int]:
        """``root`` and everything nested below it, ascending."""
    def subgraph(self, nodes: Sequence[int]) -> SceneGraph:
        """The sub-scene graph over ``nodes`` (every layer kept)."""
    def bfs(self, start: int, direction: str = "out") -> List[int]:
        """Breadth-first order over ``start``'s layer edges (``"out"`` or ``"both"``)."""
    def dfs(self, start: int, direction: str = "out") -> List[int]:
        """Depth-first pre-order (as ``bfs``)."""
    def shortest_path(self, source: int, target: int, direction: str = "out") -> Optional[List[int]]:
        """Fewest-edges path, both ends included, or ``None``."""
    def nearest_nodes_many(
        self, points: _Points, layer: Optional[str] = None
    ) -> Tuple[np.ma.MaskedArray[Any, np.dtype[np.uint64]], npt.NDArray[np.float32]]:
        """``nearest_nodes(p, 1)`` per row, without the GIL: ``(ids, distances)``, the ids a
        masked ``uint64`` array (node ids use all 64 bits), masked where the scope holds no
        point, the distances ``inf`` there."""
    def newest_pose(self) -> Optional[AgentPose]:
        """The newest agent pose, or ``None`` before the first one."""
    def room_of(self, point: _Point) -> Optional[int]:
        """The room whose box holds ``point`` in x and y (smallest id), or ``None``."""
    def room_scope(self, room: int) -> Optional[RoomScope]:
        """Where ``room``'s objects live (per-room layouts), or ``None``."""
    def owners(self, nodes: Sequence[int]) -> List[int]:
        """The distinct parents of ``nodes`` (objects owning mesh nodes), ascending."""

class Node:
    """One node of a ``Scene``."""

    @property
    def id(self) -> int:
        """The node id."""
    @property
    def layer(self) -> str:
        """The layer's name."""
    @property
    def parent(self) -> Optional[int]:
        """The parent's id."""
    @property
    def children(self) -> List[int]:
        """The children's ids, ascending."""
    @property
    def labels(self) -> List[str]:
        """The labels, sorted."""
    @property
    def features(self) -> Dict[str, _FeatureValue]:
        """The features, as a new dict."""
    @property
    def aabb(self) -> Optional[_Box]:
        """The kept bounding box ``((min), (max))``, or ``None``."""
    @property
    def points(self) -> npt.NDArray[np.float32]:
        """Read-only ``(n, 3)`` float32 view of the mapped snapshot (no copy); keeps it alive."""

class Layer:
    """One layer of a ``Scene``."""

    @property
    def id(self) -> int:
        """The layer id."""
    @property
    def name(self) -> str:
        """The layer name."""
    @property
    def generation(self) -> int:
        """The layer's generation."""
    @property
    def nodes(self) -> List[int]:
        """Node ids, ascending."""
    @property
    def children(self) -> List[str]:
        """Names of the layers it encompasses."""
    @property
    def parents(self) -> List[str]:
        """Names of the layers encompassing it."""
    def __len__(self) -> int: ...
    def spark_dsg_columns(
        self,
    ) -> Tuple[
        List[int],
        npt.NDArray[np.float64],
        List[str],
        List[int],
        List[Optional[Tuple[float, float, float, float, float, float]]],
        List[Optional[int]],
        List[Tuple[int, int]],
    ]:
        """The layer as the columns ``yggdrasil.dsg`` builds its nodes from, rows ascending by
        id: ``(ids, positions, names, semantic_labels, boxes, parents, edges)``; positions an
        ``(n, 3)`` float64 array, ``""`` / ``2**32 - 1`` for no name / label, ``None`` for no
        stored box or parent, ``edges`` every ``(source, target)`` leaving the layer's nodes."""

class ObjectQueries:
    """The object contract of ``ygg query``: Spark-DSG object ids, ascending."""

    def nearest(self, point: _Point) -> Optional[int]:
        """The object with the closest vertex (ties to the smaller id), or ``None``."""
    def within(self, point: _Point, radius: float) -> List[int]:
        """Objects with a vertex at distance ``<= radius``."""
    def visible(self, eye: _Point, dir: _Point, half_angle_deg: float, range: float) -> List[int]:
        """Objects with a vertex in the view cone (half-angle in degrees, ``[0, 180]``)."""
    def with_label(self, label: str) -> List[int]:
        """Objects carrying ``label``."""
    def ids(self) -> List[int]:
        """Every object node of the catalog."""
    def nearest_many(self, points: _Points) -> npt.NDArray[np.int64]:
        """``nearest`` per row, without the GIL: ``int64`` ids, ``NO_NODE`` (-1) for none."""
    def within_many(self, points: _Points, radius: float) -> _Ragged:
        """``within`` per row, without the GIL: ``(offsets, ids)``."""
    def visible_many(self, eyes: _Points, dirs: _Points, half_angle_deg: float, range: float) -> _Ragged:
        """``visible`` per row, without the GIL: ``(offsets, ids)``."""

class SceneGraph:
    """An editable scene graph; a refused mutation raises ``MutationError`` and changes nothing."""

    def __init__(self) -> None: ...
    @staticmethod
    def import_spark_dsg(path: _Path, layout: str = "mint", lenient: bool = False) -> SceneGraph:
        """Imports a Spark-DSG file in one of the paper's layouts; raises ``FileError``."""
    def add_layer(self, name: str) -> int:
        """Adds a layer; returns its id."""
    def layer_id(self, name: str) -> int:
        """The id of the layer called ``name``."""
    def remove_layer(self, layer: _LayerArg) -> None:
        """Removes an empty layer."""
    def add_layer_edge(self, parent: _LayerArg, child: _LayerArg) -> None:
        """Adds the DAG edge ``parent -> child``."""
    def remove_layer_edge(self, parent: _LayerArg, child: _LayerArg) -> None:
        """Removes a DAG edge no nesting uses."""
    def add_node(self, id: int, layer: _LayerArg) -> None:
        """Adds a node."""
    def remove_node(self, id: int) -> None:
        """Removes a node with its edges and nestings."""
    def set_geometry(self, id: int, points: _Points) -> None:
        """Replaces a node's points."""
    def append_points(self, id: int, points: _Points) -> None:
        """Appends points to a node's geometry (a growing mesh: costs the appended points)."""
    def set_feature(self, id: int, key: str, value: _FeatureValue) -> None:
        """Sets a feature."""
    def remove_feature(self, id: int, key: str) -> None:
        """Removes a feature."""
    def add_label(self, id: int, label: str) -> None:
        """Adds a label."""
    def remove_label(self, id: int, label: str) -> None:
        """Removes a label."""
    def add_edge(self, source: int, target: int, description: str = "") -> None:
        """Adds an intra-layer edge."""
    def remove_edge(self, source: int, target: int) -> None:
        """Removes an edge."""
    def nest(self, parent: int, child: int) -> None:
        """Nests ``child`` under ``parent``."""
    def unnest(self, child: int) -> None:
        """Removes ``child``'s nesting."""
    def enable_bounding_box(self, id: int) -> None:
        """Keeps an exact box of the node's sub-tree."""
    def disable_bounding_box(self, id: int) -> None:
        """Stops keeping the box."""
    def enable_layer_index(self, layer: _LayerArg) -> None:
        """Keeps a kd-tree over the layer's points."""
    def disable_layer_index(self, layer: _LayerArg) -> None:
        """Drops the layer's kd-tree."""
    def enable_node_index(self, id: int) -> None:
        """Keeps a kd-tree over the node's sub-tree."""
    def disable_node_index(self, id: int) -> None:
        """Drops the node's kd-tree."""
    def has_node(self, id: int) -> bool:
        """Whether the node exists."""
    @property
    def node_count(self) -> int:
        """Total number of nodes."""
    @property
    def layers(self) -> List[str]:
        """Every layer's name."""
    def save(self, path: _Path) -> None:
        """Writes a ``.ygg`` file atomically; raises ``FileError``."""
    def nodes_with_label(self, label: str, layer: Optional[str] = None) -> List[int]:
        """``Scene.nodes_with_label`` answered by the live graph (no snapshot)."""
    def edges_from(self, node: int) -> List[Tuple[int, int, str]]:
        """``Scene.edges_from`` answered by the live graph (no snapshot)."""
    def snapshot(self) -> Scene:
        """An archived snapshot of the graph as it is now."""

class Reader:
    """Follows a live scene; waits release the GIL."""

    def __init__(self, scene_name: str, wait_for_writer: float = 0.0, copy_segments: bool = False) -> None: ...
    def wait_next(self, timeout: float = 1.0) -> Optional[Scene]:
        """The next snapshot, or ``None`` after ``timeout`` seconds; raises ``WriterGoneError``."""
    def latest(self) -> Optional[Scene]:
        """The newest snapshot without blocking (``None`` before the first one).

        A rejected snapshot raises ``TransportError`` once; until a newer one arrives,
        later calls return the last accepted snapshot."""
    @property
    def writer_status(self) -> str:
        """``"unknown"``, ``"alive"`` or ``"gone"``."""
    @property
    def scene_name(self) -> str:
        """The scene name."""
    @property
    def validations(self) -> int:
        """Layer segments validated so far."""
    def close(self) -> None:
        """Detaches."""
    def __enter__(self) -> Reader: ...
    def __exit__(self, *args: object) -> None: ...

class Writer:
    """Publishes a ``SceneGraph``; its later mutations go to the writer."""

    def __init__(
        self,
        scene_name: str,
        graph: SceneGraph,
        max_readers: int = 8,
        max_layers: Optional[int] = None,
        part_rows: Optional[int] = None,
    ) -> None:
        """Creates the scene and publishes ``graph``; ``max_layers`` bounds its segments
        (default a quarter more than the graph's, at least 256 more); ``part_rows`` rows
        fill a layer's newest part before another starts (default 128; each publish
        resends only the parts whose rows changed); raises ``TransportError``, and
        ``ValueError`` for ``part_rows=0``."""
    def publish(self) -> Dict[str, int]:
        """Sends the changed parts of the changed layers and a manifest:
        ``{"generation", "layers_sent", "parts_sent", "layers_unchanged", "bytes_sent",
        "segments"}``."""
    @property
    def generation(self) -> int:
        """The last generation published."""
    @property
    def graph(self) -> SceneGraph:
        """The graph being published."""
    @property
    def scene_name(self) -> str:
        """The scene name."""
    def close(self) -> None:
        """Stops publishing and removes the shared memory."""
    def __enter__(self) -> Writer: ...
    def __exit__(self, *args: object) -> None: ...

class Recording:
    """A recording of a live scene; times are seconds since the Unix epoch (writer's clock)."""

    @property
    def cuts(self) -> Dict[str, np.ndarray]:
        """Per cut: ``generation`` (uint64), ``time``, ``recorded_time`` (float64), ``bytes_added`` (uint64)."""
    @property
    def start_time(self) -> float: ...
    @property
    def end_time(self) -> float: ...
    @property
    def defects(self) -> List[str]: ...
    def __len__(self) -> int: ...
    def at(self, time: Optional[float] = None, generation: Optional[int] = None) -> Scene:
        """The scene as it was at ``time`` (the last cut at or before it) or at cut ``generation``."""
    def changes(self, t0: float, t1: float, tolerance: float = 0.05) -> Dict[str, Any]:
        """Nodes added, removed, moved (beyond ``tolerance`` m), relabelled; edges added and removed."""

class Recorder:
    """Records a live scene into a recording folder; waits release the GIL."""

    def __init__(
        self,
        scene_name: str,
        path: _Path,
        wait_for_writer: float = 5.0,
        max_size: Optional[int] = None,
        max_age: Optional[float] = None,
    ) -> None: ...
    def record_next(self, timeout: float = 1.0) -> bool:
        """Records the next cut within ``timeout`` seconds; True if one was recorded."""
    @property
    def cuts_recorded(self) -> int: ...
    @property
    def bytes_recorded(self) -> int: ...
    def sync(self) -> None: ...
