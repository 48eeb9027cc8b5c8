"""``python -m yggdrasil.bench --dsg-api``: spark_dsg 1.1.3's API calls that users make in
loops, through ``yggdrasil.dsg`` and through spark_dsg itself, side by side in one run.

Files: the built-in office (seed 7) as Spark-DSG JSON and binary and as ``.ygg``, and a
10,000-place graph (spark_dsg-built, saved by spark_dsg as JSON and binary). Every timing
is the median over ``--reps`` repetitions; per-call numbers are a repetition's total over
its calls divided by the number of calls.
"""
from __future__ import annotations

import gc
import pathlib
import random
import statistics
import sys
import time
from typing import Callable, Dict, List, Tuple

import numpy as np

import yggdrasil
import yggdrasil.dsg as ydsg

N_PLACES = 10_000
MARK_BEGIN = "<!-- dsg-api: begin (python -m yggdrasil.bench --dsg-api) -->"
MARK_END = "<!-- dsg-api: end -->"


def _log(msg: str) -> None:
    sys.stderr.write(f"[yggdrasil.bench --dsg-api] {msg}\n")
    sys.stderr.flush()


def _fresh(fn: Callable[[], float]) -> float:
    """``fn()`` (which times itself) from a collected heap."""
    gc.collect()
    return fn()


def _median(fn: Callable[[], object], reps: int) -> float:
    times = []
    for _ in range(reps):
        gc.collect()  # each repetition starts from the same heap, for both libraries
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _places_graph(dsg, n: int, seed: int = 5):
    """``n`` places in a chain with random extra edges under 20 rooms and a building."""
    rng = random.Random(seed)
    G = dsg.DynamicSceneGraph()
    b = dsg.NodeSymbol("B", 0)
    G.add_node(dsg.DsgLayers.BUILDINGS, b, dsg.SemanticNodeAttributes())
    for r in range(20):
        attrs = dsg.RoomNodeAttributes()
        attrs.position = np.array([r * 5.0, 0.0, 1.0])
        attrs.name = f"room {r}"
        G.add_node(dsg.DsgLayers.ROOMS, dsg.NodeSymbol("R", r), attrs)
        G.insert_edge(b, dsg.NodeSymbol("R", r))
    for i in range(n):
        attrs = dsg.PlaceNodeAttributes()
        attrs.position = np.array([rng.uniform(0, 100), rng.uniform(0, 20), rng.uniform(0, 3)])
        attrs.name = f"place {i}"
        attrs.semantic_label = rng.randrange(30)
        attrs.distance = rng.uniform(0.2, 2.0)
        p = dsg.NodeSymbol("p", i)
        G.add_node(dsg.DsgLayers.PLACES, p, attrs)
        G.insert_edge(dsg.NodeSymbol("R", i % 20), p)
        if i:
            G.insert_edge(dsg.NodeSymbol("p", i - 1), p)
        if i > 10 and rng.random() < 0.5:
            G.insert_edge(dsg.NodeSymbol("p", rng.randrange(i - 1)), p)
    return G


def run(out: str, reps: int, machine: Dict[str, object]) -> int:
    import spark_dsg
    import spark_dsg.networkx as snx

    tmp = pathlib.Path(__import__("tempfile").mkdtemp(prefix="ygg-dsgapi-"))
    office_json, office_bin, office_ygg = tmp / "office.json", tmp / "office.sparkdsg", tmp / "office.ygg"
    yggdrasil.write_office(office_json)
    yggdrasil.write_office(office_bin)
    yggdrasil.SceneGraph.import_spark_dsg(office_json, layout="vanilla").save(office_ygg)
    big = _places_graph(spark_dsg, N_PLACES)
    places_json, places_bin, places_ygg = tmp / "places.json", tmp / "places.sparkdsg", tmp / "places.ygg"
    big.save(str(places_json))
    big.save(str(places_bin))
    ydsg.load(places_json).save(places_ygg)
    _log(f"files in {tmp}; machine {machine}")

    rows: List[Tuple[str, float, float, str]] = []  # what, yggdrasil, spark_dsg, unit

    # ---- load
    for label, mine_path, their_path in (
        ("load office, Spark-DSG JSON", office_json, office_json),
        ("load office, Spark-DSG binary", office_bin, office_bin),
        ("load office: .ygg (facade) vs binary (spark_dsg)", office_ygg, office_bin),
        ("load 10,000 places, Spark-DSG JSON", places_json, places_json),
        ("load 10,000 places, Spark-DSG binary", places_bin, places_bin),
        ("load 10,000 places: .ygg (facade) vs binary (spark_dsg)", places_ygg, places_bin),
    ):
        m = _median(lambda: ydsg.DynamicSceneGraph.load(mine_path), reps)
        t = _median(lambda: spark_dsg.DynamicSceneGraph.load(str(their_path)), reps)
        rows.append((label, m * 1e3, t * 1e3, "ms"))
        _log(f"{label}: {m * 1e3:.1f} ms vs {t * 1e3:.1f} ms")

    def load_and_walk(load, path, layer):
        def go():
            G = load(path)  # kept alive while its nodes are read (spark_dsg needs it)
            for node in G.get_layer(layer).nodes:
                a = node.attributes
                a.position, a.name, a.semantic_label
        return go

    for label, mine_path, their_path in (
        ("load 10,000 places (JSON) and read every place once", places_json, places_json),
        ("load 10,000 places and read every place once: .ygg (facade) vs binary (spark_dsg)", places_ygg, places_bin),
    ):
        m = _median(load_and_walk(ydsg.DynamicSceneGraph.load, mine_path, ydsg.DsgLayers.PLACES), reps)
        t = _median(load_and_walk(spark_dsg.DynamicSceneGraph.load, str(their_path), spark_dsg.DsgLayers.PLACES), reps)
        rows.append((label, m * 1e3, t * 1e3, "ms"))
        _log(f"{label}: {m * 1e3:.1f} ms vs {t * 1e3:.1f} ms")

    mine, theirs = ydsg.load(places_json), spark_dsg.DynamicSceneGraph.load(str(places_json))
    ids = [n.id.value for n in theirs.get_layer(spark_dsg.DsgLayers.PLACES).nodes]
    n = len(ids)

    def per_call(label: str, fm: Callable[[], object], ft: Callable[[], object], calls: int) -> None:
        m, t = _median(fm, reps) / calls * 1e6, _median(ft, reps) / calls * 1e6
        rows.append((label, m, t, "µs per call"))
        _log(f"{label}: {m:.2f} µs vs {t:.2f} µs")

    def iterate(G, layer):
        def go():
            for node in G.get_layer(layer).nodes:
                a = node.attributes
                a.position, a.name, a.semantic_label
        return go

    per_call("iterate the 10,000-place layer reading position, name, semantic_label (per node)",
             iterate(mine, ydsg.DsgLayers.PLACES), iterate(theirs, spark_dsg.DsgLayers.PLACES), n)

    def positions(G):
        return lambda: [G.get_node(i).attributes.position for i in ids]

    per_call("get_node(id).attributes.position", positions(mine), positions(theirs), n)
    mnodes, tnodes = [mine.get_node(i) for i in ids], [theirs.get_node(i) for i in ids]
    per_call("node.get_parent()", lambda: [x.get_parent() for x in mnodes], lambda: [x.get_parent() for x in tnodes], n)
    per_call("node.children() (rooms)", lambda: [mine.get_node(x.get_parent()).children() for x in mnodes[:2000]],
             lambda: [theirs.get_node(x.get_parent()).children() for x in tnodes[:2000]], 2000)
    per_call("node.siblings()", lambda: [x.siblings() for x in mnodes], lambda: [x.siblings() for x in tnodes], n)

    def adds(dsg):
        attrs = dsg.PlaceNodeAttributes()
        attrs.position = np.array([1.0, 2.0, 3.0])
        attrs.name = "p"

        def go():
            G = dsg.DynamicSceneGraph()
            for i in range(n):
                G.add_node(dsg.DsgLayers.PLACES, i, attrs)
        return go

    per_call("add_node (PlaceNodeAttributes, into a new graph)", adds(ydsg), adds(spark_dsg), n)

    def catch_up():
        G = ydsg.DynamicSceneGraph()
        attrs = ydsg.PlaceNodeAttributes()
        for i in range(n):
            G.add_node(ydsg.DsgLayers.PLACES, i, attrs)
        t0 = time.perf_counter()
        G.scene
        return time.perf_counter() - t0

    m = statistics.median(_fresh(catch_up) for _ in range(reps))
    rows.append((f"the first `G.scene` after {n:,} add_node (the logged edits reach the SceneGraph, snapshot)", m * 1e3, float("nan"), "ms"))
    _log(f"first G.scene after the adds: {m * 1e3:.1f} ms")

    def edges(dsg):
        def go():
            G = dsg.DynamicSceneGraph()
            attrs = dsg.PlaceNodeAttributes()
            for i in range(n):
                G.add_node(dsg.DsgLayers.PLACES, i, attrs)
            t0 = time.perf_counter()
            for i in range(1, n):
                G.insert_edge(i - 1, i)
            return time.perf_counter() - t0
        return go

    m = statistics.median(_fresh(edges(ydsg)) for _ in range(reps)) / (n - 1) * 1e6
    t = statistics.median(_fresh(edges(spark_dsg)) for _ in range(reps)) / (n - 1) * 1e6
    rows.append(("insert_edge (places, in one layer)", m, t, "µs per call"))
    _log(f"insert_edge: {m:.2f} µs vs {t:.2f} µs")

    def load_and_convert(load, convert):
        def go():
            convert(load(office_json))
        return go

    m = _median(load_and_convert(ydsg.DynamicSceneGraph.load, ydsg.graph_to_networkx), reps)
    t = _median(load_and_convert(lambda p: spark_dsg.DynamicSceneGraph.load(str(p)), snx.graph_to_networkx), reps)
    rows.append(("load office (JSON), then graph_to_networkx: every attribute of every node read once", m * 1e3, t * 1e3, "ms"))
    _log(f"load + graph_to_networkx: {m * 1e3:.1f} ms vs {t * 1e3:.1f} ms")

    office_mine, office_theirs = ydsg.load(office_json), spark_dsg.DynamicSceneGraph.load(str(office_json))
    ydsg.graph_to_networkx(office_mine)  # the fields a scene does not keep: read from the file once
    m = _median(lambda: ydsg.graph_to_networkx(office_mine), reps)
    t = _median(lambda: snx.graph_to_networkx(office_theirs), reps)
    rows.append(("graph_to_networkx (office, loaded and converted once before)", m * 1e3, t * 1e3, "ms"))
    _log(f"graph_to_networkx: {m * 1e3:.1f} ms vs {t * 1e3:.1f} ms")

    _write(out, rows, reps, machine, n)
    return 0


def _write(out: str, rows, reps: int, machine, n: int) -> None:
    lines = [
        MARK_BEGIN,
        "## spark_dsg's API: `yggdrasil.dsg` against spark_dsg 1.1.3 (issue 39)",
        "",
        f"`python3 -m yggdrasil.bench --dsg-api` (from the repository root; {reps} repetitions, medians). "
        "Files: the built-in office (seed 7, full size) as Spark-DSG JSON and binary, and as `.ygg` "
        f"(vanilla layout); a {n:,}-place graph built and saved by spark_dsg (JSON, binary) and as `.ygg`. "
        "Per-call rows: the calls over every place (children: over 2,000 places' rooms).",
        "",
        f"Machine: {machine}.",
        "",
        "| operation | yggdrasil.dsg | spark_dsg | unit | yggdrasil.dsg / spark_dsg |",
        "|---|---|---|---|---|",
    ]
    for what, m, t, unit in rows:
        if t != t:  # nothing to compare with
            lines.append(f"| {what} | {m:.3g} | — | {unit} | — |")
        else:
            lines.append(f"| {what} | {m:.3g} | {t:.3g} | {unit} | {m / t:.3g}× |")
    lines.append("")
    lines.append(MARK_END)
    path = pathlib.Path(out)
    text = path.read_text() if path.exists() else ""
    block = "\n".join(lines)
    if MARK_BEGIN in text and MARK_END in text:
        a, b = text.index(MARK_BEGIN), text.index(MARK_END) + len(MARK_END)
        text = text[:a] + block + text[b:]
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    path.write_text(text)
    _log(f"wrote {out}")
