"""The browser view (viser): ``SceneViewer`` sends a ``SceneDrawing``'s changed layers to
every connected page and keeps the panel (status, layer toggles, legend, selected node,
query, timeline). Built on viser, spark_dsg's own viewer library: pure Python, its
three.js client ships in its wheel, and each update goes out over one websocket."""
from __future__ import annotations

import html
import json
import threading
import time
from typing import Callable, Dict, Optional, Tuple

import numpy as np
import viser

from .drawing import DrawingUpdate, SceneDrawing
from .lines import line_segments_glb
from .queries import QueryDrawing, answer, parse_query
from .sources import ColoredMesh, Timeline
from .style import ROLE_COLORS, Style

HIGHLIGHT = (255, 215, 0)
SELECTED = (255, 0, 255)
QUERY_SHAPE = (230, 0, 60)
PARTS = ("nodes", "edges", "nesting", "boxes", "mesh")
# Intra-layer edges take their role's node color (the agent's trajectory red, wide).
ROLE_COLORS_EDGE = {role: ROLE_COLORS[role] for role in ("agents", "places", "rooms", "objects")}


def _safe(layer: str) -> str:
    return layer.replace("/", "|")


class SceneViewer:
    """A viser server showing one scene at a time (live or from a timeline).

    ``show(scene)`` redraws only the layers whose generation changed; ``emit`` receives
    one dict per event (``ready``, ``shown``, ``query``, ``selected``) for the command's
    JSON lines."""

    def __init__(
        self,
        style: Style,
        host: str = "127.0.0.1",
        port: int = 8080,
        title: str = "yggdrasil",
        emit: Callable[[dict], None] = lambda event: None,
    ) -> None:
        self.style = style
        self.emit = emit
        self.server = viser.ViserServer(host=host, port=port, label=title, verbose=False)
        self.server.scene.set_up_direction("+z")
        self.drawing = SceneDrawing(style)
        self._lock = threading.RLock()
        self._handles: Dict[Tuple[str, str], object] = {}
        self._role_on: Dict[str, object] = {}
        self._kind_on: Dict[str, object] = {}
        self._query: Optional[dict] = None
        self._camera_set = False
        self._file_mesh: Optional[ColoredMesh] = None
        gui = self.server.gui
        self._status = gui.add_markdown("waiting for the first scene")
        with gui.add_folder("Layers"):
            self._roles_folder = gui.add_folder("Roles")
            with gui.add_folder("Parts"):
                for kind in PARTS:
                    box = gui.add_checkbox(kind, initial_value=True)
                    box.on_update(lambda _e: self._apply_visibility())
                    self._kind_on[kind] = box
        with gui.add_folder("Legend", expand_by_default=True):
            self._legend = gui.add_html("")
        with gui.add_folder("Query"):
            self._query_text = gui.add_text("query", initial_value="")
            run = gui.add_button("Run")
            run.on_click(lambda _e: self._run_typed_query())
            self._query_result = gui.add_markdown("")
        with gui.add_folder("Selected node"):
            self._details = gui.add_markdown("click a node")
        self._legend_shown: Dict[str, Tuple[int, int, int]] = {}
        self.server.scene.on_click()(self._clicked)

    @property
    def port(self) -> int:
        """The port the page is served on."""
        return self.server.get_port()

    # ------------------------------------------------------------------ drawing
    def show(self, scene, mesh: Optional[ColoredMesh] = None) -> DrawingUpdate:
        """Shows ``scene``: sends the changed layers, removes the layers gone, redraws the
        nesting edges into changed layers, the legend, the query's answer and the status
        line (last, so that a page seeing the new status holds the new scene)."""
        with self._lock:
            started = time.monotonic_ns()
            update = self.drawing.update(scene)
            if mesh is not self._file_mesh:
                self._file_mesh = mesh
                self._send_file_mesh()
            for name in update.removed:
                for kind in PARTS:
                    handle = self._handles.pop((name, kind), None)
                    if handle is not None:
                        handle.remove()
            for name in update.changed:
                self._send_layer(name)
            for name in update.nesting:
                self._send_nesting(name)
            self._update_legend()
            if self._query is not None:
                self._draw_query()
            if not self._camera_set:
                self._set_camera()
            layers = len(self.drawing.layers)
            nodes = self.drawing.node_count
            self._status.content = f"**generation {update.generation}** · {layers} layers · {nodes} nodes"
            self.emit(
                {
                    "event": "shown",
                    "generation": update.generation,
                    "layers_sent": len(update.changed),
                    "layers": layers,
                    "nodes": nodes,
                    "draw_ms": round((time.monotonic_ns() - started) / 1e6, 3),
                    "wall_ns": time.time_ns(),
                }
            )
            return update

    def _role_visible(self, role: str) -> bool:
        box = self._role_on.get(role)
        return box is None or bool(box.value)

    def _visible(self, role: str, kind: str) -> bool:
        return self._role_visible(role) and bool(self._kind_on[kind].value)

    def _ensure_role_toggle(self, role: str) -> None:
        if role in self._role_on:
            return
        with self._roles_folder:
            box = self.server.gui.add_checkbox(role, initial_value=True)
        box.on_update(lambda _e: self._apply_visibility())
        self._role_on[role] = box

    def _apply_visibility(self) -> None:
        with self._lock:
            for (name, kind), handle in self._handles.items():
                d = self.drawing.layers.get(name)
                role = d.role if d is not None else "mesh"
                handle.visible = self._visible(role, kind)

    def _put(self, name: str, kind: str, handle) -> None:
        old = self._handles.get((name, kind))
        self._handles[(name, kind)] = handle
        if old is not None and old is not handle and old.name != handle.name:
            old.remove()

    def _cloud(self, name: str, kind: str, path: str, points: np.ndarray, colors, **props) -> None:
        """Draws a point cloud: a changed cloud of the same name is updated in place (its
        points and colors sent, the page's object kept), else a new one is added."""
        colors = np.broadcast_to(np.asarray(colors, np.uint8), (len(points), 3))
        handle = self._handles.get((name, kind))
        if isinstance(handle, viser.PointCloudHandle) and handle.name == path:
            handle.points = np.asarray(points, handle.points.dtype)
            handle.colors = np.ascontiguousarray(colors)
            return
        self._put(name, kind, self.server.scene.add_point_cloud(path, points, np.ascontiguousarray(colors), **props))

    def _lines(self, name: str, kind: str, path: str, segments: np.ndarray, colors, thickness: Optional[float] = None,
               visible: bool = True) -> None:
        """Draws line segments: one-pixel lines (a GLB of GL lines, ``lines.py``: cheap for
        the many edges, boxes and nesting lines of a layer), or viser's wide lines of
        ``thickness`` screen pixels (few segments: the agent's trajectory), updated in
        place like ``_cloud``."""
        if thickness is None:
            glb = line_segments_glb(segments, colors)
            self._put(name, kind, self.server.scene.add_glb(path, glb, visible=visible, cast_shadow=False,
                                                            receive_shadow=False))
            return
        colors = np.ascontiguousarray(np.broadcast_to(np.asarray(colors, np.uint8).reshape(-1, 1, 3)
                                                      if np.ndim(colors) == 2 else np.asarray(colors, np.uint8),
                                                      (len(segments), 2, 3)))
        handle = self._handles.get((name, kind))
        if isinstance(handle, viser.LineSegmentsHandle) and handle.name == path:
            handle.points = np.asarray(segments, np.float32)
            handle.colors = colors
            return
        self._put(name, kind, self.server.scene.add_line_segments(path, segments, colors, thickness=thickness,
                                                                  thickness_units="screen", visible=visible))

    def _drop(self, name: str, kind: str) -> None:
        handle = self._handles.pop((name, kind), None)
        if handle is not None:
            handle.remove()

    def _send_layer(self, name: str) -> None:
        d = self.drawing.layers[name]
        self._ensure_role_toggle(d.role)
        base = f"/{d.role}/{_safe(name)}"
        if len(d.ids) and d.role != "mesh":
            self._cloud(
                name, "nodes", f"{base}/nodes", d.positions, d.colors, point_size=self.style.node_size(d.role),
                point_shape="circle", point_shading="flat", precision="float32", visible=self._visible(d.role, "nodes"),
            )
        else:
            self._drop(name, "nodes")
        if len(d.edges):
            self._lines(
                name, "edges", f"{base}/edges", d.edges, ROLE_COLORS_EDGE.get(d.role, (60, 60, 60)),
                thickness=4.0 if d.role == "agents" else None, visible=self._visible(d.role, "edges"),
            )
        else:
            self._drop(name, "edges")
        if len(d.boxes):
            self._lines(name, "boxes", f"{base}/boxes", d.boxes, d.box_colors, visible=self._visible(d.role, "boxes"))
        else:
            self._drop(name, "boxes")
        if len(d.mesh_points) and self._file_mesh is None:
            self._cloud(
                name, "mesh", f"{base}/mesh", d.mesh_points, d.mesh_colors, point_size=self.style.mesh_point_size,
                visible=self._visible(d.role, "mesh"),
            )
        else:
            self._drop(name, "mesh")

    def _send_nesting(self, name: str) -> None:
        d = self.drawing.layers[name]
        segs = self.drawing.nesting.get(name)
        if segs is None or not len(segs):
            self._drop(name, "nesting")
            return
        self._lines(name, "nesting", f"/{d.role}/{_safe(name)}/nesting", segs, (200, 200, 200),
                    visible=self._visible(d.role, "nesting"))

    def _send_file_mesh(self) -> None:
        self._drop("<file>", "mesh")
        if self._file_mesh is not None:
            self._put("<file>", "mesh", self.server.scene.add_point_cloud(
                "/mesh/file", self._file_mesh.points[:: self.style.mesh_stride],
                self._file_mesh.colors[:: self.style.mesh_stride],
                point_size=self.style.mesh_point_size, visible=self._visible("mesh", "mesh"),
            ))

    def _update_legend(self) -> None:
        legend = self.drawing.legend()
        if legend == self._legend_shown:
            return
        self._legend_shown = legend
        rows = "".join(
            f'<div style="font-size:0.8em"><span style="display:inline-block;width:0.9em;height:0.9em;'
            f'background:rgb{color};margin-right:0.4em"></span>{html.escape(label)}</div>'
            for label, color in legend.items()
        )
        self._legend.content = rows or "<i>no labels</i>"

    def _set_camera(self) -> None:
        pts = [d.positions for d in self.drawing.layers.values() if len(d.positions)]
        if not pts:
            return
        allp = np.concatenate(pts)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        center = (lo + hi) / 2.0
        extent = float(max(hi[0] - lo[0], hi[1] - lo[1], 1.0))
        self.server.initial_camera.look_at = tuple(center)
        self.server.initial_camera.position = (center[0], center[1] - 0.75 * extent, center[2] + 0.55 * extent)
        self._camera_set = True

    # ------------------------------------------------------------------ interaction
    def _clicked(self, event) -> None:
        """A click in the scene selects the shown node nearest to its ray (mesh aside)."""
        with self._lock:
            shown = [n for n, d in self.drawing.layers.items() if d.role != "mesh" and self._visible(d.role, "nodes")]
            hit = self.drawing.nearest_node(event.ray_origin, event.ray_direction, shown)
            if hit is not None:
                self.select(hit[0])

    def select(self, node_id: int) -> dict:
        """Shows a node's details (id, layer, labels, features, parent, children, box) in
        the panel and marks it; returns them."""
        with self._lock:
            scene = self.drawing.scene
            node = scene.node(node_id)
            details = {
                "id": node.id, "layer": node.layer, "labels": node.labels, "features": node.features,
                "parent": node.parent, "children": len(node.children), "points": int(len(node.points)),
                "aabb": node.aabb,
            }
            d = self.drawing.layers[node.layer]
            row = int(np.searchsorted(d.ids, np.uint64(node_id)))
            self.server.scene.add_point_cloud(
                "/selected", d.positions[row:row + 1], SELECTED, point_size=self.style.node_size(d.role) * 2.5,
                point_shape="circle",
            )
            text = "\n".join(f"- **{k}**: `{json.dumps(v, default=str)}`" for k, v in details.items())
            self._details.content = text
            self.emit({"event": "selected", **{k: details[k] for k in ("id", "layer", "labels")}})
            return details

    def set_query(self, text: Optional[str]) -> Optional[QueryDrawing]:
        """Draws a query line of the contract on the scene shown (and on every later one):
        its answer's objects highlighted, its point, ball or cone drawn; ``None`` clears it.
        A bad query is reported in the panel and raises ``ValueError``."""
        with self._lock:
            if text is None or not str(text).strip():
                self._query = None
                for kind in ("query-shape", "query-ids", "query-boxes"):
                    self._drop("<query>", kind)
                self._query_result.content = ""
                return None
            try:
                self._query = parse_query(text)
            except ValueError as e:
                self._query_result.content = f"**error**: {html.escape(str(e))}"
                raise
            self._query_text.value = json.dumps(self._query)
            return self._draw_query()

    def _run_typed_query(self) -> None:
        try:
            self.set_query(self._query_text.value or None)
        except ValueError:
            pass  # set_query wrote the error in the panel

    def _draw_query(self) -> Optional[QueryDrawing]:
        scene = self.drawing.scene
        if scene is None or self._query is None:
            return None
        try:
            drawn = answer(scene, self._query)
        except Exception as e:  # the scene's QueryError: shown, and the query kept for the next scene
            self._query_result.content = f"**error**: {html.escape(str(e))}"
            return None
        positions = self.drawing.positions_of(drawn.ids)
        scene_api = self.server.scene
        if len(drawn.shape):
            self._put("<query>", "query-shape", scene_api.add_line_segments(
                "/query/shape", drawn.shape, QUERY_SHAPE, thickness=3.0, thickness_units="screen"))
        else:
            self._drop("<query>", "query-shape")
        if len(positions):
            self._put("<query>", "query-ids", scene_api.add_point_cloud(
                "/query/answer", positions, HIGHLIGHT, point_size=self.style.node_size("objects") * 1.5,
                point_shape="circle"))
        else:
            self._drop("<query>", "query-ids")
        boxes = self.drawing.boxes_of(drawn.ids)
        if len(boxes):
            self._put("<query>", "query-boxes", scene_api.add_line_segments(
                "/query/boxes", boxes, HIGHLIGHT, thickness=3.0, thickness_units="screen"))
        else:
            self._drop("<query>", "query-boxes")
        shown = ", ".join(str(i) for i in drawn.ids[:20]) + (" ..." if len(drawn.ids) > 20 else "")
        self._query_result.content = f"**{len(drawn.ids)} objects**: {shown}"
        self.emit({"event": "query", "op": drawn.query["op"], "ids": drawn.ids, "generation": scene.generation})
        return drawn

    # ------------------------------------------------------------------ timeline
    def attach_timeline(self, timeline: Timeline, on_show: Callable[[int], None]) -> None:
        """Adds the timeline slider; moving it calls ``on_show(index)``."""
        gui = self.server.gui
        with gui.add_folder("Timeline", expand_by_default=True):
            label = gui.add_markdown(timeline.entries[0].label)
            slider = gui.add_slider("scene", min=0, max=max(len(timeline) - 1, 1), step=1, initial_value=0,
                                    disabled=len(timeline) < 2)

        def moved(_event) -> None:
            index = int(slider.value)
            label.content = timeline.entries[index].label
            on_show(index)

        slider.on_update(moved)

    def stop(self) -> None:
        """Stops the server and lets go of the scene shown (a live snapshot holds the
        reader's shared memory)."""
        self.server.stop()
        self.drawing.scene = None

