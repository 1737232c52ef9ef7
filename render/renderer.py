"""FrameRenderer: what a nose camera sees from a pose in the runway frame.

One instance owns one EGL context (use one per process; worker processes must be started
with the *spawn* method). Building it generates the textures and the scene (a second or two
at the default settings); each :meth:`FrameRenderer.render` then draws one frame.
"""
from __future__ import annotations

import hashlib
import shutil
import tempfile

import numpy as np

from visland.camera import CameraModel
from visland.runway import Runway

from .glview import OffscreenView
from .params import SceneParams
from .scene import SKY_RADIUS_M, build_scene
from .sensor import (NoiseBank, apply_blur, apply_distortion, apply_gain, distortion_maps, jpeg_round_trip,
                     to_monochrome, vignetting_gain)
from .shaders import write_shaders

__all__ = ["FrameRenderer", "clip_planes"]

ZFAR_M = 1.5 * SKY_RADIUS_M


def clip_planes(height_above_ground_m: float, max_structure_height_m: float) -> tuple[float, float]:
    """Near and far clipping distances for a camera at ``height_above_ground_m``.

    Nothing is nearer than the ground or the tallest structure below the camera, so the near
    plane sits at half that clearance (at least 0.5 m); the far plane lies beyond the sky dome.
    No two surfaces overlap in the scene (see :mod:`visland.render.scene`), so depth precision
    only has to separate buildings from the ground and the ground from the sky.

    Parameters
    ----------
    height_above_ground_m : float
        Camera height above the runway plane, metres.
    max_structure_height_m : float
        Height of the tallest structure in the scene, metres.

    Returns
    -------
    near_m, far_m : float
    """
    clearance = height_above_ground_m - max_structure_height_m
    return float(np.clip(0.5 * clearance, 0.5, 500.0)), ZFAR_M


class FrameRenderer:
    """Render frames of the airport scene through an exact pinhole camera.

    Parameters
    ----------
    params : SceneParams
        Look of the scene and sensor degradations.
    camera : CameraModel
        Image size and intrinsics (pixels are exact: :func:`visland.render.glview.gl_projection_matrix`).
        Its mounting is not used: :meth:`render` takes the camera attitude directly. With lens
        distortion, the pinhole image of the same intrinsics is drawn and resampled through the
        lens (:func:`visland.render.sensor.distortion_maps`), so pinhole labels stay exact.
    runway : Runway
        Runway size (and heading, which orients the sun and the designators).

    Examples
    --------
    >>> with FrameRenderer(SceneParams(), camera, runway) as renderer:   # doctest: +SKIP
    ...     rgb = renderer.render(p_runway_m, R_camera_from_runway)
    """

    def __init__(self, params: SceneParams, camera: CameraModel, runway: Runway):
        if not isinstance(params, SceneParams):
            raise ValueError(f"params must be a SceneParams, got {type(params).__name__}")
        if not isinstance(camera, CameraModel):
            raise ValueError(f"camera must be a CameraModel, got {type(camera).__name__}")
        if not isinstance(runway, Runway):
            raise ValueError(f"runway must be a Runway, got {type(runway).__name__}")
        self.params = params
        self.camera = camera
        self.runway = runway
        self._shader_dir = tempfile.mkdtemp(prefix="visland-shaders-")
        self._view = None
        try:
            write_shaders(self._shader_dir, params, runway.heading_deg)
            self._view = OffscreenView(camera.without_distortion(), self._shader_dir, samples=params.msaa_samples,
                                       anisotropy=1.0)
            self._handles = build_scene(runway, params)
        except BaseException:
            self.close()
            raise
        self._noise = (NoiseBank(camera.height, camera.width, params.noise_std, params.seed)
                       if params.noise_std > 0 else None)
        self._lens_maps = distortion_maps(camera) if camera.has_distortion else None
        self._vignetting = (vignetting_gain(camera.height, camera.width, params.vignetting)
                            if params.vignetting > 0 else None)

    def render(self, p_runway_m, R_camera_from_runway, frame_seed: int | None = None) -> np.ndarray:
        """One frame seen from camera centre ``p_runway_m`` with attitude ``R_camera_from_runway``.

        Parameters
        ----------
        p_runway_m : (3,) camera centre in the runway frame R (z down: above ground means z < 0).
        R_camera_from_runway : (3, 3) rotation from R to the OpenCV camera frame C, e.g.
            ``visland.features.batch_R_camera_from_runway(roll, pitch, dpsi, camera.mount_rpy_rad)``.
        frame_seed : seed of this frame's sensor noise (default: derived from the pose), so a
            frame rendered twice is identical.

        Returns
        -------
        rgb : ndarray of uint8, shape (H, W, 3)
            RGB image; ``rgb[v, u]`` is the pixel whose centre is ``(u, v)`` in the SPEC
            convention ((0, 0) at the centre of the top-left pixel), the same pixels as
            :meth:`visland.camera.CameraModel.project`.
        """
        if self._view is None:
            raise ValueError("this FrameRenderer is closed")
        p = np.asarray(p_runway_m, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"p_runway_m must be 3 finite numbers, got {p_runway_m!r}")
        height = -p[2]
        if height <= 0.3:
            raise ValueError(f"p_runway_m must be above the ground (z < -0.3 m, z down), got z = {p[2]:g} m")
        znear, zfar = clip_planes(height, self._handles.max_structure_height_m)
        scene = self._handles.scene
        sky_pose = np.eye(4)
        sky_pose[:3, 3] = p
        scene.set_pose(self._handles.sky_node, sky_pose)
        rgb = self._view.render(scene, p, R_camera_from_runway, znear, zfar)
        if self._lens_maps is not None:
            rgb = apply_distortion(rgb, self._lens_maps)
        if self._vignetting is not None:
            rgb = apply_gain(rgb, self._vignetting)
        if self.params.blur_sigma_px > 0:
            rgb = apply_blur(rgb, self.params.blur_sigma_px)
        if self.params.monochrome:
            rgb = to_monochrome(rgb)
        if self._noise is not None:
            if frame_seed is None:
                digest = hashlib.sha256(np.concatenate([p, np.asarray(R_camera_from_runway, float).ravel()]).tobytes())
                frame_seed = int.from_bytes(digest.digest()[:8], "little")
            rgb = self._noise.apply(rgb, frame_seed)
            if self.params.monochrome:
                rgb = np.repeat(rgb[..., 1:2], 3, axis=-1)
        if self.params.jpeg_quality:
            rgb = jpeg_round_trip(rgb, self.params.jpeg_quality)
            if self.params.monochrome:
                rgb = np.repeat(rgb[..., 1:2], 3, axis=-1)
        return rgb

    def close(self) -> None:
        """Release the GL context and temporary shader files (idempotent)."""
        if getattr(self, "_view", None) is not None:
            self._view.close()
            self._view = None
        if getattr(self, "_shader_dir", None):
            shutil.rmtree(self._shader_dir, ignore_errors=True)
            self._shader_dir = None

    def __enter__(self) -> "FrameRenderer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
