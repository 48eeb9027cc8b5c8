"""A query of the ``ygg query`` contract made visible: its answer (object ids, to
highlight) and its shape as line segments (the query point, the ball of
``objects_within``, the cone of ``visible_objects``). No viewer library here."""
from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Union

import numpy as np

#: The query ops of the contract (docs/cli.md) and the fields each one needs.
QUERY_FIELDS: Dict[str, tuple] = {
    "nearest_object": ("point",),
    "objects_within": ("point", "radius"),
    "visible_objects": ("eye", "dir", "half_angle_deg", "range"),
    "objects_with_label": ("label",),
}


@dataclass
class QueryDrawing:
    """A query answered on one scene: the answer's ids and the query's shape."""

    query: Dict[str, Any]
    ids: List[int]
    shape: np.ndarray
    """``(k, 2, 3)`` float32 segments: a cross at the point, three great circles of the
    ball, or the cone's rim and eight rays from the eye (empty for a label query)."""


def parse_query(text: Union[str, Mapping[str, Any]]) -> Dict[str, Any]:
    """A query line (JSON text or a dict) checked for its op and fields; raises
    ``ValueError`` naming what is wrong."""
    if isinstance(text, Mapping):
        q = dict(text)
    else:
        try:
            q = json.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"query {text!r}: not JSON ({e})") from None
        if not isinstance(q, dict):
            raise ValueError(f"query {text!r}: expected a JSON object")
    op = q.get("op")
    if op not in QUERY_FIELDS:
        raise ValueError(f"query {json.dumps(q)}: unknown op {op!r} (expected one of {', '.join(QUERY_FIELDS)})")
    missing = [f for f in QUERY_FIELDS[op] if f not in q]
    if missing:
        raise ValueError(f"query {json.dumps(q)}: {op} needs {', '.join(missing)}")
    return q


def _circle(center, u, v, radius, n=48) -> np.ndarray:
    a = np.linspace(0.0, 2.0 * np.pi, n + 1)
    ring = center + radius * (np.cos(a)[:, None] * u + np.sin(a)[:, None] * v)
    return np.stack([ring[:-1], ring[1:]], axis=1)


def _basis(direction) -> tuple:
    d = np.asarray(direction, np.float64)
    d = d / max(float(np.linalg.norm(d)), 1e-12)
    helper = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    return d, u, np.cross(d, u)


def query_shape(q: Mapping[str, Any]) -> np.ndarray:
    """The query's shape as ``(k, 2, 3)`` segments."""
    op = q["op"]
    if op in ("nearest_object", "objects_within"):
        p = np.asarray(q["point"], np.float64)
        size = 0.3
        segs = [np.stack([p - size * e, p + size * e]) for e in np.eye(3)]
        out = np.array(segs)
        if op == "objects_within":
            r = float(q["radius"])
            e = np.eye(3)
            out = np.concatenate([out] + [_circle(p, e[i], e[(i + 1) % 3], r) for i in range(3)])
        return out.astype(np.float32)
    if op == "visible_objects":
        eye = np.asarray(q["eye"], np.float64)
        d, u, v = _basis(q["dir"])
        half = np.radians(float(q["half_angle_deg"]))
        rng = float(q["range"])
        if half >= np.pi / 2:  # a cone wider than a half-space: draw its range ball's rim
            return _circle(eye, u, v, rng).astype(np.float32)
        center = eye + d * rng * np.cos(half)
        radius = rng * np.sin(half)
        rim = _circle(center, u, v, radius)
        a = np.linspace(0.0, 2.0 * np.pi, 9)[:-1]
        rays = [np.stack([eye, center + radius * (np.cos(t) * u + np.sin(t) * v)]) for t in a]
        return np.concatenate([rim, np.array(rays)]).astype(np.float32)
    return np.zeros((0, 2, 3), np.float32)


def answer(scene, q: Mapping[str, Any]) -> QueryDrawing:
    """Answers ``q`` on ``scene`` (``Scene.query``, the CLI's contract); raises
    ``yggdrasil.QueryError`` with the CLI's message."""
    ids = scene.query(dict(q))["ids"]
    return QueryDrawing(dict(q), [int(i) for i in ids], query_shape(q))
