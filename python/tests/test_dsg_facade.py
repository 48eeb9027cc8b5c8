"""yggdrasil.dsg reads what spark_dsg 1.1.3 reads, from Spark-DSG files and .ygg files."""
import numpy as np
import pytest

import yggdrasil
import yggdrasil.dsg as ydsg
from conftest import REPO

spark_dsg = pytest.importorskip("spark_dsg")

LAYERS = ("OBJECTS", "PLACES", "MESH_PLACES", "ROOMS", "BUILDINGS")


def same_node(mine, theirs, parents=True):
    assert mine.id.value == theirs.id.value
    assert mine.id.category == theirs.id.category
    assert mine.id.category_id == theirs.id.category_id
    assert np.allclose(mine.attributes.position, theirs.attributes.position, atol=1e-5)
    if parents:
        assert mine.get_parent() == theirs.get_parent()
        assert mine.children() == set(theirs.children())


@pytest.mark.parametrize("name", ["office.json", "office.sparkdsg"])
def test_facade_reads_spark_dsg_files_as_spark_dsg_does(small_office, name):
    path = small_office / name
    mine, theirs = ydsg.load(path), spark_dsg.DynamicSceneGraph.load(str(path))
    assert mine.num_nodes() == theirs.num_nodes()
    for layer in LAYERS:
        a, b = mine.get_layer(layer), theirs.get_layer(layer)
        assert sorted(n.id.value for n in a.nodes) == sorted(n.id.value for n in b.nodes)
        assert a.num_nodes() == b.num_nodes()
        for n in b.nodes:
            same_node(mine.get_node(n.id.value), n)
    assert mine.get_layer(2).id == theirs.get_layer(2).id == 2
    for n in theirs.get_layer(spark_dsg.DsgLayers.OBJECTS).nodes:
        m = mine.get_layer(ydsg.DsgLayers.OBJECTS).get_node(n.id.value)
        assert m.attributes.name == n.attributes.name
        assert m.attributes.semantic_label == n.attributes.semantic_label
        assert np.allclose(m.attributes.bounding_box.min, n.attributes.bounding_box.min)
        assert np.allclose(m.attributes.bounding_box.max, n.attributes.bounding_box.max)
        assert np.allclose(m.attributes.bounding_box.dimensions, n.attributes.bounding_box.dimensions)
    edges = lambda g: sorted((e.source, e.target) for e in g.get_layer("PLACES").edges)  # noqa: E731
    assert edges(mine) == edges(theirs)
    some = next(iter(theirs.get_layer("ROOMS").nodes)).id.value
    assert mine.has_node(some) and mine.find_node(some) is not None
    assert not mine.has_node(12345) and mine.find_node(12345) is None
    with pytest.raises(IndexError):
        mine.get_node(12345)


@pytest.mark.parametrize("layout", ["vanilla", "mint"])
def test_facade_reads_ygg_files(small_office, tmp_path, layout):
    path = tmp_path / f"{layout}.ygg"
    yggdrasil.SceneGraph.import_spark_dsg(small_office / "office.json", layout=layout).save(path)
    mine = ydsg.load(path)
    theirs = spark_dsg.DynamicSceneGraph.load(str(small_office / "office.json"))
    ids = lambda g, l: sorted(n.id.value for n in g.get_layer(l).nodes)  # noqa: E731
    for layer in LAYERS:
        assert ids(mine, layer) == ids(theirs, layer)
    rooms = set(ids(theirs, "ROOMS"))
    for n in theirs.get_layer("OBJECTS").nodes:
        m = mine.get_node(n.id.value)
        same_node(m, n, parents=(layout == "vanilla"))
        if layout == "mint":
            assert m.get_parent() in rooms
    for room in rooms:
        kids = mine.get_node(room).children()
        if layout == "vanilla":
            assert kids == set(theirs.get_node(room).children())


def test_graph_to_networkx(small_office):
    nx = pytest.importorskip("networkx")
    mine = ydsg.load(small_office / "office.json")
    theirs = spark_dsg.DynamicSceneGraph.load(str(small_office / "office.json"))
    a = ydsg.graph_to_networkx(mine)
    import spark_dsg.networkx as snx

    b = snx.graph_to_networkx(theirs)
    assert isinstance(a, nx.Graph)
    assert set(a.nodes) == set(b.nodes)
    assert {frozenset(e) for e in a.edges} == {frozenset(e) for e in b.edges}
    some = next(iter(a.nodes))
    assert np.allclose(a.nodes[some]["position"], b.nodes[some]["position"], atol=1e-5)


def test_facade_has_spark_dsg_1_1_4s_name_and_reads_its_binary_files():
    """spark_dsg 1.1.4 renames DynamicSceneGraph to SceneGraph and changes the binary
    layout of mesh places; the fixture was written by spark_dsg 1.1.4 itself (built from
    its develop branch: dsg/tests/fixtures/README.md)."""
    assert ydsg.SceneGraph is ydsg.DynamicSceneGraph
    fixtures = REPO / "dsg" / "tests" / "fixtures"
    mine = ydsg.SceneGraph.load(fixtures / "office_tiny_v1_1_4.sparkdsg")
    theirs = spark_dsg.DynamicSceneGraph.load(str(fixtures / "office_tiny.json"))
    assert mine.num_nodes() == theirs.num_nodes()
    for layer in LAYERS:
        a, b = mine.get_layer(layer), theirs.get_layer(layer)
        assert sorted(n.id.value for n in a.nodes) == sorted(n.id.value for n in b.nodes)
        for n in b.nodes:
            same_node(mine.get_node(n.id.value), n, parents=False)
