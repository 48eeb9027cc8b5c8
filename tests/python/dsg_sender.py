"""A Spark-DSG ZMQ publisher driven by commands on stdin: the real peer of `ygg
bridge zmq` in the tests and in `ygg-bench hydra`.

Loads a graph, binds spark_dsg's own `DsgSender` to a free TCP port on 127.0.0.1 and
prints `port=N`. Then reads one command a line and answers one line each (`ok ...` or
`error ...`):

  send [PATH]          send the graph once (PATH: also write the bytes sent there);
                       answers with the bytes and the CLOCK_MONOTONIC ns just before
                       the socket's send (after serializing)
  send-minimal         send a graph of one room R(0) at the origin (same answer): the
                       smallest graph every layout builds
  move ID DX DY DZ     move node ID (a u64) by the offset
  add ID LAYER X Y Z   add an object node ID to layer LAYER (an int) at X Y Z
  remove ID            remove node ID
  edge A B             add the edge A -> B
  shift DX DY DZ       translate the whole graph (every node and mesh vertex)
  garbage N            send N bytes that are not a graph
  truncated            send the graph cut in half
  ids LAYER            print the ids of the nodes of layer LAYER
  quit                 exit

Usage: dsg_sender.py GRAPH_FILE [--mesh]
"""

import sys
import time

import numpy as np
import spark_dsg as dsg
import zmq
from spark_dsg.zmq import DsgSender


def main() -> int:
    path = sys.argv[1]
    mesh = "--mesh" in sys.argv[2:]
    graph = dsg.DynamicSceneGraph.load(path)
    sender = DsgSender("tcp://127.0.0.1:*")
    endpoint = sender._socket.getsockopt(zmq.LAST_ENDPOINT).decode()
    print(f"port={endpoint.rsplit(':', 1)[1]} nodes={graph.num_nodes()}", flush=True)
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        cmd, args = words[0], words[1:]
        try:
            if cmd == "send":
                data = graph.to_binary(include_mesh=mesh)
                if args:
                    with open(args[0], "wb") as f:
                        f.write(data)
                # What DsgSender.send does (`self._socket.send(graph.to_binary(...))`),
                # with the serialization before the timestamp.
                t = time.monotonic_ns()
                sender._socket.send(data)
                print(f"ok sent bytes={len(data)} t_ns={t}", flush=True)
            elif cmd == "send-minimal":
                minimal = dsg.DynamicSceneGraph()
                attrs = dsg.RoomNodeAttributes()
                attrs.position = np.zeros(3)
                minimal.add_node(dsg.DsgLayers.ROOMS, dsg.NodeSymbol("R", 0).value, attrs)
                data = minimal.to_binary(include_mesh=mesh)
                t = time.monotonic_ns()
                sender._socket.send(data)
                print(f"ok sent bytes={len(data)} t_ns={t}", flush=True)
            elif cmd == "move":
                node = graph.get_node(int(args[0]))
                node.attributes.position = node.attributes.position + np.array(
                    [float(a) for a in args[1:4]]
                )
                print("ok moved", flush=True)
            elif cmd == "add":
                attrs = dsg.ObjectNodeAttributes()
                attrs.position = np.array([float(a) for a in args[2:5]])
                attrs.name = "added"
                graph.add_node(int(args[1]), int(args[0]), attrs)
                print("ok added", flush=True)
            elif cmd == "remove":
                graph.remove_node(int(args[0]))
                print("ok removed", flush=True)
            elif cmd == "edge":
                ok = graph.insert_edge(int(args[0]), int(args[1]))
                print(f"ok edge {ok}", flush=True)
            elif cmd == "shift":
                pose = np.eye(4)
                pose[:3, 3] = [float(a) for a in args[:3]]
                graph.transform(pose)
                print("ok shifted", flush=True)
            elif cmd == "garbage":
                sender._socket.send(bytes(range(256)) * (int(args[0]) // 256 + 1))
                print("ok garbage", flush=True)
            elif cmd == "truncated":
                data = graph.to_binary(include_mesh=mesh)
                sender._socket.send(data[: len(data) // 2])
                print("ok truncated", flush=True)
            elif cmd == "ids":
                layer = graph.get_layer(int(args[0]))
                print("ok " + " ".join(str(n.id.value) for n in layer.nodes), flush=True)
            elif cmd == "quit":
                break
            else:
                print(f"error unknown command {cmd}", flush=True)
        except Exception as e:  # noqa: BLE001 - report any failure to the driver
            print(f"error {cmd}: {e}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
