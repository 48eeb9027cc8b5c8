"""Recordings from Python: a `Recorder` follows a live scene published by a Python
`Writer`; `open_recording(...).at(...)` gives back every recorded moment as a `Scene` that
answers as the graph did then; `cuts` are numpy arrays; `changes` names what moved and
was added; the `ygg` command answers the same on the same cut."""
import json
import subprocess

import numpy as np
import pytest

import yggdrasil
from conftest import binary

TICKS = 12
PROBE = [3.0, 4.0, 1.0]


def answers(scene):
    """What a consumer would ask: nearest places, objects near a point, a label."""
    return (
        scene.nearest_nodes(PROBE, m=3, layer="PLACES"),
        scene.nodes_within_radius(PROBE, 4.0, layer="PLACES"),
        scene.objects.within(PROBE, 3.0),
        scene.objects.with_label("recorded"),
    )


def test_every_recorded_moment_answers_as_the_graph_did(scene_name, tmp_path):
    graph = yggdrasil.office_graph("vanilla", scale=0.05)
    path = tmp_path / "run.yggrec"
    places = graph.snapshot().layer("PLACES").nodes
    expected = {}
    with yggdrasil.Writer(scene_name, graph) as writer:
        recorder = yggdrasil.Recorder(scene_name, path, wait_for_writer=10)
        assert recorder.record_next(10)
        expected[writer.generation] = answers(graph.snapshot())
        for tick in range(TICKS):
            graph.set_geometry(places[tick % 3], np.array([[0.5 * tick, 4.0, 1.0]], np.float32))
            graph.add_node(9_000_000 + tick, "OBJECTS")
            graph.set_geometry(9_000_000 + tick, np.array([[3.0, 4.0 + 0.1 * tick, 1.0]], np.float32))
            graph.add_label(9_000_000 + tick, "recorded")
            writer.publish()
            expected[writer.generation] = answers(graph.snapshot())
            assert recorder.record_next(10), f"tick {tick} was not recorded"
        recorder.sync()
        assert recorder.cuts_recorded == TICKS + 1
        del recorder

    recording = yggdrasil.open_recording(path)
    assert len(recording) == TICKS + 1
    cuts = recording.cuts
    assert cuts["generation"].dtype == np.uint64 and cuts["time"].dtype == np.float64
    assert list(cuts["generation"]) == sorted(expected)
    assert np.all(np.diff(cuts["time"]) >= 0)
    assert recording.defects == []
    for i, generation in enumerate(cuts["generation"]):
        by_generation = recording.at(generation=int(generation))
        assert by_generation.generation == generation
        assert answers(by_generation) == expected[int(generation)]
        # A cut's own time, and a time before the next cut, give that cut.
        assert recording.at(time=float(cuts["time"][i])).generation == generation
        if i + 1 < len(recording):
            between = (cuts["time"][i] + cuts["time"][i + 1]) / 2
            assert recording.at(time=float(between)).generation == generation
    assert recording.at().generation == cuts["generation"][-1]
    with pytest.raises(yggdrasil.QueryError, match="no cut at or before"):
        recording.at(time=recording.start_time - 10)
    with pytest.raises(yggdrasil.QueryError):
        recording.at(time=1.0, generation=2)

    changes = recording.changes(recording.start_time, recording.end_time, tolerance=0.01)
    assert list(changes["nodes_added"]) == [9_000_000 + t for t in range(TICKS)]
    assert set(places[:3]) <= set(changes["nodes_moved"].tolist())
    assert changes["moved_to"].shape == (len(changes["nodes_moved"]), 3)
    assert len(changes["nodes_removed"]) == 0

    # The command line answers the same on the same past cut.
    middle = int(cuts["generation"][TICKS // 2])
    line = json.dumps({"op": "objects_within", "point": PROBE, "radius": 3.0})
    out = subprocess.run([binary("ygg"), "query", str(path), "--at", str(middle)],
                         input=line + "\n", capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["ids"] == expected[middle][2]


def test_a_folder_that_is_not_a_recording_raises_file_error(tmp_path):
    with pytest.raises(yggdrasil.FileError, match="no complete cut"):
        yggdrasil.open_recording(tmp_path)
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(yggdrasil.FileError, match="notes.txt"):
        yggdrasil.open_recording(tmp_path)
