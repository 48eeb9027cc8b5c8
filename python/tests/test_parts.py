"""Layers split into parts (row chunks): a Python reader of a Python writer that appends,
edits, nests and removes rows of a layer of many parts answers every query as the live
graph does, and an append resends a few parts, not the layer."""
import numpy as np

import yggdrasil


def answers(scene, places, probes):
    """What the comparison looks at: nearest and radius queries over the poses, the
    places' children, the poses' parents, the node count."""
    out = {"count": scene.node_count}
    for p in probes:
        out[("nearest", tuple(p))] = scene.nearest_nodes(p, 5, layer="POSES")
        out[("within", tuple(p))] = scene.nodes_within_radius(p, 2.5, layer="POSES")
    for place in places:
        out[("children", place)] = scene.children(place)
    return out


def until_generation(reader, generation):
    """The reader's snapshot of `generation` (it may first hand out older ones)."""
    while True:
        scene = reader.wait_next(10)
        assert scene is not None, f"no snapshot {generation} within 10 s"
        if scene.generation >= generation:
            assert scene.generation == generation
            return scene


def test_a_reader_of_a_layer_in_many_parts_answers_as_the_live_graph(scene_name):
    g = yggdrasil.SceneGraph()
    places_layer = g.add_layer("PLACES")
    poses_layer = g.add_layer("POSES")
    g.add_layer_edge("PLACES", "POSES")
    g.enable_layer_index("POSES")
    places = [1000 + k for k in range(10)]
    for k, place in enumerate(places):
        g.add_node(place, places_layer)
        g.set_geometry(place, np.array([[10.0 * k, 0.0, 0.0]], dtype=np.float32))
    rng = np.random.default_rng(7)
    probes = [rng.uniform(-5.0, 100.0, 3).astype(np.float32) for _ in range(6)]
    next_pose = 10_000
    with yggdrasil.Writer(scene_name, g, part_rows=16) as writer, \
            yggdrasil.Reader(scene_name, wait_for_writer=10) as reader:
        for step in range(60):
            # Append a batch of poses along a line, each nested under its nearest place
            # and linked to the previous one (an odometry edge).
            for _ in range(20):
                x = (next_pose - 10_000) * 0.1
                g.add_node(next_pose, poses_layer)
                g.set_geometry(next_pose, np.array([[x, 1.0, 0.0]], dtype=np.float32))
                g.nest(places[min(int(x // 10), len(places) - 1)], next_pose)
                if next_pose > 10_000:
                    g.add_edge(next_pose - 1, next_pose, "odometry")
                next_pose += 1
            if step % 10 == 5:
                # An edit in the middle of the layer (a pose the removals below have not
                # reached), and the oldest poses dropped.
                g.set_geometry(next_pose - 30, np.array([[50.0, 5.0, 0.0]], dtype=np.float32))
                for old in range(10_000 + (step - 5) * 8, 10_000 + (step + 5) * 8):
                    if g.snapshot().has_node(old):
                        g.remove_node(old)
            report = writer.publish()
            scene = until_generation(reader, report["generation"])
            assert answers(scene, places, probes) == answers(g.snapshot(), places, probes), step
        # Hundreds of poses in parts: an append sends its part (and perhaps a merge of cold
        # parts), not the layer.
        assert report["segments"] > 10, report
        g.add_node(next_pose, poses_layer)
        g.set_geometry(next_pose, np.array([[1.0, 1.0, 1.0]], dtype=np.float32))
        report = writer.publish()
        assert 1 <= report["parts_sent"] and 2 * report["parts_sent"] < report["segments"], report
        scene = until_generation(reader, report["generation"])
        assert scene.nearest_nodes([1.0, 1.0, 1.0], 1, layer="POSES")[0][0] == next_pose
