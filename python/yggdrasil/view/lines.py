"""Line segments as a glTF binary (GLB) of one ``LINES`` primitive, for viser's
``add_glb``: the page draws them as plain one-pixel GL lines (three.js ``LineSegments``),
where viser's ``add_line_segments`` draws every segment as an instanced quad with a
screen-space-width shader. Without a GPU (Chromium's software WebGL) the office's ~20k
segments cost ~0.5 s a frame that way, a few milliseconds this way. Written with
pygltflib."""
from __future__ import annotations

import numpy as np
import pygltflib as gltf


def line_segments_glb(segments: np.ndarray, colors: np.ndarray) -> bytes:
    """The GLB of ``segments`` (``(k, 2, 3)`` float positions) colored per segment
    (``(k, 3)``) or per end (``(k, 2, 3)``) with uint8 RGB."""
    positions = np.ascontiguousarray(np.asarray(segments, np.float32).reshape(-1, 3))
    rgb = np.asarray(colors, np.uint8)
    rgb = np.broadcast_to(rgb.reshape(-1, 1, 3) if rgb.ndim == 2 else rgb, (len(segments), 2, 3)).reshape(-1, 3)
    # RGBA: glTF vertex attributes are 4-byte aligned.
    rgba = np.empty((len(rgb), 4), np.uint8)
    rgba[:, :3] = rgb
    rgba[:, 3] = 255
    position_bytes, color_bytes = positions.tobytes(), rgba.tobytes()
    bounds = (positions.min(axis=0).tolist(), positions.max(axis=0).tolist()) if len(positions) else ([0.0] * 3,) * 2
    doc = gltf.GLTF2(
        scene=0,
        scenes=[gltf.Scene(nodes=[0])],
        nodes=[gltf.Node(mesh=0)],
        meshes=[gltf.Mesh(primitives=[gltf.Primitive(attributes=gltf.Attributes(POSITION=0, COLOR_0=1),
                                                     mode=gltf.LINES)])],
        accessors=[
            gltf.Accessor(bufferView=0, componentType=gltf.FLOAT, count=len(positions), type=gltf.VEC3,
                          min=bounds[0], max=bounds[1]),
            gltf.Accessor(bufferView=1, componentType=gltf.UNSIGNED_BYTE, normalized=True, count=len(rgba),
                          type=gltf.VEC4),
        ],
        bufferViews=[
            gltf.BufferView(buffer=0, byteOffset=0, byteLength=len(position_bytes), target=gltf.ARRAY_BUFFER),
            gltf.BufferView(buffer=0, byteOffset=len(position_bytes), byteLength=len(color_bytes),
                            target=gltf.ARRAY_BUFFER),
        ],
        buffers=[gltf.Buffer(byteLength=len(position_bytes) + len(color_bytes))],
    )
    doc.set_binary_blob(position_bytes + color_bytes)
    return b"".join(doc.save_to_bytes())
