"""``spark_dsg.networkx``: a graph or a layer as a ``networkx.Graph``, with every
attribute field of each node and edge as its networkx attributes."""
from __future__ import annotations

from typing import Any, Dict


def _fields(obj) -> Dict[str, Any]:
    return {name: getattr(obj, name) for name in dir(obj) if not name.startswith("_")}


def _add_layer(out, layer) -> None:
    for node in layer.nodes:
        out.add_node(node.id.value, **_fields(node.attributes))
    for edge in layer.edges:
        out.add_edge(edge.source, edge.target, **_fields(edge.info))


def graph_to_networkx(G, include_partitions: bool = True):
    """The graph as a ``networkx.Graph`` keyed by node id (``include_partitions=False``
    leaves out the partitions and the edges touching them)."""
    import networkx as nx

    out = nx.Graph()
    for layer in G.layers:
        _add_layer(out, layer)
    if include_partitions:
        for layer in G.layer_partitions:
            _add_layer(out, layer)
    for edge in G.interlayer_edges:
        if edge.source in out and edge.target in out:
            out.add_edge(edge.source, edge.target, **_fields(edge.info))
    return out


def layer_to_networkx(layer):
    """One layer as a ``networkx.Graph``."""
    import networkx as nx

    out = nx.Graph()
    _add_layer(out, layer)
    return out
