"""``spark_dsg.io``: collections of layers saved side by side (``{path}.graphs`` with the
layers' bytes, ``{path}.json`` with where each one is)."""
from __future__ import annotations

import json
import pathlib
from typing import Dict, Iterator, List, Union

from ._graph import SceneGraphLayer


class LayerCollection:
    """Reads a collection written by ``LayerCollection.save``; use as a context manager."""

    def __init__(self, path: Union[str, pathlib.Path]):
        self._path = pathlib.Path(path)
        self._index: Dict[int, Dict[str, int]] = {}
        self._data: bytes = b""
        self._open = False

    def __enter__(self) -> "LayerCollection":
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def open(self) -> None:
        """Reads the index and the layers' bytes; raises ``FileNotFoundError`` naming a missing file."""
        record, graphs = self._path.with_suffix(".json"), self._path.with_suffix(".graphs")
        for p in (record, graphs):
            if not p.exists():
                raise FileNotFoundError(f"missing {p}")
        self._index = {r["index"]: r for r in json.loads(record.read_text())["offsets"]}
        self._data = graphs.read_bytes()
        self._open = True

    def close(self) -> None:
        """Forgets the bytes."""
        self._data, self._open = b"", False

    def _check(self) -> None:
        if not self._open:
            raise RuntimeError(f"the collection {self._path} is not open")

    def _get(self, index: int) -> SceneGraphLayer:
        r = self._index.get(index)
        if r is None:
            raise IndexError(f"no graph with index {index} in {self._path}")
        return SceneGraphLayer.from_binary(self._data[r["offset"] : r["offset"] + r["size"]])

    def __getitem__(self, index):
        self._check()
        if isinstance(index, slice):
            return [self._get(i) for i in list(range(len(self)))[index]]
        return self._get(index + len(self) if index < 0 else index)

    def __len__(self) -> int:
        self._check()
        return len(self._index)

    def __iter__(self) -> Iterator[SceneGraphLayer]:
        self._check()
        return (self._get(i) for i in range(len(self)))

    @property
    def indices(self) -> List[int]:
        """The collection's indices."""
        self._check()
        return list(self._index)

    @staticmethod
    def save(collection: Dict[int, SceneGraphLayer], path: Union[str, pathlib.Path]) -> None:
        """Writes the layers to ``{path}.graphs`` and the index to ``{path}.json``."""
        path = pathlib.Path(path)
        offsets, offset = [], 0
        with path.with_suffix(".graphs").open("wb") as out:
            for index, layer in collection.items():
                data = layer.to_binary()
                out.write(data)
                offsets.append({"index": index, "offset": offset, "size": len(data), "num_nodes": layer.num_nodes(), "num_edges": layer.num_edges()})
                offset += len(data)
        path.with_suffix(".json").write_text(json.dumps({"offsets": offsets}))
