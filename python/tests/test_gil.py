"""Waits and batch queries release the GIL: another Python thread makes progress."""
import threading
import time

import numpy as np

import yggdrasil


class Counter(threading.Thread):
    def __init__(self):
        super().__init__(daemon=True)
        self.count = 0
        self.stop = False
        self.running = threading.Event()

    def run(self):
        self.running.set()
        while not self.stop:
            self.count += 1


def progress_during(fn):
    c = Counter()
    c.start()
    assert c.running.wait(10), "the counter thread did not start"
    before = c.count
    t0 = time.perf_counter()
    fn()
    elapsed = time.perf_counter() - t0
    during = c.count - before
    c.stop = True
    c.join()
    return during, elapsed


def test_wait_next_releases_the_gil(scene_name):
    graph = yggdrasil.SceneGraph()
    graph.add_layer("rooms")
    with yggdrasil.Writer(scene_name, graph):
        with yggdrasil.Reader(scene_name, wait_for_writer=5) as reader:
            reader.wait_next(5)
            during, elapsed = progress_during(lambda: reader.wait_next(0.5))
            assert elapsed >= 0.4
            assert during > 10_000, f"counter thread advanced only {during} times in {elapsed:.2f} s"


def test_batch_queries_release_the_gil(office_dir):
    scene = yggdrasil.open(office_dir / "mint.ygg")
    points = np.random.default_rng(1).uniform(0, 10, (100_000, 3)).astype(np.float32)
    during, elapsed = progress_during(lambda: scene.objects.nearest_many(points))
    assert during > 1_000, f"counter thread advanced only {during} times in {elapsed:.2f} s"
    mesh = next(name for name in scene.layers if name.endswith("/claimed-mesh"))  # indexed
    during, _ = progress_during(lambda: scene.nearest_nodes_many(points, layer=mesh))
    assert during > 1_000
