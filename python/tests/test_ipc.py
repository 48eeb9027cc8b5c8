"""Across processes: a Python reader follows a Rust writer, and a Rust reader follows a
Python writer. Every child is stopped by the `procs` fixture (a watchdog)."""
import contextlib
import json
import subprocess
import time

import numpy as np
import pytest

import yggdrasil
from conftest import binary


def test_python_reader_follows_a_rust_writer(scene_name, procs):
    # Growing layers in parts of a few rows: the reader joins many part segments.
    writer = procs([binary("ygg"), "serve", "--scene", scene_name, "--scale", "0.05",
                    "--rate", "30", "--seconds", "30", "--part-rows", "8"])
    with yggdrasil.Reader(scene_name, wait_for_writer=20) as reader:
        generations = []
        while len(generations) < 5:
            scene = reader.wait_next(10)
            assert scene is not None, "no snapshot within 10 s"
            generations.append(scene.generation)
            assert scene.objects.nearest([5.0, 5.0, 1.0]) is not None
            assert scene.query({"op": "objects_with_label", "label": "light"})["ids"] == \
                scene.objects.with_label("light")
        assert generations == sorted(set(generations))
        assert reader.writer_status == "alive"
        writer.stop()
        with pytest.raises(yggdrasil.WriterGoneError):
            for _ in range(50):
                reader.wait_next(0.2)
        assert reader.writer_status == "gone"
        assert scene.objects.nearest([5.0, 5.0, 1.0]) is not None  # the last snapshot stays usable


def test_rust_reader_follows_a_python_writer(scene_name, procs):
    graph = yggdrasil.office_graph("mint", scale=0.05)
    with yggdrasil.Writer(scene_name, graph) as writer, contextlib.ExitStack() as stack:
        watch = procs([binary("ygg"), "watch", "--scene", scene_name, "--count", "4",
                       "--wait-for-writer", "10"])
        mine = stack.enter_context(yggdrasil.Reader(scene_name, wait_for_writer=5))
        first = mine.wait_next(5)
        obj = first.objects.ids()[0]
        mesh = first.node(obj).children[0]
        del first
        deadline = time.monotonic() + 20
        step = 0
        while time.monotonic() < deadline:
            step += 1
            time.sleep(0.05)  # pacing: a 20 Hz writer; the loop ends on the watch's exit
            graph.set_geometry(mesh, np.full((3, 3), 0.01 * step, dtype=np.float32))
            report = writer.publish()
            assert report["layers_sent"] >= 1 and report["layers_unchanged"] >= 1
            if watch.p.poll() is not None:
                break
            mine.wait_next(0.25)
        code, out, err = watch.wait(timeout=20)
        assert code == 0, err
        assert "received 4 snapshots" in out or out.count("\n") >= 4, out
        line = json.dumps({"op": "nearest_object", "point": [0.0, 0.0, 0.0]})
        run = subprocess.run([binary("ygg"), "query", "--scene", scene_name],
                             input=line + "\n", capture_output=True, text=True, timeout=60)
        assert run.returncode == 0, run.stderr
        assert json.loads(run.stdout) == mine.latest().query(line)
        mine.close()
