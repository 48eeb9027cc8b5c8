"""Where the scenes shown come from: a file (``.ygg``, Spark-DSG JSON or binary), a
timeline of scenes to scrub, or a live scene followed through a ``Reader``.

A ``Timeline`` is a list of ``TimelineEntry(time_ns, label, load)``: anything that yields
scenes in time order plugs in (``of_files``: ``.ygg`` files; ``of_scenes``: snapshots;
``of_cuts``: a recording's cuts, each loaded by its ``at(generation=...)``)."""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np

import yggdrasil

SPARK_DSG_SUFFIXES = (".json", ".json.gz", ".sparkdsg", ".dsg")


@dataclass
class ColoredMesh:
    """A Spark-DSG file's mesh with its vertex colors (drawn instead of the mesh layers'
    points, which carry no color)."""

    points: np.ndarray
    colors: np.ndarray


@dataclass
class LoadedFile:
    """A file as shown: its scene and, for a Spark-DSG file with colors, its mesh."""

    scene: object
    mesh: Optional[ColoredMesh] = None


def load_file(path: str, layout: str = "mint") -> LoadedFile:
    """Opens a ``.ygg`` snapshot (mapped) or imports a Spark-DSG file (JSON, ``.json.gz``
    or binary) in ``layout``; raises ``yggdrasil.FileError`` naming the file."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise yggdrasil.FileError(f"{path}: no such file")
    if path.endswith(".ygg"):
        return LoadedFile(yggdrasil.open(path))
    scene = yggdrasil.SceneGraph.import_spark_dsg(path, layout=layout).snapshot()
    return LoadedFile(scene, spark_dsg_mesh(path))


def spark_dsg_mesh(path: str) -> Optional[ColoredMesh]:
    """The mesh of a Spark-DSG file with its vertex colors, or ``None`` when it has no
    mesh or no colors (every vertex black)."""
    from yggdrasil import dsg

    mesh = dsg.DynamicSceneGraph.load(path).mesh
    if mesh is None or mesh.num_vertices() == 0:
        return None
    vertices = mesh.get_vertices()  # (6, n): positions, then RGB in [0, 1]
    colors = np.round(vertices[3:6].T * 255.0).astype(np.uint8)
    if not colors.any():
        return None
    return ColoredMesh(vertices[:3].T.astype(np.float32), colors)


@dataclass
class TimelineEntry:
    """One scene of a timeline: when it was (ns), what the slider says, how to load it."""

    time_ns: int
    label: str
    load: Callable[[], object]


class Timeline:
    """Scenes in time order, loaded when the slider reaches them (the newest load kept)."""

    def __init__(self, entries: Sequence[TimelineEntry]) -> None:
        if not entries:
            raise ValueError("a timeline needs at least one scene")
        self.entries: List[TimelineEntry] = sorted(entries, key=lambda e: e.time_ns)
        self._cached: Tuple[int, object] = (-1, None)

    def __len__(self) -> int:
        return len(self.entries)

    def scene(self, index: int):
        """The scene at ``index`` (0 is the earliest)."""
        if self._cached[0] != index:
            self._cached = (index, self.entries[index].load())
        return self._cached[1]

    @classmethod
    def of_scenes(cls, scenes: Sequence[object], times_ns: Optional[Sequence[int]] = None) -> "Timeline":
        """A timeline over scenes already open (snapshots), one second apart unless
        ``times_ns`` says when each was."""
        times = list(times_ns) if times_ns is not None else [i * 1_000_000_000 for i in range(len(scenes))]
        return cls(
            [TimelineEntry(t, f"{i}: generation {s.generation}", (lambda s=s: s)) for i, (s, t) in enumerate(zip(scenes, times))]
        )

    @classmethod
    def of_cuts(cls, generations: Sequence[int], times_s: Sequence[float], at: Callable[..., object]) -> "Timeline":
        """A timeline over the cuts of a recorded scene: cut ``i`` is generation
        ``generations[i]`` at ``times_s[i]`` (seconds since the epoch), loaded by
        ``at(generation=g)`` when the slider reaches it (a recording's ``cuts["generation"]``,
        ``cuts["time"]`` and ``at``)."""
        entries = [
            TimelineEntry(int(round(float(t) * 1e9)), f"generation {int(g)} at {float(t):.3f} s",
                          (lambda g=int(g): at(generation=g)))
            for g, t in zip(generations, times_s)
        ]
        return cls(entries)

    @classmethod
    def of_recording(cls, path: str) -> "Timeline":
        """A timeline over every cut of a recording folder (``ygg record``); each cut is
        opened in place when the slider reaches it. Raises ``yggdrasil.FileError``."""
        recording = yggdrasil.open_recording(path)
        cuts = recording.cuts
        return cls.of_cuts(cuts["generation"], cuts["time"], recording.at)

    @classmethod
    def of_files(cls, paths: Sequence[str], layout: str = "mint") -> "Timeline":
        """A timeline over files, in the order given (each one's modification time is
        shown); each file is opened when the slider reaches it."""
        entries = []
        for i, path in enumerate(paths):
            if not os.path.exists(path):
                raise yggdrasil.FileError(f"{path}: no such file")
            entries.append(TimelineEntry(i, f"{i}: {os.path.basename(path)}", (lambda p=path: load_file(p, layout).scene)))
        return cls(entries)


class LiveSource:
    """A live scene, followed through a ``yggdrasil.Reader`` (the viewer is one more
    reader: the writer does not know it is there)."""

    def __init__(self, scene_name: str, wait_for_writer: float = 10.0) -> None:
        self.reader = yggdrasil.Reader(scene_name, wait_for_writer=wait_for_writer)

    def next_scene(self, timeout: float):
        """The newest snapshot after the one returned last, or ``None`` after
        ``timeout`` seconds; snapshots published meanwhile are skipped over."""
        scene = self.reader.wait_next(timeout)
        if scene is None:
            return None
        newest = self.reader.latest()
        return newest if newest is not None and newest.generation > scene.generation else scene

    def close(self) -> None:
        """Detaches from the scene."""
        self.reader.close()
