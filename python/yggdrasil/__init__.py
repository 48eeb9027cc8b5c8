"""Yggdrasil: a layer-first 3D scene graph store for robots, queried zero-copy.

Read side:
    scene = yggdrasil.open("office.ygg")          # a .ygg snapshot file, mapped
    reader = yggdrasil.Reader("office", wait_for_writer=5)
    scene = reader.wait_next(1.0)                 # a live scene's next snapshot
    scene.objects.nearest([5, 5, 1])              # the object contract of ygg query
    scene.node(42).points                         # read-only numpy view of the mapped bytes

Write side:
    graph = yggdrasil.SceneGraph()                # or SceneGraph.import_spark_dsg(path)
    writer = yggdrasil.Writer("office", graph)    # publish; edit graph; writer.publish()

spark_dsg-style reading: ``yggdrasil.dsg``.
"""
from ._yggdrasil import (
    NO_NODE,
    Error,
    FileError,
    Layer,
    MutationError,
    Node,
    ObjectQueries,
    QueryError,
    Reader,
    Scene,
    SceneGraph,
    TransportError,
    Writer,
    WriterGoneError,
    office_graph,
    open,
    write_office,
)

__all__ = [
    "NO_NODE",
    "Error",
    "FileError",
    "Layer",
    "MutationError",
    "Node",
    "ObjectQueries",
    "QueryError",
    "Reader",
    "Scene",
    "SceneGraph",
    "TransportError",
    "Writer",
    "WriterGoneError",
    "office_graph",
    "open",
    "write_office",
]
