"""Yggdrasil against spark_dsg 1.1.3, side by side in one run, through Python.

Run from the repository root (it reuses the Spark-DSG paths of the ladder's anchor,
``bench/spark_dsg/anchor.py``: attribute walk, cached numpy arrays, scipy cKDTree built
once and rebuilt after an update)::

    python3 -m yggdrasil.bench --out bench/results/python.md

On the built-in office (seed 7, full size; the mint layout for Yggdrasil): the ladder's
Q1a (nearest object), Q1b (objects within 0.25..4 m), Q2 (field of view) and Q3 (objects
by label) over 64 points per room, each answered by every path and checked equal; the
batch form; time from nothing to the first answer (open a ``.ygg`` or attach to a live
scene, against spark_dsg's load plus its arrays and trees); and the query after a writer
in another process moved an object, against spark_dsg's rebuild path. Medians.
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import pathlib
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import yggdrasil

RADII = (0.25, 0.5, 1.0, 2.0, 4.0)
LABELS = ("light", "shelf", "bulletin", "unicorn")
TRANSLATION = (0.0, 0.0, 0.0)


def log(msg):
    sys.stderr.write(f"[yggdrasil.bench] {msg}\n")
    sys.stderr.flush()


def load_anchor(path):
    spec = importlib.util.spec_from_file_location("ygg_anchor", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ------------------------------------------------------------ workload
def make_workload(scene, per_room, seed=42):
    """64 points per room, uniform in its exact box: one Q1a, one Q1b per radius and one
    Q2 each (as the ladder); Q3 for four labels; an update moving one object."""
    rng = np.random.default_rng(seed)
    rooms = scene.layer("ROOMS").nodes
    queries = []
    for room in rooms:
        lo, hi = (np.asarray(v) for v in scene.node(room).aabb)
        for _ in range(per_room):
            p = [float(v) for v in rng.uniform(lo, hi)]
            d = rng.normal(size=3)
            d = [float(v) for v in d / np.linalg.norm(d)]
            queries.append({"family": "Q1a", "room": room, "point": p})
            for r in RADII:
                queries.append({"family": "Q1b", "room": room, "point": p, "radius": r})
            queries.append({"family": "Q2", "room": room, "eye": p, "dir": d,
                            "half_angle_deg": float(rng.uniform(30, 70)), "range": float(rng.uniform(0.3, 8))})
    for label in LABELS:
        queries.append({"family": "Q3", "label": label})
    for i, q in enumerate(queries):
        q["id"] = i
    # the update: an object with a mesh, moved 0.5 m along x; its own query point is
    # one of its vertices after the move, so the answer changes to it
    room = rooms[0]
    obj = scene.objects_in(room).ids()[0]
    mesh = scene.node(obj).children
    vertex = np.asarray(scene.node(mesh[0]).points[0], dtype=np.float64)
    t = np.array([0.5, 0.0, 0.0])
    q = {"family": "Q1a", "room": room, "point": [float(v) for v in vertex + t], "id": len(queries)}
    queries.append(q)
    return queries, {"object": obj, "translation": t.tolist(), "query": q["id"]}


def family_of(q):
    if q["family"] == "Q1b":
        return f"Q1b@{q['radius']:g}"
    if q["family"] == "Q3":
        return f"Q3:{q['label']}"
    return q["family"]


class YggPath:
    """Yggdrasil's object contract on the mapped .ygg, one room's catalog per Q1/Q2 (as
    the ladder's ``Objects::in_subtree``), the whole scene's for Q3."""

    name = "yggdrasil"

    def __init__(self, scene):
        self.scene = scene
        self.rooms = {r: scene.objects_in(r) for r in scene.layer("ROOMS").nodes}
        self.all = scene.objects

    def run(self, q):
        f = q["family"]
        if f == "Q3":
            return self.all.with_label(q["label"])
        o = self.rooms[q["room"]]
        if f == "Q1a":
            nearest = o.nearest(q["point"])
            return [] if nearest is None else [nearest]
        if f == "Q1b":
            return o.within(q["point"], q["radius"])
        return o.visible(q["eye"], q["dir"], q["half_angle_deg"], q["range"])


def time_path(path, queries, reps):
    pc = time.perf_counter_ns
    answers, samples = {}, {}
    for q in queries:
        ss = samples.setdefault(family_of(q), [])
        for _ in range(reps):
            t0 = pc()
            a = path.run(q)
            ss.append(pc() - t0)
        answers[q["id"]] = a
    return answers, samples


def median_us(ns):
    return statistics.median(ns) / 1e3


# ------------------------------------------------------------ live scenes
def serve(name, obj, translation):
    """The writer process: the office (mint), published; on `move k` it moves `obj`'s
    mesh by k%2 * translation and publishes, printing the monotonic time before the move."""
    graph = yggdrasil.office_graph("mint")
    snap = graph.snapshot()
    meshes = snap.node(obj).children
    orig = {m: np.array(snap.node(m).points) for m in meshes}
    del snap
    t = np.asarray(translation, dtype=np.float32)
    with yggdrasil.Writer(name, graph) as writer:
        print("ready", flush=True)
        for line in sys.stdin:
            cmd = line.split()
            if not cmd or cmd[0] == "quit":
                break
            k = int(cmd[1])
            t0 = time.monotonic_ns()
            for m in meshes:
                graph.set_geometry(m, orig[m] + t * (k % 2))
            writer.publish()
            print(t0, writer.generation, flush=True)


class Server:
    def __init__(self, name, update):
        self.p = subprocess.Popen(
            [sys.executable, "-m", "yggdrasil.bench", "--serve", name, "--serve-object",
             str(update["object"]), "--serve-translation", json.dumps(update["translation"])],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self.p.stdout.readline().strip() == "ready"

    def move(self, k):
        self.p.stdin.write(f"move {k}\n")
        self.p.stdin.flush()
        t0, generation = self.p.stdout.readline().split()
        return int(t0), int(generation)

    def close(self):
        self.p.stdin.write("quit\n")
        self.p.stdin.flush()
        self.p.wait(30)


def attach_to_first_answer(name, q, reps):
    ns = []
    for _ in range(reps):
        t0 = time.perf_counter_ns()
        with yggdrasil.Reader(name, wait_for_writer=10) as reader:
            scene = reader.latest() or reader.wait_next(10)
            scene.objects_in(q["room"]).nearest(q["point"])
            ns.append(time.perf_counter_ns() - t0)
            del scene
    return ns


def after_update_ipc(server, name, q, obj, samples):
    total, query = [], []
    with yggdrasil.Reader(name, wait_for_writer=10) as reader:
        reader.wait_next(5)
        for k in range(samples + 3):
            t0, generation = server.move(k + 1)
            scene = reader.wait_next(5)
            while scene is None or scene.generation < generation:
                scene = reader.wait_next(5)
            t1 = time.monotonic_ns()
            answer = scene.objects_in(q["room"]).nearest(q["point"])
            t2 = time.monotonic_ns()
            if (k + 1) % 2 == 1 and answer != obj:
                raise AssertionError(f"after the move the answer is {answer}, not {obj}")
            if k >= 3:
                total.append(t2 - t0)
                query.append(t2 - t1)
            del scene
    return total, query


# ------------------------------------------------------------ main
def package_version(name):
    """The installed version of package ``name``, or ``"not installed"``."""
    from importlib import metadata
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "not installed"


def machine():
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "loadavg": " ".join(f"{x:.2f}" for x in os.getloadavg()),
            "python": platform.python_version(), "spark_dsg": package_version("spark-dsg"),
            "numpy": np.__version__, "scipy": package_version("scipy")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="bench/results/python.md")
    ap.add_argument("--anchor", default="bench/spark_dsg/anchor.py")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--per-room", type=int, default=64)
    ap.add_argument("--dsg-api", action="store_true",
                    help="spark_dsg's API through yggdrasil.dsg against spark_dsg (a section of --out)")
    ap.add_argument("--serve", help=argparse.SUPPRESS)
    ap.add_argument("--serve-object", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--serve-translation", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.serve:
        serve(args.serve, args.serve_object, json.loads(args.serve_translation))
        return 0
    if args.dsg_api:
        from . import _dsg_bench
        return _dsg_bench.run(args.out, args.reps, machine())

    import spark_dsg
    anchor = load_anchor(args.anchor)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="ygg-pybench-"))
    os.environ.setdefault("YGG_IOX2_PREFIX", f"ygt{os.getpid()}x9_")
    js, sb, ygg = tmp / "office.json", tmp / "office.sparkdsg", tmp / "office.ygg"
    yggdrasil.write_office(js)
    yggdrasil.write_office(sb)
    yggdrasil.office_graph("mint").save(ygg)
    info = machine()
    log(f"machine {info}")

    scene = yggdrasil.open(ygg)
    queries, update = make_workload(scene, args.per_room)
    timed = queries[:-1]
    log(f"{len(timed)} queries x {args.reps} repetitions")

    G = spark_dsg.DynamicSceneGraph.load(str(js))
    sc = anchor.Scene(G)
    kd, npath = anchor.KdPath(sc), anchor.NumpyPath(sc)
    walk = anchor.WalkPath(sc)
    ygg_path = YggPath(scene)

    rows = {}
    answers = {}
    for path, qs in ((ygg_path, timed), (kd, timed), (npath, timed),
                     (walk, [q for i, q in enumerate(timed) if q["family"] == "Q3" or i % 40 == 0])):
        time_path(path, qs, 1)  # warm-up: lazily built catalogs, caches
        t0 = time.perf_counter()
        a, s = time_path(path, qs, args.reps)
        log(f"{path.name}: {len(qs)} queries x {args.reps} in {time.perf_counter() - t0:.2f} s")
        answers[path.name] = a
        rows[path.name] = {f: median_us(ns) for f, ns in s.items()}
    differ = [i for i, a in answers["yggdrasil"].items() if a != answers[anchor.KdPath.name][i]]
    differ += [i for i, a in answers[anchor.WalkPath.name].items() if a != answers["yggdrasil"][i]]
    log(f"answers differing from spark_dsg: {len(differ)}")

    # ---- batch: every Q1a point of a room in one call, all rooms
    by_room = {}
    for q in timed:
        if q["family"] == "Q1a":
            by_room.setdefault(q["room"], []).append(q["point"])
    by_room = {r: np.asarray(p, dtype=np.float32) for r, p in by_room.items()}
    big = {r: np.tile(p, (200, 1)) for r, p in by_room.items()}
    n_big = sum(len(p) for p in big.values())

    def ygg_batch():
        return {r: ygg_path.rooms[r].nearest_many(p) for r, p in big.items()}

    def kd_batch():
        out = {}
        for r, p in big.items():
            x, y, z, tree, c = kd.rooms[r]
            _, h = tree.query(p.astype(np.float64), k=1)
            out[r] = c.min_owner[h]
        return out

    batch = {}
    for name, fn in (("yggdrasil", ygg_batch), ("spark-dsg-ckdtree", kd_batch)):
        ns = []
        for _ in range(args.reps):
            t0 = time.perf_counter_ns()
            got = fn()
            ns.append(time.perf_counter_ns() - t0)
        batch[name] = n_big / (statistics.median(ns) / 1e9)
    for r, p in by_room.items():
        single = [ygg_path.rooms[r].nearest(x) for x in p]
        assert [None if i == yggdrasil.NO_NODE else int(i) for i in ygg_batch()[r][: len(p)]] == single

    # ---- nothing to first answer
    first_q = next(q for q in timed if q["family"] == "Q1a")
    first = {}
    ns = []
    for _ in range(args.reps):
        t0 = time.perf_counter_ns()
        s = yggdrasil.open(ygg)
        s.objects_in(first_q["room"]).nearest(first_q["point"])
        ns.append(time.perf_counter_ns() - t0)
        del s
    first["yggdrasil: open .ygg + first Q1a"] = ns
    for label, path in (("spark_dsg: load JSON + arrays + cKDTree + first Q1a", js),
                        ("spark_dsg: load binary + arrays + cKDTree + first Q1a", sb)):
        ns = []
        for _ in range(max(1, args.reps // 2)):
            t0 = time.perf_counter_ns()
            g = spark_dsg.DynamicSceneGraph.load(str(path))
            k = anchor.KdPath(anchor.Scene(g))
            k.run(first_q)
            ns.append(time.perf_counter_ns() - t0)
        first[label] = ns

    # ---- live scene: attach, and the query after a move across processes
    name = f"pybench-{os.getpid()}"
    server = Server(name, update)
    try:
        first["yggdrasil: attach to live scene + first Q1a"] = attach_to_first_answer(name, first_q, args.reps)
        uq = queries[-1]
        total, query = after_update_ipc(server, name, uq, update["object"], 20 * args.reps)
    finally:
        server.close()
    _, spark_rows = anchor.run_update(sc, npath, kd, timed + [queries[-1]],
                                      {"object": update["object"], "translation": update["translation"],
                                       "query": queries[-1]["id"]}, 4 * args.reps)
    spark_after = {r["name"]: r["median_us"] for r in spark_rows}

    write_report(args.out, info, rows, differ, len(timed), args.reps, batch, n_big, first, total, query,
                 spark_after)
    log(f"wrote {args.out}")
    return 0


def write_report(out, info, rows, differ, n_queries, reps, batch, n_batch, first, total, query, spark_after):
    names = ["yggdrasil", "spark-dsg-ckdtree", "spark-dsg-numpy", "spark-dsg-walk"]
    fams = list(rows["yggdrasil"])
    lines = [
        "# Python: Yggdrasil against spark_dsg 1.1.3 (one run)",
        "",
        "`python3 -m yggdrasil.bench --out bench/results/python.md` (from the repository root). The built-in "
        "office (seed 7, full size): Yggdrasil on the mint `.ygg`, mapped; spark_dsg 1.1.3 on the same office "
        "as Spark-DSG JSON, queried the ways of the ladder's anchor (`bench/spark_dsg/anchor.py`).",
        "",
        f"Machine: {json.dumps(info)}.",
        f"Workload: 64 points per room (9 rooms), {n_queries} queries, {reps} repetitions each "
        f"(the walk path on every 40th query); answers of Yggdrasil and spark_dsg differing: **{len(differ)}**.",
        "",
        "## Per query, median µs (Python call to answer)",
        "",
        "| query | " + " | ".join(names) + " | fastest spark_dsg / yggdrasil |",
        "|---|" + "---|" * (len(names) + 1),
    ]
    for f in fams:
        cells = [f"{rows[n][f]:.3g}" if f in rows[n] else "–" for n in names]
        fastest = min(rows[n][f] for n in names[1:] if f in rows[n])
        lines.append(f"| {f} | " + " | ".join(cells) + f" | {fastest / rows['yggdrasil'][f]:.1f}× |")
    lines += [
        "",
        "## Batch nearest object (Q1a points of each room, 200 times over, one call per room)",
        "",
        "| path | queries per second |",
        "|---|---|",
    ]
    for n, qps in batch.items():
        lines.append(f"| {n} | {qps / 1e6:.2f} M |")
    lines += [
        "",
        f"({n_batch} queries per repetition; Yggdrasil's answers checked equal to its single queries; "
        "spark_dsg's vectorised `cKDTree.query` with its smallest-owner lookup.)",
        "",
        "## From nothing to the first answer, median ms",
        "",
        "| what | ms |",
        "|---|---|",
    ]
    for k, ns in first.items():
        lines.append(f"| {k} | {statistics.median(ns) / 1e6:.1f} |")
    ygg_total, ygg_query = median_us(total), median_us(query)
    rebuild = spark_after.get("spark-dsg-rebuild")
    lines += [
        "",
        "## Query after the writer moved an object (the workload's update: one object's mesh, 0.5 m), median µs",
        "",
        "| path | µs |",
        "|---|---|",
        f"| yggdrasil, across processes: mutation + publish in the writer -> new snapshot -> Q1a answer in this process | {ygg_total:.0f} |",
        f"| yggdrasil, of which: the Q1a on the new snapshot (room catalog + query) | {ygg_query:.1f} |",
    ]
    for k, v in spark_after.items():
        lines.append(f"| {k} (in-process: mutate the mesh, re-extract, rebuild, Q1a) | {v:.0f} |")
    if rebuild:
        lines.append("")
        lines.append(f"Ratio spark-dsg-rebuild / yggdrasil across processes: {rebuild / ygg_total:.1f}×; "
                     f"spark-dsg-rebuild / yggdrasil's query on the new snapshot: {rebuild / ygg_query:.0f}×.")
    q1a = rows["yggdrasil"]["Q1a"]
    q1a_spark = min(rows[n]["Q1a"] for n in names[1:])
    labels = {f: rows["yggdrasil"][f] for f in fams if f.startswith("Q3")}
    open_ms = statistics.median(first["yggdrasil: open .ygg + first Q1a"]) / 1e6
    attach_ms = statistics.median(first["yggdrasil: attach to live scene + first Q1a"]) / 1e6

    def verdict(ok):
        return "met" if ok else "**missed**"

    lines += [
        "",
        "## Targets (issue 18), this run",
        "",
        f"- nearest_object per call >= 10x the fastest spark_dsg path (aim <= 3 µs): {q1a:.3g} µs against "
        f"{q1a_spark:.3g} µs, {q1a_spark / q1a:.1f}x: {verdict(q1a_spark / q1a >= 10)}.",
        "- label query <= 1 µs: " + ", ".join(f"{f} {v:.3g} µs ({verdict(v <= 1)})" for f, v in labels.items()) + ".",
        f"- batch nearest >= 1 M queries/s: {batch['yggdrasil'] / 1e6:.2f} M/s: {verdict(batch['yggdrasil'] >= 1e6)}.",
        f"- open .ygg to first answer <= 20 ms: {open_ms:.2f} ms: {verdict(open_ms <= 20)}.",
        f"- attach to a live scene to first answer (report): {attach_ms:.0f} ms.",
    ]
    if rebuild:
        lines.append(f"- query after a move across processes >= 1000x spark_dsg's rebuild path: end to end (mutation in "
                     f"the writer to answer here) {rebuild / ygg_total:.1f}x: {verdict(rebuild / ygg_total >= 1000)}; "
                     f"the query on the new snapshot alone {rebuild / ygg_query:.0f}x: {verdict(rebuild / ygg_query >= 1000)}.")
    pathlib.Path(out).parent.mkdir(parents=True, exist_ok=True)
    pathlib.Path(out).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
