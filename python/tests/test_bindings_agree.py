"""The package's conventions (issue 37): a nearest object is an id or None, batch answers
hold -1 for none, angles are degrees everywhere, ``query`` reads a dict without JSON,
where the agent is comes from ``ygg_dsg::layout``, and the transport is quiet."""
import json
import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import yggdrasil


def agent_graph():
    """Two rooms, three agent poses (the newest in room 2), one object with a mesh node."""
    g = yggdrasil.SceneGraph()
    for layer in ("ROOMS", "OBJECTS", "MESH", "AGENTS"):
        g.add_layer(layer)
    g.add_layer_edge("ROOMS", "OBJECTS")
    g.add_layer_edge("OBJECTS", "MESH")
    for room, x0 in ((1, 0.0), (2, 10.0)):
        g.add_node(room, "ROOMS")
        g.set_geometry(room, [[x0, 0.0, 0.0], [x0 + 5.0, 4.0, 3.0]])
        g.enable_bounding_box(room)
    g.add_node(20, "OBJECTS")
    g.nest(2, 20)
    g.add_node(30, "MESH")
    g.set_geometry(30, [[12.0, 2.0, 0.5]])
    g.nest(20, 30)
    for pose, x in ((100, 1.0), (101, 9.0), (102, 12.0)):
        g.add_node(pose, "AGENTS")
        g.set_geometry(pose, [[x, 2.0, 1.0]])
    return g


def test_nearest_is_an_id_or_none_and_batches_hold_minus_one():
    scene = agent_graph().snapshot()
    assert scene.objects.nearest([12.0, 2.0, 0.0]) == 20
    empty = yggdrasil.SceneGraph()
    empty.add_layer("OBJECTS")
    none = empty.snapshot()
    assert none.objects.nearest([0.0, 0.0, 0.0]) is None
    assert yggdrasil.NO_NODE == -1
    ids = none.objects.nearest_many(np.zeros((3, 3)))
    assert ids.dtype == np.int64 and ids.tolist() == [-1, -1, -1]
    near, dist = none.nearest_nodes_many(np.zeros((2, 3)))
    assert near.dtype == np.uint64 and near.mask.tolist() == [True, True] and np.isinf(dist).all()
    near, dist = scene.nearest_nodes_many(np.array([[12.0, 2.0, 0.5], [0.0, 0.0, 0.0]]), layer="MESH")
    assert near.mask.tolist() == [False, False] and near.tolist() == [30, 30]
    assert scene.objects.nearest_many(np.array([[12.0, 2.0, 0.0]])).tolist() == [20]


def test_every_angle_is_degrees():
    g = yggdrasil.SceneGraph()
    g.add_layer("OBJECTS")
    g.add_layer("MESH")
    g.add_layer_edge("OBJECTS", "MESH")
    g.add_node(1, "OBJECTS")
    g.add_node(2, "MESH")
    g.nest(1, 2)
    # 30 degrees off the +x axis, 2 m away.
    g.set_geometry(2, [[2.0 * math.cos(math.radians(30)), 2.0 * math.sin(math.radians(30)), 0.0]])
    scene = g.snapshot()
    eye, ahead = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]
    assert scene.visible(1, eye, ahead, 35.0, 5.0) == [2]  # the nodes with a point
    assert scene.visible(1, eye, ahead, 25.0, 5.0) == []
    assert scene.objects.visible(eye, ahead, 35.0, 5.0) == [1]
    assert scene.objects.visible(eye, ahead, 25.0, 5.0) == []
    with pytest.raises(yggdrasil.QueryError, match="180"):
        scene.visible(1, eye, ahead, 190.0, 5.0)


def test_query_reads_a_dict_without_json(monkeypatch):
    scene = agent_graph().snapshot()

    def no_json(*args, **kwargs):
        raise AssertionError("scene.query encoded its dict as JSON")

    monkeypatch.setattr(json, "dumps", no_json)
    assert scene.query({"op": "nearest_object", "point": [12, 2, 0]}) == {"ids": [20]}
    assert scene.query({"op": "nearest_object", "point": np.array([12.0, 2.0, 0.0]).tolist()}) == {"ids": [20]}
    assert scene.query({"op": "objects_within", "point": (12.0, 2.0, 0.0), "radius": np.float32(1)}) == {"ids": [20]}
    with pytest.raises(yggdrasil.QueryError, match='missing field "op"'):
        scene.query({"point": [1, 2, 3]})
    with pytest.raises(yggdrasil.QueryError, match='field "point"'):
        scene.query({"op": "nearest_object", "point": [1, 2]})
    with pytest.raises(yggdrasil.QueryError, match='"radius"'):
        scene.query({"op": "nearest_object", "point": [1, 2, 3], "radius": 1})
    with pytest.raises(yggdrasil.QueryError, match="finite"):
        scene.query({"op": "nearest_object", "point": [float("nan"), 0, 0]})


def test_where_the_agent_is():
    scene = agent_graph().snapshot()
    pose = scene.newest_pose()
    assert pose.node == 102
    assert pose.position == (12.0, 2.0, 1.0) and pose.previous == (9.0, 2.0, 1.0)
    assert pose.heading == (1.0, 0.0, 0.0)
    assert scene.room_of(pose.position) == 2
    assert scene.room_of([1.0, 1.0, 9.0]) == 1  # x and y only
    assert scene.room_of([7.0, 1.0, 0.0]) is None
    assert scene.owners([30, 30, 20, 999]) == [2, 20]
    assert scene.room_scope(2) is None  # not a per-room layout
    assert yggdrasil.SceneGraph().snapshot().newest_pose() is None


def test_room_scope_in_a_per_room_layout():
    scene = yggdrasil.office_graph("mint", scale=0.05).snapshot()
    scopes = [s for s in map(scene.room_scope, scene.layer("ROOMS").nodes) if s is not None]
    assert scopes
    for s in scopes:
        assert s.mesh_layer in scene.layers
        # The claimed group node's sub-tree holds exactly the objects of the room.
        inside = scene.objects_in(s.claimed).ids()
        assert set(inside) <= set(scene.objects.ids())
        assert all(scene.parent(o) is not None for o in inside)


QUIET = textwrap.dedent("""
    import sys, yggdrasil
    if len(sys.argv) > 2:
        yggdrasil.set_log_level(sys.argv[2])
    g = yggdrasil.SceneGraph()
    g.add_layer("OBJECTS")
    with yggdrasil.Writer(sys.argv[1], g) as w, yggdrasil.Reader(sys.argv[1], wait_for_writer=10) as r:
        assert r.wait_next(10) is not None
    print("done")
""")


def run_reader_and_writer(scene_name, *args, env=None):
    import os

    run = subprocess.run([sys.executable, "-c", QUIET, scene_name, *args], capture_output=True, text=True,
                         timeout=60, env={**os.environ, **(env or {})})
    assert run.returncode == 0 and run.stdout.strip() == "done", run.stderr
    return run.stderr


def test_the_transport_is_quiet_unless_asked(scene_name, monkeypatch):
    monkeypatch.delenv("YGG_LOG", raising=False)
    assert run_reader_and_writer(scene_name) == ""
    # The noise the default hides is there when asked for (so the check above can fail).
    for asked in (run_reader_and_writer(scene_name, "warn"), run_reader_and_writer(scene_name, env={"YGG_LOG": "info"})):
        assert "No config file was loaded" in asked, asked
    with pytest.raises(ValueError, match="loud"):
        yggdrasil.set_log_level("loud")


def test_the_live_graph_answers_label_and_edge_queries_as_its_snapshot_does():
    """``SceneGraph.nodes_with_label`` and ``edges_from`` run the store's queries over the
    live graph: the same answers as a snapshot of it, after every kind of edit."""
    import random

    rng = random.Random(7)
    g = yggdrasil.SceneGraph()
    for layer in ("A", "B"):
        g.add_layer(layer)
    labels = ["chair", "desk", "door"]
    nodes = []
    for step in range(300):
        action = rng.random()
        if action < 0.4 or len(nodes) < 4:
            n = 1000 + step
            g.add_node(n, rng.choice(["A", "B"]))
            nodes.append(n)
        elif action < 0.6:
            g.add_label(rng.choice(nodes), rng.choice(labels))
        elif action < 0.8:
            a, b = rng.sample(nodes, 2)
            try:
                g.add_edge(a, b, rng.choice(["near", "connects to"]))
            except yggdrasil.MutationError:
                pass  # an edge already there
        else:
            gone = nodes.pop(rng.randrange(len(nodes)))
            g.remove_node(gone)
        if step % 25 == 0:
            s = g.snapshot()
            for label in labels:
                for layer in (None, "A", "B"):
                    assert g.nodes_with_label(label, layer) == s.nodes_with_label(label, layer)
            for n in nodes:
                assert g.edges_from(n) == s.edges_from(n)
    assert any(g.edges_from(n) for n in nodes), "the walk made edges"
    with pytest.raises(yggdrasil.QueryError, match="unknown node 5"):
        g.edges_from(5)
    with pytest.raises(yggdrasil.QueryError, match="unknown layer"):
        g.nodes_with_label("chair", "C")
