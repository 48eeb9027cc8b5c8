"""`scene.query(...)` and `scene.objects` answer exactly what `ygg query` answers
for the same lines, on the office in every layout."""
import json
import subprocess

import numpy as np
import pytest

import yggdrasil
from conftest import LAYOUTS, binary


def query_lines(scene, n=60, seed=3):
    """Queries of every op around the office's objects, plus lines the CLI refuses."""
    rng = np.random.default_rng(seed)
    positions = []
    for oid in scene.objects.ids():
        f = scene.node(oid).features
        positions.append([f["position_x"], f["position_y"], f["position_z"]])
    positions = np.asarray(positions)
    lines = []
    for _ in range(n):
        p = positions[rng.integers(len(positions))] + rng.normal(0, 1.0, 3)
        d = rng.normal(0, 1, 3)
        p, d = [round(float(v), 4) for v in p], [round(float(v), 4) for v in d]
        lines.append({"op": "nearest_object", "point": p})
        lines.append({"op": "objects_within", "point": p, "radius": float(rng.choice([0.25, 0.5, 1, 2, 4]))})
        lines.append({"op": "visible_objects", "eye": p, "dir": d,
                      "half_angle_deg": float(rng.uniform(30, 70)), "range": float(rng.uniform(0.3, 8))})
    for label in ("light", "shelf", "bulletin", "unicorn", "5"):
        lines.append({"op": "objects_with_label", "label": label})
    bad = [
        {"op": "nearest_object", "point": [1, 2]},
        {"op": "teleport"},
        {"op": "objects_within", "point": [0, 0, 0], "radius": -1},
        {"op": "visible_objects", "eye": [0, 0, 0], "dir": [0, 0, 0], "half_angle_deg": 30, "range": 2},
        {"op": "visible_objects", "eye": [0, 0, 0], "dir": [1, 0, 0], "half_angle_deg": 200, "range": 2},
        {"op": "objects_with_label", "label": 7},
        [1, 2, 3],
    ]
    return lines, bad


def cli_answers(path, lines, tmp_path):
    q = tmp_path / "queries.jsonl"
    q.write_text("".join(json.dumps(line) + "\n" for line in lines))
    run = subprocess.run([binary("ygg"), "query", str(path), "--queries", str(q)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    return [json.loads(line) for line in run.stdout.splitlines()]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_every_op_answers_as_the_cli_does(office_dir, tmp_path, layout):
    path = office_dir / f"{layout}.ygg"
    scene = yggdrasil.open(path)
    lines, bad = query_lines(scene)
    cli = cli_answers(path, lines + bad, tmp_path)
    assert len(cli) == len(lines) + len(bad)
    for i, (line, want) in enumerate(zip(lines, cli)):
        assert "ids" in want, want
        assert scene.query(line) == want, line
        assert scene.query(json.dumps(line)) == want
        o = scene.objects
        got = {
            "nearest_object": lambda: [n for n in [o.nearest(line["point"])] if n is not None],
            "objects_within": lambda: o.within(line["point"], line["radius"]),
            "visible_objects": lambda: o.visible(line["eye"], line["dir"], line["half_angle_deg"], line["range"]),
            "objects_with_label": lambda: o.with_label(line["label"]),
        }[line["op"]]()
        assert got == want["ids"], line
    for i, (line, want) in enumerate(zip(bad, cli[len(lines):])):
        number = len(lines) + i + 1
        assert "error" in want, want
        with pytest.raises(yggdrasil.QueryError) as e:
            scene.query(line)
        assert want["error"] == f"line {number}: {e.value}"


@pytest.mark.parametrize("layout", LAYOUTS)
def test_batch_queries_answer_as_single_ones(office_dir, layout):
    scene = yggdrasil.open(office_dir / f"{layout}.ygg")
    lines, _ = query_lines(scene, n=40, seed=9)
    points = np.array([line["point"] for line in lines if line["op"] == "nearest_object"], dtype=np.float32)
    o = scene.objects
    ids = o.nearest_many(points)
    assert ids.dtype == np.int64 and ids.shape == (len(points),)
    assert [None if i == yggdrasil.NO_NODE else int(i) for i in ids] == [o.nearest(p) for p in points]
    offsets, flat = o.within_many(points, 1.0)
    assert [flat[offsets[i]:offsets[i + 1]].tolist() for i in range(len(points))] == [o.within(p, 1.0) for p in points]
    dirs = np.tile(np.array([[1.0, 0.2, 0.0]], dtype=np.float32), (len(points), 1))
    offsets, flat = o.visible_many(points, dirs, 45.0, 4.0)
    assert [flat[offsets[i]:offsets[i + 1]].tolist() for i in range(len(points))] == [
        o.visible(p, d, 45.0, 4.0) for p, d in zip(points, dirs)]
    near, dist = scene.nearest_nodes_many(points)
    single = [scene.nearest_nodes(p, 1) for p in points]
    assert [int(i) for i in near] == [s[0][0] for s in single]
    assert np.allclose(dist, [s[0][1] for s in single])
