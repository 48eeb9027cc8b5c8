#!/usr/bin/env python3
"""Test workload for anchor.py (the Rust side writes the real one).

Reads a Spark-DSG JSON office file with the json module only (no spark_dsg),
takes the floor plan from metadata.generator.rooms_xy (room i = node R(i)) and
draws, with a fixed seed, --per-room points uniformly inside each room box
(z in [0, ceiling]). Each point gives one Q1a, one Q1b per radius
(0.25/0.5/1/2/4), and one Q2 (eye = the point, random unit direction,
half-angle 30-70 deg, range 0.3-8 m). Q3 asks light, shelf, bulletin and an
absent label.

The update moves a random object `obj` (from a room with at least 3 objects)
so that one of its own vertices lands 5 cm from another object B of the same
room, and adds one more Q1a at that point (`update.query` names it): its
answer changes from B (or whoever is nearest) to `obj`, so the update path is
really tested.

Usage: make_test_workload.py --dsg FILE.json[.gz] --out WORKLOAD.json [--per-room 64] [--seed 1]
"""
import argparse
import gzip
import json
import sys

import numpy as np

RADII = (0.25, 0.5, 1.0, 2.0, 4.0)
LABELS = ("light", "shelf", "bulletin", "unicorn")  # the last one occurs nowhere
ROOMS_LAYER, OBJECTS_LAYER = 4, 2


def sym(prefix, idx):
    return (ord(prefix) << 56) | int(idx)


def parents(g):
    """child id -> parent id, from the JSON edges (on a cross-layer edge the higher layer is the parent)."""
    layer = {n["id"]: n["layer"] for n in g["nodes"]}
    parent = {}
    for e in g["edges"]:
        a, b = e["source"], e["target"]
        if layer[a] != layer[b]:
            lo, hi = (a, b) if layer[a] < layer[b] else (b, a)
            parent[lo] = hi
    return layer, parent


def ancestor_room(layer, parent, n):
    while n in parent and layer[n] != ROOMS_LAYER:
        n = parent[n]
    return n if layer[n] == ROOMS_LAYER else None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dsg", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--per-room", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    opener = gzip.open if args.dsg.endswith(".gz") else open
    with opener(args.dsg, "rt") as fh:
        g = json.load(fh)
    gen = g["metadata"]["generator"]
    rooms_xy, ceiling = gen["rooms_xy"], float(gen.get("ceiling", 3.0))
    node_ids = {n["id"] for n in g["nodes"]}
    rng = np.random.default_rng(args.seed)
    queries = []

    def add(**kw):
        queries.append(dict(id=len(queries), **kw))

    for r, (x0, x1, y0, y1) in enumerate(rooms_xy):
        room = sym("R", r)
        assert room in node_ids, f"R({r}) missing from the graph"
        for _ in range(args.per_room):
            p = [float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1)), float(rng.uniform(0.0, ceiling))]
            add(family="Q1a", room=room, point=p)
            for rad in RADII:
                add(family="Q1b", room=room, point=p, radius=rad)
            u = rng.normal(size=3)
            u /= np.linalg.norm(u)
            add(family="Q2", room=room, eye=p, dir=[float(c) for c in u],
                half_angle_deg=float(rng.uniform(30.0, 70.0)), range=float(rng.uniform(0.3, 8.0)))
    for lab in LABELS:
        add(family="Q3", label=lab)

    # ---- update
    layer, parent = parents(g)
    mcs = {n["id"]: n["attributes"]["mesh_connections"] for n in g["nodes"]
           if n["layer"] == OBJECTS_LAYER and n.get("partition", 0) == 0
           and n["attributes"].get("mesh_connections")}
    per_room = {}
    for o in sorted(mcs):
        per_room.setdefault(ancestor_room(layer, parent, o), []).append(o)
    cands = [o for o in sorted(mcs) if len(per_room[ancestor_room(layer, parent, o)]) >= 3]
    obj = int(cands[rng.integers(len(cands))])
    room = ancestor_room(layer, parent, obj)
    other = next(o for o in per_room[room] if o != obj)
    claims = {}
    for mc in mcs.values():
        for v in mc:
            claims[v] = claims.get(v, 0) + 1
    pts = g["mesh"]["points"]

    def own_vertex(o):
        own = [v for v in mcs[o] if claims[v] == 1] or mcs[o]
        return np.asarray(pts[own[len(own) // 2]], dtype=np.float32)

    target = own_vertex(other) + np.array([0.05, 0.0, 0.0], dtype=np.float32)
    v = own_vertex(obj)
    tr = target - v  # float32
    moved = v + tr  # where the vertex lands (f32 + f32, as the anchor moves it)
    add(family="Q1a", room=room, point=[float(c) for c in moved])
    upd = {"object": obj, "translation": [float(c) for c in tr], "query": queries[-1]["id"]}
    with open(args.out, "w") as fh:
        json.dump({"queries": queries, "update": upd}, fh)
    sys.stderr.write(f"wrote {args.out}: {len(queries)} queries, update moves object {obj} "
                     f"by {upd['translation']} (re-asks query {upd['query']})\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
