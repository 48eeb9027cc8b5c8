"""Bad input raises a typed exception with the Rust message, never crashes the interpreter."""
import numpy as np
import pytest

import yggdrasil


def small_graph():
    g = yggdrasil.SceneGraph()
    g.add_layer("rooms")
    g.add_layer("objects")
    g.add_layer_edge("rooms", "objects")
    g.add_node(1, "rooms")
    g.add_node(7, "objects")
    g.set_geometry(7, [[1.0, 2.0, 0.5]])
    g.add_label(7, "chair")
    g.nest(1, 7)
    return g


def test_the_hierarchy():
    for e in (yggdrasil.FileError, yggdrasil.QueryError, yggdrasil.MutationError, yggdrasil.TransportError):
        assert issubclass(e, yggdrasil.Error)
    assert issubclass(yggdrasil.WriterGoneError, yggdrasil.TransportError)


def test_corrupted_and_foreign_files_raise_file_error(office_dir, tmp_path):
    good = (office_dir / "chocolate.ygg").read_bytes()
    cases = {
        "missing.ygg": None,
        "empty.ygg": b"",
        "text.ygg": b"hello, world\n" * 10,
        "truncated.ygg": good[: len(good) // 2],
        "header.ygg": good[:40],
    }
    rng = np.random.default_rng(5)
    for i in range(20):
        b = bytearray(good)
        for at in rng.integers(16, len(b), 64):
            b[at] ^= 0xFF
        cases[f"flipped{i}.ygg"] = bytes(b)
    raised = 0
    for name, data in cases.items():
        p = tmp_path / name
        if data is not None:
            p.write_bytes(data)
        try:
            scene = yggdrasil.open(p)
        except yggdrasil.FileError as e:
            raised += 1
            assert str(p) in str(e) or "segment" in str(e) or name in str(e), str(e)
        else:  # a flip that validation cannot see (padding): queries still work
            scene.objects.nearest([1, 2, 3])
    assert raised >= 5
    with pytest.raises(yggdrasil.FileError, match="missing.ygg"):
        yggdrasil.open(tmp_path / "missing.ygg")
    with pytest.raises(yggdrasil.FileError):
        yggdrasil.SceneGraph.import_spark_dsg(tmp_path / "text.ygg")
    with pytest.raises(yggdrasil.FileError):
        import yggdrasil.dsg as dsg
        dsg.load(tmp_path / "truncated.ygg")


def test_garbage_queries_raise_query_error():
    scene = small_graph().snapshot()
    bad_queries = [
        {"op": "nearest_object"}, {"op": 1}, {}, "not json", "[]", 42, {"op": "nearest_object", "point": "xyz"},
        {"op": "nearest_object", "point": [float("nan"), 0, 0]}, {"op": "objects_within", "point": [0, 0, 0], "radius": "r"},
        {"op": "objects_with_label", "label": None}, object(),
    ]
    for q in bad_queries:
        with pytest.raises(yggdrasil.QueryError):
            scene.query(q)
    with pytest.raises(yggdrasil.QueryError, match="non-finite"):
        scene.objects.nearest([float("inf"), 0, 0])
    with pytest.raises(yggdrasil.QueryError, match="point"):
        scene.nearest_nodes([1, 2])
    with pytest.raises(yggdrasil.QueryError, match="radius"):
        scene.nodes_within_radius([0, 0, 0], -1.0)
    with pytest.raises(yggdrasil.QueryError, match="unknown node 99"):
        scene.node(99)
    with pytest.raises(yggdrasil.QueryError, match="unknown layer"):
        scene.nodes_with_label("chair", layer="nope")
    with pytest.raises(yggdrasil.QueryError, match=r"\(n, 3\)"):
        scene.objects.nearest_many(np.zeros((4, 2)))
    with pytest.raises(yggdrasil.QueryError):
        scene.objects.nearest_many("garbage")
    with pytest.raises(yggdrasil.QueryError, match="direction"):
        scene.bfs(1, direction="sideways")
    with pytest.raises(OverflowError):
        scene.node(-1)


def test_invalid_mutations_raise_mutation_error_and_change_nothing(tmp_path):
    g = small_graph()
    g.save(tmp_path / "before.ygg")
    before = (tmp_path / "before.ygg").read_bytes()
    refused = [
        lambda: g.add_layer("rooms"),
        lambda: g.add_layer_edge("objects", "rooms"),  # cycle
        lambda: g.add_node(7, "objects"),
        lambda: g.add_node(8, "nowhere"),
        lambda: g.add_node(2**64 - 1, "rooms"),
        lambda: g.add_edge(1, 7),  # across layers
        lambda: g.add_edge(7, 7),
        lambda: g.nest(7, 1),
        lambda: g.nest(1, 7),  # already nested
        lambda: g.set_geometry(7, [[float("nan"), 0, 0]]),
        lambda: g.set_geometry(7, [[1, 2]]),
        lambda: g.append_points(7, [[0, 0, 0], [float("inf"), 0, 0]]),
        lambda: g.append_points(42, [[0, 0, 0]]),
        lambda: g.set_feature(7, "x", float("nan")),
        lambda: g.set_feature(7, "x", [1, 2]),
        lambda: g.remove_label(7, "table"),
        lambda: g.remove_node(42),
        lambda: g.remove_layer_edge("rooms", "objects"),  # in use
    ]
    for edit in refused:
        with pytest.raises(yggdrasil.MutationError):
            edit()
    g.save(tmp_path / "after.ygg")
    assert (tmp_path / "after.ygg").read_bytes() == before


def test_appending_points_equals_setting_the_longer_list(tmp_path):
    appended, replaced = small_graph(), small_graph()
    appended.append_points(7, np.array([[3.0, 1.0, 0.0], [4.0, 2.0, 1.0]], dtype=np.float32))
    appended.append_points(7, [])
    replaced.set_geometry(7, [[1.0, 2.0, 0.5], [3.0, 1.0, 0.0], [4.0, 2.0, 1.0]])
    appended.save(tmp_path / "appended.ygg")
    replaced.save(tmp_path / "replaced.ygg")
    assert (tmp_path / "appended.ygg").read_bytes() == (tmp_path / "replaced.ygg").read_bytes()


def test_no_writer_raises_transport_error(scene_name):
    with pytest.raises(yggdrasil.TransportError, match="no writer"):
        yggdrasil.Reader(scene_name)
    with pytest.raises(yggdrasil.TransportError):
        yggdrasil.Writer("bad name with spaces!", yggdrasil.SceneGraph())


def test_a_graph_past_the_writers_layer_bound_raises_and_keeps_the_last_snapshot(scene_name):
    g = yggdrasil.SceneGraph()
    g.add_layer("rooms")
    with yggdrasil.Writer(scene_name, g, max_layers=1) as writer, yggdrasil.Reader(
        scene_name
    ) as reader:
        assert reader.wait_next(5.0).layers == ["rooms"]
        g.add_layer("objects")
        with pytest.raises(yggdrasil.TransportError, match="max_layers"):
            writer.publish()
        assert reader.latest().layers == ["rooms"]
        g.remove_layer("objects")
        writer.publish()
        assert reader.latest().layers == ["rooms"]
