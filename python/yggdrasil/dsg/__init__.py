"""spark_dsg 1.1.3's Python API over Yggdrasil.

Code written against spark_dsg runs by changing one import::

    import yggdrasil.dsg as spark_dsg        # was: import spark_dsg

    G = spark_dsg.DynamicSceneGraph.load("office.json")  # or .json.gz, binary, .ygg
    for node in G.get_layer(spark_dsg.DsgLayers.OBJECTS).nodes:
        print(node.id, node.attributes.name, node.attributes.position)
    H = spark_dsg.DynamicSceneGraph()
    H.add_node(spark_dsg.DsgLayers.OBJECTS, spark_dsg.NodeSymbol("O", 1), spark_dsg.ObjectNodeAttributes())
    H.save("graph.json")                     # spark_dsg 1.1.3 loads it (also .sparkdsg); .ygg for Yggdrasil
    H.scene.objects.nearest([0, 0, 0])       # Yggdrasil's queries on the same graph, live

``install_as_spark_dsg()`` registers this package as ``spark_dsg`` (with
``spark_dsg.networkx`` and ``spark_dsg.io``) for code that imports spark_dsg itself.

Writes (``add_layer``, ``add_node``, ``insert_edge``, ``remove_node``, ``remove_edge``,
setting a node's ``position``, ``name`` or ``semantic_label``) go to a
``yggdrasil.SceneGraph`` (``G.scene_graph``); ``G.scene`` is its snapshot after the
last write. A loaded graph reads its nodes, nesting and layer edges from the file's
``yggdrasil.Scene``; the attribute fields a scene does not keep and the edge weights
are read from a JSON file the first time one is asked for (binary and ``.ygg`` files
give spark_dsg's defaults for them). Not covered: ``to_torch``, ``transform``,
``from_binary`` of a whole graph, ``KhronosObjectAttributes`` and ``TraversabilityNodeAttributes``; edges between
partitions and a node's second parent stay on the Python side (Yggdrasil nests a node
under one parent and keeps edges inside a layer).
"""
from __future__ import annotations

import sys

from . import io, networkx
from ._graph import (
    DynamicSceneGraph,
    LayerView,
    SceneGraphEdge,
    SceneGraphLayer,
    SceneGraphNode,
    add_bounding_boxes_to_layer,
    compute_ancestor_bounding_box,
    load,
)
from ._mesh import Mesh
from ._types import (
    AgentNodeAttributes,
    BoundingBox,
    BoundingBoxType,
    DsgLayers,
    EdgeAttributes,
    Labelspace,
    LayerKey,
    Metadata,
    NodeAttributes,
    NodeSymbol,
    ObjectNodeAttributes,
    Place2dNodeAttributes,
    PlaceNodeAttributes,
    Quaternion,
    RoomNodeAttributes,
    SemanticNodeAttributes,
)
from .networkx import graph_to_networkx, layer_to_networkx

#: spark_dsg 1.1.4's name for the graph class (its ``develop`` branch renames
#: ``DynamicSceneGraph`` to ``SceneGraph``); both names are the same class here.
SceneGraph = DynamicSceneGraph

__all__ = [
    "AgentNodeAttributes",
    "BoundingBox",
    "BoundingBoxType",
    "DsgLayers",
    "DynamicSceneGraph",
    "EdgeAttributes",
    "Labelspace",
    "LayerKey",
    "LayerView",
    "Mesh",
    "Metadata",
    "NodeAttributes",
    "NodeSymbol",
    "ObjectNodeAttributes",
    "Place2dNodeAttributes",
    "PlaceNodeAttributes",
    "Quaternion",
    "RoomNodeAttributes",
    "SceneGraph",
    "SceneGraphEdge",
    "SceneGraphLayer",
    "SceneGraphNode",
    "SemanticNodeAttributes",
    "add_bounding_boxes_to_layer",
    "compute_ancestor_bounding_box",
    "graph_to_networkx",
    "install_as_spark_dsg",
    "io",
    "layer_to_networkx",
    "load",
    "networkx",
]


def install_as_spark_dsg() -> None:
    """Makes ``import spark_dsg`` (and ``spark_dsg.networkx``, ``spark_dsg.io``) import
    this package, for code that cannot change its imports. Call it before that code
    imports spark_dsg."""
    sys.modules["spark_dsg"] = sys.modules[__name__]
    sys.modules["spark_dsg.networkx"] = networkx
    sys.modules["spark_dsg.io"] = io
