"""Sensor degradations applied to a rendered frame.

Order (``FrameRenderer.render``): the pinhole render, resampled through the lens distortion
(:func:`distortion_maps`), vignetting, optical blur, monochrome conversion, additive noise,
JPEG compression.

Noise is Gaussian with a chosen standard deviation in digital numbers. Drawing 12 million
normal samples per 2048x2048 frame costs 50-130 ms here, so :class:`NoiseBank` draws one
seeded bank slightly larger than the image once, and each frame takes a window of it at an
offset derived from the frame's seed: every frame gets a different noise field (a pattern
shifted by a random offset), the same frame always gets the same one, and the cost is two
saturating 8-bit additions (about 2 ms).
"""
from __future__ import annotations

import numpy as np

__all__ = ["NoiseBank", "apply_blur", "distortion_maps", "apply_distortion", "vignetting_gain", "apply_gain",
           "to_monochrome", "jpeg_round_trip"]

_MARGIN = 97  # offsets per axis (prime, so horizontal and vertical shifts do not line up)


def apply_blur(rgb: np.ndarray, sigma_px: float) -> np.ndarray:
    """Gaussian optical blur of ``sigma_px`` pixels; returns a new image.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3), uint8
        The rendered frame.
    sigma_px : float
        Standard deviation of the blur, pixels (0: unchanged copy).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    import cv2
    if sigma_px <= 0:
        return rgb
    return cv2.GaussianBlur(rgb, (0, 0), sigmaX=float(sigma_px), sigmaY=float(sigma_px),
                            borderType=cv2.BORDER_REFLECT_101)


def distortion_maps(camera) -> tuple[np.ndarray, np.ndarray]:
    """``cv2.remap`` maps from the pinhole render to the distorted frame of ``camera``.

    ``frame[v_d, u_d] = pinhole[map_v, map_u]`` with ``(map_u, map_v) =
    camera.undistort_pixels((u_d, v_d))``: each frame pixel takes the pinhole pixel its ray
    goes through (the inverse of :meth:`visland.camera.CameraModel.undistortion_maps`), so a
    pinhole label ``(u, v)`` sits at ``camera.distort_pixels((u, v))`` in the frame. Rays that
    the pinhole image does not hold (or Newton does not invert) read black.

    Parameters
    ----------
    camera : visland.camera.CameraModel
        A camera with lens distortion.

    Returns
    -------
    map_u, map_v : ndarray, shape (H, W), float32
        Pinhole pixel coordinates (SPEC convention) of each frame pixel.
    """
    v, u = np.mgrid[0:camera.height, 0:camera.width].astype(float)
    uv = camera.undistort_pixels(np.stack([u, v], axis=-1))
    uv = np.where(np.isfinite(uv), uv, -1e6)
    return uv[..., 0].astype(np.float32), uv[..., 1].astype(np.float32)


def apply_distortion(rgb: np.ndarray, maps) -> np.ndarray:
    """The distorted frame from the pinhole render ``rgb`` with :func:`distortion_maps` ``maps``.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3), uint8
        The pinhole render.
    maps : tuple of ndarray
        ``(map_u, map_v)`` from :func:`distortion_maps` (bilinear resampling).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    import cv2
    return cv2.remap(rgb, maps[0], maps[1], interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                     borderValue=(0, 0, 0))


def vignetting_gain(height: int, width: int, strength: float) -> np.ndarray:
    """Gain: 1 at the centre, ``1 - strength`` at the corners (cos^4-like, radial).

    Parameters
    ----------
    height, width : int
        Frame size, pixels.
    strength : float
        Light lost at the corners, 0 to 0.6.

    Returns
    -------
    ndarray, shape (height, width), float32
    """
    v, u = np.mgrid[0:height, 0:width].astype(np.float32)
    r2 = ((u - (width - 1) / 2) ** 2 + (v - (height - 1) / 2) ** 2) / (((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2)
    return (1.0 - np.float32(strength) * r2 ** 2).astype(np.float32)


def apply_gain(rgb: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """``rgb`` times ``gain``, rounded and saturated.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3), uint8
        The frame.
    gain : ndarray, shape (H, W)
        Per-pixel gain (:func:`vignetting_gain`).

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    return np.clip(np.rint(rgb.astype(np.float32) * gain[..., None]), 0, 255).astype(np.uint8)


def to_monochrome(rgb: np.ndarray) -> np.ndarray:
    """Grey levels (Rec. 601 luma) replicated to three equal channels.

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3), uint8
        The frame, RGB.

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    import cv2
    grey = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY)
    return np.repeat(grey[..., None], 3, axis=-1)


def jpeg_round_trip(rgb: np.ndarray, quality: int) -> np.ndarray:
    """``rgb`` encoded as JPEG at ``quality`` and decoded again (blocking, ringing).

    Parameters
    ----------
    rgb : ndarray, shape (H, W, 3), uint8
        The frame, RGB.
    quality : int
        JPEG quality, 5 to 100.

    Returns
    -------
    ndarray, shape (H, W, 3), uint8
    """
    import cv2
    ok, data = cv2.imencode(".jpg", np.ascontiguousarray(rgb[..., ::-1]), [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RuntimeError("JPEG encoding failed")
    return np.ascontiguousarray(cv2.imdecode(data, cv2.IMREAD_COLOR)[..., ::-1])


class NoiseBank:
    """Seeded additive Gaussian noise for (height, width, 3) uint8 frames.

    Parameters
    ----------
    height, width : int
        Frame size in pixels.
    std : float
        Standard deviation in digital numbers (0-255 scale).
    seed : int
        Seed of the bank (the scene's seed).
    """

    def __init__(self, height: int, width: int, std: float, seed: int):
        self.height, self.width, self.std = int(height), int(width), float(std)
        rng = np.random.default_rng([seed, 0x5E4])
        bank = rng.normal(0.0, self.std, size=(self.height + _MARGIN, (self.width + _MARGIN) * 3)).astype(np.float32)
        bank = np.clip(np.rint(bank), -127, 127).astype(np.int16)
        self._positive = np.clip(bank, 0, None).astype(np.uint8)
        self._negative = np.clip(-bank, 0, None).astype(np.uint8)

    def offsets(self, frame_seed: int) -> tuple[int, int]:
        """Row and column offset of the window used for ``frame_seed``."""
        rng = np.random.default_rng([int(frame_seed), 0x0FF5])
        return int(rng.integers(0, _MARGIN)), int(rng.integers(0, _MARGIN))

    def apply(self, rgb: np.ndarray, frame_seed: int) -> np.ndarray:
        """``rgb`` (H, W, 3) uint8 plus this frame's noise, saturated to [0, 255] (a new array)."""
        import cv2
        if rgb.shape != (self.height, self.width, 3) or rgb.dtype != np.uint8:
            raise ValueError(f"rgb must be a ({self.height}, {self.width}, 3) uint8 image, got {rgb.shape} {rgb.dtype}")
        dy, dx = self.offsets(frame_seed)
        cols = slice(3 * dx, 3 * (dx + self.width))
        rows = slice(dy, dy + self.height)
        flat = np.ascontiguousarray(rgb).reshape(self.height, self.width * 3)
        out = cv2.add(flat, self._positive[rows, cols])
        cv2.subtract(out, self._negative[rows, cols], dst=out)
        return out.reshape(self.height, self.width, 3)
