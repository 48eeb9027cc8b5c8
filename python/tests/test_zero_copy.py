"""node.points views the mapped snapshot (no copy) and keeps it alive."""
import gc

import numpy as np

import yggdrasil


def mappings():
    """(start, end, path) of this process's memory mappings."""
    out = []
    with open("/proc/self/maps") as fh:
        for line in fh:
            parts = line.split()
            lo, hi = (int(x, 16) for x in parts[0].split("-"))
            out.append((lo, hi, parts[5] if len(parts) > 5 else ""))
    return out


def mapping_of(address):
    for lo, hi, path in mappings():
        if lo <= address < hi:
            return path
    return None


def mesh_node(scene):
    """An object's mesh node with points."""
    for oid in scene.objects.ids():
        for child in scene.node(oid).children:
            if len(scene.node(child).points) > 10:
                return child
    raise AssertionError("no mesh node")


def test_points_view_the_mapped_file_without_copy(office_dir):
    path = office_dir / "mint.ygg"
    scene = yggdrasil.open(path)
    points = scene.node(mesh_node(scene)).points
    assert points.dtype == np.float32 and points.ndim == 2 and points.shape[1] == 3
    assert not points.flags.writeable and not points.flags.owndata
    assert mapping_of(points.ctypes.data) == str(path)
    again = scene.node(mesh_node(scene)).points
    assert again.ctypes.data == points.ctypes.data


def test_held_points_keep_a_file_snapshot_alive(office_dir):
    scene = yggdrasil.open(office_dir / "mint.ygg")
    node = mesh_node(scene)
    points = scene.node(node).points
    copy = points.copy()
    del scene
    gc.collect()
    assert mapping_of(points.ctypes.data) is not None
    assert np.array_equal(points, copy)


def test_live_points_view_shared_memory_and_outlive_newer_snapshots(scene_name):
    graph = yggdrasil.SceneGraph()
    graph.add_layer("objects")
    graph.add_node(1, "objects")
    graph.set_geometry(1, np.arange(300, dtype=np.float32).reshape(100, 3))
    with yggdrasil.Writer(scene_name, graph) as writer:
        with yggdrasil.Reader(scene_name, wait_for_writer=5) as reader:
            scene = reader.wait_next(5) or reader.latest()
            held = scene.node(1).points
            assert mapping_of(held.ctypes.data).startswith("/dev/shm/")
            want = held.copy()
            del scene
            for step in range(1, 6):
                graph.set_geometry(1, np.full((100, 3), step, dtype=np.float32))
                writer.publish()
                newer = reader.wait_next(5)
                assert newer is not None
                assert np.all(newer.node(1).points == step)
                del newer
                gc.collect()
            assert np.array_equal(held, want)
            del held
