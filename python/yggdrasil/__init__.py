"""Yggdrasil: a layer-first 3D scene graph store for robots, queried zero-copy.

Read side:
    scene = yggdrasil.open("office.ygg")          # a .ygg snapshot file, mapped
    reader = yggdrasil.Reader("office", wait_for_writer=5)
    scene = reader.wait_next(1.0)                 # a live scene's next snapshot
    scene.objects.nearest([5, 5, 1])              # the object contract of ygg query (an id or None)
    scene.newest_pose(), scene.room_of(p)         # where the agent is (Spark-DSG layouts)
    scene.node(42).points                         # read-only numpy view of the mapped bytes

Write side:
    graph = yggdrasil.SceneGraph()                # or SceneGraph.import_spark_dsg(path)
    writer = yggdrasil.Writer("office", graph)    # publish; edit graph; writer.publish()

Angles are degrees wherever you pass one; ``objects.nearest`` answers an id or ``None``,
``objects.nearest_many`` ``int64`` ids with ``NO_NODE`` (-1) for none, and
``nearest_nodes_many`` a masked ``uint64`` array (node ids use all 64 bits). The transport prints errors only, unless ``YGG_LOG=warn`` (or
``set_log_level("warn")``) asks for more.

spark_dsg 1.1.3's API (reads and writes, over a SceneGraph): ``yggdrasil.dsg``.

Recordings of a live scene (``ygg record`` or ``Recorder``): ``open_recording(path)``;
``recording.at(time=t)`` is the scene as it was then (a ``Scene``, queried in place).
"""
from ._yggdrasil import (
    NO_NODE,
    AgentPose,
    Error,
    FileError,
    Layer,
    MutationError,
    Node,
    ObjectQueries,
    QueryError,
    Reader,
    Recorder,
    Recording,
    RoomScope,
    Scene,
    SceneGraph,
    TransportError,
    Writer,
    WriterGoneError,
    office_graph,
    open,
    open_recording,
    set_log_level,
    write_office,
)

__all__ = [
    "NO_NODE",
    "AgentPose",
    "Error",
    "FileError",
    "Layer",
    "MutationError",
    "Node",
    "ObjectQueries",
    "QueryError",
    "Reader",
    "Recorder",
    "Recording",
    "RoomScope",
    "Scene",
    "SceneGraph",
    "TransportError",
    "Writer",
    "WriterGoneError",
    "office_graph",
    "open",
    "open_recording",
    "set_log_level",
    "write_office",
]
