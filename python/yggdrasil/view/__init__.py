"""The browser viewer of a scene: ``python3 -m yggdrasil.view`` (``ygg view``).

It is a reader like any other: a live scene is followed through ``yggdrasil.Reader`` and
only the layers whose generation changed are sent to the page. Built on viser (the
package extra ``yggdrasil[view]``), the library spark_dsg's own viewer uses.

- ``style``: layer roles, heights, label colors;
- ``drawing``: a scene as numpy arrays per layer, redrawn per changed layer;
- ``queries``: a query line's answer and shape;
- ``sources``: files, timelines of scenes, live scenes;
- ``viewer``: the viser server and its panel (imports viser);
- ``cli``: the command line.
"""
