"""S3DSG (Social 3D Scene Graphs; its code is not public): the social cost field, from
the original's hand-rolled indexes against Yggdrasil's metric layers.

Assumptions (from the paper's description; stated in the results):

* The apartment: 10 m x 8 m, 83 objects (boxes of 0.1-2 m) with 84 relation edges
  between them, and a floor. Each object's Open3D cloud is its box's surface sampled at
  about 400 points per m^2 (60-1,500 points per object); the floor is a 5 cm grid
  (32,000 points). Positions are float32-representable (Yggdrasil keeps float32 points).
* The original keeps the scene in NetworkX with a cloud on every object node, one
  ``scipy.spatial.cKDTree`` per object and one over the floor (built once, not timed),
  and takes the minimum over the 84 trees for each query point.
* Yggdrasil keeps the same points as three position-indexed metric layers of one node
  per point (``FLOOR_POINTS``; ``FURNITURE_POINTS`` for objects larger than 0.5 m;
  ``ITEM_POINTS`` for the rest), each point nested under its object in an ``OBJECTS``
  layer carrying the 84 relation edges; the minimum is over the three layers.
* The cost field: a 179 x 141 grid (7 cm) at 0.4 m above the floor, 25,239 points, so
  84 x 25,239 = 2,120,076 nearest-neighbour queries for the original (the paper:
  2,115,650). cost(p) = exp(-d(p)^2 / (2 * 0.3^2)) for the clearance d(p) (distance to
  the nearest point of any cloud) plus a Gaussian around the segment between two
  interacting people (sigma 0.5 m); identical arithmetic on both sides.
* "One query at a time": a Python loop over grid points, one tree query per object and
  the floor (original) or one ``nearest_nodes`` per layer (Yggdrasil). The original is
  timed on a uniform random sample of grid points and its field time is the sample's
  mean per point times the grid; Yggdrasil answers every point. "Batch": the original
  queries each tree with the whole grid and reduces with ``np.minimum``; Yggdrasil calls
  ``nearest_nodes_many`` once per layer.
"""
from __future__ import annotations

import math
import statistics

import numpy as np

from ._common import perf_ns

LAYERS = ("FLOOR_POINTS", "FURNITURE_POINTS", "ITEM_POINTS")
SIGMA, SOCIAL_SIGMA, Z = 0.3, 0.5, 0.4
PEOPLE = (np.array([4.0, 3.0]), np.array([5.2, 3.6]))
PAPER = {"cost field": (6885, 4936)}          # ms


def apartment(seed=3, objects=83, relations=84):
    rng = np.random.default_rng(seed)
    clouds, kinds, boxes = [], [], []
    for _ in range(objects):
        size = rng.uniform([0.1, 0.1, 0.1], [2.0, 1.2, 1.2]) * (1.0 if rng.random() < 0.4 else 0.35)
        lo = np.array([rng.uniform(0.2, 9.8 - size[0]), rng.uniform(0.2, 7.8 - size[1]), 0.0])
        lo[2] = 0.0 if size[2] > 0.3 else rng.uniform(0.4, 1.0)
        hi = lo + size
        area = 2 * (size[0] * size[1] + size[0] * size[2] + size[1] * size[2])
        n = int(np.clip(area * 400, 60, 1500))
        pts = rng.uniform(lo, hi, size=(n, 3))
        face = rng.integers(0, 3, n)                   # snap each point onto a face
        side = rng.random(n) < 0.5
        pts[np.arange(n), face] = np.where(side, lo[face], hi[face])
        clouds.append(pts.astype(np.float32).astype(np.float64))
        kinds.append("FURNITURE_POINTS" if size.max() > 0.5 else "ITEM_POINTS")
        boxes.append((lo, hi))
    gx, gy = np.meshgrid(np.arange(0, 10, 0.05), np.arange(0, 8, 0.05), indexing="ij")
    floor = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], 1).astype(np.float32).astype(np.float64)
    pairs = set()
    while len(pairs) < relations:
        a, b = (int(x) for x in rng.integers(0, objects, 2))
        if a != b:
            pairs.add((min(a, b), max(a, b)))
    return clouds, kinds, floor, sorted(pairs)


def grid(nx_=179, ny=141):
    gx, gy = np.meshgrid(np.linspace(0.05, 9.95, nx_), np.linspace(0.05, 7.95, ny), indexing="ij")
    return np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, Z)], 1)


def cost(clearance, points):
    """The cost field from the clearance (vectorised; the same on both sides)."""
    a, b = PEOPLE
    ab = b - a
    t = np.clip(((points[:, :2] - a) @ ab) / (ab @ ab), 0, 1)
    social = np.linalg.norm(points[:, :2] - (a + t[:, None] * ab), axis=1)
    return np.exp(-clearance ** 2 / (2 * SIGMA ** 2)) + np.exp(-social ** 2 / (2 * SOCIAL_SIGMA ** 2))


def cost_one(clearance, p):
    a, b = PEOPLE
    ab = b - a
    t = min(max(((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / (ab @ ab), 0.0), 1.0)
    social = math.hypot(p[0] - a[0] - t * ab[0], p[1] - a[1] - t * ab[1])
    return math.exp(-clearance ** 2 / (2 * SIGMA ** 2)) + math.exp(-social ** 2 / (2 * SOCIAL_SIGMA ** 2))


class Original:
    """NetworkX with a cloud per node, a cKDTree per object and one over the floor."""

    def __init__(self, clouds, floor, pairs):
        import networkx as nx
        from scipy.spatial import cKDTree
        t0 = perf_ns()
        self.g = nx.Graph()
        self.g.add_node("floor", cloud=floor)
        for i, c in enumerate(clouds):
            self.g.add_node(i, cloud=c)
        for a, b in pairs:
            self.g.add_edge(a, b, relation="near")
        self.trees = [cKDTree(d["cloud"]) for _, d in self.g.nodes(data=True)]
        self.build_ns = perf_ns() - t0

    def field_one(self, points):
        out = []
        trees = self.trees
        for p in points:
            out.append(cost_one(min(t.query(p)[0] for t in trees), p))
        return np.array(out)

    def field_batch(self, points):
        clearance = np.full(len(points), np.inf)
        for t in self.trees:
            np.minimum(clearance, t.query(points)[0], out=clearance)
        return cost(clearance, points)


class Yggdrasil:
    """Three position-indexed metric layers of one node per point under OBJECTS."""

    def __init__(self, clouds, kinds, floor, pairs):
        import yggdrasil
        t0 = perf_ns()
        g = yggdrasil.SceneGraph()
        g.add_layer("OBJECTS")
        for name in LAYERS:
            g.add_layer(name)
            g.add_layer_edge("OBJECTS", name)
        next_id = 1 << 32
        owners = [(0, "FLOOR_POINTS", floor)] + [(i + 1, k, c) for i, (k, c) in enumerate(zip(kinds, clouds))]
        for oid, layer, cloud in owners:
            g.add_node(oid, "OBJECTS")
            for p in cloud:
                g.add_node(next_id, layer)
                g.set_geometry(next_id, [p])
                g.nest(oid, next_id)
                next_id += 1
        for a, b in pairs:
            g.add_edge(a + 1, b + 1, "near")
            g.add_edge(b + 1, a + 1, "near")
        for name in LAYERS:
            g.enable_layer_index(name)
        self.scene = g.snapshot()
        self.build_ns = perf_ns() - t0
        self.nodes = next_id - (1 << 32)

    def field_one(self, points):
        nearest = self.scene.nearest_nodes
        out = []
        for p in points.tolist():
            out.append(cost_one(min(nearest(p, 1, layer)[0][1] for layer in LAYERS), p))
        return np.array(out)

    def field_batch(self, points):
        clearance = np.full(len(points), np.inf)
        for layer in LAYERS:
            _, d = self.scene.nearest_nodes_many(points, layer)
            np.minimum(clearance, d, out=clearance)
        return cost(clearance, points)


def _median_ms(fn, reps):
    times, out = [], None
    for _ in range(reps):
        t0 = perf_ns()
        out = fn()
        times.append((perf_ns() - t0) / 1e6)
    return statistics.median(times), out


def study(quick, progress=None):
    clouds, kinds, floor, pairs = apartment()
    original = Original(clouds, floor, pairs)
    ygg = Yggdrasil(clouds, kinds, floor, pairs)
    points = grid()
    n = len(points)
    sample = np.sort(np.random.default_rng(9).choice(n, 400 if quick else 4000, replace=False))
    # one query at a time
    reps = 3
    o_ms, o_cost = _median_ms(lambda: original.field_one(points[sample]), reps)
    y_ms, y_cost = _median_ms(lambda: ygg.field_one(points), reps)
    worst_one = float(np.max(np.abs(o_cost - y_cost[sample])))
    if worst_one > 1e-5:
        raise AssertionError(f"S3DSG: one-at-a-time cost fields differ by {worst_one:.3g} (> 1e-5)")
    o_field = o_ms * n / len(sample)
    if progress:
        progress.step("S3DSG one query at a time")
    ob_ms, ob_cost = _median_ms(lambda: original.field_batch(points), reps)
    yb_ms, yb_cost = _median_ms(lambda: ygg.field_batch(points), reps * 2)
    worst_batch = float(np.max(np.abs(ob_cost - yb_cost)))
    if worst_batch > 1e-5:
        raise AssertionError(f"S3DSG: batch cost fields differ by {worst_batch:.3g} (> 1e-5)")
    if float(np.max(np.abs(y_cost - yb_cost))) > 1e-5:
        raise AssertionError("S3DSG: Yggdrasil's one-at-a-time and batch fields differ")
    if progress:
        progress.step("S3DSG batch")
    po, py = PAPER["cost field"]
    rows = [
        {"study": "S3DSG", "scene": None, "operation": "cost field", "unit": "ms", "original": o_field,
         "yggdrasil": y_ms, "ratio": o_field / y_ms, "paper_original": po, "paper_yggdrasil": py,
         "paper_ratio": po / py, "calls": n * len(original.trees)},
        {"study": "S3DSG", "scene": None, "operation": "cost field (batch)", "unit": "ms", "original": ob_ms,
         "yggdrasil": yb_ms, "ratio": ob_ms / yb_ms, "paper_original": None, "paper_yggdrasil": None,
         "paper_ratio": None, "calls": n * len(original.trees)},
    ]
    total_points = sum(len(c) for c in clouds) + len(floor)
    note = "\n".join([
        "## S3DSG: how it was run", "",
        f"- {len(clouds)} objects ({sum(k == 'FURNITURE_POINTS' for k in kinds)} furniture, "
        f"{sum(k == 'ITEM_POINTS' for k in kinds)} items; {min(map(len, clouds))}-{max(map(len, clouds))} "
        f"points each), {len(pairs)} relation edges, a floor of {len(floor):,} points: {total_points:,} points, "
        f"{len(original.trees)} trees for the original, {ygg.nodes:,} point nodes in 3 layers for Yggdrasil. "
        f"Grid: {n:,} points, {n * len(original.trees):,} nearest-neighbour queries for the original. "
        f"Builds (not in the rows, as in the paper): the original's graph and trees "
        f"{original.build_ns / 1e6:.0f} ms, Yggdrasil's graph through the Python API, one node per point, "
        f"{ygg.build_ns / 1e6:.0f} ms.",
        f"- One query at a time: the original on a uniform sample of {len(sample):,} grid points "
        f"({o_ms:.0f} ms, median of {reps}), scaled to the grid; Yggdrasil on every point (median of {reps}). "
        f"Batch: whole grid, median of {reps} (original) and {reps * 2} (Yggdrasil) evaluations; "
        "`nearest_nodes_many` runs without the GIL on both cores.",
        f"- Agreement: largest cost difference {worst_one:.2g} (one at a time, on the sample) and "
        f"{worst_batch:.2g} (batch, every point); the check is 1e-5.",
        "- Why the ratios are far above the paper's 1.39×: the original's per-object trees cost one Python "
        "call each per query point (84 per point) where Yggdrasil's layers cost three; in batch the "
        "original's 84 vectorised tree queries stay in C but each touches every grid point. The paper's "
        "original is not public, so how it batched is unknown; both forms are shown.",
    ])
    batch = rows[1]["ratio"]
    if batch < 10:
        note += ("\n- The batch target (10×) is missed in this run: "
                 f"{batch:.1f}×. The original's 84 tree queries are single-threaded C loops over the grid; "
                 "Yggdrasil's three `nearest_nodes_many` calls split the grid over both cores, which the "
                 "other CI build on this machine shares (see the load average above), and its per-query "
                 "cost in the two larger layers is close to a `cKDTree`'s. Tried: float32 input (no "
                 "change), one call per layer (the form used); merging layers would change the design "
                 "the paper describes.")
    for s in __doc__.split("Assumptions")[1:]:
        note += "\n\nAssumptions" + s.rstrip()
    return rows, note
