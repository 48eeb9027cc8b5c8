"""The LP2 scenes and trajectories, generated (LP2's own data is downloaded from a cloud
drive and is not public in its repository).

* office: Yggdrasil's built-in office (``yggdrasil.write_office``, seed 7), 1,130 places,
  215 objects, 9 rooms.
* home: 861 places (a jittered 41 x 21 grid, 0.35 m apart), 110 objects, 6 rooms, written
  with spark_dsg's own API; positions are float32-representable, as in the office.

Both are saved as Spark-DSG JSON files (the facade keeps edge weights from JSON, not from the binary encoding) with every interlayer edge stored parent first
(room -> place, place -> object), the orientation LP2's edge scans assume
(``edge.target == place`` finds the room edge). The generator writes child-first edges,
so the office is re-inserted parent first before saving.

Trajectories have the columns of LP2's CSVs (``t, x, y, z, interaction_id, room_id,
action``): a person walks at 1.4 m/s along the places graph's shortest paths between
objects, sampled at 10 Hz, and interacts with each object for 2-8 s.
"""
from __future__ import annotations

import csv
import os

import numpy as np

HOME_CLASSES = ("chair", "table", "sofa", "bed", "lamp", "tv", "cabinet", "shelf", "plant",
                "fridge", "oven", "sink", "toilet", "desk", "book", "cup", "pillow", "window")
ACTIONS = ("use", "sit on", "pick up", "look at", "open", "clean")


def _sd():
    import spark_dsg
    return spark_dsg


def _layer_of(G, node):
    key = G.get_node(node).layer
    return key.layer if hasattr(key, "layer") else int(key)


def _parent_first(G):
    """Re-inserts every interlayer edge with the higher layer's node as its source."""
    for e in list(G.interlayer_edges):
        s, t = e.source, e.target
        if _layer_of(G, t) > _layer_of(G, s):
            info = G.get_edge(s, t).info
            G.remove_edge(s, t)
            G.insert_edge(t, s, info)


def office_file(workdir, seed=7, scale=1.0):
    import yggdrasil
    sd = _sd()
    raw = os.path.join(workdir, f"office_raw_{seed}.sparkdsg")
    out = os.path.join(workdir, f"office_{seed}.json")
    yggdrasil.write_office(raw, seed=seed, scale=scale)
    G = sd.DynamicSceneGraph.load(raw)
    _parent_first(G)
    G.save(out, include_mesh=False)
    os.remove(raw)
    return out


def home_file(workdir, seed=11, nx_=41, ny=21, spacing=0.35, objects=110):
    sd = _sd()
    rng = np.random.default_rng(seed)
    G = sd.DynamicSceneGraph()
    NS = sd.NodeSymbol

    def add(layer, sym, attrs, pos, name=None, label=None):
        # float32-representable, as the office generator writes them: Yggdrasil keeps
        # points as float32, so both backends then measure from the same numbers
        attrs.position = np.asarray(pos, dtype=np.float32).astype(np.float64)
        if name is not None:
            attrs.name = name
        if label is not None:
            attrs.semantic_label = label
        G.add_node(layer, sym, attrs)

    xcut = (nx_ // 3, 2 * nx_ // 3)
    ycut = ny // 2

    def room_index(i, j):
        return (0 if i < xcut[0] else 1 if i < xcut[1] else 2) + (0 if j < ycut else 3)

    add(sd.DsgLayers.BUILDINGS, NS("B", 0), sd.SemanticNodeAttributes(), [0, 0, 0])
    grid = np.stack(np.meshgrid(np.arange(nx_), np.arange(ny), indexing="ij"), -1).reshape(-1, 2)
    rooms = {}
    for i, j in grid:
        rooms.setdefault(room_index(i, j), []).append((i, j))
    for r, cells in sorted(rooms.items()):
        c = np.mean(cells, axis=0) * spacing
        add(sd.DsgLayers.ROOMS, NS("R", r), sd.RoomNodeAttributes(), [c[0], c[1], 1.5], name=f"room {r}")
        G.insert_edge(NS("B", 0), NS("R", r))
    pos = {}
    for k, (i, j) in enumerate(grid):
        p = [i * spacing + rng.uniform(-0.06, 0.06), j * spacing + rng.uniform(-0.06, 0.06),
             1.0 + rng.uniform(-0.05, 0.05)]
        pos[(i, j)] = (k, np.array(p, dtype=np.float32).astype(np.float64))
        add(sd.DsgLayers.PLACES, NS("p", k), sd.PlaceNodeAttributes(), p)
        G.insert_edge(NS("R", room_index(i, j)), NS("p", k))
    doors_x = {b: int(rng.integers(2, ny - 2)) for b in xcut}     # door row across x cuts
    doors_y = {c: int(rng.integers(1, xcut[0] - 1)) for c in range(3)}

    def crossing_ok(a, b):
        ra, rb = room_index(*a), room_index(*b)
        if ra == rb:
            return True
        if a[1] == b[1]:                       # across an x cut
            return abs(a[1] - doors_x[max(a[0], b[0])]) <= 1
        third = ra % 3                         # across the y cut
        return abs(a[0] - (third * xcut[0] + doors_y[third])) <= 1

    for (i, j), (k, p) in pos.items():
        for di, dj in ((1, 0), (0, 1)):
            n = (i + di, j + dj)
            if n in pos and crossing_ok((i, j), n):
                kn, pn = pos[n]
                info = sd.EdgeAttributes()
                info.weight = float(np.linalg.norm(p - pn))
                info.weighted = True
                G.insert_edge(NS("p", k), NS("p", kn), info)
    ids = np.array([pos[tuple(c)][0] for c in grid])
    pts = np.array([pos[tuple(c)][1] for c in grid])
    weights = np.linspace(2.0, 0.5, len(HOME_CLASSES))
    weights /= weights.sum()
    for o in range(objects):
        k = int(rng.integers(len(pts)))
        p = pts[k] + [rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-0.7, 0.6)]
        label = int(rng.choice(len(HOME_CLASSES), p=weights))
        room = room_index(*grid[k])
        same = [q for q in range(len(pts)) if room_index(*grid[q]) == room]
        near = same[int(np.argmin(np.linalg.norm(pts[same] - p, axis=1)))]
        add(sd.DsgLayers.OBJECTS, NS("O", o), sd.ObjectNodeAttributes(), p,
            name=HOME_CLASSES[label], label=label)
        G.insert_edge(NS("p", int(ids[near])), NS("O", o))
    out = os.path.join(workdir, f"home_{seed}.json")
    G.save(out, include_mesh=False)
    return out


def trajectories(path, workdir, count, seed, interactions=3):
    """Writes ``count`` trajectory CSVs for the scene file ``path``; returns their paths.
    Built with spark_dsg + NetworkX here (test data, not timed)."""
    import networkx as nx
    sd = _sd()
    G = sd.DynamicSceneGraph.load(path)
    places = G.get_layer(sd.DsgLayers.PLACES)
    graph = nx.Graph()
    for n in places.nodes:
        graph.add_node(n.id.value, position=np.asarray(n.attributes.position))
    for e in places.edges:
        graph.add_edge(e.source, e.target, weight=e.info.weight)
    room_of = {}
    for n in places.nodes:
        parent = n.get_parent()
        room_of[n.id.value] = sd.NodeSymbol(parent).category_id if parent is not None else -1
    objects = [(o.id.value, o.get_parent(), np.asarray(o.attributes.position))
               for o in G.get_layer(sd.DsgLayers.OBJECTS).nodes if o.get_parent() is not None]
    biggest = max(nx.connected_components(graph), key=len)
    objects = [o for o in objects if o[1] in biggest]
    rng = np.random.default_rng(seed)
    files = []
    for k in range(count):
        rows, t = [], 0.0
        chosen = [objects[int(i)] for i in rng.choice(len(objects), interactions, replace=False)]
        here = chosen[0][1]
        for oid, place, opos in chosen:
            route = nx.shortest_path(graph, here, place, weight="weight")
            for a, b in zip(route, route[1:]):
                pa, pb = graph.nodes[a]["position"], graph.nodes[b]["position"]
                steps = max(1, int(np.linalg.norm(pb - pa) / 0.14))
                for s in range(steps):
                    x = pa + (pb - pa) * s / steps
                    rows.append((round(t, 2), *x, -1, room_of[a], ""))
                    t += 0.1
            here = place
            action = ACTIONS[int(rng.integers(len(ACTIONS)))]
            p = graph.nodes[place]["position"]
            for _ in range(int(rng.integers(20, 80))):
                rows.append((round(t, 2), *p, sd.NodeSymbol(oid).category_id, room_of[place], action))
                t += 0.1
        f = os.path.join(workdir, f"{os.path.basename(path).split('.')[0]}_traj{k:02d}.csv")
        with open(f, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t", "x", "y", "z", "interaction_id", "room_id", "action"])
            w.writerows(rows)
        files.append(f)
    return files


def read_trajectory(path, labels):
    """The past trajectory's last position and its interactions (label, duration, action)
    from a CSV; ``labels`` maps object category ids to class names."""
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    interactions, current = [], None
    for r in rows:
        iid = int(r["interaction_id"])
        if iid != -1:
            if current is None or current["id"] != iid:
                current = {"id": iid, "semantic_label": labels[iid], "action": r["action"],
                           "start": float(r["t"]), "duration": 0.0}
                interactions.append(current)
            current["duration"] = float(r["t"]) - current["start"] + 0.1
        else:
            current = None
    last = rows[-1]
    return [float(last["x"]), float(last["y"]), float(last["z"])], interactions
