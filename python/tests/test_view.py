"""The browser viewer (yggdrasil.view): what it draws of a scene, that it re-sends only
the changed layers, queries made visible, and, in headless Chromium (Debian's chromium
driven by Playwright), a live scene shown by `ygg view` and an update appearing."""
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import yggdrasil
from conftest import REPO, binary

pytest.importorskip("viser", reason="the viewer extra: pip install 'yggdrasil[view]'")
from yggdrasil.view import browser  # noqa: E402
from yggdrasil.view.drawing import SceneDrawing  # noqa: E402
from yggdrasil.view.queries import parse_query, query_shape  # noqa: E402
from yggdrasil.view.sources import Timeline, load_file  # noqa: E402
from yggdrasil.view.style import Style, label_color, parse_heights, role_of  # noqa: E402

RED, GREEN = label_color("3"), label_color("2")
MOVING = 11


def small_graph():
    """A room over three objects, each with a mesh node of two points: 10 and 12
    labelled 2 (green), 11 labelled 3 (red)."""
    g = yggdrasil.SceneGraph()
    rooms, objects, mesh = g.add_layer("ROOMS"), g.add_layer("OBJECTS"), g.add_layer("MESH")
    g.add_layer_edge(rooms, objects)
    g.add_layer_edge(objects, mesh)
    g.add_node(1, rooms)
    g.set_geometry(1, [[5.0, 2.0, 0.0]])
    for node, label, p in ((10, "2", (1.0, 3.0, 0.0)), (MOVING, "3", (1.0, 0.0, 0.0)), (12, "2", (9.0, 3.0, 0.0))):
        g.add_node(node, objects)
        g.set_geometry(node, [p])
        g.add_label(node, label)
        g.nest(1, node)
        g.add_node(node + 100, mesh)
        g.set_geometry(node + 100, [p, (p[0] + 0.2, p[1], p[2])])
        g.nest(node, node + 100)
    g.add_edge(10, 12)
    return g


def test_line_drawings_are_gltf_line_lists_with_every_segment_and_color():
    """The GLB the viewer sends for a layer's edges, boxes and nesting lines holds one
    LINES primitive whose vertices are the segments' ends and whose colors are theirs."""
    import pygltflib

    from yggdrasil.view.lines import line_segments_glb

    segments = np.array([[[0, 0, 0], [1, 2, 3]], [[4, 5, 6], [-1, -2, -3]], [[7, 7, 7], [8, 8, 8]]], np.float32)
    colors = np.array([[255, 0, 0], [0, 255, 0], [1, 2, 3]], np.uint8)
    doc = pygltflib.GLTF2.load_from_bytes(line_segments_glb(segments, colors))
    (primitive,) = doc.meshes[0].primitives
    assert primitive.mode == pygltflib.LINES
    blob = doc.binary_blob()
    pos_view = doc.bufferViews[doc.accessors[primitive.attributes.POSITION].bufferView]
    col_view = doc.bufferViews[doc.accessors[primitive.attributes.COLOR_0].bufferView]
    positions = np.frombuffer(blob, np.float32, 6 * 3, pos_view.byteOffset).reshape(3, 2, 3)
    rgba = np.frombuffer(blob, np.uint8, 6 * 4, col_view.byteOffset).reshape(3, 2, 4)
    np.testing.assert_array_equal(positions, segments)
    np.testing.assert_array_equal(rgba[..., :3], np.repeat(colors[:, None, :], 2, axis=1))
    assert (rgba[..., 3] == 255).all()
    assert doc.accessors[primitive.attributes.POSITION].min == [-1.0, -2.0, -3.0]
    one_color = pygltflib.GLTF2.load_from_bytes(line_segments_glb(segments, np.array([9, 8, 7], np.uint8)))
    col_view = one_color.bufferViews[one_color.accessors[1].bufferView]
    rgba = np.frombuffer(one_color.binary_blob(), np.uint8, 6 * 4, col_view.byteOffset).reshape(6, 4)
    assert (rgba[:, :3] == [9, 8, 7]).all()


def test_a_layer_role_comes_from_its_name():
    assert role_of("OBJECTS") == "objects"
    assert role_of("room:7/claimed-mesh") == "mesh"
    assert role_of("room:7/claimed-object") == "objects"
    assert role_of("room:7") == "groups"
    assert role_of("MESH_PLACES") == "places"
    assert role_of("whatever") == "other"
    assert parse_heights(["rooms=12"]) == {"rooms": 12.0}
    with pytest.raises(ValueError, match="--height 'attic=3'"):
        parse_heights(["attic=3"])


def test_the_drawing_lifts_layers_colors_labels_and_redraws_only_changed_layers():
    g = small_graph()
    drawing = SceneDrawing(Style(layer_step=4.0))
    first = drawing.update(g.snapshot())
    assert sorted(first.changed) == ["MESH", "OBJECTS", "ROOMS"]
    objects, rooms = drawing.layers["OBJECTS"], drawing.layers["ROOMS"]
    assert objects.ids.tolist() == [10, MOVING, 12]
    assert rooms.positions[0].tolist() == [5.0, 2.0, 8.0]  # rooms two levels up
    assert [tuple(c) for c in objects.colors] == [GREEN, RED, GREEN]
    assert drawing.legend() == {"2": GREEN, "3": RED}
    assert len(objects.edges) == 1 and len(drawing.nesting["OBJECTS"]) == 3
    assert [tuple(c) for c in drawing.layers["MESH"].mesh_colors] == [GREEN, GREEN, RED, RED, GREEN, GREEN]
    g.set_geometry(MOVING, [[8.0, 0.0, 0.0]])
    second = drawing.update(g.snapshot())
    assert second.changed == ["OBJECTS"] and second.removed == []
    assert drawing.layers["OBJECTS"].positions[1].tolist() == [8.0, 0.0, 0.0]
    assert drawing.nearest_node([8.0, 0.0, 20.0], [0.0, 0.0, -1.0]) == (MOVING, "OBJECTS", 0.0)


def test_the_office_is_drawn_whole():
    scene = yggdrasil.office_graph("mint").snapshot()
    drawing = SceneDrawing(Style())
    drawing.update(scene)
    assert drawing.node_count == scene.node_count
    assert sum(len(d.mesh_points) for d in drawing.layers.values()) > 350_000
    assert "chair" in drawing.legend()
    quarter = SceneDrawing(Style(mesh_stride=4))
    quarter.update(scene)
    shown = sum(len(d.mesh_points) for d in quarter.layers.values())
    mesh_nodes = [i for name in scene.layers if role_of(name) == "mesh" for i in scene.layer(name).nodes]
    assert shown == sum(len(scene.node(i).points[::4]) for i in mesh_nodes)  # every 4th point of each node


def test_a_query_line_is_checked_and_drawn():
    q = parse_query('{"op":"visible_objects","eye":[0,0,1],"dir":[1,0,0],"half_angle_deg":30,"range":4}')
    shape = query_shape(q)
    assert shape.shape == (48 + 8, 2, 3)  # the rim and eight rays from the eye
    assert np.allclose(shape[48:, 0], [0.0, 0.0, 1.0])
    ball = query_shape(parse_query({"op": "objects_within", "point": [1, 2, 3], "radius": 2}))
    assert np.allclose(np.linalg.norm(ball[3:, 0] - [1, 2, 3], axis=1), 2.0, atol=1e-5)
    with pytest.raises(ValueError, match="unknown op 'closest'"):
        parse_query('{"op":"closest"}')
    with pytest.raises(ValueError, match="objects_within needs radius"):
        parse_query('{"op":"objects_within","point":[0,0,0]}')


def test_a_timeline_of_scenes_redraws_what_differs_between_its_steps():
    g = small_graph()
    before = g.snapshot()
    g.set_geometry(MOVING, [[8.0, 0.0, 0.0]])
    timeline = Timeline.of_scenes([before, g.snapshot()])
    drawing = SceneDrawing(Style())
    drawing.update(timeline.scene(1))
    assert drawing.update(timeline.scene(0)).changed == ["OBJECTS"]
    assert drawing.layers["OBJECTS"].positions[1].tolist() == [1.0, 0.0, 0.0]


def test_a_timeline_of_cuts_loads_each_cut_by_its_generation():
    g = small_graph()
    scenes = {5: g.snapshot()}
    g.set_geometry(MOVING, [[8.0, 0.0, 0.0]])
    scenes[9] = g.snapshot()
    asked = []

    def at(generation):
        asked.append(generation)
        return scenes[generation]

    timeline = Timeline.of_cuts([9, 5], [20.5, 10.25], at)
    assert [e.time_ns for e in timeline.entries] == [10_250_000_000, 20_500_000_000]
    assert timeline.scene(1) is scenes[9] and timeline.scene(0) is scenes[5] and asked == [9, 5]
    assert timeline.entries[0].label == "generation 5 at 10.250 s"


def test_a_recording_is_a_timeline_of_its_cuts(scene_name, tmp_path):
    graph = small_graph()
    path = tmp_path / "run.yggrec"
    with yggdrasil.Writer(scene_name, graph) as writer:
        recorder = yggdrasil.Recorder(scene_name, path, wait_for_writer=10)
        assert recorder.record_next(10)
        for x in (3.0, 6.0):
            graph.set_geometry(MOVING, [[x, 0.0, 0.0]])
            writer.publish()
            assert recorder.record_next(10)
        del recorder
    timeline = Timeline.of_recording(str(path))
    recording = yggdrasil.open_recording(path)
    assert len(timeline) == len(recording) == 3
    for i, generation in enumerate(recording.cuts["generation"]):
        scene = timeline.scene(i)
        assert scene.generation == generation
        assert scene.node(MOVING).points.tolist() == recording.at(generation=int(generation)).node(MOVING).points.tolist()
    assert timeline.scene(2).node(MOVING).points.tolist() == [[6.0, 0.0, 0.0]]


def test_view_reports_a_missing_file_and_a_bad_height(tmp_path):
    ygg = binary("ygg")
    run = subprocess.run([ygg, "view", str(tmp_path / "none.ygg")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "none.ygg: no such file" in run.stderr
    run = subprocess.run([ygg, "view", "x.ygg", "--height", "rooms=high"], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "'high' is not a number" in run.stderr


def test_readme_viewer_example_runs():
    text = (REPO / "README.md").read_text()
    section = text.split("## See the scene", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert blocks, "README: no python block in the viewer's section"
    exec(compile(blocks[0], "README.md", "exec"), {})


def test_a_spark_dsg_file_is_imported_in_a_layout(small_office):
    loaded = load_file(str(small_office / "office.sparkdsg"), "mint")
    assert loaded.scene.node_count > 0 and "ROOMS" in loaded.scene.layers
    assert loaded.mesh is None  # the generated office's mesh has no colors: drawn in label colors
    drawing = SceneDrawing(Style())
    drawing.update(loaded.scene)
    assert drawing.node_count == loaded.scene.node_count


# ------------------------------------------------------------------ in the browser
needs_browser = pytest.mark.skipif(
    browser.chromium_path() is None and not os.environ.get("CI"),
    reason="Debian's chromium is not installed (.ci/view installs it)",
)


def start_view(procs, *args):
    """`ygg view ARGS --port 0` started; returns the process, its page's address and the
    events it printed before it was ready."""
    p = procs([binary("ygg"), "view", *args, "--port", "0", "--seconds", "300"])
    events = []
    for line in p.p.stdout:
        events.append(json.loads(line))
        if events[-1]["event"] == "ready":
            return p, events[-1]["url"], events
    pytest.fail(f"ygg view exited: {p.p.stderr.read()}")


# The 3D view's region of a 1280x800 screenshot: left of the panel, below the notice.
CANVAS = (0, 160, 900, 800)


@needs_browser
def test_a_live_scene_is_shown_in_chromium_and_an_update_appears(scene_name, procs, tmp_path):
    graph = small_graph()
    with yggdrasil.Writer(scene_name, graph) as writer:
        view, url, _ = start_view(procs, "--scene", scene_name)
        with browser.open_viewer(url) as page:
            generation, layers, nodes = page.status()
            scene = graph.snapshot()
            assert (layers, nodes) == (len(scene.layers), scene.node_count)
            before, after = str(tmp_path / "before.png"), str(tmp_path / "after.png")

            def pixels(path, color):
                return browser.color_pixels(path, color, region=CANVAS)

            # viser fades new nodes in: screenshots until the labels' colors are drawn.
            assert page.screenshot_until(before, lambda p: len(pixels(p, RED)) > 20 and len(pixels(p, GREEN)) > 40)
            red = pixels(before, RED)
            graph.set_geometry(MOVING, [[8.0, 0.0, 0.0]])  # 7 m to the right (+x)
            writer.publish()
            page.wait_generation(writer.generation)

            def moved_right(path):
                now = pixels(path, RED)
                return len(now) > 20 and now[:, 0].mean() > red[:, 0].mean() + 100

            assert page.screenshot_until(after, moved_right), (red.mean(axis=0), pixels(after, RED).mean(axis=0))
        view.stop()
        assert view.p.returncode == 0, view.p.stderr.read()


@needs_browser
def test_a_timeline_of_files_is_scrubbed_with_its_slider(procs, tmp_path):
    g = small_graph()
    g.save(tmp_path / "t0.ygg")
    g.add_node(13, "OBJECTS")
    g.set_geometry(13, [[5.0, 5.0, 0.0]])
    g.save(tmp_path / "t1.ygg")
    view, url, _ = start_view(procs, str(tmp_path / "t0.ygg"), str(tmp_path / "t1.ygg"))
    with browser.open_viewer(url) as page:
        assert page.status()[1:] == (3, 7)
        slider = page.page.get_by_role("slider")
        slider.focus()
        page.page.keyboard.press("ArrowRight")  # one step later: t1.ygg
        page.page.wait_for_function("/· 8 nodes/.test(document.body.innerText)")
        page.page.keyboard.press("ArrowLeft")
        page.page.wait_for_function("/· 7 nodes/.test(document.body.innerText)")
    view.stop()
    assert view.p.returncode == 0


@needs_browser
def test_a_query_is_drawn_its_answer_highlighted(procs, tmp_path):
    path = tmp_path / "small.ygg"
    small_graph().save(path)
    q = '{"op":"objects_within","point":[1,3,0],"radius":1}'
    view, url, events = start_view(procs, str(path), "--query", q)
    with browser.open_viewer(url) as page:
        assert page.status()[2] == 7
        page.page.get_by_text("1 objects").wait_for()
        shot = str(tmp_path / "query.png")

        def drawn(path):
            gold = browser.color_pixels(path, (255, 215, 0), region=CANVAS)
            ring = browser.color_pixels(path, (230, 0, 60), region=CANVAS)
            return len(gold) > 20 and len(ring) > 20

        assert page.screenshot_until(shot, drawn), "no highlight or ball in the screenshot"
    view.stop()
    assert {"event": "query", "op": "objects_within", "ids": [10], "generation": 0} in events


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
