"""The browser viewer of a scene: ``python3 -m yggdrasil.view`` (``ygg view``).

It is a reader like any other: a live scene is followed through ``yggdrasil.Reader`` and
only the layers whose generation changed are sent to the page. Built on viser (the
package extra ``yggdrasil[view]``), the library spark_dsg's own viewer uses.

    from yggdrasil.view import SceneViewer, Style
    viewer = SceneViewer(Style(), port=0)        # serves the page; viewer.port
    viewer.show(scene)                           # again with each newer snapshot
    viewer.set_query({"op": "objects_within", "point": [5, 5, 1], "radius": 2})

- ``style``: layer roles, heights, label colors;
- ``drawing``: a scene as numpy arrays per layer, redrawn per changed layer;
- ``queries``: a query line's answer and shape;
- ``sources``: files, timelines of scenes, live scenes;
- ``viewer``: the viser server and its panel (the only module importing viser);
- ``browser``: the page in headless Chromium (tests and benchmark);
- ``cli``: the command line; ``bench``: the benchmark.
"""
from .sources import LiveSource, Timeline, TimelineEntry, load_file
from .style import Style

__all__ = ["LiveSource", "SceneViewer", "Style", "Timeline", "TimelineEntry", "load_file"]


def __getattr__(name):
    # viser is imported only when the viewer itself is asked for, so that the command
    # line can say which extra is missing.
    if name == "SceneViewer":
        from .viewer import SceneViewer

        return SceneViewer
    raise AttributeError(f"module 'yggdrasil.view' has no attribute {name!r}")
