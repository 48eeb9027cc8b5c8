"""``spark_dsg.Mesh`` over numpy arrays."""
from __future__ import annotations

from typing import Any, Dict, Iterable

import numpy as np


class Mesh:
    """A triangle mesh: per-vertex position (float32), color (RGBA uint8), timestamp,
    first-seen timestamp and label; faces as vertex index triples."""

    def __init__(self, has_colors: bool = True, has_timestamps: bool = True, has_labels: bool = True, has_first_seen_stamps: bool = True):
        self.has_colors = has_colors
        self.has_timestamps = has_timestamps
        self.has_labels = has_labels
        self.has_first_seen_stamps = has_first_seen_stamps
        self.clear()

    def clear(self) -> None:
        """Removes every vertex and face."""
        self._points = np.zeros((0, 3), dtype=np.float32)
        self._colors = np.zeros((0, 4), dtype=np.uint8)
        self._stamps = np.zeros(0, dtype=np.uint64)
        self._first_seen = np.zeros(0, dtype=np.uint64)
        self._labels = np.zeros(0, dtype=np.uint32)
        self._faces = np.zeros((0, 3), dtype=np.uint64)

    def empty(self) -> bool:
        """Whether the mesh has no vertex and no face."""
        return len(self._points) == 0 and len(self._faces) == 0

    def num_vertices(self) -> int:
        """Number of vertices."""
        return len(self._points)

    def num_faces(self) -> int:
        """Number of faces."""
        return len(self._faces)

    def _vertex(self, i: int) -> int:
        if not 0 <= i < len(self._points):
            raise IndexError(f"vertex {i} is out of range (the mesh has {len(self._points)})")
        return i

    def resize_vertices(self, n: int) -> None:
        """Grows (zero-filled) or shrinks the vertex arrays to ``n``."""
        m = len(self._points)

        def fit(a: np.ndarray) -> np.ndarray:
            if n <= m:
                return a[:n].copy()
            return np.concatenate([a, np.zeros((n - m,) + a.shape[1:], dtype=a.dtype)])

        self._points, self._colors, self._stamps = fit(self._points), fit(self._colors), fit(self._stamps)
        self._first_seen, self._labels = fit(self._first_seen), fit(self._labels)
        if n > m:
            self._colors[m:, 3] = 255

    def resize_faces(self, n: int) -> None:
        """Grows (zero-filled) or shrinks the face array to ``n``."""
        m = len(self._faces)
        self._faces = self._faces[:n].copy() if n <= m else np.concatenate([self._faces, np.zeros((n - m, 3), dtype=np.uint64)])

    def set_pos(self, i: int, pos) -> None:
        """Sets vertex ``i``'s position."""
        self._points[self._vertex(i)] = np.asarray(pos, dtype=np.float32).reshape(3)

    def pos(self, i: int) -> np.ndarray:
        """Vertex ``i``'s position."""
        return self._points[self._vertex(i)].astype(np.float64)

    def set_color(self, i: int, color) -> None:
        """Sets vertex ``i``'s color (RGB or RGBA, 0-255)."""
        c = np.asarray(color, dtype=np.uint8).reshape(-1)
        self._colors[self._vertex(i), : len(c)] = c

    def color(self, i: int) -> np.ndarray:
        """Vertex ``i``'s RGBA color."""
        return self._colors[self._vertex(i)].copy()

    def set_timestamp(self, i: int, stamp: int) -> None:
        """Sets vertex ``i``'s timestamp (ns)."""
        self._stamps[self._vertex(i)] = stamp

    def timestamp(self, i: int) -> int:
        """Vertex ``i``'s timestamp (ns)."""
        return int(self._stamps[self._vertex(i)])

    def set_first_seen_timestamp(self, i: int, stamp: int) -> None:
        """Sets vertex ``i``'s first-seen timestamp (ns)."""
        self._first_seen[self._vertex(i)] = stamp

    def first_seen_timestamp(self, i: int) -> int:
        """Vertex ``i``'s first-seen timestamp (ns)."""
        return int(self._first_seen[self._vertex(i)])

    def set_label(self, i: int, label: int) -> None:
        """Sets vertex ``i``'s semantic label."""
        self._labels[self._vertex(i)] = label

    def label(self, i: int) -> int:
        """Vertex ``i``'s semantic label."""
        return int(self._labels[self._vertex(i)])

    def get_labels(self) -> list:
        """Every vertex's label."""
        return self._labels.tolist()

    def set_face(self, i: int, face) -> None:
        """Sets face ``i`` (three vertex indices)."""
        if not 0 <= i < len(self._faces):
            raise IndexError(f"face {i} is out of range (the mesh has {len(self._faces)})")
        self._faces[i] = np.asarray(face, dtype=np.uint64).reshape(3)

    def face(self, i: int) -> np.ndarray:
        """Face ``i``'s vertex indices."""
        return self._faces[i].copy()

    def set_faces(self, faces) -> None:
        """Replaces the faces with a ``(3, m)`` index array."""
        f = np.asarray(faces)
        if f.ndim != 2 or f.shape[0] != 3:
            raise ValueError(f"faces are a (3, m) array, not shape {f.shape}")
        self._faces = f.T.astype(np.uint64)

    def get_faces(self) -> np.ndarray:
        """The faces as a ``(3, m)`` index array."""
        return self._faces.T.copy()

    def set_vertices(self, vertices) -> None:
        """Replaces the vertices with a ``(3, n)`` positions or ``(6, n)`` positions and
        RGB colors in ``[0, 1]`` array."""
        v = np.asarray(vertices, dtype=np.float64)
        if v.ndim != 2 or v.shape[0] not in (3, 6):
            raise ValueError(f"vertices are a (3, n) or (6, n) array, not shape {v.shape}")
        self.resize_vertices(v.shape[1])
        self._points[:] = v[:3].T
        if v.shape[0] == 6:
            self._colors[:, :3] = np.clip(np.round(v[3:].T * 255), 0, 255).astype(np.uint8)

    def get_vertices(self) -> np.ndarray:
        """A ``(6, n)`` array: positions, then RGB colors in ``[0, 1]``."""
        return np.vstack([self._points.T.astype(np.float64), self._colors[:, :3].T / 255.0])

    def erase_faces(self, indices: Iterable[int], update_vertices: bool = True) -> None:
        """Removes these faces; with ``update_vertices``, also the vertices no face uses any more."""
        keep = np.ones(len(self._faces), dtype=bool)
        keep[[i for i in indices if 0 <= i < len(keep)]] = False
        self._faces = self._faces[keep]
        if update_vertices:
            used = np.zeros(len(self._points), dtype=bool)
            used[self._faces.reshape(-1).astype(np.int64)] = True
            self._keep_vertices(used)

    def erase_vertices(self, indices: Iterable[int]) -> None:
        """Removes these vertices and every face using one of them."""
        keep = np.ones(len(self._points), dtype=bool)
        keep[[i for i in indices if 0 <= i < len(keep)]] = False
        self._keep_vertices(keep)

    def _keep_vertices(self, keep: np.ndarray) -> None:
        new_index = np.cumsum(keep) - 1
        faces = self._faces.astype(np.int64)
        whole = keep[faces].all(axis=1) if len(faces) else np.zeros(0, dtype=bool)
        self._faces = new_index[faces[whole]].astype(np.uint64).reshape(-1, 3)
        self._points, self._colors = self._points[keep], self._colors[keep]
        self._stamps, self._first_seen, self._labels = self._stamps[keep], self._first_seen[keep], self._labels[keep]

    def clone(self) -> "Mesh":
        """A deep copy."""
        other = Mesh(self.has_colors, self.has_timestamps, self.has_labels, self.has_first_seen_stamps)
        for k in ("_points", "_colors", "_stamps", "_first_seen", "_labels", "_faces"):
            setattr(other, k, getattr(self, k).copy())
        return other

    def append(self, other: "Mesh") -> None:
        """Appends another mesh's vertices and faces (its indices shifted)."""
        n = len(self._points)
        for k in ("_points", "_colors", "_stamps", "_first_seen", "_labels"):
            setattr(self, k, np.concatenate([getattr(self, k), getattr(other, k)]))
        self._faces = np.concatenate([self._faces, other._faces + np.uint64(n)])

    def _to_json(self) -> Dict[str, Any]:
        c = self._colors
        return {
            "colors": [{"a": int(a), "b": int(b), "g": int(g), "r": int(r)} for r, g, b, a in c.tolist()] if self.has_colors else [],
            "faces": self._faces.tolist(),
            "first_seen_stamps": self._first_seen.tolist() if self.has_first_seen_stamps else [],
            "has_colors": self.has_colors,
            "has_first_seen_stamps": self.has_first_seen_stamps,
            "has_labels": self.has_labels,
            "has_timestamps": self.has_timestamps,
            "header": {"project_name": "main", "version": {"major": 1, "minor": 1, "patch": 3}},
            "labels": self._labels.tolist() if self.has_labels else [],
            "points": self._points.astype(np.float64).tolist(),
            "stamps": self._stamps.tolist() if self.has_timestamps else [],
        }

    @classmethod
    def _from_arrays(cls, parts) -> "Mesh":
        """A mesh from ``_yggdrasil.spark_dsg_json_mesh``'s flags and arrays."""
        flags, points, colors, stamps, labels, first_seen, faces = parts
        m = cls(*flags)
        m._points, m._colors, m._stamps, m._labels, m._first_seen, m._faces = points, colors, stamps, labels, first_seen, faces
        return m

    @classmethod
    def _from_json(cls, d: Dict[str, Any]) -> "Mesh":
        m = cls(d.get("has_colors", True), d.get("has_timestamps", True), d.get("has_labels", True), d.get("has_first_seen_stamps", True))
        m._points = np.asarray(d.get("points") or np.zeros((0, 3)), dtype=np.float32).reshape(-1, 3)
        n = len(m._points)

        def column(key: str, dtype) -> np.ndarray:
            v = d.get(key) or []
            return np.asarray(v, dtype=dtype) if len(v) == n else np.zeros(n, dtype=dtype)

        colors = d.get("colors") or []
        m._colors = np.zeros((n, 4), dtype=np.uint8)
        m._colors[:, 3] = 255
        if len(colors) == n and n:
            m._colors[:] = [(c.get("r", 0), c.get("g", 0), c.get("b", 0), c.get("a", 255)) if isinstance(c, dict) else tuple(c)[:4] for c in colors]
        m._stamps, m._first_seen = column("stamps", np.uint64), column("first_seen_stamps", np.uint64)
        m._labels = column("labels", np.uint32)
        m._faces = np.asarray(d.get("faces") or np.zeros((0, 3)), dtype=np.uint64).reshape(-1, 3)
        return m

    def __repr__(self) -> str:
        return f"Mesh<vertices={self.num_vertices()}, faces={self.num_faces()}>"

