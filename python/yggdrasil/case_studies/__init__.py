"""The paper's case studies, reproduced from Python against the pipelines they replaced.

    python -m yggdrasil.case_studies [--quick] [--json FILE] [--md FILE]

Writes ``bench/results/case_studies.md``, ``.json`` and ``.svg`` (run from the
repository root). Each study replaces only the scene-graph interaction of its original
and checks that both backends give the same answers on every call (a difference raises
``AssertionError`` and the command fails):

* ``LP2`` (``lp2``): MIT-SPARK/LP2's spark_dsg + NetworkX backend against the
  ``yggdrasil.dsg`` facade plus Yggdrasil's queries, office and home scenes.
* ``OSG`` (``osg``): OSG's flat NetworkX scene graph against the paper's four-layer
  Yggdrasil design, built and queried in the same scripted exploration loop.
* ``S3DSG`` (``s3dsg``): the cost field from one ``cKDTree`` per object plus one over
  the floor against Yggdrasil's position-indexed metric layers, one query at a time and
  batched.

Needs spark-dsg 1.1.3, networkx and scipy. ``--quick`` (CI) runs fewer trajectories and
repetitions and samples the original's slowest call more sparsely.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

from . import _report
from ._common import Progress, machine

STUDIES = ("LP2", "OSG", "S3DSG")
# The targets (office scene for LP2): a row meets it when ratio >= target.
TARGETS = {
    ("LP2", "office", "room of a waypoint"): 500,
    ("LP2", "office", "nearest waypoint"): 30,
    ("LP2", "office", "waypoints within 0.5 m"): 107,
    ("LP2", "office", "build time"): 77,
    ("LP2", "office", "total graph time"): 250,      # a 99.6 % reduction
    ("OSG", None, "total graph-update time"): 2.5,
    **{("OSG", None, op): 1.0 for op in ("serialize graph to prompt", "get nodes by type", "check node type",
                                        "add node", "count instances", "add edge")},
    ("S3DSG", None, "cost field"): 1.4,
    ("S3DSG", None, "cost field (batch)"): 10,
}


def _to_us(value, unit):
    return value * 1e3 if unit == "ms" else value


def run(quick=False, studies=STUDIES, quiet=False, workdir=None):
    """Runs the studies; returns the result document (rows, notes, machine)."""
    t0 = time.monotonic()
    rows, notes = [], []
    steps = (4 if quick else 12) * ("LP2" in studies) + 2 * ("OSG" in studies) + 2 * ("S3DSG" in studies)
    progress = Progress(steps, quiet=quiet)
    with tempfile.TemporaryDirectory(prefix="ygg-case-studies-") as tmp:
        work = workdir or tmp
        if "LP2" in studies:
            from . import lp2
            r, n = lp2.study(work, quick, progress)
            rows += r
            notes.append(lp2.notes_md(n, r))
        if "OSG" in studies:
            from . import osg
            r, n = osg.study(quick, progress)
            rows += r
            notes.append(n)
        if "S3DSG" in studies:
            from . import s3dsg
            r, n = s3dsg.study(quick, progress)
            rows += r
            notes.append(n)
    progress.close()
    for r in rows:
        r["target"] = TARGETS.get((r["study"], r.get("scene"), r["operation"]))
        r["original_us"] = _to_us(r["original"], r["unit"])
        r["yggdrasil_us"] = _to_us(r["yggdrasil"], r["unit"])
    return {"rows": rows, "notes": notes, "machine": machine(), "quick": quick,
            "seconds": time.monotonic() - t0}


def failures(doc):
    """Rows that miss their target."""
    return [r for r in doc["rows"] if r.get("target") is not None and r["ratio"] < r["target"]]


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m yggdrasil.case_studies", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the CI size (fewer trajectories and runs)")
    ap.add_argument("--json", default=None, help="JSON file (default bench/results/case_studies.json)")
    ap.add_argument("--md", default=None, help="Markdown file (default bench/results/case_studies.md)")
    ap.add_argument("--study", action="append", choices=STUDIES, help="run only this study (repeatable)")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    args = ap.parse_args(argv)
    md = args.md or os.path.join("bench", "results", "case_studies.md")
    js = args.json or (os.path.splitext(md)[0] + ".json")
    svg = os.path.splitext(md)[0] + ".svg"
    for p in (md, js):
        d = os.path.dirname(os.path.abspath(p))
        if not os.path.isdir(d):
            ap.error(f"{d} does not exist (run from the repository root or pass --md/--json)")
    try:
        import networkx  # noqa: F401
        import scipy  # noqa: F401
        import spark_dsg  # noqa: F401
    except ImportError as e:
        ap.error(f"the case studies need spark-dsg==1.1.3, networkx and scipy: {e}")
    doc = run(args.quick, tuple(args.study or STUDIES), args.quiet)
    doc["command"] = "python -m yggdrasil.case_studies" + (" --quick" if args.quick else "")
    _report.write_json(js, doc)
    _report.write_svg(svg, doc["rows"])
    _report.write_md(md, doc, os.path.basename(svg))
    for r in doc["rows"]:
        paper = "-" if r["paper_ratio"] is None else f"{r['paper_ratio']:.2f}x"
        print(f"{_report.label(r):<48} {r['ratio']:9.2f}x  (paper {paper})")
    missed = failures(doc)
    print(f"{len(doc['rows'])} rows, every answer equal; {len(missed)} target(s) missed; "
          f"{doc['seconds']:.0f} s; wrote {md}, {js}, {svg}")
    return 0
