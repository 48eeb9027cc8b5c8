"""How a layer is drawn: its role (mesh, objects, agents, places, rooms, buildings), the
height its nodes are lifted to, and the colors of labels and roles. No viewer library here."""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from typing import Dict, Mapping, Optional, Tuple

import numpy as np

#: Roles in drawing order, bottom up, with their default level: a layer of role ``r`` is
#: lifted by ``level * layer_step`` metres (Hydra's visualizer stacks its layers the same
#: way: the mesh and the objects where they are, places, rooms and buildings above).
ROLE_LEVELS: Dict[str, float] = {
    "mesh": 0.0,
    "objects": 0.0,
    "agents": 0.0,
    "groups": 0.5,
    "places": 1.0,
    "other": 1.0,
    "rooms": 2.0,
    "buildings": 3.0,
}

#: The node color of the roles whose nodes carry no semantic label.
ROLE_COLORS: Dict[str, Tuple[int, int, int]] = {
    "mesh": (150, 150, 150),
    "objects": (230, 120, 30),
    "agents": (220, 30, 30),
    "groups": (120, 120, 200),
    "places": (40, 90, 220),
    "other": (140, 60, 180),
    "rooms": (20, 170, 80),
    "buildings": (90, 90, 90),
}

#: A node's drawn diameter per role, metres (objects and rooms stand out, the many places
#: stay small).
ROLE_NODE_SIZES: Dict[str, float] = {
    "mesh": 0.1,
    "objects": 0.4,
    "agents": 0.15,
    "groups": 0.25,
    "places": 0.12,
    "other": 0.2,
    "rooms": 0.7,
    "buildings": 0.9,
}

# 20 well-separated colors (the "tab20" order), indexed by semantic label.
_PALETTE = np.array(
    [
        (31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
        (140, 86, 75), (227, 119, 194), (188, 189, 34), (23, 190, 207), (174, 199, 232),
        (255, 187, 120), (152, 223, 138), (255, 152, 150), (197, 176, 213), (196, 156, 148),
        (247, 182, 210), (219, 219, 141), (158, 218, 229), (127, 127, 127), (199, 199, 199),
    ],
    dtype=np.uint8,
)


def role_of(layer_name: str) -> str:
    """The role of a layer from its name: Spark-DSG's layer names (``OBJECTS``, ``AGENTS``,
    ``PLACES``, ``MESH_PLACES``, ``ROOMS``, ``BUILDINGS``, ``MESH``) and the per-room
    layers of the paper's layouts (``room:<id>/claimed-object``, ``.../claimed-mesh``,
    ``.../unclaimed-mesh``, the group layer ``room:<id>``); anything else is ``"other"``."""
    base = layer_name.rsplit("/", 1)[-1].upper()
    if base in ("MESH", "CLAIMED-MESH", "UNCLAIMED-MESH"):
        return "mesh"
    if base in ("OBJECTS", "CLAIMED-OBJECT"):
        return "objects"
    if base == "AGENTS":
        return "agents"
    if base in ("PLACES", "MESH_PLACES"):
        return "places"
    if base == "ROOMS":
        return "rooms"
    if base == "BUILDINGS":
        return "buildings"
    if layer_name.startswith("room:") and "/" not in layer_name:
        return "groups"
    return "other"


def label_color(label: str) -> Tuple[int, int, int]:
    """A label's color: a semantic label number picks its palette entry (as Hydra's color
    maps do), a name a stable hash of it."""
    index = int(label) if label.isdigit() else zlib.crc32(label.encode())
    return tuple(int(c) for c in _PALETTE[index % len(_PALETTE)])  # type: ignore[return-value]


@dataclass
class Style:
    """Heights and sizes of the drawing.

    ``layer_step`` is the metres between two levels of ``ROLE_LEVELS``; ``heights`` sets a
    role's lift in metres outright (``{"rooms": 12.0}``), overriding its level."""

    layer_step: float = 4.0
    heights: Mapping[str, float] = field(default_factory=dict)
    node_scale: float = 1.0
    """Multiplies every role's node size (``ROLE_NODE_SIZES``)."""
    mesh_point_size: float = 0.04
    mesh_stride: int = 1
    """Draw every ``mesh_stride``-th mesh point (1: all). A browser without a GPU renders
    every point in software on each frame: on such a machine the full office's 386k
    points cost most of a frame (``bench/results/viewer.md``); a stride of 4 draws a
    quarter of them."""

    def node_size(self, role: str) -> float:
        """The drawn diameter of a role's nodes, metres."""
        return ROLE_NODE_SIZES.get(role, 0.2) * self.node_scale

    def height(self, role: str) -> float:
        """The lift of a role's layers, metres."""
        if role in self.heights:
            return float(self.heights[role])
        return ROLE_LEVELS.get(role, 1.0) * self.layer_step


def parse_heights(items) -> Dict[str, float]:
    """``["rooms=12", "places=6"]`` (``--height`` options) as a dict; raises ``ValueError``
    naming the bad item."""
    heights: Dict[str, float] = {}
    for item in items or ():
        role, sep, value = item.partition("=")
        if not sep or role not in ROLE_LEVELS:
            raise ValueError(f"--height {item!r}: expected ROLE=METRES with ROLE one of {', '.join(ROLE_LEVELS)}")
        try:
            heights[role] = float(value)
        except ValueError:
            raise ValueError(f"--height {item!r}: {value!r} is not a number") from None
    return heights


def display_label(labels, name: Optional[str]) -> Optional[str]:
    """The label a node is colored and listed by: its name feature's text when it has one
    (``chair``), else its first label."""
    words = [label for label in labels if not label.isdigit()]
    if words:
        return words[0]
    if name:
        return name
    return labels[0] if labels else None
