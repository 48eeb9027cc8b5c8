"""A ROS 2 peer without ROS: Eclipse Cyclone DDS (pip `cyclonedds`, the DDS behind
`rmw_cyclonedds`) with `hydra_msgs/msg/DsgUpdate` declared as ROS 2 mangles it (type
`hydra_msgs::msg::dds_::DsgUpdate_`, topic `rt/<topic>`), XCDR1 as rmw_cyclonedds sends,
and hydra_ros's QoS (reliable, transient local, keep last 1). The real peer of
`ygg bridge ros2` and `ygg export ros2` in the tests and in `ygg-bench ros2`.

    ros2_peer.py send DOMAIN TOPIC GRAPH_FILE [--mesh]
    ros2_peer.py listen DOMAIN TOPIC OUT_DIR

`send` loads a graph with spark_dsg 1.1.3 and publishes DsgUpdate messages on command,
one command a line on stdin, one answer line each (`ok ...` or `error ...`):

  send [PATH]          a full update of the graph (PATH: also write layer_contents there);
                       answers with the bytes, sequence number and CLOCK_MONOTONIC ns just
                       before the write (after serializing to CDR)
  delta [PATH]         an incremental update: the nodes moved, added or joined by an added
                       edge since the last update, the nodes and edges removed; PATH gets
                       the whole graph (spark_dsg's to_binary), to compare with
  skip                 count a sequence number without sending it (a gap)
  shift DX DY DZ       translate the whole graph (every node and mesh vertex; send it in full)
  garbage N            a full update whose layer_contents are N bytes of no graph
  move ID DX DY DZ     move node ID by the offset
  add ID LAYER X Y Z   add an object node ID to layer LAYER at X Y Z
  remove ID            remove node ID
  edge A B             add the edge A - B
  unedge A B           remove the edge A - B
  ids LAYER            print the ids of the nodes of layer LAYER
  matched N            wait (up to 60 s) until N subscriptions match the writer
  quit                 exit

`listen` subscribes and, for each message, writes its layer_contents to
OUT_DIR/<sequence_number>.bin and the rest to OUT_DIR/<sequence_number>.json
(full_update, deleted_nodes, deleted_edges), and prints
`got seq=S full=F bytes=B deleted=D nodes=N edges=E`, where N and E are what spark_dsg
1.1.3's `from_binary` decoded of layer_contents alone (`nodes=error:<why>` when it could
not). (spark_dsg's `update_from_binary` drops every node a body does not hold, so it
cannot apply an incremental update: the driver applies them.)
"""

import json
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np
import spark_dsg as dsg
from cyclonedds._clayer import ddspy_write
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import int32, int64, sequence, uint8, uint32, uint64
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_ = field(default_factory=Time_)
    frame_id: str = ""


@dataclass
class DsgUpdate_(IdlStruct, typename="hydra_msgs::msg::dds_::DsgUpdate_"):
    header: Header_ = field(default_factory=Header_)
    layer_contents: sequence[uint8] = field(default_factory=bytes)
    deleted_nodes: sequence[uint64] = field(default_factory=list)
    deleted_edges: sequence[uint64] = field(default_factory=list)
    full_update: bool = False
    sequence_number: int64 = 0


QOS = Qos(
    Policy.Reliability.Reliable(duration(milliseconds=100)),
    Policy.Durability.TransientLocal,
    Policy.History.KeepLast(1),
    Policy.DataRepresentation(use_cdrv0_representation=True),
)


def stamp() -> Header_:
    t = time.time_ns()
    return Header_(Time_(t // 10**9, t % 10**9), "map")


def say(text: str) -> None:
    print(text, flush=True)


class Sender:
    """The graph, what changed since the last update, and the writer."""

    def __init__(self, writer, graph, mesh: bool):
        self.writer, self.graph, self.mesh = writer, graph, mesh
        self.seq = 0
        self.changed, self.deleted_nodes, self.deleted_edges = set(), [], []
        self.edges = set()

    def write(self, msg: DsgUpdate_) -> None:
        msg.sequence_number = self.seq
        self.seq += 1
        # DataWriter.write(msg), with the clock read between serializing and writing, as
        # the ZeroMQ sender reads it between to_binary and the socket's send: Python's CDR
        # serializer takes ~1.4 s for the office's 31 MB (rmw_cyclonedds serializes in C++).
        ser = msg.serialize(use_version_2=self.writer._use_version_2)
        ser = ser.ljust((len(ser) + 3) & ~3, b"\0")
        t = time.monotonic_ns()
        if ddspy_write(self.writer._ref, ser) < 0:
            raise RuntimeError("cyclonedds refused the write")
        say(f"ok sent bytes={len(msg.layer_contents)} seq={msg.sequence_number} t_ns={t}")

    def full(self, path):
        data = self.graph.to_binary(include_mesh=self.mesh)
        if path:
            with open(path, "wb") as f:
                f.write(data)
        self.changed, self.deleted_nodes, self.deleted_edges = set(), [], []
        self.edges = set()
        self.write(DsgUpdate_(stamp(), data, [], [], True))

    def delta(self, path):
        part = dsg.DynamicSceneGraph()
        for node_id in sorted(self.changed):
            if not self.graph.has_node(node_id):
                continue
            node = self.graph.get_node(node_id)
            part.add_node(node.layer.layer, node_id, node.attributes, node.layer.partition)
        for a, b in sorted(self.added_edges()):
            part.insert_edge(a, b)
        data = part.to_binary(include_mesh=False)
        if path:
            with open(path, "wb") as f:
                f.write(self.graph.to_binary(include_mesh=self.mesh))
        msg = DsgUpdate_(stamp(), data, list(self.deleted_nodes), list(self.deleted_edges), False)
        self.changed, self.deleted_nodes, self.deleted_edges, self.edges = set(), [], [], set()
        self.write(msg)

    def added_edges(self):
        return self.edges

    def command(self, cmd: str, args) -> None:
        if cmd == "send":
            self.full(args[0] if args else None)
        elif cmd == "delta":
            self.delta(args[0] if args else None)
        elif cmd == "skip":
            self.seq += 1
            say("ok skipped")
        elif cmd == "garbage":
            junk = bytes(range(256)) * (int(args[0]) // 256 + 1)
            self.write(DsgUpdate_(stamp(), junk[: int(args[0])], [], [], True))
        elif cmd == "move":
            node = self.graph.get_node(int(args[0]))
            node.attributes.position = node.attributes.position + np.array(
                [float(a) for a in args[1:4]]
            )
            self.changed.add(int(args[0]))
            say("ok moved")
        elif cmd == "add":
            attrs = dsg.ObjectNodeAttributes()
            attrs.position = np.array([float(a) for a in args[2:5]])
            attrs.name = "added"
            self.graph.add_node(int(args[1]), int(args[0]), attrs)
            self.changed.add(int(args[0]))
            say("ok added")
        elif cmd == "remove":
            node_id = int(args[0])
            self.graph.remove_node(node_id)
            self.changed.discard(node_id)
            self.edges = {e for e in self.added_edges() if node_id not in e}
            self.deleted_nodes.append(node_id)
            say("ok removed")
        elif cmd == "edge":
            a, b = int(args[0]), int(args[1])
            ok = self.graph.insert_edge(a, b)
            if ok:
                self.changed.update((a, b))
                self.edges = self.added_edges() | {(a, b)}
            say(f"ok edge {ok}")
        elif cmd == "unedge":
            a, b = int(args[0]), int(args[1])
            ok = self.graph.remove_edge(a, b)
            added = self.added_edges()
            if ok and ((a, b) in added or (b, a) in added):
                # Added since the last update: it is simply not sent.
                self.edges = added - {(a, b), (b, a)}
            elif ok:
                self.deleted_edges += [a, b]
            say(f"ok unedge {ok}")
        elif cmd == "shift":
            pose = np.eye(4)
            pose[:3, 3] = [float(a) for a in args[:3]]
            self.graph.transform(pose)
            say("ok shifted")
        elif cmd == "ids":
            layer = self.graph.get_layer(int(args[0]))
            say("ok " + " ".join(str(n.id.value) for n in layer.nodes))
        elif cmd == "matched":
            until = time.monotonic() + 60
            while len(self.writer.get_matched_subscriptions()) < int(args[0]):
                if time.monotonic() > until:
                    raise TimeoutError("no match")
                time.sleep(0.01)  # Cyclone's Python binding has no blocking wait for it.
            say("ok matched")
        else:
            say(f"error unknown command {cmd}")


def send(participant, topic, path: str, mesh: bool) -> int:
    writer = DataWriter(participant, topic, qos=QOS)
    sender = Sender(writer, dsg.DynamicSceneGraph.load(path), mesh)
    say(f"ready nodes={sender.graph.num_nodes()}")
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "quit":
            break
        try:
            sender.command(words[0], words[1:])
        except Exception as e:  # noqa: BLE001 - report any failure to the driver
            say(f"error {words[0]}: {e}")
    return 0


def listen(participant, topic, out_dir: str) -> int:
    reader = DataReader(participant, topic, qos=QOS)
    say("ready")
    while True:
        for msg in reader.take_iter(timeout=duration(seconds=3600)):
            data = bytes(msg.layer_contents)
            base = os.path.join(out_dir, str(msg.sequence_number))
            with open(base + ".bin", "wb") as f:
                f.write(data)
            with open(base + ".json", "w") as f:
                json.dump(
                    {
                        "full_update": bool(msg.full_update),
                        "deleted_nodes": list(msg.deleted_nodes),
                        "deleted_edges": list(msg.deleted_edges),
                    },
                    f,
                )
            try:
                g = dsg.DynamicSceneGraph.from_binary(data)
                decoded = f"nodes={g.num_nodes()} edges={g.num_edges()}"
            except Exception as e:  # noqa: BLE001 - reported to the driver
                decoded = f"nodes=error:{type(e).__name__}"
            say(
                f"got seq={msg.sequence_number} full={int(msg.full_update)} "
                f"bytes={len(data)} deleted={len(msg.deleted_nodes)} {decoded}"
            )


def main() -> int:
    mode, domain, ros_topic = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    participant = DomainParticipant(domain)
    topic = Topic(participant, "rt" + ros_topic, DsgUpdate_, qos=QOS)
    if mode == "send":
        return send(participant, topic, sys.argv[4], "--mesh" in sys.argv[5:])
    return listen(participant, topic, sys.argv[4])


if __name__ == "__main__":
    sys.exit(main())
