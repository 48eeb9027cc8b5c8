"""OSG (GoAnywhereNUS/foundation_obj_nav, ``scene_graph.py``; read for its workload
only): OSG's flat NetworkX scene graph against the paper's four-layer Yggdrasil design,
built and queried inside the same scripted exploration loop.

* ``FlatGraph``: what OSG's ``SceneGraph`` does (with the paper's floor): an ``nx.Graph``
  with typed nodes; ``is_type`` reads the node's attribute dict; nodes by type scan every
  node; ``add_node`` names a node ``<name>_<k>`` after ``count_instances`` (a scan of every
  node); ``add_edge`` checks the relation against the specs; the prompt is
  ``print_scene_graph`` without objects (per room and entrance, its neighbours by
  relation), ``json.dumps``.
* ``LayeredGraph``: a ``yggdrasil.SceneGraph`` with the layers FLOOR; PLACE (rooms and
  entrances); OBJECT; PHYSICAL (shadow nodes made on first use and nested under their
  entrance or object, holding ``is near``). Ids carry the type in their top byte, as
  Spark-DSG's node symbols do, so ``is_type`` reads the id; every other read is a query
  of the live graph, in process as OSG's agent holds its graph (``nodes_with_label`` on
  the type's layer, with a label per type and one ``<type>/<name>`` per instance name;
  ``edges_from``): the same query implementation a snapshot answers, without archiving
  the graph per step. Each undirected relation is two directed edges.
* The loop: an agent explores the office (9 rooms and the doors between them, 215
  objects with the office's labels), one room after another; each step it discovers a
  room or a door or a few objects (new leaf nodes with their relations, each relation
  added when its newer end is discovered, as OSG's navigator adds them), then serializes
  the graph to the prompt, gets the rooms and the entrances, checks the type of the
  nodes it considers, and counts the instances of its goal label. The prompt must be
  byte-identical at every step.
"""
from __future__ import annotations

import json
import random

from ._common import Timings, perf_ns

SPECS = {
    "floor": {"contains": ["room"]},
    "room": {"contains": ["object"], "connects to": ["entrance"]},
    "entrance": {"is near": ["object"], "connects to": ["room"]},
    "object": {},
}
OPS = ("serialize graph to prompt", "get nodes by type", "check node type", "add node",
       "count instances", "add edge")
PAPER = {"serialize graph to prompt": (144.310, 20.622), "get nodes by type": (59.451, 2.223),
         "check node type": (39.903, 2.860), "add node": (83.763, 54.467),
         "count instances": (158.920, 145.510), "add edge": (1.770, 3.630),
         "total graph-update time": (488.117, 229.312)}         # ms
OFFICE_LABELS = {"light": 40, "chair": 30, "desk": 22, "monitor": 18, "plant": 14, "cabinet": 12,
                 "table": 10, "trashcan": 9, "keyboard": 8, "window": 7, "computer": 6, "door": 6,
                 "shelf": 5, "sofa": 5, "whiteboard": 4, "printer": 3, "clock": 2, "fridge": 2,
                 "lamp": 2, "microwave": 2, "picture": 2, "bulletin": 1, "coat_rack": 1,
                 "fire_extinguisher": 1, "projector": 1, "sink": 1, "water_dispenser": 1}
ROOMS = ("corridor", "office", "office", "meetingroom", "kitchen", "office", "office", "storage", "lounge")
DOORS = ((0, 1), (0, 2), (0, 3), (0, 4), (0, 5), (0, 6), (0, 7), (0, 8), (1, 2), (3, 4), (5, 6), (7, 8))


def unique_name(graph, node_type, name, attrs, timings):
    """OSG's name for a new node, ``<name>_<k>`` after ``count_instances`` (timed on its
    own); sets ``attrs["type"]``."""
    attrs["type"] = node_type
    t0 = perf_ns()
    k = graph.count_instances(node_type, name)
    timings.add("count instances", perf_ns() - t0)
    return f"{name}_{k + 1}"


class FlatGraph:
    """OSG's flat NetworkX graph (behaviour of its ``SceneGraph``, with a floor)."""

    def __init__(self):
        import networkx as nx
        self.specs = SPECS
        self.g = nx.Graph()

    def is_type(self, name, node_type):
        return self.g.nodes()[name]["type"] == node_type

    def nodes_of_type(self, node_type):
        return [n for n in self.g.nodes() if self.is_type(n, node_type)]

    def count_instances(self, node_type, name):
        return len([n for n, a in self.g.nodes(data=True)
                    if a["type"] == node_type and n.split("_")[0] == name])

    def add_node(self, node_type, name, attrs, timings):
        unique = unique_name(self, node_type, name, attrs, timings)
        self.g.add_nodes_from([(unique, attrs)])
        return unique

    def add_edge(self, src, dst, relation):
        if self.g._node[dst]["type"] not in self.specs[self.g._node[src]["type"]][relation]:
            return False
        self.g.add_edge(src, dst, relation=relation)
        return True

    def serialize(self):
        out = {}
        for node_type, relations in self.specs.items():
            if node_type == "object":
                continue
            nodes = [n for n, a in self.g.nodes(data=True) if a["type"] == node_type]
            kinds = [r for r in relations if r != "contains"]
            out[node_type] = {n: {r: [d for _, d, a in self.g.edges(n, data=True) if a["relation"] == r]
                                  for r in kinds} for n in nodes}
        return json.dumps(out)


class LayeredGraph:
    """The paper's four-layer Yggdrasil design."""

    CODE = {"floor": 1, "room": 2, "entrance": 3, "object": 4, "shadow": 5}
    LAYER = {"floor": "FLOOR", "room": "PLACE", "entrance": "PLACE", "object": "OBJECT", "shadow": "PHYSICAL"}

    def __init__(self):
        import yggdrasil
        self.specs = SPECS
        g = self.g = yggdrasil.SceneGraph()
        for layer in ("FLOOR", "PLACE", "OBJECT", "PHYSICAL"):
            g.add_layer(layer)
        for parent, child in (("FLOOR", "PLACE"), ("PLACE", "OBJECT"), ("OBJECT", "PHYSICAL"),
                              ("PLACE", "PHYSICAL")):
            g.add_layer_edge(parent, child)
        self.ids, self.names, self.attrs = {}, {}, {}
        self.shadow = {}
        self.next = 1

    def _new_id(self, node_type):
        i = (self.CODE[node_type] << 56) | self.next
        self.next += 1
        return i

    def is_type(self, name, node_type):
        return self.ids[name] >> 56 == self.CODE[node_type]

    def nodes_of_type(self, node_type):
        names = self.names
        return [names[i] for i in self.g.nodes_with_label(node_type, self.LAYER[node_type])]

    def count_instances(self, node_type, name):
        return len(self.g.nodes_with_label(f"{node_type}/{name}", self.LAYER[node_type]))

    def add_node(self, node_type, name, attrs, timings):
        unique = unique_name(self, node_type, name, attrs, timings)
        i = self._new_id(node_type)
        g = self.g
        g.add_node(i, self.LAYER[node_type])
        g.add_label(i, node_type)                    # nodes by type
        g.add_label(i, f"{node_type}/{name}")        # instances of a name
        self.ids[unique], self.names[i], self.attrs[unique] = i, unique, attrs
        return unique

    def _shadow(self, i):
        s = self.shadow.get(i)
        if s is None:
            s = self.shadow[i] = self._new_id("shadow")
            self.g.add_node(s, "PHYSICAL")
            self.g.nest(i, s)
            self.names[s] = self.names[i]
        return s

    def add_edge(self, src, dst, relation):
        a, b = self.ids[src], self.ids[dst]
        if self.attrs[dst]["type"] not in self.specs[self.attrs[src]["type"]][relation]:
            return False
        if relation == "is near":
            a, b = self._shadow(a), self._shadow(b)
        if relation != "contains":         # nesting: a floor holds rooms, a room objects
            self.g.add_edge(a, b, relation)
            self.g.add_edge(b, a, relation)
        else:
            self.g.nest(a, b)
        return True

    def serialize(self):
        g, names = self.g, self.names
        out = {}
        for node_type, relations in self.specs.items():
            if node_type == "object":
                continue
            kinds = [r for r in relations if r != "contains"]
            nodes = {}
            for i in g.nodes_with_label(node_type, self.LAYER[node_type]):
                entry = {}
                for r in kinds:
                    src = self.shadow.get(i) if r == "is near" else i
                    entry[r] = [] if src is None else [names[t] for _, t, d in g.edges_from(src) if d == r]
                nodes[names[i]] = entry
            out[node_type] = nodes
        return json.dumps(out)


def script(seed):
    """The scripted exploration: a list of steps, each a list of discoveries
    ``("room", r)``, ``("door", d)`` or ``("object", room, label, door or None)``."""
    rng = random.Random(seed)
    labels = [lab for lab, n in OFFICE_LABELS.items() for _ in range(n)]
    rng.shuffle(labels)
    objects = {r: [] for r in range(len(ROOMS))}
    for lab in labels:
        objects[rng.randrange(len(ROOMS))].append(lab)
    order, seen, frontier = [], {0}, [0]
    while frontier:                                   # rooms in a random BFS order
        r = frontier.pop(rng.randrange(len(frontier)))
        order.append(r)
        for a, b in DOORS:
            for x, y in ((a, b), (b, a)):
                if x == r and y not in seen:
                    seen.add(y)
                    frontier.append(y)
    steps, doors_seen = [], set()
    for r in order:
        steps.append([("room", r)])
        for d, (a, b) in enumerate(DOORS):
            if r in (a, b) and d not in doors_seen:
                doors_seen.add(d)
                steps.append([("door", d)])
        mine = [d for d, (a, b) in enumerate(DOORS) if r in (a, b)]
        objs = objects[r]
        while objs:
            k = rng.randint(1, 4)
            batch, objs = objs[:k], objs[k:]
            steps.append([("object", r, lab, rng.choice(mine) if rng.random() < 0.25 else None)
                          for lab in batch])
    return steps, labels


def run_episode(graph, seed, timings, log):
    steps, labels = script(seed)
    goal = labels[0]
    t = timings
    added = []

    def add(node_type, name):
        t0 = perf_ns()
        n = graph.add_node(node_type, name, {"seen": len(added)}, t)
        t.add("add node", perf_ns() - t0 - t.ns["count instances"][-1])
        added.append(n)
        return n

    def edge(a, b, relation):
        t0 = perf_ns()
        ok = graph.add_edge(a, b, relation)
        t.add("add edge", perf_ns() - t0)
        return ok

    floor = add("floor", "floor")
    room_node, door_node = {}, {}
    for step in steps:
        oks = []
        for item in step:
            if item[0] == "room":
                r = item[1]
                n = room_node[r] = add("room", ROOMS[r])
                oks.append(edge(floor, n, "contains"))
                for d in sorted((d for d, (a, b) in enumerate(DOORS) if r in (a, b) and d in door_node),
                                key=lambda d: added.index(door_node[d])):
                    oks.append(edge(n, door_node[d], "connects to"))
            elif item[0] == "door":
                d = item[1]
                n = door_node[d] = add("entrance", "entrance")  # not "door": an object label
                for r in sorted((r for r in DOORS[d] if r in room_node), key=lambda r: added.index(room_node[r])):
                    oks.append(edge(n, room_node[r], "connects to"))
            else:
                _, r, label, d = item
                n = add("object", label)
                oks.append(edge(room_node[r], n, "contains"))
                if d is not None and d in door_node:
                    oks.append(edge(door_node[d], n, "is near"))
                oks.append(edge(room_node[r], floor, "contains"))    # refused by the specs
        t0 = perf_ns()
        prompt = graph.serialize()
        t.add("serialize graph to prompt", perf_ns() - t0)
        t0 = perf_ns()
        rooms = graph.nodes_of_type("room")
        t.add("get nodes by type", perf_ns() - t0)
        t0 = perf_ns()
        doors = graph.nodes_of_type("entrance")
        t.add("get nodes by type", perf_ns() - t0)
        types = []
        for n in added[-12:]:
            t0 = perf_ns()
            types.append(graph.is_type(n, "object"))
            t.add("check node type", perf_ns() - t0)
        t0 = perf_ns()
        count = graph.count_instances("object", goal)
        t.add("count instances", perf_ns() - t0)
        log.append((prompt, rooms, doors, types, count, oks, added[-len(step):]))


def study(quick, progress=None, layered=None):
    """Both graphs through the same episodes; ``layered`` replaces ``LayeredGraph``
    (the tests pass a wrong one). Raises AssertionError at the first differing answer."""
    import statistics
    episodes = 4 if quick else 20
    results = {}
    logs = {}
    for cls in (FlatGraph, layered or LayeredGraph):
        runs = []
        log = logs["FlatGraph" if cls is FlatGraph else "LayeredGraph"] = []
        for e in range(episodes):
            t = Timings()
            t.ns["count instances"] = []
            run_episode(cls(), e, t, log)
            runs.append(t)
        results[cls.__name__ if cls is FlatGraph else "LayeredGraph"] = runs
        if progress:
            progress.step(f"OSG {cls.__name__}")
    a, b = logs["FlatGraph"], logs["LayeredGraph"]
    if len(a) != len(b):
        raise AssertionError(f"OSG: {len(a)} steps against {len(b)}")
    for k, (x, y) in enumerate(zip(a, b)):
        if x != y:
            what = ("prompt", "rooms", "entrances", "types", "count", "edges", "names")
            i = next(i for i in range(len(x)) if x[i] != y[i])
            raise AssertionError(f"OSG: step {k}: the {what[i]} differ:\n flat    {str(x[i])[:300]}\n"
                                 f" layered {str(y[i])[:300]}")
    rows = []
    per = {}
    for name, runs in results.items():
        # per episode: the sum of each operation's calls, ms; the mean over episodes
        per[name] = {op: statistics.fmean(sum(t.ns.get(op, [])) / 1e6 for t in runs) for op in OPS}
        per[name]["total graph-update time"] = sum(per[name][op] for op in OPS)
    for op in ("total graph-update time",) + OPS:
        o, y = per["FlatGraph"][op], per["LayeredGraph"][op]
        po, py = PAPER[op]
        rows.append({"study": "OSG", "scene": None, "operation": op, "unit": "ms", "original": o,
                     "yggdrasil": y, "ratio": o / y, "paper_original": po, "paper_yggdrasil": py,
                     "paper_ratio": po / py, "calls": results["FlatGraph"][0].calls.get(op, 0)})
    steps = len(a) // episodes
    note = "\n".join([
        "## OSG: how it was run", "",
        f"- {episodes} scripted episodes of the office (9 rooms, 12 doors, 215 objects with the office's "
        f"labels; {steps} steps each); per episode {len(a[-1][0]):,} bytes of prompt at the last step. Rows: "
        "per-episode sums of each operation (ms), the mean over episodes (the paper: mean per episode over 400).",
        "- Checked at every step: the prompt (byte-identical), the rooms and entrances by type, every type "
        "check, the instance count, every `add_edge` answer (including the ones the specs refuse) and every "
        "node's unique name.",
        "- Add edge: each undirected relation is two `add_edge` calls into the store (the paper's reason "
        "for 0.49×), but a Rust `add_edge` costs well under a microsecond from Python, less than "
        "NetworkX's `add_edge` with its attribute dicts; `contains` is a nesting, one call.",
        "- Yggdrasil's reads are queries of the live graph (`SceneGraph.nodes_with_label`, "
        "`SceneGraph.edges_from`: the store's query code over the live graph, as a snapshot runs it over "
        "its bytes), in process as OSG's agent holds its graph. Tried before: a snapshot per step "
        "(archiving the graph, tens of microseconds, most of the serialize time: total about 2.2×) and "
        "a snapshot inside every `add node` (count instances 0.69×).",
    ])
    total = rows[0]["ratio"]
    if total < 2.5:
        note += ("\n- The total's target (2.5×) is missed in this run: "
                 f"{total:.2f}× (the paper: 2.13×); `json.dumps` of the same prompt costs both "
                 "sides the same, and the rest is a Python call into the store per read.")
    return rows, note
