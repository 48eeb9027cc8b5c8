#!/usr/bin/env python3
"""End-to-end test of the Spark-DSG anchor.

    bench/spark_dsg/test_anchor.py [--dsg FILE.json] [--full OFFICE.json]

Runs bench/spark_dsg/run.sh --quick (which creates/reuses the venv) on the tiny
office with a test workload plus hand-made tie and edge cases, then checks the
answers against an independent reference computed from the raw JSON (json
module + numpy, no spark_dsg: parents from the edges, labels from the
labelspace), the update answer, the output schema, and that bad input fails.
--full also runs the full office in --quick mode and checks it stays under 60 s.
Prints 'N passed, N failed' and exits non-zero on any failure.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
RUN = os.path.join(HERE, "run.sh")
TINY = os.path.join(os.path.dirname(ROOT), "shared", "data", "office_tiny.json")
for cand in (TINY, "/work/shared/data/office_tiny.json"):
    if os.path.exists(cand):
        TINY = cand
        break

try:
    import numpy as np
except ImportError:  # re-run inside the anchor's venv (run.sh --help creates it)
    venv = os.environ.get("YGG_VENV", "target/spark-dsg-venv")
    venv = venv if os.path.isabs(venv) else os.path.join(ROOT, venv)
    if subprocess.run([RUN, "--help"], stdout=subprocess.DEVNULL).returncode != 0:
        print("anchor environment unavailable (see above)")
        sys.exit(2)
    py = os.path.join(venv, "bin", "python")
    os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])

F32 = np.float32
RESULTS = []


def check(name, ok, detail=""):
    ok = bool(ok)
    RESULTS.append(ok)
    print(f"{'ok  ' if ok else 'FAIL'} {name}" + (f": {detail}" if detail and not ok else ""))


# ------------------------------------------------------------ independent reference
class Ref:
    def __init__(self, path):
        with open(path) as fh:
            g = json.load(fh)
        layer = {n["id"]: (n["layer"], n.get("partition", 0)) for n in g["nodes"]}
        parent = {}
        for e in g["edges"]:
            a, b = e["source"], e["target"]
            if layer[a][0] != layer[b][0]:
                lo, hi = (a, b) if layer[a][0] < layer[b][0] else (b, a)
                parent[lo] = hi
        self.pts = np.asarray(g["mesh"]["points"], dtype=F32)
        names = dict((i, n) for i, n in g.get("metadata", {}).get("labelspaces", {}).get("_l2p0", []))
        self.objs = {}  # id -> (room, vertex idx array, label)
        for n in g["nodes"]:
            if layer[n["id"]] != (2, 0):
                continue
            r = n["id"]
            while r in parent and layer[r][0] != 4:
                r = parent[r]
            a = n["attributes"]
            lab = names.get(a.get("semantic_label"), a.get("name")) if names else a.get("name")
            self.objs[n["id"]] = (r if layer[r][0] == 4 else None,
                                  np.asarray(a.get("mesh_connections") or [], dtype=np.int64), lab)

    def d2(self, oid, p):
        P = self.pts[self.objs[oid][1]]
        d = P - np.asarray(p, dtype=np.float64).astype(F32)
        return (d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2], d

    def answer(self, q):
        f = q["family"]
        if f == "Q3":
            return sorted(o for o, (_, _, lab) in self.objs.items() if lab == q["label"])
        cands = sorted(o for o, (r, mc, _) in self.objs.items() if r == q["room"] and len(mc))
        if f == "Q1a":
            best = min(((self.d2(o, q["point"])[0].min(), o) for o in cands), default=None)
            return [] if best is None else [best[1]]
        if f == "Q1b":
            r = F32(q["radius"])
            return [o for o in cands if (self.d2(o, q["point"])[0] <= r * r).any()]
        if f == "Q2":
            u = np.asarray(q["dir"], dtype=np.float64).astype(F32)
            rng = F32(q["range"])
            c = F32(np.cos(np.radians(q["half_angle_deg"])))
            out = []
            for o in cands:
                d2, d = self.d2(o, q["eye"])
                dot = (d[:, 0] * u[0] + d[:, 1] * u[1]) + d[:, 2] * u[2]
                if ((d2 <= rng * rng) & ((d2 == 0) | (dot >= np.sqrt(d2) * c))).any():
                    out.append(o)
            return out
        raise ValueError(f)


def run_anchor(dsg, workload, out, *extra):
    t0 = time.time()
    p = subprocess.run([RUN, "--dsg", dsg, "--workload", workload, "--out", out, *extra],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    return p.returncode, p.stderr, time.time() - t0


def edge_cases(ref, queries):
    """Ties: points exactly on vertices claimed by several objects; eye on a vertex."""
    mult = {}
    for o, (r, mc, _) in ref.objs.items():
        for v in mc.tolist():
            mult.setdefault(v, []).append((r, o))
    shared = [(v, owners) for v, owners in sorted(mult.items())
              if len(owners) > 1 and len({r for r, _ in owners}) == 1][:8]
    extra = []
    nid = max(q["id"] for q in queries) + 1
    for v, owners in shared:
        room = owners[0][0]
        p = [float(c) for c in ref.pts[v]]
        extra.append({"id": nid, "family": "Q1a", "room": room, "point": p})
        extra.append({"id": nid + 1, "family": "Q1b", "room": room, "point": p, "radius": 0.0})
        extra.append({"id": nid + 2, "family": "Q2", "room": room, "eye": p, "dir": [0.0, 0.0, 1.0],
                      "half_angle_deg": 1.0, "range": 0.01})
        nid += 3
    return extra, shared


def main():
    args = sys.argv[1:]
    dsg = TINY
    full = None
    if "--dsg" in args:
        dsg = args[args.index("--dsg") + 1]
    if "--full" in args:
        full = args[args.index("--full") + 1]
    tmp = tempfile.mkdtemp(prefix="sparkdsg-anchor-test-")
    wl_path, out = os.path.join(tmp, "wl.json"), os.path.join(tmp, "rows.json")
    subprocess.run([sys.executable, os.path.join(HERE, "make_test_workload.py"), "--dsg", dsg,
                    "--out", wl_path], check=True)
    ref = Ref(dsg)
    with open(wl_path) as fh:
        wl = json.load(fh)
    extra, shared = edge_cases(ref, wl["queries"])
    check("tiny office has vertices shared by objects of one room", len(shared) > 0)
    wl["queries"] += extra
    with open(wl_path, "w") as fh:
        json.dump(wl, fh)

    rc, err, secs = run_anchor(dsg, wl_path, out, "--quick")
    check("run.sh --quick exits 0", rc == 0, err[-2000:])
    if rc != 0:
        return finish()
    with open(out) as fh:
        rows = json.load(fh)

    # answers vs the independent reference
    bad = []
    for q in wl["queries"]:
        want = ref.answer(q)
        got = rows["answers"].get(str(q["id"]))
        if got != want:
            bad.append((q["id"], q["family"], got, want))
    check(f"all {len(wl['queries'])} answers equal the JSON reference", not bad, str(bad[:5]))
    for v, owners in shared[:3]:
        q = next(q for q in extra if q["family"] == "Q1a" and q["point"] == [float(c) for c in ref.pts[v]])
        check(f"tie at vertex {v} goes to the smaller id", rows["answers"][str(q["id"])] == [min(o for _, o in owners)])
    ne = sum(1 for q in wl["queries"] if q["family"] in ("Q1b", "Q2") and rows["answers"][str(q["id"])])
    check("spatial answers are not trivially empty", ne > 100, str(ne))

    # update: reference on a moved copy of the mesh
    upd = wl["update"]
    q = next(q for q in wl["queries"] if q["id"] == upd["query"])
    before = ref.answer(q)
    mc = ref.objs[upd["object"]][1]
    ref.pts[np.unique(mc)] += np.asarray(upd["translation"], dtype=np.float64).astype(F32)
    after = ref.answer(q)
    au = rows.get("after_update", {})
    check("after_update answer_before equals reference", au.get("answer_before") == before, f"{au} {before}")
    check("after_update answer equals reference", au.get("answer") == after, f"{au} {after}")
    check("the update changes the answer (the test really tests it)", before != after)

    # schema
    fams = {"Q1a", "Q1b@0.25", "Q1b@0.5", "Q1b@1", "Q1b@2", "Q1b@4", "Q2",
            "Q3:light", "Q3:shelf", "Q3:bulletin", "Q3:unicorn"}
    for name in ("spark-dsg-walk", "spark-dsg-numpy", "spark-dsg-ckdtree"):
        got = {r["query"] for r in rows["anchors"] if r["name"] == name}
        check(f"{name} rows cover every family", fams <= got, str(fams - got))
    check("spark-dsg-rebuild after_update row",
          any(r["name"] == "spark-dsg-rebuild" and r["query"] == "after_update" for r in rows["anchors"]))
    check("rows have median_us/p99_us", all(r["median_us"] > 0 and r["p99_us"] >= r["median_us"]
                                          for r in rows["anchors"]))
    check("build rows", {b["name"] for b in rows["build"]} >= {"load", "spark-dsg-numpy", "spark-dsg-ckdtree"})
    check("machine info", rows["machine"].get("spark_dsg") == "1.1.3" and rows["machine"].get("python"))
    check("answers keyed by every query id", set(rows["answers"]) == {str(q["id"]) for q in wl["queries"]})

    # bad input fails with exit 3 and no output file
    wl["queries"][0]["room"] = 12345
    with open(wl_path, "w") as fh:
        json.dump(wl, fh)
    rc, err, _ = run_anchor(dsg, wl_path, out, "--quick")
    check("unknown room -> exit 3, no output", rc == 3 and not os.path.exists(out), f"rc={rc}")

    if full:
        wl_full = os.path.join(tmp, "wl_full.json")
        subprocess.run([sys.executable, os.path.join(HERE, "make_test_workload.py"), "--dsg", full,
                        "--out", wl_full], check=True)
        rc, err, secs = run_anchor(full, wl_full, out, "--quick")
        check("full office --quick exits 0", rc == 0, err[-2000:])
        check("full office --quick under 60 s", secs < 60, f"{secs:.1f} s")
        print(f"     full office --quick took {secs:.1f} s")
    shutil.rmtree(tmp, ignore_errors=True)
    return finish()


def finish():
    passed = sum(RESULTS)
    failed = len(RESULTS) - passed
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
