"""The real spark_dsg (pip install spark-dsg==1.1.3) as a peer for dsg/tests/binary.rs.

Usage:
  spark_dsg_peer.py summary FILE      load a .sparkdsg / .json file, print a JSON summary
  spark_dsg_peer.py body FILE         the same for a header-less to_binary() body
  spark_dsg_peer.py make-all FILE     write a body with every supported layout, fields set
  spark_dsg_peer.py make-other FILE   write a body with NodeAttributes, Khronos, Traversability
"""
import datetime
import json
import sys

import numpy as np
import spark_dsg as d


def summary(g):
    nodes = []
    for n in g.nodes:
        a = n.attributes
        rec = {
            "id": n.id.value,
            "layer": n.layer.layer,
            "partition": n.layer.partition,
            "type": type(a).__name__,
            "position": [float(x) for x in a.position],
        }
        if hasattr(a, "semantic_label"):
            rec["name"] = a.name
            rec["semantic_label"] = int(a.semantic_label)
            b = a.bounding_box
            if b.is_valid():
                rec["bbox"] = [[float(x) for x in b.min], [float(x) for x in b.max]]
        if hasattr(a, "mesh_connections"):
            rec["mesh_connections"] = [int(x) for x in a.mesh_connections]
        if isinstance(a, d.AgentNodeAttributes):
            rec["timestamp_ns"] = a.timestamp // datetime.timedelta(microseconds=1) * 1000
        nodes.append(rec)
    edges = [[e.source, e.target] for e in g.edges]
    mesh = None
    if g.has_mesh():
        m = g.mesh
        mesh = {
            "vertices": m.num_vertices(),
            "faces": m.num_faces(),
            "points": [[float(x) for x in m.pos(i)] for i in range(min(m.num_vertices(), 50))],
            "faces_head": [[int(x) for x in m.face(i)] for i in range(min(m.num_faces(), 50))],
            "labels": [int(x) for x in m.get_labels()],
        }
    per_layer = {}
    for n in nodes:
        key = f"{n['layer']}/{n['partition']}"
        per_layer[key] = per_layer.get(key, 0) + 1
    return {
        "nodes": g.num_nodes(),
        "edges": g.num_edges(),
        "nodes_per_layer": per_layer,
        "node_list": nodes,
        "edge_list": edges,
        "mesh": mesh,
    }


def semantic(a, i):
    a.position = np.array([1.5 + i, -2.25, 3.0])
    a.name = f"thing{i}"
    a.semantic_label = 7 + i
    a.color = np.array([10, 20, 30], dtype=np.uint8)
    a.bounding_box = d.BoundingBox(
        np.array([1.0, 2.0, 3.0], dtype=np.float32),
        np.array([1.5 + i, -2.25, 3.0], dtype=np.float32),
    )
    a.semantic_feature = np.arange(6, dtype=np.float32).reshape(2, 3)
    a.metadata.set({"note": "x", "i": i})
    a.last_update_time_ns = 99
    a.is_active = True
    a.is_predicted = True
    return a


def nearest_vertex():
    v = d.NearestVertexInfo()
    v.block = [1, -2, 3]
    v.voxel_pos = [0.5, 0.25, -1.0]
    v.vertex = 12
    v.label = 4
    return v


def make_all():
    S = d.NodeSymbol
    g = d.DynamicSceneGraph()
    o = semantic(d.ObjectNodeAttributes(), 0)
    o.mesh_connections = [0, 2, 1]
    o.registered = True
    g.add_node(d.LayerKey(2, 0), S("O", 1), o)
    p = semantic(d.PlaceNodeAttributes(), 1)
    p.distance = 0.75
    p.num_basis_points = 3
    p.voxblox_mesh_connections = [nearest_vertex(), nearest_vertex()]
    p.pcl_mesh_connections = [5, 6]
    p.mesh_vertex_labels = [1, 2, 3]
    p.deformation_connections = [9]
    p.real_place = False
    p.active_frontier = True
    p.anti_frontier = True
    p.frontier_scale = np.array([1.0, 2.0, 3.0])
    p.need_cleanup = True
    p.num_frontier_voxels = 17
    g.add_node(d.LayerKey(3, 0), S("p", 2), p)
    q = semantic(d.Place2dNodeAttributes(), 2)
    q.boundary = [np.array([0.0, 1.0, 2.0]), np.array([3.0, 4.0, 5.0])]
    q.ellipse_centroid = np.array([1.0, 1.0, 0.0])
    q.ellipse_matrix_compress = np.array([[2.0, 0.5], [0.5, 3.0]])
    q.ellipse_matrix_expand = np.array([[1.0, 0.0], [0.0, 4.0]])
    q.pcl_boundary_connections = [1, 2]
    q.voxblox_mesh_connections = [nearest_vertex()]
    q.pcl_mesh_connections = [3]
    q.mesh_vertex_labels = [7]
    q.deformation_connections = [8, 9]
    g.add_node(d.LayerKey(3, 1), S("Q", 3), q)
    r = semantic(d.RoomNodeAttributes(), 3)
    r.semantic_class_probabilities = {"kitchen": 0.25, "office": 0.75}
    g.add_node(d.LayerKey(4, 0), S("R", 4), r)
    g.add_node(d.LayerKey(5, 0), S("B", 5), semantic(d.SemanticNodeAttributes(), 4))
    a = d.AgentNodeAttributes()
    a.position = np.array([0.5, 0.5, 0.5])
    a.timestamp = datetime.timedelta(microseconds=123456)
    a.world_R_body = d.Quaternion(1.0, 0.0, 0.0, 0.0)
    a.external_key = S("x", 9).value
    a.dbow_ids = np.array([1, 2, 3], dtype=np.uint32)
    a.dbow_values = np.array([0.5, 0.25], dtype=np.float32)
    g.add_node(d.LayerKey(2, ord("a")), S("a", 0), a)
    e = d.EdgeAttributes()
    e.weight = 0.5
    e.weighted = True
    g.insert_edge(S("p", 2), S("Q", 3), e)
    g.insert_edge(S("O", 1), S("p", 2))
    g.insert_edge(S("p", 2), S("R", 4))
    g.insert_edge(S("a", 0), S("p", 2))
    return g


def make_other():
    S = d.NodeSymbol
    g = d.DynamicSceneGraph()
    n = d.NodeAttributes()
    n.position = np.array([1.0, 2.0, 3.0])
    g.add_node(d.LayerKey(3, 0), S("n", 0), n)
    # The Khronos-only fields have no Python setters: they stay empty (mesh included).
    g.add_node(d.LayerKey(2, 0), S("K", 1), semantic(d.KhronosObjectAttributes(), 5))
    t = d.TraversabilityNodeAttributes()
    t.position = np.array([0.0, 1.0, 0.0])
    t.distance = 2.5
    t.first_observed_ns = 11
    t.last_observed_ns = 12
    g.add_node(d.LayerKey(3, 0), S("t", 1), t)
    return g


def main():
    cmd, path = sys.argv[1], sys.argv[2]
    if cmd == "summary":
        print(json.dumps(summary(d.DynamicSceneGraph.load(path))))
    elif cmd == "body":
        with open(path, "rb") as f:
            print(json.dumps(summary(d.DynamicSceneGraph.from_binary(f.read()))))
    elif cmd in ("make-all", "make-other"):
        g = make_all() if cmd == "make-all" else make_other()
        with open(path, "wb") as f:
            f.write(g.to_binary())
    else:
        sys.exit(f"unknown command {cmd}")


if __name__ == "__main__":
    main()
