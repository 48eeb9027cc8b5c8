"""``python3 -m yggdrasil.view`` (and ``ygg view``): the command line of the viewer.

Prints one JSON line per event on stdout: ``{"event":"ready","url":...}`` once the page is
served and the first scene is shown, ``{"event":"shown","generation":...,"layers_sent":...,
"layers":...,"nodes":...,"wall_ns":...}`` per scene shown, ``query``, ``selected``,
``writer_gone``; errors go to stderr with exit status 2 (bad input) or 1."""
from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import threading
import time
from typing import List, Optional

import yggdrasil

from .sources import LiveSource, Timeline, load_file
from .style import ROLE_LEVELS, Style, parse_heights


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="ygg view",
        description="Show a scene in the browser: a live scene (--scene NAME), or files (a .ygg, a "
        "Spark-DSG JSON or binary file; several files make a timeline to scrub).",
    )
    ap.add_argument("files", nargs="*", help=".ygg or Spark-DSG files (several: a timeline, in the order given)")
    ap.add_argument("--scene", help="follow this live scene (a reader of it)")
    ap.add_argument("--layout", default="mint", help="layout to import Spark-DSG files in (default mint)")
    ap.add_argument("--query", help='a query line to draw, e.g. \'{"op":"visible_objects","eye":[5,5,1],"dir":[1,0,0],'
                    '"half_angle_deg":30,"range":4}\'')
    ap.add_argument("--host", default="127.0.0.1", help="address to serve the page on (default 127.0.0.1)")
    ap.add_argument("--port", type=int, default=8080, help="port (default 8080; 0 picks a free one)")
    ap.add_argument("--layer-step", type=float, default=4.0, help="metres between two layer levels (default 4)")
    ap.add_argument("--height", action="append", metavar="ROLE=METRES",
                    help=f"lift a role's layers to a height ({', '.join(ROLE_LEVELS)}); repeatable")
    ap.add_argument("--mesh-stride", type=int, default=1, metavar="K",
                    help="draw every K-th mesh point (default 1: all; for a browser without a GPU)")
    ap.add_argument("--max-rate", type=float, default=30.0, help="live updates shown per second at most (default 30)")
    ap.add_argument("--wait-for-writer", type=float, default=10.0, help="seconds to wait for the live scene's writer")
    ap.add_argument("--save", metavar="OUT.viser", help="on exit, write what was shown to a .viser recording "
                    "(viser's offline file; play it with viser's client)")
    ap.add_argument("--seconds", type=float, help="exit after this many seconds (default: until Ctrl-C)")
    return ap


_EVENTS = sys.stdout


def _emit(event: dict) -> None:
    print(json.dumps(event), file=_EVENTS, flush=True)


def main(argv: Optional[List[str]] = None) -> int:
    """Runs the viewer; returns the exit status."""
    global _EVENTS
    args = _parser().parse_args(argv)
    # stdout carries the JSON event lines only: viser's own messages go to stderr.
    _EVENTS, sys.stdout = sys.stdout, sys.stderr
    if bool(args.scene) == bool(args.files):
        print("ygg view: give either --scene NAME or one or more files", file=sys.stderr)
        return 2
    try:
        if args.mesh_stride < 1:
            raise ValueError(f"--mesh-stride {args.mesh_stride}: must be 1 or more")
        style = Style(layer_step=args.layer_step, heights=parse_heights(args.height), mesh_stride=args.mesh_stride)
    except ValueError as e:
        print(f"ygg view: {e}", file=sys.stderr)
        return 2
    try:
        from .viewer import SceneViewer
    except ImportError as e:
        print(f"ygg view: the viewer needs the package extra `view` ({e}): pip install 'yggdrasil[view]' "
              "(or pip install viser pygltflib)", file=sys.stderr)
        return 2

    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    deadline = time.monotonic() + args.seconds if args.seconds is not None else None

    source = None
    try:
        # The input first: a missing file or writer is reported before a page is served.
        if len(args.files) == 1 and os.path.isdir(args.files[0]):
            timeline = Timeline.of_recording(args.files[0])
            first, mesh = timeline.scene(0), None
        elif len(args.files) == 1:
            loaded = load_file(args.files[0], args.layout)
            first, mesh, timeline = loaded.scene, loaded.mesh, None
        elif args.files:
            timeline = Timeline.of_files(args.files, args.layout)
            first, mesh = timeline.scene(0), None
        else:
            source = LiveSource(args.scene, wait_for_writer=args.wait_for_writer)
            first, mesh, timeline = None, None, None
            while first is None and not stop.is_set():
                first = source.next_scene(0.5)
    except (yggdrasil.Error, ValueError) as e:
        if source is not None:
            source.close()
        print(f"ygg view: {e}", file=sys.stderr)
        return 2
    try:
        viewer = SceneViewer(style, host=args.host, port=args.port, emit=_emit)
    except OSError as e:
        if source is not None:
            source.close()
        print(f"ygg view: cannot serve on {args.host}:{args.port}: {e}", file=sys.stderr)
        return 1
    serializer = viewer.server.get_scene_serializer() if args.save else None
    try:
        if timeline is not None:
            viewer.attach_timeline(timeline, lambda i: viewer.show(timeline.scene(i)))
        if first is not None:
            viewer.show(first, mesh)
        del first
        if args.query:
            viewer.set_query(args.query)
        _emit({"event": "ready", "url": f"http://{args.host}:{viewer.port}/"})
        _follow(viewer, source, stop, deadline, args.max_rate)
    except (yggdrasil.Error, ValueError) as e:
        print(f"ygg view: {e}", file=sys.stderr)
        return 2
    finally:
        if serializer is not None:
            with open(args.save, "wb") as out:
                out.write(serializer.serialize())
        viewer.stop()
        if source is not None:
            source.close()
    return 0


def _follow(viewer, source: Optional[LiveSource], stop: threading.Event, deadline: Optional[float], max_rate: float) -> None:
    """Shows each new snapshot of ``source`` (at most ``max_rate`` per second) until
    ``stop`` is set or ``deadline`` passes; without a source, just waits."""
    min_gap = 1.0 / max_rate if max_rate > 0 else 0.0
    following = source is not None
    while not stop.is_set():
        left = None if deadline is None else deadline - time.monotonic()
        if left is not None and left <= 0:
            return
        if not following:
            stop.wait(0.5 if left is None else min(left, 0.5))
            continue
        try:
            scene = source.next_scene(0.25 if left is None else min(left, 0.25))
        except yggdrasil.WriterGoneError:
            _emit({"event": "writer_gone"})
            following = False
            continue
        if scene is None:
            continue
        shown_at = time.monotonic()
        viewer.show(scene)
        del scene
        rest = min_gap - (time.monotonic() - shown_at)
        if rest > 0:
            stop.wait(rest)  # rate cap: later snapshots are coalesced into the newest
