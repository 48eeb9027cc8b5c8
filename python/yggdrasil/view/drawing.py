"""What the viewer draws of a scene, as numpy arrays, one ``LayerDrawing`` per layer: node
positions lifted to the layer's height and colored by label, intra-layer edges, kept
bounding boxes, the mesh's points. ``SceneDrawing`` follows a sequence of scenes and
rebuilds only the layers whose generation changed (and the nesting edges into them). No
viewer library here: ``viewer.py`` sends these arrays to the browser."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Set, Tuple

import numpy as np

from .style import ROLE_COLORS, Style, label_color, role_of

Color = Tuple[int, int, int]

# The 12 edges of a box as pairs of corner indices (corner bit 0: x, 1: y, 2: z).
_BOX_EDGES = np.array(
    [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]
)


@dataclass
class LayerDrawing:
    """One layer as drawn. Arrays are float32 positions (already lifted) and uint8 colors."""

    name: str
    role: str
    generation: int
    height: float
    ids: np.ndarray
    """Node ids (uint64), ascending."""
    positions: np.ndarray
    """``(n, 3)`` drawn node positions; a node with no geometry of its own sits at the
    centroid of its children (group nodes), else where the scene puts it."""
    colors: np.ndarray
    """``(n, 3)`` node colors: by label where a node has one, else the role's color."""
    labels: List[Optional[str]]
    """The label a node is listed by in the legend (``None``: the role's color)."""
    parents: np.ndarray
    """Parent id per node (uint64), 0 where there is none (``has_parent`` tells)."""
    has_parent: np.ndarray
    edges: np.ndarray
    """``(k, 2, 3)`` intra-layer edge segments."""
    boxes: np.ndarray
    """``(12 b, 2, 3)`` segments of the kept bounding boxes, lifted."""
    box_colors: np.ndarray
    """``(12 b, 3)`` colors of those segments (the node's color)."""
    mesh_points: np.ndarray
    """``(m, 3)`` the points of the layer's nodes (mesh layers only; every
    ``Style.mesh_stride``-th), at their true height."""
    mesh_colors: np.ndarray
    """``(m, 3)`` their colors: the owning object's label color, else the role's gray."""
    placed: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    """Whether a node has geometry of its own (else it was placed at its children)."""

    @property
    def node_count(self) -> int:
        """Nodes in the layer."""
        return len(self.ids)


def box_segments(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The ``(12 b, 2, 3)`` edge segments of ``b`` boxes given by their ``(b, 3)`` corners."""
    bits = np.array([[(c >> 0) & 1, (c >> 1) & 1, (c >> 2) & 1] for c in range(8)], dtype=bool)
    corners = np.where(bits[None, :, :], hi[:, None, :], lo[:, None, :])  # (b, 8, 3)
    return corners[:, _BOX_EDGES, :].reshape(-1, 2, 3).astype(np.float32)


def _node_label(labels: List[str], name: str) -> Tuple[Optional[str], Optional[Color]]:
    words = [label for label in labels if not label.isdigit()]
    numbers = [label for label in labels if label.isdigit()]
    shown = words[0] if words else (name or (numbers[0] if numbers else None))
    if shown is None:
        return None, None
    return shown, label_color(numbers[0] if numbers else shown)


def draw_layer(scene, name: str, style: Style, object_colors: Dict[int, Color]) -> LayerDrawing:
    """One layer of ``scene`` as drawn. ``object_colors`` (object id -> color) colors the
    points of mesh nodes owned by an object."""
    layer = scene.layer(name)
    role = role_of(name)
    lift = np.array([0.0, 0.0, style.height(role)], dtype=np.float32)
    ids, positions, names, _semantic, boxes, parents, edges = layer.spark_dsg_columns()
    n = len(ids)
    ids_arr = np.array(ids, dtype=np.uint64)
    pos = np.asarray(positions, dtype=np.float32).reshape(n, 3).copy()
    placed = np.ones(n, dtype=bool)
    colors = np.tile(np.array(ROLE_COLORS[role], dtype=np.uint8), (n, 1))
    shown: List[Optional[str]] = [None] * n
    mesh_pts: List[np.ndarray] = []
    mesh_cols: List[np.ndarray] = []
    box_lo, box_hi, box_rows = [], [], []
    for row, node_id in enumerate(ids):
        node = scene.node(node_id)
        points = node.points
        if len(points) > 1:
            pos[row] = points.mean(axis=0)
        elif len(points) == 0 and not pos[row].any():
            placed[row] = False
        label, color = _node_label(node.labels, names[row])
        if color is not None and role != "mesh":
            colors[row] = color
            shown[row] = label
        if role == "mesh" and len(points):
            owner = parents[row]
            col = object_colors.get(owner, ROLE_COLORS["mesh"]) if owner is not None else ROLE_COLORS["mesh"]
            colors[row] = col
            shown_points = points[:: style.mesh_stride]
            mesh_pts.append(shown_points)
            mesh_cols.append(np.tile(np.array(col, dtype=np.uint8), (len(shown_points), 1)))
        box = node.aabb
        if box is None and boxes[row] is not None:
            b = boxes[row]
            box = (b[:3], b[3:])
        if box is not None and role in ("objects", "rooms", "buildings", "other"):
            box_lo.append(box[0])
            box_hi.append(box[1])
            box_rows.append(row)
    index = {int(i): r for r, i in enumerate(ids)}
    segs = [(pos[index[s]], pos[index[t]]) for s, t in edges if s in index and t in index]
    edge_arr = np.array(segs, dtype=np.float32).reshape(-1, 2, 3) + lift
    if box_rows:
        box_arr = box_segments(np.array(box_lo, np.float32), np.array(box_hi, np.float32)) + lift
        box_colors = np.repeat(colors[box_rows], 12, axis=0)
    else:
        box_arr, box_colors = np.zeros((0, 2, 3), np.float32), np.zeros((0, 3), np.uint8)
    parent_arr = np.array([p if p is not None else 0 for p in parents], dtype=np.uint64)
    has_parent = np.array([p is not None for p in parents], dtype=bool)
    return LayerDrawing(
        name=name,
        role=role,
        generation=layer.generation,
        height=float(lift[2]),
        ids=ids_arr,
        positions=pos + lift,
        colors=colors,
        labels=shown,
        parents=parent_arr,
        has_parent=has_parent,
        edges=edge_arr,
        boxes=box_arr,
        box_colors=box_colors,
        mesh_points=np.concatenate(mesh_pts).astype(np.float32) if mesh_pts else np.zeros((0, 3), np.float32),
        mesh_colors=np.concatenate(mesh_cols) if mesh_cols else np.zeros((0, 3), np.uint8),
        placed=placed,
    )


@dataclass
class DrawingUpdate:
    """What changed between two scenes: the layers to (re)send, the layers gone, and the
    child layers whose nesting edges must be redrawn."""

    generation: int
    changed: List[str]
    removed: List[str]
    nesting: List[str]


class SceneDrawing:
    """The drawing of the newest scene shown, kept per layer. ``update(scene)`` rebuilds
    only the layers whose generation differs from the one drawn."""

    def __init__(self, style: Style) -> None:
        self.style = style
        self.layers: Dict[str, LayerDrawing] = {}
        self.nesting: Dict[str, np.ndarray] = {}
        """Per child layer, the ``(k, 2, 3)`` segments from each node to its parent."""
        self._parents_of: Dict[str, List[str]] = {}
        self.scene = None

    @property
    def node_count(self) -> int:
        """Nodes in the drawn layers."""
        return sum(d.node_count for d in self.layers.values())

    def update(self, scene) -> DrawingUpdate:
        """Follows ``scene``: redraws the changed layers (a group node takes its children's
        centroid; a mesh point its object's color) and the nesting edges into them."""
        names = scene.layers
        changed = [n for n in names if n not in self.layers or self.layers[n].generation != scene.layer(n).generation]
        removed = [n for n in self.layers if n not in set(names)]
        for n in removed:
            del self.layers[n]
            self.nesting.pop(n, None)
        # Objects first, so that their mesh takes their colors; groups after their children.
        order = {"objects": 0, "agents": 1, "mesh": 2, "places": 3, "other": 4, "groups": 5, "rooms": 6, "buildings": 7}
        changed.sort(key=lambda n: order[role_of(n)])
        object_colors: Dict[int, Color] = {}
        for d in self.layers.values():
            if d.role == "objects" and d.name not in changed:
                object_colors.update(self._colors_of(d))
        for n in changed:
            d = draw_layer(scene, n, self.style, object_colors)
            if d.role == "objects":
                object_colors.update(self._colors_of(d))
            self.layers[n] = d
        self._place_unplaced([self.layers[n] for n in changed])
        for n in names:
            self._parents_of[n] = scene.layer(n).parents
        dirty: Set[str] = set(changed)
        nesting = [n for n in names if n in dirty or any(p in dirty for p in self._parents_of[n])]
        positions = self._positions()
        for n in nesting:
            self.nesting[n] = self._nesting_segments(self.layers[n], positions)
        self.scene = scene
        return DrawingUpdate(scene.generation, changed, removed, nesting)

    @staticmethod
    def _colors_of(d: LayerDrawing) -> Dict[int, Color]:
        return {int(i): tuple(int(c) for c in col) for i, col, lab in zip(d.ids, d.colors, d.labels) if lab}

    def _positions(self) -> Dict[int, np.ndarray]:
        positions: Dict[int, np.ndarray] = {}
        for d in self.layers.values():
            positions.update(zip(d.ids.tolist(), d.positions))
        return positions

    def _place_unplaced(self, changed: List[LayerDrawing]) -> None:
        """Puts each node without geometry at the centroid of its children (lifted to its
        own layer's height), parents after children."""
        if not any((~d.placed).any() for d in changed):
            return
        children: Dict[int, List[np.ndarray]] = {}
        for d in self.layers.values():
            for pid, has, p, ok in zip(d.parents.tolist(), d.has_parent, d.positions, d.placed):
                if has and ok:
                    children.setdefault(pid, []).append(p)
        for d in changed:
            for row in np.flatnonzero(~d.placed):
                kids = children.get(int(d.ids[row]))
                if kids:
                    c = np.mean(kids, axis=0)
                    d.positions[row] = (c[0], c[1], d.height)

    @staticmethod
    def _nesting_segments(d: LayerDrawing, positions: Dict[int, np.ndarray]) -> np.ndarray:
        segs = [
            (positions[pid], child)
            for pid, has, child in zip(d.parents.tolist(), d.has_parent, d.positions)
            if has and pid in positions
        ]
        return np.array(segs, dtype=np.float32).reshape(-1, 2, 3)

    def positions_of(self, ids) -> np.ndarray:
        """The drawn positions of the nodes ``ids`` that are drawn, ``(k, 3)``."""
        wanted = np.array(sorted(set(int(i) for i in ids)), dtype=np.uint64)
        found = [d.positions[np.isin(d.ids, wanted)] for d in self.layers.values() if len(d.ids)]
        return np.concatenate(found) if found else np.zeros((0, 3), np.float32)

    def boxes_of(self, ids) -> np.ndarray:
        """The drawn box segments of the nodes ``ids`` that have a kept box."""
        scene = self.scene
        lo, hi, lift = [], [], []
        for i in ids:
            if not scene.has_node(int(i)):
                continue
            node = scene.node(int(i))
            if node.aabb is not None:
                lo.append(node.aabb[0])
                hi.append(node.aabb[1])
                lift.append(self.layers[node.layer].height)
        if not lo:
            return np.zeros((0, 2, 3), np.float32)
        segs = box_segments(np.array(lo, np.float32), np.array(hi, np.float32)).reshape(-1, 12, 2, 3)
        segs[..., 2] += np.array(lift, np.float32)[:, None, None]
        return segs.reshape(-1, 2, 3)

    def legend(self) -> Dict[str, Color]:
        """Every object label drawn, with its color, sorted by label."""
        seen: Dict[str, Color] = {}
        for d in self.layers.values():
            if d.role != "objects":
                continue
            for lab, col in zip(d.labels, d.colors):
                if lab and lab not in seen:
                    seen[lab] = tuple(int(c) for c in col)  # type: ignore[assignment]
        return dict(sorted(seen.items()))

    def nearest_node(self, origin, direction, layers: Optional[List[str]] = None) -> Optional[Tuple[int, str, float]]:
        """The drawn node closest to a ray (a click), as ``(id, layer, distance to the
        ray)``, among ``layers`` (default every layer but the mesh)."""
        o = np.asarray(origin, np.float32)
        v = np.asarray(direction, np.float32)
        v = v / max(float(np.linalg.norm(v)), 1e-9)
        best = None
        for d in self.layers.values():
            if (layers is not None and d.name not in layers) or (layers is None and d.role == "mesh") or not len(d.ids):
                continue
            rel = d.positions - o
            along = np.clip(rel @ v, 0.0, None)
            dist = np.linalg.norm(rel - along[:, None] * v, axis=1)
            row = int(np.argmin(dist))
            if best is None or dist[row] < best[2]:
                best = (int(d.ids[row]), d.name, float(dist[row]))
        return best
