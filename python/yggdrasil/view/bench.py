"""The viewer's benchmark (issue 43): ``python3 -m yggdrasil.view.bench`` writes
``bench/results/viewer.md`` (``.json`` beside it) and the screenshots
``bench/results/viewer_office.png`` and ``viewer_query.png``.

1. Update latency: a writer process serves the office (mint) and, on command, moves an
   object's mesh and publishes; ``python3 -m yggdrasil.view --scene`` follows it; headless
   Chromium shows the page. Measured: the writer's wall clock just before ``publish()``
   to the page's wall clock when its status line named that generation (a
   ``MutationObserver`` hook; the viewer writes that line after the changed layers).
2. The writer's ``publish()`` per tick, paired: the same writer process runs the same
   30 Hz stream (an object's mesh moved and the newest agent pose moved per tick) in
   alternating phases without and with the viewer (process and page) attached.
3. The full office shown after the page opens: a fresh page, from ``goto`` to the status
   line naming every node plus two drawn frames, repeated."""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import yggdrasil

from . import browser
from ..bench import machine


def log(msg: str) -> None:
    print(f"[view-bench] {msg}", file=sys.stderr, flush=True)


# ------------------------------------------------------------------ the writer process
def serve(name: str, scale: float) -> None:
    """The writer: the office (mint) at ``scale`` published; reads commands on stdin:
    ``move K`` moves one object's mesh by K%2 * 0.5 m in x and publishes, printing
    ``<wall ns before publish> <generation>``; ``ticks N HZ`` runs N ticks at HZ (the
    mesh and the newest pose moved per tick) and prints the ``publish()`` ns of each as a
    JSON list; ``quit`` exits."""
    graph = yggdrasil.office_graph("mint", scale=scale)
    snap = graph.snapshot()
    obj = snap.objects.ids()[0]
    meshes = snap.node(obj).children
    orig = {m: np.array(snap.node(m).points) for m in meshes}
    agents = snap.layer("AGENTS").nodes
    pose = agents[-1]
    pose_p = np.array(snap.node(pose).points)
    del snap
    shift = np.array([0.5, 0.0, 0.0], np.float32)
    with yggdrasil.Writer(name, graph) as writer:
        print("ready", flush=True)
        for line in sys.stdin:
            cmd = line.split()
            if not cmd or cmd[0] == "quit":
                break
            if cmd[0] == "move":
                k = int(cmd[1])
                for m in meshes:
                    graph.set_geometry(m, orig[m] + shift * (k % 2))
                t0 = time.time_ns()
                writer.publish()
                print(t0, writer.generation, flush=True)
            elif cmd[0] == "ticks":
                n, hz = int(cmd[1]), float(cmd[2])
                period = 1e9 / hz
                start = time.monotonic_ns()
                publish_ns = []
                for k in range(n):
                    for m in meshes:
                        graph.set_geometry(m, orig[m] + shift * (k % 2))
                    graph.set_geometry(pose, pose_p + np.float32(0.01 * (k % 50)))
                    t0 = time.perf_counter_ns()
                    writer.publish()
                    publish_ns.append(time.perf_counter_ns() - t0)
                    # The stream's clock: the next tick is due at start + (k+1) periods.
                    due = start + (k + 1) * period
                    rest = due - time.monotonic_ns()
                    if rest > 0:
                        time.sleep(rest / 1e9)
                print(json.dumps(publish_ns), flush=True)


class Writer:
    """The writer process, driven over its stdin."""

    def __init__(self, name: str, scale: float = 1.0) -> None:
        self.p = subprocess.Popen([sys.executable, "-m", "yggdrasil.view.bench", "--serve", name, "--serve-scale",
                                   str(scale)],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self.p.stdout.readline().strip() == "ready"

    def command(self, line: str) -> str:
        self.p.stdin.write(line + "\n")
        self.p.stdin.flush()
        return self.p.stdout.readline()

    def close(self) -> None:
        self.command("quit")
        self.p.wait(30)


class Viewer:
    """``python3 -m yggdrasil.view`` with ``args``, until closed; its page's address."""

    def __init__(self, *args: str) -> None:
        self.p = subprocess.Popen([sys.executable, "-m", "yggdrasil.view", *args, "--port", "0"],
                                  stdout=subprocess.PIPE, text=True)
        for line in self.p.stdout:
            event = json.loads(line)
            if event["event"] == "ready":
                self.url = event["url"]
                return
        raise RuntimeError("the viewer exited before it was ready")

    def close(self) -> None:
        self.p.send_signal(2)
        self.p.wait(30)


#: The query drawn in ``viewer_query.png``: the objects in a cone along the office's corridor.
QUERY_SHOWN = {"op": "visible_objects", "eye": [12.0, 12.5, 1.5], "dir": [1.0, 0.0, 0.0], "half_angle_deg": 30,
               "range": 10}


def screenshot_query(out: pathlib.Path) -> None:
    """``viewer_query.png``: the office as a file with ``QUERY_SHOWN`` drawn."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "office.ygg")
        yggdrasil.office_graph("mint").save(path)
        viewer = Viewer(path, "--query", json.dumps(QUERY_SHOWN))
        with browser.open_viewer(viewer.url) as page:
            page.status()
            page.page.get_by_text("objects:").first.wait_for()
            page.dismiss_notices()
            gold = (255, 215, 0)
            page.screenshot_until(str(out.with_name("viewer_query.png")),
                                  lambda p: len(browser.color_pixels(p, gold)) > 50)
        viewer.close()


def pct(xs, q):
    return float(np.percentile(np.asarray(xs, np.float64), q))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="bench/results/viewer.md")
    ap.add_argument("--updates", type=int, default=40, help="moves timed per latency row")
    ap.add_argument("--ticks", type=int, default=600, help="ticks per phase of the paired publish() run")
    ap.add_argument("--phases", type=int, default=3, help="pairs of phases (without, with)")
    ap.add_argument("--opens", type=int, default=5, help="fresh pages timed for the full office")
    ap.add_argument("--screenshot-only", action="store_true", help="only write viewer_query.png beside --out")
    ap.add_argument("--serve", help=argparse.SUPPRESS)
    ap.add_argument("--serve-scale", type=float, default=1.0, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.serve:
        serve(args.serve, args.serve_scale)
        return 0
    os.environ.setdefault("YGG_IOX2_PREFIX", f"ygt{os.getpid()}x9_")
    out = pathlib.Path(args.out)
    if args.screenshot_only:
        screenshot_query(out)
        return 0
    name = f"viewbench-{os.getpid()}"
    info = machine()
    info["viser"] = __import__("viser").__version__
    info["chromium"] = subprocess.run([browser.chromium_path(), "--version"], capture_output=True, text=True).stdout.strip()
    log(f"machine {info}")
    results = {"machine": info}
    opens, latency = {}, {}
    cases = (
        ("the full office (3,774 nodes, 386k mesh points)", 1.0, []),
        ("the full office, every 4th mesh point drawn (--mesh-stride 4)", 1.0, ["--mesh-stride", "4"]),
        ("the office at scale 0.25 (987 nodes, 96k mesh points)", 0.25, []),
    )
    for case, scale, extra in cases:
        # ---- 1 and 3: the scene shown after the page opens, and the update latency
        writer = Writer(f"{name}-{len(opens)}", scale)
        viewer = Viewer("--scene", f"{name}-{len(opens)}", *extra)
        opens[case] = []
        for _ in range(args.opens):
            with browser.open_viewer(None) as page:
                t0 = time.time_ns()
                page.goto(viewer.url)
                _, layers, nodes = page.status()
                page.page.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
                opens[case].append((time.time_ns() - t0) / 1e6)
        log(f"shown after the page opens, {case}: {opens[case]} ms ({layers} layers, {nodes} nodes)")
        modes = [case, f"{case}, mesh hidden (the panel's toggle)"] if not extra and scale == 1.0 else [case]
        with browser.open_viewer(viewer.url) as page:
            page.status()
            if len(modes) == 2:
                page.dismiss_notices()
                page.screenshot(str(out.with_name("viewer_office.png")))
            k = 0
            for mode in modes:
                if mode.endswith("(the panel's toggle)"):  # the page stops drawing the mesh's points
                    page.page.get_by_text("mesh", exact=True).last.click()
                latency[mode] = []
                for i in range(args.updates + 3):
                    k += 1
                    t0, generation = (int(x) for x in writer.command(f"move {k}").split())
                    shown = page.wait_generation(generation)
                    if i >= 3:
                        latency[mode].append((shown - t0) / 1e6)
                log(f"update latency, {mode}: p50 {statistics.median(latency[mode]):.1f} ms")
        viewer.close()
        writer.close()

    writer = Writer(name)
    try:
        # ---- 2: publish() per tick, paired phases without and with the viewer
        phases = {"without": [], "with": []}
        for _ in range(args.phases):
            for mode in ("without", "with"):
                if mode == "with":
                    viewer = Viewer("--scene", name)
                    with browser.open_viewer(viewer.url) as page:
                        page.status()
                        ns = json.loads(writer.command(f"ticks {args.ticks} 30"))
                    viewer.close()
                else:
                    ns = json.loads(writer.command(f"ticks {args.ticks} 30"))
                phases[mode].append(statistics.median(ns) / 1e3)
                log(f"publish() median {mode} the viewer: {phases[mode][-1]:.1f} us")
    finally:
        writer.close()

    screenshot_query(out)
    ratio = [w / wo for w, wo in zip(phases["with"], phases["without"])]
    results.update({
        "update_latency_ms": {
            mode: {"p50": statistics.median(x), "p95": pct(x, 95), "max": max(x), "samples": len(x)}
            for mode, x in latency.items()
        },
        "full_office_shown_ms": {
            case: {"median": statistics.median(x), "all": x} for case, x in opens.items()
        },
        "publish_us_median": phases,
        "publish_ratio_with_over_without": ratio,
        "query_shown": QUERY_SHOWN,
    })
    out.with_suffix(".json").write_text(json.dumps(results, indent=2))
    write_report(out, results, args)
    log(f"wrote {out}")
    return 0


def write_report(out: pathlib.Path, r: dict, args) -> None:
    lat, full, pub = r["update_latency_ms"], r["full_office_shown_ms"], r["publish_us_median"]
    ratio = statistics.median(r["publish_ratio_with_over_without"])
    m = r["machine"]

    def verdict(ok):
        return "met" if ok else "**missed**"

    lines = [
        "# The browser viewer (issue 43)",
        "",
        f"`python3 -m yggdrasil.view.bench` on {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
        f"{m['cpu']}, {m['cores']} cores, load average {m['loadavg']} at the start; Python {m['python']}, "
        f"viser {m['viser']}, {m['chromium']} headless with software WebGL (no GPU).",
        "",
        "| target | measured | target | verdict |",
        "|---|---|---|---|",
        *(
            f"| an update visible in the browser after `publish()` ({mode}; one object's mesh moved, "
            f"{x['samples']} updates) | p50 {x['p50']:.1f} ms, p95 {x['p95']:.1f} ms, max {x['max']:.1f} ms "
            f"| ≤ 100 ms | {verdict(x['p50'] <= 100)} |"
            for mode, x in lat.items()
        ),
        f"| the writer's `publish()` per tick with the viewer attached / without (median of the "
        f"{len(pub['with'])} pairs' ratios of medians, {args.ticks} ticks at 30 Hz per phase) | "
        f"{ratio:.3f} ({', '.join(f'{w:.0f}/{wo:.0f} µs' for w, wo in zip(pub['with'], pub['without']))}) "
        f"| ≤ 1.05 | {verdict(ratio <= 1.05)} |",
        *(
            f"| {case} shown after the page opens (median of {len(x['all'])} fresh pages) | {x['median']:.0f} ms "
            f"({', '.join(f'{v:.0f}' for v in x['all'])}) | ≤ 3000 ms | {verdict(x['median'] <= 3000)} |"
            for case, x in full.items()
        ),
        "",
        "How each is measured:",
        "",
        "- **update latency**: a writer process serves the office (mint) and, per command, moves one object's "
        "mesh and publishes; `python3 -m yggdrasil.view --scene` follows it, headless Chromium shows the page. "
        "From the writer's wall clock just before `publish()` to the page's wall clock (`performance.timeOrigin + "
        "performance.now()`) when its status line first names that generation, seen by a `MutationObserver` "
        "(`yggdrasil/view/browser.py`). The viewer sends the changed layers before that line over the same "
        "websocket, so the page holds them by then; drawing them is the next animation frame. Measured with "
        "the mesh shown, and with the mesh hidden by the panel's toggle (the page then stops drawing its "
        "386k points: what a frame costs in software WebGL is the difference).",
        "- **publish() per tick**: the same writer process runs the same stream (an object's mesh and the "
        "newest agent pose moved per tick, 30 Hz) in alternating phases without and with the viewer (its process "
        "following the scene and a Chromium page open), medians per phase.",
        "- **full office shown**: a fresh Chromium page per run (browser already started), from `goto` to "
        "the status line naming every node (sent after every layer) plus two animation frames.",
        "",
        f"Screenshots: the office live ([viewer_office.png](viewer_office.png)) and the office with the query "
        f"`{json.dumps(QUERY_SHOWN)}` drawn ([viewer_query.png](viewer_query.png)).",
        "",
        "![the office in the viewer](viewer_office.png)",
        "",
    ]
    out.write_text("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
