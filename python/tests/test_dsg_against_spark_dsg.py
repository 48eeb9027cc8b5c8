"""yggdrasil.dsg against spark_dsg 1.1.3 itself: the same files loaded by both, and the
same random spark_dsg-style calls made on both, give the same nodes, attributes, edges,
parents, children, siblings and layer keys; a graph the facade writes loads in spark_dsg
equal to the one spark_dsg builds."""
import datetime
import os
import pathlib
import random

import numpy as np
import pytest

import yggdrasil
import yggdrasil.dsg as ydsg

spark_dsg = pytest.importorskip("spark_dsg")

# The fields a Yggdrasil scene keeps; the others come from a JSON file only.
KEPT = {"position", "name", "semantic_label", "bounding_box"}


def same_value(name, mine, theirs):
    if isinstance(theirs, np.ndarray):
        assert mine.dtype == theirs.dtype, name
        assert mine.shape == theirs.shape, name
        assert np.allclose(mine, theirs, atol=1e-5), name
    elif type(theirs).__name__ == "BoundingBox":
        assert mine.type.name == theirs.type.name, name
        if theirs.type.name != "INVALID":
            assert np.allclose(mine.dimensions, theirs.dimensions, atol=1e-5), name
            assert np.allclose(mine.world_P_center, theirs.world_P_center, atol=1e-5), name
            assert np.allclose(mine.world_R_center, theirs.world_R_center, atol=1e-5), name
    elif type(theirs).__name__ == "Quaternion":
        assert np.allclose([mine.w, mine.x, mine.y, mine.z], [theirs.w, theirs.x, theirs.y, theirs.z]), name
    elif isinstance(theirs, float):
        assert mine == pytest.approx(theirs, rel=1e-6), name
    elif isinstance(theirs, datetime.timedelta):
        assert mine == theirs, name
    elif isinstance(theirs, list) and theirs and not isinstance(theirs[0], (int, float)):
        assert len(mine) == len(theirs), name  # spark_dsg's connection objects: count them
    else:
        assert mine == theirs, name


def same_graph(mine, theirs, fields="all"):
    assert mine.layer_keys == [ydsg.LayerKey(k.layer, k.partition) for k in theirs.layer_keys]
    assert [layer.id for layer in mine.layers] == [layer.id for layer in theirs.layers]
    for name in ("OBJECTS", "AGENTS", "PLACES", "ROOMS", "BUILDINGS"):
        a, b = mine.get_layer_key(name), theirs.get_layer_key(name)
        assert (a.layer, a.partition) == (b.layer, b.partition), name
    assert mine.num_nodes() == theirs.num_nodes()
    assert mine.num_nodes(include_partitions=False) == theirs.num_nodes(include_partitions=False)
    # spark_dsg 1.1.3 keeps an edge between partitions after removing one of its nodes
    # (it still counts and iterates it); the facade drops it with the node
    dangling = {frozenset((e.source, e.target)) for e in theirs.edges if not (theirs.has_node(e.source) and theirs.has_node(e.target))}
    assert mine.num_edges() == theirs.num_edges() - len(dangling)
    unpartitioned = sum(
        1
        for e in theirs.edges
        if frozenset((e.source, e.target)) not in dangling
        and theirs.get_node(e.source).layer.partition == 0
        and theirs.get_node(e.target).layer.partition == 0
    )
    assert mine.num_edges(include_partitions=False) == unpartitioned
    if not dangling:
        assert unpartitioned == theirs.num_edges(include_partitions=False)
    checked = 0
    for t in theirs.nodes:
        m = mine.get_node(t.id.value)
        assert (m.layer.layer, m.layer.partition) == (t.layer.layer, t.layer.partition)
        assert str(m.id) == str(t.id) and m.id.category == t.id.category
        assert m.get_parent() == t.get_parent()
        assert m.parents() == set(t.parents())
        assert m.children() == set(t.children())
        assert m.siblings() == {x for x in t.siblings() if theirs.has_node(x)}  # as above: dangling
        assert type(m.attributes).__name__ == type(t.attributes).__name__
        names = [n for n in dir(t.attributes) if not n.startswith("_") and n not in ("metadata", "NO_SEMANTIC_LABEL")]
        assert sorted(names) == sorted(n for n in dir(m.attributes) if n not in ("metadata", "NO_SEMANTIC_LABEL"))
        for name in names:
            if fields == "all" or name in KEPT:
                same_value(name, getattr(m.attributes, name), getattr(t.attributes, name))
                checked += 1
        if fields == "all":
            assert dict(m.attributes.metadata.get()) == dict(t.attributes.metadata.get())
    assert checked > 0

    def edges(g):
        return {frozenset((e.source, e.target)): (e.info.weight, e.info.weighted) for e in g.edges}

    mine_edges, their_edges = edges(mine), edges(theirs)
    their_edges = {k: v for k, v in their_edges.items() if k not in dangling}
    assert mine_edges.keys() == their_edges.keys()
    if fields == "all":
        for k, (w, weighted) in their_edges.items():
            assert mine_edges[k][1] == weighted and mine_edges[k][0] == pytest.approx(w, rel=1e-6)


def files(small_office):
    out = [(small_office / "office.json", "all"), (small_office / "office.sparkdsg", "kept")]
    resources = os.environ.get("YGG_SPARK_DSG_TESTS")
    if resources:
        out.append((pathlib.Path(resources) / "resources" / "apartment_dsg.json", "all"))
    return out


@pytest.mark.parametrize("which", [0, 1, 2])
def test_loaded_files_read_as_spark_dsg_reads_them(small_office, which):
    choices = files(small_office)
    if which >= len(choices):
        pytest.skip("the apartment comes with spark-dsg's sdist: set YGG_SPARK_DSG_TESTS (.ci/python does)")
    path, fields = choices[which]
    mine, theirs = ydsg.DynamicSceneGraph.load(path), spark_dsg.DynamicSceneGraph.load(str(path))
    same_graph(mine, theirs, fields)
    if fields == "all":
        assert dict(mine.metadata.get()) == dict(theirs.metadata.get())
        assert mine.has_mesh() == theirs.has_mesh()
        if theirs.has_mesh():
            a, b = mine.mesh, theirs.mesh
            assert (a.num_vertices(), a.num_faces()) == (b.num_vertices(), b.num_faces())
            assert np.allclose(a.get_vertices(), b.get_vertices(), atol=1e-6)  # positions, colors
            assert np.array_equal(a.get_faces(), b.get_faces())
            assert a.get_labels() == b.get_labels()


def random_calls(dsg, seed):
    """One graph from seeded spark_dsg-style calls (the same on either module)."""
    rng = random.Random(seed)
    G = dsg.DynamicSceneGraph()
    G.add_layer(2, "a", dsg.DsgLayers.AGENTS)
    G.metadata.add({"run": seed, "nested": {"a": 1}})
    G.set_labelspace(dsg.Labelspace({0: "wall", 1: "chair"}), 2, 0)
    kinds = [
        ("O", dsg.DsgLayers.OBJECTS, dsg.ObjectNodeAttributes),
        ("p", dsg.DsgLayers.PLACES, dsg.PlaceNodeAttributes),
        ("R", dsg.DsgLayers.ROOMS, dsg.RoomNodeAttributes),
        ("B", dsg.DsgLayers.BUILDINGS, dsg.SemanticNodeAttributes),
    ]
    ids = []
    for i in range(120):
        prefix, layer, cls = kinds[rng.randrange(4)]
        attrs = cls()
        attrs.position = np.array([rng.uniform(-5, 5) for _ in range(3)])
        attrs.name = f"{prefix}{i}"
        attrs.semantic_label = rng.randrange(3)
        attrs.color = np.array([rng.randrange(256) for _ in range(3)], dtype=np.uint8)
        attrs.last_update_time_ns = rng.randrange(10**12)
        attrs.is_active = rng.random() < 0.5
        if prefix == "O":
            lo = np.array([rng.uniform(-1, 0) for _ in range(3)])
            attrs.bounding_box = dsg.BoundingBox(np.array([1.0, 2.0, 0.5]), lo)
            attrs.registered = True
            attrs.world_R_object = dsg.Quaternion(0.5, 0.5, -0.5, 0.5)
            attrs.semantic_feature = np.arange(6, dtype=np.float32).reshape(2, 3) * i
            attrs.mesh_connections = [i, i + 1]
        if prefix == "R":
            attrs.semantic_class_probabilities = {"kitchen": 0.25, "office": 0.75}
        if prefix == "p":
            attrs.distance = rng.uniform(0, 2)
            attrs.num_basis_points = rng.randrange(5)
            attrs.orientation = dsg.Quaternion(0.0, 0.0, 1.0, 0.0)
            attrs.deformation_connections = [i]
            attrs.pcl_mesh_connections = [i, 2 * i]
        attrs.metadata.add({"i": i})
        sym = dsg.NodeSymbol(prefix, i)
        assert G.add_node(layer, sym, attrs)
        ids.append(sym.value)
    for i in range(10):
        attrs = dsg.AgentNodeAttributes()
        attrs.position = np.array([i, 0.0, 0.0])
        attrs.external_key = i
        attrs.world_R_body = dsg.Quaternion(np.cos(i / 10), 0.0, 0.0, np.sin(i / 10))  # spark_dsg leaves it unset
        assert G.add_node(2, dsg.NodeSymbol("a", i), attrs, "a")
        ids.append(dsg.NodeSymbol("a", i).value)
    for _ in range(300):
        a, b = rng.choice(ids), rng.choice(ids)
        info = dsg.EdgeAttributes()
        info.weight = rng.uniform(0, 1)
        info.weighted = rng.random() < 0.5
        G.insert_edge(a, b, info, rng.random() < 0.3)
    for _ in range(10):
        G.remove_node(rng.choice(ids))
    for _ in range(30):
        G.remove_edge(rng.choice(ids), rng.choice(ids))
    return G


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_calls_build_the_graph_spark_dsg_builds(tmp_path, seed):
    """Built by the same calls; then written by the facade as JSON and as spark_dsg's
    binary encoding, read back by spark_dsg."""
    mine, theirs = random_calls(ydsg, seed), random_calls(spark_dsg, seed)
    assert mine.num_edges() > 100  # the calls made a real graph
    same_graph(mine, theirs)
    assert mine.get_labelspace(2, 0).labels_to_names == theirs.get_labelspace(2, 0).labels_to_names
    # written through the facade, read by spark_dsg: the graph spark_dsg built
    path = tmp_path / "facade.json"
    mine.save(path)
    same_graph(mine, spark_dsg.DynamicSceneGraph.load(str(path)))
    binary = tmp_path / "facade.sparkdsg"
    mine.save(binary)
    same_graph(mine, spark_dsg.DynamicSceneGraph.load(str(binary)))
    same_graph(mine, spark_dsg.DynamicSceneGraph.from_binary(mine.to_binary()))
    loaded = spark_dsg.DynamicSceneGraph.load(str(path))
    assert dict(loaded.metadata.get()) == dict(theirs.metadata.get()) | {"labelspaces": {"_l2p0": [[0, "wall"], [1, "chair"]]}} or dict(
        loaded.metadata.get()
    ) == dict(theirs.metadata.get())
    assert loaded.get_labelspace(2, 0).labels_to_names == theirs.get_labelspace(2, 0).labels_to_names
    # and Yggdrasil's queries answer on the same graph
    scene = mine.scene
    assert scene.node_count >= mine.num_nodes()
    some = next(iter(mine.get_layer(ydsg.DsgLayers.PLACES).nodes))
    hit = scene.nearest_nodes(some.attributes.position, 1, layer="PLACES")
    assert hit and hit[0][1] == pytest.approx(0.0, abs=1e-5)


def test_a_scene_is_read_in_place_and_copied_on_the_first_write(small_office):
    graph = yggdrasil.SceneGraph.import_spark_dsg(small_office / "office.json", layout="vanilla")
    scene = graph.snapshot()
    G = ydsg.DynamicSceneGraph.from_scene(scene)
    theirs = spark_dsg.DynamicSceneGraph.load(str(small_office / "office.json"))
    assert G.num_nodes() == theirs.num_nodes()
    some = next(iter(theirs.get_layer(spark_dsg.DsgLayers.OBJECTS).nodes))
    assert np.allclose(G.get_node(some.id.value).attributes.position, some.attributes.position, atol=1e-5)
    assert G.scene is scene
    assert G.remove_node(some.id.value)
    assert not G.scene.has_node(some.id.value) and scene.has_node(some.id.value)
    with pytest.raises(TypeError, match="DynamicSceneGraph.from_scene"):
        ydsg.DynamicSceneGraph(scene)


def test_a_loaded_object_renamed_loses_its_old_labels(small_office):
    G = ydsg.load(small_office / "office.json")
    node = next(n for n in G.get_layer(ydsg.DsgLayers.OBJECTS).nodes if n.attributes.name)
    old = set(G.scene.node(node.id.value).labels)
    assert old  # the import labels objects by name and semantic label
    node.attributes.name = "unicorn"
    node.attributes.semantic_label = 12345
    assert set(G.scene.node(node.id.value).labels) == {"unicorn", "12345"}
    assert G.scene.nodes_with_label("unicorn") == [node.id.value]


def test_writes_reach_yggdrasil_queries_live():
    G = ydsg.DynamicSceneGraph()
    attrs = ydsg.ObjectNodeAttributes()
    attrs.position = np.array([1.0, 2.0, 3.0])
    attrs.name = "chair"
    G.add_node(ydsg.DsgLayers.OBJECTS, ydsg.NodeSymbol("O", 1), attrs)
    assert G.scene.nodes_with_label("chair") == [ydsg.NodeSymbol("O", 1).value]
    node = G.get_node(ydsg.NodeSymbol("O", 1))
    node.attributes.position = np.array([7.0, 7.0, 7.0])
    node.attributes.name = "desk"
    assert G.scene.nodes_with_label("chair") == []
    assert G.scene.objects.nearest([7, 7, 6]) == node.id.value
    assert G.scene.objects.within([7, 7, 7], 0.1) == [node.id.value]
    # an object's geometry is the mesh vertices it claims
    mesh = ydsg.Mesh()
    mesh.resize_vertices(3)
    for i, p in enumerate(([0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0])):
        mesh.set_pos(i, p)
    G.mesh = mesh
    node.attributes.mesh_connections = [1, 2]
    assert G.scene.objects.nearest([9.0, 0.0, 0.0]) == node.id.value
    assert G.scene.objects.within([10.0, 0.0, 0.0], 0.01) == [node.id.value]
    assert G.scene.objects.within([7, 7, 7], 0.1) == []
    G.remove_node(node.id)
    assert not G.scene.has_node(node.id.value)
    assert G.scene.objects.nearest([9.0, 0.0, 0.0]) is None


def test_bad_input_names_what_is_wrong(tmp_path):
    G = ydsg.DynamicSceneGraph()
    with pytest.raises(ValueError, match="category is one character"):
        ydsg.NodeSymbol("Ob", 1)
    with pytest.raises(TypeError, match="NodeAttributes, not str"):
        G.add_node(ydsg.DsgLayers.OBJECTS, 1, "chair")
    with pytest.raises(TypeError, match="a node id is an int or a NodeSymbol, not str"):
        G.has_node("O(1)")
    with pytest.raises(IndexError, match=r"missing node O\(7\)"):
        G.get_node(ydsg.NodeSymbol("O", 7))
    with pytest.raises(IndexError, match="missing layer 'NOPE'"):
        G.get_layer("NOPE")
    with pytest.raises(IndexError, match=r"missing layer 9\[1\]"):
        G.get_layer(9, 1)
    attrs = ydsg.ObjectNodeAttributes()
    with pytest.raises(ValueError, match="a position is 3 numbers"):
        attrs.position = [1.0, 2.0]
    with pytest.raises(ValueError, match="a semantic label is in"):
        attrs.semantic_label = -1
    with pytest.raises(TypeError, match="a rotation is a Quaternion"):
        attrs.world_R_object = (1, 0, 0, 0)
    with pytest.raises(TypeError):
        G.metadata.add({"when": object()})
    with pytest.raises(FileNotFoundError, match="no-such-dir"):
        G.save(tmp_path / "no-such-dir" / "graph.sparkdsg")
    with pytest.raises(yggdrasil.FileError, match="missing.json"):
        ydsg.load(tmp_path / "missing.json")
    with pytest.raises(ValueError, match="not a layer written by SceneGraphLayer.to_binary"):
        ydsg.SceneGraphLayer.from_binary(b"\x00garbage")
    # a refused call changed nothing
    assert G.num_nodes() == 0 and not G.metadata.get()


@pytest.mark.parametrize("name", ["mesh.json", "mesh.sparkdsg"])
def test_a_mesh_written_through_the_facade_loads_in_spark_dsg(tmp_path, name):
    G = ydsg.DynamicSceneGraph()
    mesh = ydsg.Mesh()
    mesh.resize_vertices(4)
    for i in range(4):
        mesh.set_pos(i, (i, 2.0 * i, 0.5))
        mesh.set_color(i, (10 * i, 20, 30))
        mesh.set_label(i, i + 1)
        mesh.set_timestamp(i, 100 + i)
    mesh.set_faces(np.array([[0, 1], [1, 2], [2, 3]]))
    G.mesh = mesh
    G.save(tmp_path / name)
    theirs = spark_dsg.DynamicSceneGraph.load(str(tmp_path / name)).mesh
    assert theirs.num_vertices() == 4 and theirs.num_faces() == 2
    assert np.allclose(theirs.get_vertices(), mesh.get_vertices())
    assert np.array_equal(theirs.get_faces(), mesh.get_faces())
    assert theirs.get_labels() == mesh.get_labels()
    assert [theirs.timestamp(i) for i in range(4)] == [mesh.timestamp(i) for i in range(4)]


def test_a_facade_graph_is_published_live(scene_name):
    """Writes through the facade reach a reader of the published scene."""
    G = ydsg.DynamicSceneGraph()
    attrs = ydsg.ObjectNodeAttributes()
    attrs.name = "chair"
    attrs.position = np.array([1.0, 1.0, 0.5])
    G.add_node(ydsg.DsgLayers.OBJECTS, ydsg.NodeSymbol("O", 0), attrs)
    with yggdrasil.Writer(scene_name, G.scene_graph) as writer, \
            yggdrasil.Reader(scene_name, wait_for_writer=10) as reader:
        first = reader.wait_next(10)
        assert first.nodes_with_label("chair") == [ydsg.NodeSymbol("O", 0).value]
        attrs.name = "desk"
        attrs.position = np.array([4.0, 0.0, 0.5])
        G.add_node(ydsg.DsgLayers.OBJECTS, ydsg.NodeSymbol("O", 1), attrs)
        G.get_node(ydsg.NodeSymbol("O", 0)).attributes.name = "stool"
        assert G.scene_graph.has_node(ydsg.NodeSymbol("O", 1).value)  # edits applied on asking
        writer.publish()
        scene = reader.wait_next(10)
        assert scene.nodes_with_label("desk") == [ydsg.NodeSymbol("O", 1).value]
        assert scene.nodes_with_label("chair") == []
        assert scene.objects.nearest([4.0, 0.0, 0.6]) == ydsg.NodeSymbol("O", 1).value


def test_writes_to_a_per_room_layout(small_office, tmp_path):
    """A mint .ygg (objects in per-room layers) takes the facade's writes."""
    path = tmp_path / "mint.ygg"
    yggdrasil.SceneGraph.import_spark_dsg(small_office / "office.json", layout="mint").save(path)
    G = ydsg.load(path)
    rooms = [n.id.value for n in G.get_layer(ydsg.DsgLayers.ROOMS).nodes]
    by_room = {}
    for o in G.get_layer(ydsg.DsgLayers.OBJECTS).nodes:
        by_room.setdefault(o.get_parent(), []).append(o.id.value)
    a, b = (objs[0] for objs in list(by_room.values())[:2])
    assert G.insert_edge(a, b) and b in G.get_node(a).siblings()  # two rooms' objects
    attrs = ydsg.ObjectNodeAttributes()
    attrs.name = "unicorn"
    new = ydsg.NodeSymbol("O", 99999)
    assert G.add_node(ydsg.DsgLayers.OBJECTS, new, attrs)
    assert G.insert_edge(rooms[0], new)
    assert G.remove_edge(a, b)
    scene = G.scene
    assert scene.nodes_with_label("unicorn") == [new.value]
    assert scene.parent(new.value) == rooms[0]
    assert G.get_node(new).get_parent() == rooms[0]
