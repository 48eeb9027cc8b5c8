#!/usr/bin/env python3
"""Spark-DSG anchor for the Yggdrasil benchmark ladder.

Loads a Spark-DSG JSON scene graph with the spark_dsg Python bindings (1.1.3)
and answers the ladder's query workload the way Spark-DSG's Python users do,
along three paths, timing every query:

  spark-dsg-walk     per query: walk the graph through the Python API (objects
                     layer, parent relation up to the room, mesh_connections,
                     mesh points fetched with Mesh.get_vertices()); no caching.
  spark-dsg-numpy    per-room numpy arrays (claimed vertex coordinates, one row
                     per claim, + owner ids) built once; brute force per query.
  spark-dsg-ckdtree  per-room scipy cKDTree over the room's distinct claimed
                     vertices, built once; a label -> ids dict for Q3.
  spark-dsg-rebuild  the update: mutate the mesh through the API, re-extract the
                     arrays of every room that claims a moved vertex, rebuild
                     their trees, answer one Q1a.

The script checks that walk, numpy and ckdtree agree on every query they all
ran and exits non-zero (without writing --out) when they do not.

Exact semantics (what the Rust side must match), all arithmetic in float32:
  p  = f32(point);  d = v - p per axis (f32);  d2 = (dx*dx + dy*dy) + dz*dz (f32)
  Q1a: argmin over (d2, object id)                      -> [id] or []
  Q1b: d2 <= f32(r) * f32(r)                            -> sorted distinct ids
  Q2 : d2 <= f32(range) * f32(range) and
       (d2 == 0 or dot(d, f32(dir)) >= sqrt(d2) * f32(cos(radians(half_angle))))
       (dot = (dx*ux + dy*uy) + dz*uz in f32; cos computed in f64, then rounded)
  Q3 : objects-layer nodes whose label name (labelspace _l2p0, else the node's
       name attribute) equals the label.
  candidates: objects whose ancestor room (climbing get_parent()) is `room`
  and that claim at least one vertex; a vertex claimed by several objects
  counts for each of them.

Usage: anchor.py --dsg FILE.json --workload WORKLOAD.json --out ROWS.json [--quick]
"""
import argparse
import json
import math
import os
import platform
import sys
import time

import numpy as np

try:
    import spark_dsg as dsg
    from scipy.spatial import cKDTree
except ImportError as e:  # pragma: no cover - run.sh installs them
    sys.stderr.write(f"anchor.py: missing dependency: {e}\n")
    sys.exit(2)

F32 = np.float32
U64 = np.uint64


def log(msg):
    sys.stderr.write(f"[spark-dsg anchor] {msg}\n")
    sys.stderr.flush()


class AnchorError(Exception):
    pass


# ------------------------------------------------------------ exact kernels
def prep_point(q):
    return np.asarray(q, dtype=np.float64).astype(F32)


def d_f32(x, y, z, p):
    """Per-axis differences and squared distance, float32, fixed summation order."""
    dx = x - p[0]
    dy = y - p[1]
    dz = z - p[2]
    return dx, dy, dz, (dx * dx + dy * dy) + dz * dz


def cone_params(q):
    u = np.asarray(q["dir"], dtype=np.float64)
    n = float(np.linalg.norm(u))
    if not (abs(n - 1.0) < 1e-5):
        raise AnchorError(f"query {q['id']}: dir is not a unit vector (|dir| = {n})")
    rng = F32(q["range"])
    return (prep_point(q["eye"]), u.astype(F32), rng * rng,
            F32(math.cos(math.radians(float(q["half_angle_deg"])))), float(q["range"]))


def cone_mask(x, y, z, eye, u, rng2, cosh):
    dx, dy, dz, d2 = d_f32(x, y, z, eye)
    dot = (dx * u[0] + dy * u[1]) + dz * u[2]
    return (d2 <= rng2) & ((d2 == 0) | (dot >= np.sqrt(d2) * cosh))


def radius2(r):
    r = F32(r)
    return r * r


def family_of(q):
    f = q["family"]
    if f == "Q1b":
        return f"Q1b@{float(q['radius']):g}"
    if f == "Q3":
        return f"Q3:{q['label']}"
    return f


# ------------------------------------------------------------ scene helpers
class Scene:
    """Thin facts about the loaded graph (layer ids, labelspace), nothing cached per object."""

    def __init__(self, G):
        self.G = G
        self.objects_layer = G.get_layer(dsg.DsgLayers.OBJECTS).id
        self.rooms_layer = G.get_layer(dsg.DsgLayers.ROOMS).id
        if not G.has_mesh():
            raise AnchorError("the scene graph has no mesh (need mesh points for spatial queries)")

    def objects(self):
        return self.G.get_layer(dsg.DsgLayers.OBJECTS).nodes

    def ancestor_room(self, node):
        """Climb the parent relation (object -> place -> room) to a ROOMS-layer node."""
        G, rooms = self.G, self.rooms_layer
        seen = 0
        while True:
            pid = node.get_parent()
            if pid is None:
                return None
            node = G.get_node(pid)
            if node.layer.layer == rooms and node.layer.partition == 0:
                return node.id.value
            seen += 1
            if seen > 64:
                return None

    def labelspace(self):
        ls = self.G.get_labelspace(self.objects_layer, 0)
        # get_labelspace never returns None: a missing one is an empty Labelspace
        return ls if ls.labels_to_names else None

    def label_name(self, ls, node):
        if ls is not None:
            return ls.get_node_category(node, "")
        return node.attributes.name

    def room_ids(self):
        return sorted(n.id.value for n in self.G.get_layer(dsg.DsgLayers.ROOMS).nodes)


# ------------------------------------------------------------ path: walk
class WalkPath:
    name = "spark-dsg-walk"

    def __init__(self, scene):
        self.s = scene

    def _candidates(self, room):
        s = self.s
        V = s.G.mesh.get_vertices()  # fresh 6 x N float64 copy, every query
        out = []
        for node in s.objects():
            if s.ancestor_room(node) != room:
                continue
            mc = node.attributes.mesh_connections
            if not mc:
                continue
            P = V[:3, mc].astype(F32)
            out.append((node.id.value, P))
        return out

    def run(self, q):
        f = q["family"]
        if f == "Q3":
            s = self.s
            ls = s.labelspace()
            lab = q["label"]
            return sorted(n.id.value for n in s.objects() if s.label_name(ls, n) == lab)
        cands = self._candidates(int(q["room"]))
        if f == "Q1a":
            p = prep_point(q["point"])
            best = None
            for oid, P in cands:
                m = d_f32(P[0], P[1], P[2], p)[3].min()
                if best is None or (m, oid) < best:
                    best = (m, oid)
            return [] if best is None else [best[1]]
        if f == "Q1b":
            p = prep_point(q["point"])
            r2 = radius2(q["radius"])
            return sorted(oid for oid, P in cands if (d_f32(P[0], P[1], P[2], p)[3] <= r2).any())
        if f == "Q2":
            eye, u, rng2, cosh, _ = cone_params(q)
            return sorted(oid for oid, P in cands if cone_mask(P[0], P[1], P[2], eye, u, rng2, cosh).any())
        raise AnchorError(f"unknown family {f}")


# ------------------------------------------------------------ cached claim structure
class RoomClaims:
    """One room's claims, read from the graph once: which object claims which vertex.

    vidx/owner: one row per claim (a vertex claimed by k objects appears k times).
    uv: the room's distinct claimed vertex indices (sorted); for each, its owners in
    CSR form (start, cnt into claim_owner, owners ascending) and min_owner."""
    __slots__ = ("vidx", "owner", "uv", "start", "cnt", "claim_owner", "min_owner")

    def __init__(self, lst):
        self.vidx = np.concatenate([m for _, m in lst])
        self.owner = np.concatenate([np.full(len(m), oid, dtype=U64) for oid, m in lst])
        uv, inv = np.unique(self.vidx, return_inverse=True)
        inv = inv.reshape(-1)
        order = np.lexsort((self.owner, inv))
        self.uv = uv
        self.claim_owner = self.owner[order]
        self.cnt = np.bincount(inv[order], minlength=len(uv))
        self.start = np.concatenate(([0], np.cumsum(self.cnt)[:-1]))
        self.min_owner = self.claim_owner[self.start]

    def claims_any(self, vidx):
        pos = np.searchsorted(self.uv, vidx)
        pos[pos >= len(self.uv)] = 0
        return bool((self.uv[pos] == vidx).any())


def extract_claims(scene):
    """room id -> RoomClaims, walking the objects layer and the parent relation once."""
    acc = {}
    for node in scene.objects():
        r = scene.ancestor_room(node)
        if r is None:
            continue
        mc = node.attributes.mesh_connections
        if not mc:
            continue
        acc.setdefault(r, []).append((node.id.value, np.asarray(mc, dtype=np.int64)))
    return {r: RoomClaims(lst) for r, lst in acc.items()}


def gather_owners(h, c):
    """Owners (RoomClaims c) of the hit distinct vertices h, as sorted distinct python ints."""
    if len(h) == 0:
        return []
    n = c.cnt[h]
    off = np.repeat(c.start[h] - (np.cumsum(n) - n), n) + np.arange(int(n.sum()))
    return [int(x) for x in np.unique(c.claim_owner[off])]


# ------------------------------------------------------------ path: numpy
class NumpyPath:
    name = "spark-dsg-numpy"

    def __init__(self, scene):
        self.s = scene
        self.claims = extract_claims(scene)
        self.rooms = {}
        self.extract(self.claims)
        ls = scene.labelspace()
        ids, names = [], []
        for node in scene.objects():
            ids.append(node.id.value)
            names.append(scene.label_name(ls, node))
        order = np.argsort(np.asarray(ids, dtype=U64), kind="stable")
        self.obj_ids = np.asarray(ids, dtype=U64)[order]
        self.obj_names = np.asarray(names, dtype=object)[order]

    def extract(self, rooms):
        """(Re-)extract the claim coordinates of `rooms` from the Spark-DSG mesh."""
        V = self.s.G.mesh.get_vertices()  # 6 x N float64 copy
        for r in rooms:
            c = self.claims[r]
            P = V[:3, c.vidx].astype(F32)
            self.rooms[r] = (np.ascontiguousarray(P[0]), np.ascontiguousarray(P[1]),
                             np.ascontiguousarray(P[2]), c.owner)

    def run(self, q):
        f = q["family"]
        if f == "Q3":
            return [int(x) for x in self.obj_ids[self.obj_names == q["label"]]]
        R = self.rooms.get(int(q["room"]))
        if R is None:
            return []
        x, y, z, owner = R
        if f == "Q1a":
            d2 = d_f32(x, y, z, prep_point(q["point"]))[3]
            return [int(owner[d2 == d2.min()].min())]
        if f == "Q1b":
            d2 = d_f32(x, y, z, prep_point(q["point"]))[3]
            return [int(v) for v in np.unique(owner[d2 <= radius2(q["radius"])])]
        if f == "Q2":
            eye, u, rng2, cosh, _ = cone_params(q)
            return [int(v) for v in np.unique(owner[cone_mask(x, y, z, eye, u, rng2, cosh)])]
        raise AnchorError(f"unknown family {f}")


# ------------------------------------------------------------ path: cKDTree
SLACK_REL, SLACK_ABS = 1e-5, 1e-6  # widen float64 tree radii, then filter exactly in f32
KNN = 16  # Q1a asks this many neighbours; ties beyond them fall back to a ball query


class KdPath:
    name = "spark-dsg-ckdtree"

    def __init__(self, scene):
        self.s = scene
        self.claims = extract_claims(scene)
        self.rooms = {}
        self.extract(self.claims)
        ls = scene.labelspace()
        labels = {}
        for node in scene.objects():
            labels.setdefault(scene.label_name(ls, node), []).append(node.id.value)
        self.labels = {k: sorted(v) for k, v in labels.items()}

    def extract(self, rooms):
        """(Re-)extract the distinct claimed vertices of `rooms` from the mesh, (re)build trees."""
        V = self.s.G.mesh.get_vertices()
        for r in rooms:
            c = self.claims[r]
            P = V[:3, c.uv].astype(F32)
            self.rooms[r] = (np.ascontiguousarray(P[0]), np.ascontiguousarray(P[1]),
                             np.ascontiguousarray(P[2]), cKDTree(P.T.astype(np.float64)), c)

    def rooms_claiming(self, vidx):
        return {r for r, c in self.claims.items() if c.claims_any(vidx)}

    @staticmethod
    def widen(r):
        return r * (1 + SLACK_REL) + SLACK_ABS

    def run(self, q):
        f = q["family"]
        if f == "Q3":
            return list(self.labels.get(q["label"], ()))
        R = self.rooms.get(int(q["room"]))
        if R is None:
            return []
        x, y, z, tree, c = R
        if f == "Q1a":
            p = prep_point(q["point"])
            p64 = p.astype(np.float64)
            d, h = tree.query(p64, k=KNN)
            lim = self.widen(float(d[0]))
            if d[-1] <= lim:  # possibly more ties than KNN neighbours
                h = np.asarray(tree.query_ball_point(p64, lim), dtype=np.int64)
            else:
                h = h[d <= lim]
            d2 = d_f32(x[h], y[h], z[h], p)[3]
            return [int(c.min_owner[h[d2 == d2.min()]].min())]
        if f == "Q1b":
            p = prep_point(q["point"])
            h = np.asarray(tree.query_ball_point(p.astype(np.float64), self.widen(float(q["radius"]))),
                           dtype=np.int64)
            d2 = d_f32(x[h], y[h], z[h], p)[3]
            return gather_owners(h[d2 <= radius2(q["radius"])], c)
        if f == "Q2":
            eye, u, rng2, cosh, rng = cone_params(q)
            h = np.asarray(tree.query_ball_point(eye.astype(np.float64), self.widen(rng)), dtype=np.int64)
            m = cone_mask(x[h], y[h], z[h], eye, u, rng2, cosh)
            return gather_owners(h[m], c)
        raise AnchorError(f"unknown family {f}")


# ------------------------------------------------------------ update
class Mutation:
    """Translate every vertex claimed by `object` in the Spark-DSG mesh (Mesh.set_pos)."""

    def __init__(self, scene, obj, translation):
        self.G = scene.G
        node = self.G.get_node(obj) if self.G.has_node(obj) else None
        if node is None or node.layer.layer != scene.objects_layer:
            raise AnchorError(f"update object {obj} is not an object node")
        self.obj = obj
        self.t = np.asarray(translation, dtype=np.float64).astype(F32)
        mesh = self.G.mesh
        self.vidx = sorted(set(node.attributes.mesh_connections))
        self.orig = [mesh.pos(i).copy() for i in self.vidx]

    def apply(self):
        """The timed mutation, as a Spark-DSG user does it: read the object's claims
        from the graph and move each vertex through the mesh API (f32 + f32)."""
        mesh = self.G.mesh
        node = self.G.get_node(self.obj)
        t = self.t
        mc = node.attributes.mesh_connections
        for i in set(mc):
            mesh.set_pos(i, mesh.pos(i) + t)
        return mc

    def undo(self):
        mesh = self.G.mesh
        for i, p in zip(self.vidx, self.orig):
            mesh.set_pos(i, p)


# ------------------------------------------------------------ timing
def time_path(path, queries, reps):
    """-> answers {id: list}, samples {family: [ns, ...]}"""
    answers, samples = {}, {}
    pc = time.perf_counter_ns
    for q in queries:
        fam = family_of(q)
        ss = samples.setdefault(fam, [])
        ans = None
        for _ in range(reps):
            t0 = pc()
            a = path.run(q)
            ss.append(pc() - t0)
            if ans is not None and a != ans:
                raise AnchorError(f"{path.name}: query {q['id']} answer changed between repetitions")
            ans = a
        answers[q["id"]] = ans
    return answers, samples


def stats_rows(name, samples, n_queries, reps, note=None):
    rows = []
    for fam, ns in samples.items():
        a = np.asarray(ns, dtype=np.float64) / 1e3
        row = {"name": name, "query": fam, "median_us": round(float(np.median(a)), 3),
               "p99_us": round(float(np.percentile(a, 99)), 3), "mean_us": round(float(a.mean()), 3),
               "n_queries": n_queries[fam], "reps": reps, "samples": len(ns)}
        if note and fam in note:
            row["note"] = note[fam]
        rows.append(row)
    return rows


def machine_info():
    cpu = None
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    from importlib import metadata
    import scipy

    def ver(pkg):
        try:
            return metadata.version(pkg)
        except metadata.PackageNotFoundError:
            return None

    return {"cpu": cpu or platform.processor() or platform.machine(), "cores": os.cpu_count(),
            "os": platform.platform(), "python": platform.python_version(),
            "spark_dsg": ver("spark-dsg") or ver("spark_dsg"), "numpy": np.__version__,
            "scipy": scipy.__version__}


def compare(ref_name, ref, other_name, other, ids):
    bad = [i for i in ids if ref[i] != other[i]]
    for i in bad[:10]:
        log(f"MISMATCH query {i}: {ref_name}={ref[i]} {other_name}={other[i]}")
    return bad


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dsg", required=True, help="Spark-DSG JSON file (v1.1.x, with mesh)")
    ap.add_argument("--workload", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true", help="1 repetition, walk path sampled")
    ap.add_argument("--reps", type=int, help="repetitions per query (default 5, 1 with --quick)")
    ap.add_argument("--walk-stride", type=int,
                    help="walk path runs every N-th spatial query of each family (default: "
                         "about 96 per family, 64 with --quick; 1 = all)")
    args = ap.parse_args(argv)
    reps = args.reps or (1 if args.quick else 5)
    if os.path.exists(args.out):
        os.remove(args.out)

    with open(args.workload) as fh:
        wl = json.load(fh)
    queries = wl["queries"]
    for q in queries:
        if q["family"] not in ("Q1a", "Q1b", "Q2", "Q3"):
            raise AnchorError(f"query {q.get('id')}: unknown family {q['family']!r}")
    ids = [q["id"] for q in queries]
    if len(set(ids)) != len(ids):
        raise AnchorError("duplicate query ids in the workload")

    machine = machine_info()
    log(f"spark_dsg {machine['spark_dsg']}, python {machine['python']}, cpu {machine['cpu']}")
    log(f"loading {args.dsg} ...")
    t0 = time.perf_counter()
    G = dsg.DynamicSceneGraph.load(args.dsg)
    load_ms = (time.perf_counter() - t0) * 1e3
    scene = Scene(G)
    log(f"loaded in {load_ms:.0f} ms: {G.num_nodes()} nodes, {G.num_edges()} edges, "
        f"{G.mesh.num_vertices()} mesh vertices")
    rooms = set(scene.room_ids())
    for q in queries:
        if q["family"] != "Q3" and int(q["room"]) not in rooms:
            raise AnchorError(f"query {q['id']}: room {q['room']} is not a ROOMS node")

    build = [{"name": "load", "ms": round(load_ms, 3)}]
    t0 = time.perf_counter()
    npath = NumpyPath(scene)
    build.append({"name": NumpyPath.name, "ms": round((time.perf_counter() - t0) * 1e3, 3)})
    t0 = time.perf_counter()
    kpath = KdPath(scene)
    build.append({"name": KdPath.name, "ms": round((time.perf_counter() - t0) * 1e3, 3)})
    log(f"built numpy arrays in {build[1]['ms']:.1f} ms, cKDTrees in {build[2]['ms']:.1f} ms "
        f"({sum(len(c.uv) for c in kpath.claims.values())} distinct claimed vertices in "
        f"{len(kpath.rooms)} rooms)")

    n_per_fam = {}
    for q in queries:
        n_per_fam[family_of(q)] = n_per_fam.get(family_of(q), 0) + 1

    # walk sample: every stride-th query of each spatial family, all Q3
    stride = args.walk_stride
    if stride is None:
        stride = max(1, max(n_per_fam.values()) // (64 if args.quick else 96))
    seen, walk_q = {}, []
    for q in queries:
        fam = family_of(q)
        k = seen.get(fam, 0)
        seen[fam] = k + 1
        if q["family"] == "Q3" or k % stride == 0:
            walk_q.append(q)
    walk_n = {}
    for q in walk_q:
        walk_n[family_of(q)] = walk_n.get(family_of(q), 0) + 1

    anchors = []
    results = {}
    for path, qs, nf in ((kpath, queries, n_per_fam), (npath, queries, n_per_fam),
                         (WalkPath(scene), walk_q, walk_n)):
        t0 = time.perf_counter()
        ans, samples = time_path(path, qs, reps)
        log(f"{path.name}: {len(qs)} queries x {reps} in {time.perf_counter() - t0:.1f} s")
        note = None
        if nf is walk_n and stride > 1:
            note = {f: f"sampled: {walk_n[f]} of {n_per_fam[f]} queries (stride {stride})"
                    for f in walk_n if walk_n[f] != n_per_fam[f]}
        anchors += stats_rows(path.name, samples, nf, reps, note)
        results[path.name] = ans

    kd = results[KdPath.name]
    bad = compare(KdPath.name, kd, NumpyPath.name, results[NumpyPath.name], ids)
    bad += compare(KdPath.name, kd, WalkPath.name, results[WalkPath.name], [q["id"] for q in walk_q])
    if bad:
        raise AnchorError(f"paths disagree on {len(bad)} answers (see above)")
    log(f"answers agree: ckdtree = numpy on {len(ids)} queries, = walk on {len(walk_q)}")

    # ---- update
    after = None
    upd = wl.get("update")
    if upd:
        after, rows = run_update(scene, npath, kpath, queries, upd, 5 if args.quick else 20)
        anchors += rows

    out = {"machine": machine, "dsg": os.path.abspath(args.dsg), "quick": bool(args.quick),
           "reps": reps, "anchors": anchors, "build": build,
           "answers": {str(i): kd[i] for i in ids}}
    if after is not None:
        out["after_update"] = after
    tmp = args.out + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(out, fh, indent=1)
    os.replace(tmp, args.out)
    log(f"wrote {args.out}")
    return 0


def pick_update_query(scene, queries, upd):
    q1a = [q for q in queries if q["family"] == "Q1a"]
    if "query" in upd:
        m = [q for q in q1a if q["id"] == upd["query"]]
        if not m:
            raise AnchorError(f"update.query {upd['query']} is not a Q1a query id")
        return m[0]
    if not q1a:
        raise AnchorError("the update needs at least one Q1a query in the workload")
    room = scene.ancestor_room(scene.G.get_node(int(upd["object"])))
    same = [q for q in q1a if int(q["room"]) == room]
    return (same or q1a)[0]


def run_update(scene, npath, kpath, queries, upd, reps):
    """Timed: mutation -> (re-extract, rebuild) -> Q1a answer, for each path.
    Untimed between repetitions: the mesh and the caches are restored."""
    mut = Mutation(scene, int(upd["object"]), upd["translation"])
    q = pick_update_query(scene, queries, upd)
    walk = WalkPath(scene)
    pc = time.perf_counter_ns
    old_np, old_kd = dict(npath.rooms), dict(kpath.rooms)
    rows, answers, parts = [], {}, {"mutate": [], "rebuild": [], "query": []}

    def once(name):
        t0 = pc()
        mc = mut.apply()
        t1 = pc()
        if name == "spark-dsg-rebuild":
            kpath.extract(kpath.rooms_claiming(np.asarray(mc, dtype=np.int64)))
        elif name == NumpyPath.name:
            npath.extract(kpath.rooms_claiming(np.asarray(mc, dtype=np.int64)))
        t2 = pc()
        a = {"spark-dsg-rebuild": kpath, NumpyPath.name: npath, WalkPath.name: walk}[name].run(q)
        t3 = pc()
        mut.undo()
        npath.rooms.clear()
        npath.rooms.update(old_np)
        kpath.rooms.clear()
        kpath.rooms.update(old_kd)
        return a, (t3 - t0, t1 - t0, t2 - t1, t3 - t2)

    for name in ("spark-dsg-rebuild", NumpyPath.name, WalkPath.name):
        ns, ans = [], None
        for _ in range(reps):
            a, (tot, tm, tr, tq) = once(name)
            if ans is not None and a != ans:
                raise AnchorError(f"{name}: after_update answer changed between repetitions")
            ans = a
            ns.append(tot)
            if name == "spark-dsg-rebuild":
                parts["mutate"].append(tm)
                parts["rebuild"].append(tr)
                parts["query"].append(tq)
        answers[name] = ans
        row = stats_rows(name, {"after_update": ns}, {"after_update": 1}, reps)[0]
        if name == "spark-dsg-rebuild":
            row["breakdown_median_us"] = {k: round(float(np.median(v)) / 1e3, 3) for k, v in parts.items()}
        rows.append(row)
    if len({json.dumps(a) for a in answers.values()}) != 1:
        for k, v in answers.items():
            log(f"MISMATCH after_update {k}: {v}")
        raise AnchorError("paths disagree on the after_update answer")
    before = kpath.run(q)
    log(f"after_update: object {upd['object']} moved by {list(map(float, mut.t))} "
        f"({len(mut.vidx)} vertices), Q1a id {q['id']}: {before} -> {answers['spark-dsg-rebuild']}")
    return {"query": q["id"], "object": int(upd["object"]), "answer": answers["spark-dsg-rebuild"],
            "answer_before": before}, rows


if __name__ == "__main__":
    try:
        sys.exit(main())
    except AnchorError as e:
        log(f"FAILED: {e}")
        sys.exit(3)
