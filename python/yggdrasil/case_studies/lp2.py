"""LP2 (MIT-SPARK/LP2): its scene-graph backend, spark_dsg + NetworkX, against Yggdrasil.

Only the scene-graph interaction differs between the two backends; the application
logic (``LP2Run``: one prediction per trajectory, as LP2's pipeline makes it) is shared.
What each backend does is what LP2's code does (read for behaviour, not copied):

* build (``on_episode_init`` of the goal and the planning module): the original copies the
  places layer to NetworkX and, for every place, scans every interlayer edge for the one
  whose target is the place (its room), twice (each module builds its own copy); a
  ``cKDTree`` over the places per module; the objects layer to NetworkX; per object its
  nearest place (tree query, then an O(places) list) and its parent (another edge scan);
  ``nx.single_source_dijkstra`` from each object's place, stored as dicts.
  Yggdrasil: the facade (``yggdrasil.dsg``) loads the same file, a kd-tree is kept on the
  PLACES layer, positions and parents come from the layer's columns, the nearest place
  from ``nearest_nodes``, shortest paths from one ``scipy.sparse.csgraph.dijkstra`` call
  over the facade's edge weights (a path is rebuilt from the distances when first asked,
  with NetworkX's choice among equally short paths, then kept).
* room of a waypoint (``low_level_ctmc.get_node_data``, per node of every predicted path):
  an interlayer-edge scan against ``scene.parent``.
* nearest waypoint (``get_closest_node`` with the tree): ``nearest_nodes(p, 1, "PLACES")``.
* waypoints within 0.5 m (``get_closest_nodes``: an O(places) nearest scan and a dict
  over every place): ``nearest_nodes`` + ``nodes_within_radius`` (radius 0.5 + 1e-4, then
  the exact ``<= 0.5`` test on the same float64 distances LP2 computes).
* shortest-path lookup (``shortest_paths_between_objects[a][b]``) and grounding distances
  (``compute_instance_probabilities``: one distance lookup per instance of a class).

The LLM is replaced by a seeded choice of classes (the same for both backends), standing
in for LP2's recorded responses.
"""
from __future__ import annotations

import math
import os
import random

import numpy as np

from . import _lp2_data
from ._common import Timings, euclid, perf_ns

MASK56 = (1 << 56) - 1
ROOM = "room of a waypoint"
NEAREST = "nearest waypoint"
WITHIN = "waypoints within 0.5 m"
LOOKUP = "shortest-path lookup"
GROUNDING = "grounding distances"
BUILD = "build time"
OTHER = "other lookups"
OPS = (ROOM, NEAREST, WITHIN, LOOKUP, GROUNDING)
# The paper's Table (office, home): per-call medians in us, build and total in ms.
PAPER = {
    "office": {ROOM: (987, 1.13), NEAREST: (169, 5.7), WITHIN: (8420, 79), LOOKUP: (0.50, 0.63),
               GROUNDING: (20, 23), BUILD: (2681, 35), "total graph time": (7747, 31)},
    "home": {ROOM: (725, 1.14), NEAREST: (134, 5.3), WITHIN: (5981, 69), LOOKUP: (0.50, 0.65),
             GROUNDING: (14, 14), BUILD: (1355, 27), "total graph time": (1752, 21)},
}


def category_id(node):
    return node & MASK56


# ------------------------------------------------------------------ original backend
class OriginalBackend:
    """spark_dsg 1.1.3 + NetworkX + scipy, as LP2 uses them."""

    name = "original"

    def __init__(self, path):
        import networkx  # noqa: F401  (imports are not build time)
        import scipy.spatial  # noqa: F401
        import spark_dsg
        import spark_dsg.networkx  # noqa: F401
        self.sd = spark_dsg
        t0 = perf_ns()
        self.G = spark_dsg.DynamicSceneGraph.load(path)
        self.load_ns = perf_ns() - t0

    def _construct_places_layer_nx(self):
        import spark_dsg.networkx as dsg_nx
        places = dsg_nx.layer_to_networkx(self.G.get_layer(self.sd.DsgLayers.PLACES))
        for node in places.nodes:
            room = [self.sd.NodeSymbol(e.source).category_id
                    for e in self.G.interlayer_edges if e.target == node]
            places.nodes[node]["room_id"] = room[0] if room else -1
        return places

    def _closest(self, places, position, kdtree):
        idx = kdtree.query(position)[1]
        node = list(places.nodes(data=True))[idx][0]
        return node, euclid(position, places.nodes[node]["position"][:len(position)])

    def build(self):
        import networkx as nx
        import spark_dsg.networkx as dsg_nx
        from scipy.spatial import cKDTree
        # goal module
        self.places = self._construct_places_layer_nx()
        self.kdtree = cKDTree([d["position"] for _, d in self.places.nodes(data=True)])
        objects_nx = dsg_nx.layer_to_networkx(self.G.get_layer(self.sd.DsgLayers.OBJECTS))
        info = {}
        for node in objects_nx.nodes:
            attrs = self.G.get_node(node).attributes
            position = list(attrs.position)
            nearest, dist = self._closest(self.places, position, self.kdtree)
            room = [self.sd.NodeSymbol(e.source).category_id
                    for e in self.G.interlayer_edges if e.target == node]
            info[node] = {"node_id": self.sd.NodeSymbol(node).category_id,
                          "semantic_class": attrs.name, "position": position,
                          "nearest_places_node": nearest,
                          "distance_to_nearest_places_node": dist,
                          "room_id": room[0] if room else -1}
        self.table = {}
        for obj in info.values():
            src = obj["nearest_places_node"]
            distances, paths = nx.single_source_dijkstra(self.places, src, weight="weight")
            self.table[src] = {k: {"path": paths[k], "distance": d} for k, d in distances.items()}
        # planning module: its own copy and tree
        self.planning_places = self._construct_places_layer_nx()
        self.planning_kdtree = cKDTree([d["position"] for _, d in self.planning_places.nodes(data=True)])
        return info

    def reference_node_data(self):
        """``get_node_data``'s answer for every place, from the scans the build made."""
        return {n: (d["position"][0], d["position"][1], d["room_id"] if d["room_id"] != -1 else 0)
                for n, d in self.places.nodes(data=True)}

    def nearest(self, position):
        return self._closest(self.places, position, self.kdtree)

    def closest_nodes(self, position):
        best, best_d = None, math.inf
        for node, data in self.places.nodes(data=True):          # get_closest_node, no tree
            d = euclid(position, data["position"][:len(position)])
            if d < best_d:
                best, best_d = node, d
        distances = {n: euclid(position, self.places.nodes[n]["position"]) for n in self.places.nodes}
        keep = [best] + [n for n in self.places.nodes if n != best and distances[n] <= 0.5]
        return {n: euclid(position, self.places.nodes[n]["position"]) for n in keep}

    def place_room(self, node):
        return self.places.nodes[node]["room_id"]

    def place_position(self, node):
        return self.planning_places.nodes[node]["position"]

    def edge_weight(self, a, b):
        return self.planning_places.edges[a, b]["weight"]

    def has_source(self, node):
        return node in self.table

    def path(self, src, dst):
        entry = self.table[src][dst]
        return entry["path"], entry["distance"]

    def distance(self, src, dst):
        return self.table[src][dst]["distance"]

    def node_data(self, node):
        position = self.G.get_node(node).attributes.position
        edge = [e for e in self.G.interlayer_edges if e.target == node]
        room = self.sd.NodeSymbol(edge[0].source).category_id if edge else 0
        return position[0], position[1], room


# ------------------------------------------------------------------ Yggdrasil backend
class YggdrasilBackend:
    """The drop-in facade ``yggdrasil.dsg`` plus Yggdrasil's own queries."""

    name = "yggdrasil"

    def __init__(self, path):
        import scipy.sparse.csgraph  # noqa: F401  (imports are not build time)
        import yggdrasil.dsg as dsg
        self.dsg = dsg
        t0 = perf_ns()
        self.G = dsg.DynamicSceneGraph.load(path)
        # The facade loads on first use: that is its load, as spark_dsg's load above
        # (edge weights are still parsed in build, when LP2 asks for them).
        self.graph = self.G.scene_graph
        self.places_layer = self.G.get_layer(dsg.DsgLayers.PLACES)
        self.load_ns = perf_ns() - t0

    def build(self):
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import dijkstra
        graph = self.graph
        graph.enable_layer_index("PLACES")
        self.scene = scene = graph.snapshot()
        ids, pos, _, _, _, parents, _ = scene.layer("PLACES").spark_dsg_columns()
        self.ids = ids
        self.row = {n: i for i, n in enumerate(ids)}
        self.pos = pos
        self.pos_of = dict(zip(ids, pos.tolist()))
        self.room_of = {n: (category_id(p) if p is not None else -1) for n, p in zip(ids, parents)}
        o_ids, o_pos, o_names, _, _, o_parents, _ = scene.layer("OBJECTS").spark_dsg_columns()
        info = {}
        for node, position, name, parent in zip(o_ids, o_pos.tolist(), o_names, o_parents):
            nearest, dist = self.nearest(position)
            info[node] = {"node_id": category_id(node), "semantic_class": name, "position": position,
                          "nearest_places_node": nearest, "distance_to_nearest_places_node": dist,
                          "room_id": category_id(parent) if parent is not None else -1}
        # edge weights from the facade (Yggdrasil keeps no weights), one Dijkstra call
        layer = self.places_layer
        src, dst, w = [], [], []
        row = self.row
        self.weight = {}
        self.adj = [[] for _ in ids]
        for e in layer.edges:
            a, b, weight = e.source, e.target, e.info.weight
            src.append(row[a])
            dst.append(row[b])
            w.append(weight)
            self.weight[(a, b)] = self.weight[(b, a)] = weight
            self.adj[row[a]].append((row[b], weight))
            self.adj[row[b]].append((row[a], weight))
        n = len(ids)
        matrix = csr_matrix((w, (src, dst)), shape=(n, n))
        sources = sorted({obj["nearest_places_node"] for obj in info.values()})
        self.source_row = {s: i for i, s in enumerate(sources)}
        self.dist = dijkstra(matrix, directed=False, indices=[row[s] for s in sources])
        self.dist_rows = {}
        self.paths = {}
        return info

    def nearest(self, position):
        node = self.scene.nearest_nodes(position, 1, "PLACES")[0][0]
        return node, euclid(position, self.pos_of[node])

    def closest_nodes(self, position):
        best, best_d = self.nearest(position)
        out = {best: best_d}
        pos_of = self.pos_of
        for n in self.scene.nodes_within_radius(position, 0.5 + 1e-4, "PLACES"):
            if n != best:
                d = euclid(position, pos_of[n])
                if d <= 0.5:
                    out[n] = d
        return out

    def place_room(self, node):
        return self.room_of[node]

    def place_position(self, node):
        return self.pos_of[node]

    def edge_weight(self, a, b):
        return self.weight[(a, b)]

    def has_source(self, node):
        return node in self.source_row

    def _dist_row(self, r):
        row = self.dist_rows.get(r)
        if row is None:
            row = self.dist_rows[r] = self.dist[r].tolist()
        return row

    def distance(self, src, dst):
        d = self._dist_row(self.source_row[src])[self.row[dst]]
        if d == math.inf:
            raise KeyError(dst)
        return d

    def path(self, src, dst):
        """The path NetworkX's ``single_source_dijkstra`` returns: among equally short
        ways, its path to a node is the one through the neighbour it settled first (the
        smallest distance), so each step back takes the neighbour ``v`` with
        ``dist[v] + w == dist[u]`` and the smallest ``dist[v]``."""
        key = (src, dst)
        p = self.paths.get(key)
        if p is None:
            dist = self._dist_row(self.source_row[src])
            at = self.row[dst]
            d = dist[at]
            if d == math.inf:
                raise KeyError(dst)
            root, adj, ids = self.row[src], self.adj, self.ids
            rev = [ids[at]]
            while at != root:
                du = dist[at]
                at = min((dist[v], v) for v, w in adj[at] if dist[v] + w == du)[1]
                rev.append(ids[at])
            p = self.paths[key] = (rev[::-1], d)
        return p

    def node_data(self, node):
        x, y, _ = self.pos_of[node]
        parent = self.scene.parent(node)
        return x, y, category_id(parent) if parent is not None else 0


# ------------------------------------------------------------------ the application
class LP2Run:
    """One backend through LP2's per-trajectory flow; every graph call is timed (the
    original's room-of-a-waypoint scans on a uniform sample, ``room_sample``)."""

    def __init__(self, backend, depth=2, width=2, instances=5, room_sample=1.0, seed=0):
        self.b = backend
        self.depth, self.width, self.instances = depth, width, instances
        self.room_sample = room_sample
        self.sample_rng = random.Random(seed)
        self.t = Timings()
        self.log = []              # every answer, in call order, for the comparison
        self.reference = None

    def _call(self, op, fn, *args):
        t0 = perf_ns()
        out = fn(*args)
        self.t.add(op, perf_ns() - t0)
        return out

    def build(self):
        t0 = perf_ns()
        self.objects = self.b.build()
        self.t.add(BUILD, perf_ns() - t0)
        self.by_class = {}
        for info in self.objects.values():
            self.by_class.setdefault(info["semantic_class"], []).append(info)
        if isinstance(self.b, OriginalBackend):
            self.reference = self.b.reference_node_data()
        return self.objects

    def prompt(self):
        """The scene part of LP2's prompt: rooms and the objects in them."""
        rooms = {}
        for info in self.objects.values():
            rooms.setdefault(info["room_id"], []).append(info)
        lines = ["The environment contains the following objects:"]
        for room in sorted(rooms):
            names = ", ".join(f"{i['semantic_class']} (id {i['node_id']})"
                              for i in sorted(rooms[room], key=lambda i: i["node_id"]))
            lines.append(f"- near place {room}: {names}")
        lines.append("Object classes: " + ", ".join(sorted(self.by_class)))
        return "\n".join(lines) + "\n"

    def node_data(self, node):
        if self.reference is not None and self.sample_rng.random() >= self.room_sample:
            self.t.count(ROOM)
            return self.reference[node]
        out = self._call(ROOM, self.b.node_data, node)
        if self.reference is not None and out != self.reference[node]:
            raise AssertionError(f"get_node_data({node}) scanned {out}, the build's scan gave {self.reference[node]}")
        return out

    def predict(self, trajectory_id, position, interactions):
        rng = random.Random(f"{trajectory_id}")        # the recorded LLM answers' stand-in
        classes = sorted(self.by_class)
        closest = self._call(WITHIN, self.b.closest_nodes, position)
        self.log.append(("within", list(closest.items())))
        start, start_d = self._call(NEAREST, self.b.nearest, position)
        room = self._call(OTHER, self.b.place_room, start)
        self.log.append(("nearest", start, start_d, room))
        # the semantic tree: width classes per level, depth levels
        semantic = []

        def grow(parent, depth):
            if depth == self.depth:
                return
            picks = rng.sample(classes, min(self.width, len(classes)))
            raw = [rng.uniform(0.1, 1.0) for _ in picks]
            for c, p in zip(picks, raw):
                node = {"class": c, "p": p / sum(raw), "duration": rng.uniform(1, 30), "children": []}
                parent.append(node)
                grow(node["children"], depth + 1)
        grow(semantic, 0)
        start2, _ = self._call(NEAREST, self.b.nearest, position)
        paths = []
        self._instances(semantic, start2, closest, True, [], paths)
        self.log.append(("paths", [[tuple(seg) for seg in p] for p in paths]))
        self._low_level(paths)

    def _grounding(self, previous_place, instances, probability):
        b = self.b
        distances = []
        for inst in instances:
            place = inst["nearest_places_node"]
            if b.has_source(previous_place):
                distances.append(b.distance(previous_place, place))
            else:
                distances.append(b.distance(place, previous_place))
        weights = [math.exp(-d / 5.0) for d in distances]
        total = sum(weights)
        return [dict(inst, probability=probability * w / total, distance=d)
                for inst, w, d in zip(instances, weights, distances)]

    def _instances(self, semantic, previous_place, closest, at_root, prefix, out):
        for node in semantic:
            inst = self._call(GROUNDING, self._grounding, previous_place,
                              self.by_class[node["class"]], node["p"])
            if len(inst) > self.instances:
                inst = sorted(inst, key=lambda i: i["probability"], reverse=True)[:self.instances]
            self.log.append(("grounding", [(i["node_id"], i["distance"]) for i in inst]))
            for i in inst:
                place = i["nearest_places_node"]
                if at_root:                       # get_path_from_root
                    best, best_path = math.inf, None
                    for n, d in closest.items():
                        p, dist = self._call(LOOKUP, self.b.path, place, n)
                        if dist + d < best:
                            best, best_path = dist + d, p[::-1]
                    segment = best_path
                elif self.b.has_source(previous_place):
                    segment, _ = self._call(LOOKUP, self.b.path, previous_place, place)
                else:
                    p, _ = self._call(LOOKUP, self.b.path, place, previous_place)
                    segment = p[::-1]
                path = prefix + [segment]
                if node["children"]:
                    self._instances(node["children"], place, closest, False, path, out)
                else:
                    out.append(path)

    def _low_level(self, paths):
        b = self.b
        rooms = []
        for path in paths:
            for k, segment in enumerate(path):
                for a, c in zip(segment, segment[1:]):          # the transition tree
                    self._call(OTHER, b.edge_weight, a, c)
                    self._call(OTHER, b.place_position, c)
                data = [self.node_data(n) for n in segment]
                if len(segment) < 2:
                    data.append(self.node_data(path[k + 1][0] if k == 0 and len(path) > 1 else segment[-1]))
                data.append(self.node_data(segment[-1]))
                rooms.append(tuple(r for _, _, r in data))
        self.log.append(("rooms", rooms))


def run_scene(scene, path, csvs, reps, room_sample, progress=None):
    """Both backends on one scene, ``reps`` runs each; returns per-op numbers and counts.
    Raises AssertionError on the first differing answer."""
    from ._lp2_data import read_trajectory
    results = {"original": [], "yggdrasil": []}
    loads = {"original": [], "yggdrasil": []}
    logs = {}
    prompts = {}
    for rep in range(reps):
        for cls in (OriginalBackend, YggdrasilBackend):
            backend = cls(path)
            loads[cls.name].append(backend.load_ns / 1e6)
            run = LP2Run(backend, room_sample=room_sample if cls is OriginalBackend else 1.0, seed=rep)
            objects = run.build()
            labels = {info["node_id"]: info["semantic_class"] for info in objects.values()}
            for k, f in enumerate(csvs):
                position, interactions = read_trajectory(f, labels)
                run.predict(k, position, interactions)
            results[cls.name].append(run.t)
            logs[cls.name] = (objects, run.log)
            prompts[cls.name] = run.prompt()
            if progress:
                progress.step(f"LP2 {scene} run {rep + 1}/{reps} {cls.name}")
        check_equal(scene, logs, prompts)
    load_ms = tuple(sorted(loads[k])[len(loads[k]) // 2] for k in ("original", "yggdrasil"))
    return results, prompts["original"], load_ms


def check_equal(scene, logs, prompts):
    (o_objects, o_log), (y_objects, y_log) = logs["original"], logs["yggdrasil"]
    if o_objects != y_objects:
        bad = [n for n in o_objects if o_objects[n] != y_objects.get(n)][:3]
        raise AssertionError(f"LP2 {scene}: object information differs, e.g. "
                             f"{[(o_objects[n], y_objects.get(n)) for n in bad]}")
    if len(o_log) != len(y_log):
        raise AssertionError(f"LP2 {scene}: {len(o_log)} answers against {len(y_log)}")
    for k, (a, b) in enumerate(zip(o_log, y_log)):
        if a != b:
            raise AssertionError(f"LP2 {scene}: answer {k} ({a[0]}) differs:\n original  {str(a)[:300]}\n"
                                 f" yggdrasil {str(b)[:300]}")
    if prompts["original"] != prompts["yggdrasil"]:
        raise AssertionError(f"LP2 {scene}: the prompts differ")


def study(workdir, quick, progress=None):
    """Rows for both scenes. quick: fewer trajectories and runs, a sparser sample."""
    scenes = {"office": (_lp2_data.office_file(workdir), 45), "home": (_lp2_data.home_file(workdir), 31)}
    reps = 1 if quick else 3      # the original's office build alone takes ~10 s here
    room_sample = 0.01 if quick else 0.05
    rows, notes = [], {}
    for scene, (path, count) in scenes.items():
        n = max(6, count // 4) if quick else count
        csvs = _lp2_data.trajectories(path, workdir, n, seed=17)
        results, prompt, load_ms = run_scene(scene, path, csvs, reps, room_sample, progress)
        rows += scene_rows(scene, results)
        o = results["original"][0]
        notes[scene] = {"trajectories": n, "runs": reps, "calls": dict(o.calls),
                        "room_sampled": sum(len(t.ns[ROOM]) for t in results["original"]),
                        "prompt_bytes": len(prompt.encode()), "load_ms": load_ms}
    return rows, notes


def _pool(timings, op):
    ns = [x for t in timings for x in t.ns.get(op, [])]
    return ns


def scene_rows(scene, results):
    import statistics
    rows = []
    per = {}
    for name, ts in results.items():
        per[name] = {op: statistics.median(_pool(ts, op)) / 1e3 for op in OPS}
        per[name][BUILD] = statistics.median(_pool(ts, BUILD)) / 1e6
        totals = []
        for t in ts:
            totals.append(sum(t.total_ms(op) for op in OPS + (BUILD, OTHER)))
        per[name]["total graph time"] = statistics.median(totals)
    for op in OPS + (BUILD, "total graph time"):
        o, y = per["original"][op], per["yggdrasil"][op]
        po, py = PAPER[scene][op]
        unit = "us" if op in OPS else "ms"
        rows.append({"study": "LP2", "scene": scene, "operation": op, "unit": unit,
                     "original": o, "yggdrasil": y, "ratio": o / y if y else math.inf,
                     "paper_original": po, "paper_yggdrasil": py, "paper_ratio": po / py,
                     "calls": results["original"][0].calls.get(op, 1)})
    return rows


def notes_md(notes, rows):
    """The LP2 section of the results' notes."""
    by = {(r["scene"], r["operation"]): r for r in rows}
    lines = ["## LP2: how it was run", ""]
    for scene, n in notes.items():
        total = by[(scene, "total graph time")]
        calls = n["calls"]
        lines.append(
            f"- **{scene}**: {n['trajectories']} trajectories, {n['runs']} run(s) per backend; per run "
            f"{calls.get(ROOM, 0):,} room-of-a-waypoint calls (the original's edge scan timed on a uniform "
            f"random sample, {n['room_sampled']:,} calls over all runs, its total is calls × the sample's mean; "
            f"every other call of both backends is timed), {calls.get(NEAREST, 0)} nearest, {calls.get(WITHIN, 0)} "
            f"within 0.5 m, {calls.get(LOOKUP, 0):,} path lookups, {calls.get(GROUNDING, 0)} groundings, "
            f"{calls.get(OTHER, 0):,} other lookups (positions, weights, a place's room). Total graph time "
            f"reduced by {100 * (1 - 1 / total['ratio']):.2f} %. Loading the file (not in build time, both "
            f"sides): spark_dsg {n['load_ms'][0]:.0f} ms, the facade {n['load_ms'][1]:.0f} ms. Prompt "
            f"{n['prompt_bytes']:,} bytes, byte-identical.")
    lines += [
        "- Checked on every call: the object information (ids, classes, positions, nearest place and its "
        "distance, parent), every nearest / within-0.5 m answer with its distances, every grounding's "
        "distances, every predicted path (place ids), every room id LP2's low level reads, and the prompt. "
        "The original's sampled scans are also checked against the build's scans of the same node.",
        "- Scenes: the office is `yggdrasil.write_office(seed=7)` (1,130 places, 215 objects); the home is "
        "generated (861 places on a jittered 41 × 21 grid, 110 objects, 6 rooms). Both are Spark-DSG JSON "
        "with interlayer edges stored parent first, the orientation LP2's `edge.target == node` scans need "
        "(our generator writes them child first, so they are re-inserted). Trajectories: CSVs with LP2's "
        "columns (walks along shortest paths between objects at 1.4 m/s, 10 Hz, 2-8 s interactions). "
        "LP2's LLM answers are replaced by a seeded choice of classes, the same for both backends "
        "(depth 2, width 2, at most 5 instances per class, LP2's defaults).",
        "- Build: LP2 builds once per module per run (`on_episode_init` of the goal and planning "
        "modules), not per iteration as the paper says. The original's build is two NetworkX copies of the "
        "places layer with an interlayer-edge scan per place, two `cKDTree`s, the objects' information and "
        "a `single_source_dijkstra` per object. Yggdrasil's: a kd-tree kept on PLACES, a snapshot, the "
        "layers' columns, `nearest_nodes` per object, the edge weights read through the facade (it parses "
        "them on first use: about half of the build) and one `scipy.sparse.csgraph.dijkstra` call.",
        "- Shortest-path lookup: the original reads dicts NetworkX filled at build; Yggdrasil reads the "
        "distance matrix and rebuilds a path on its first lookup (NetworkX's choice among equally short "
        "paths: the neighbour settled first), then keeps it, so its median is a first lookup; there is no "
        "target on this row.",
    ]
    return "\n".join(lines)
