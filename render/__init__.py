"""visland.render: what a nose camera sees on approach, rendered headless (trimesh + pyrender, EGL).

Use::

    from visland.camera import CameraModel
    from visland.features import batch_R_camera_from_runway
    from visland.render import SceneParams, FrameRenderer
    from visland.runway import Runway

    camera = CameraModel.default(2048)
    with FrameRenderer(SceneParams(), camera, Runway()) as renderer:   # one GL context here
        R_camera_from_runway = batch_R_camera_from_runway(roll, pitch, dpsi, camera.mount_rpy_rad)
        rgb = renderer.render(p_runway_m, R_camera_from_runway)       # (H, W, 3) uint8 RGB

``p_runway_m`` is the camera centre in the runway frame R (x along the centre line from the
threshold, y right, z down), ``R_camera_from_runway`` the rotation from R to the OpenCV camera
frame. Pixels are exact: ``rgb[v, u]`` is centred on ``(u, v)`` as given by
``CameraModel.project`` (SPEC pixel convention), to well under 0.1 px.

One renderer holds one OpenGL context: create one per process, and start worker processes
with the *spawn* method. Set ``PYOPENGL_PLATFORM=egl`` before anything imports OpenGL (this
package sets it if unset). ``SceneParams.flat()`` gives a flat-colour scene (white runway on
black) for label checks.

Modules: ``params`` (SceneParams), ``glview`` (OpenCV-to-OpenGL camera, EGL context,
colour readback), ``markings`` (ICAO Annex 14 layout), ``textures`` (procedural textures),
``scene`` (airport geometry), ``shaders`` (GLSL: haze, sky, lighting), ``sensor`` (blur,
noise), ``renderer`` (FrameRenderer), ``bench`` (``visland bench render``).
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING

from visland.exports import lazy_exports

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

# Exports load on first use (visland.exports, PEP 562): FrameRenderer pulls in pyrender and
# OpenGL. The imports below are the same names for readers and editors; they are not executed.
if TYPE_CHECKING:
    from visland.render.glview import RenderingUnavailable
    from visland.render.params import SceneParams
    from visland.render.renderer import FrameRenderer

_EXPORTS = {
    "SceneParams": "visland.render.params",
    "FrameRenderer": "visland.render.renderer",
    "RenderingUnavailable": "visland.render.glview",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
