"""Template operations: cut a reference, measure its texture, warp it, find it again (pure functions).

Pixels follow :mod:`visland.camera`: ``(u, v)`` with u right, v down and ``(0, 0)`` the
centre of the top-left pixel, so image row ``i``, column ``j`` is the pixel ``(u, v) = (j, i)``.

A reference is cut at whole pixels (no interpolation blur): its centre pixel is the tracked
point rounded, and ``offset_px`` keeps the sub-pixel remainder, so the point is
``centre_px + offset_px``. Matching uses normalised cross-correlation (OpenCV
``matchTemplate`` with ``TM_CCOEFF_NORMED``: zero-mean, unit-norm correlation in [-1, 1],
insensitive to brightness and contrast changes) in a window around a prediction. The whole-
pixel peak is refined to sub-pixel precision either by Gauss-Newton on the normalised
difference (:func:`refine_translation`, the default: a few hundredths of a pixel on smooth
texture) or by a parabola through the peak and its two neighbours along each axis (cheaper,
but biased towards whole pixels by up to a few tenths on sharp peaks, which re-cut templates
then accumulate as drift).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["ReferencePatch", "Texture", "Match", "cut_reference", "patch_texture", "template_from_reference",
           "match_in_window", "refine_translation", "homography_jacobian", "apply_homography", "SUBPIXEL_METHODS"]

#: Sub-pixel refinement of the correlation peak (see :func:`match_in_window`).
SUBPIXEL_METHODS = ("gradient", "parabola")


@dataclass(frozen=True)
class ReferencePatch:
    """A square patch cut around a tracked point, larger than the template (room to warp it).

    Attributes
    ----------
    pixels : ndarray, shape (2 * half_px + 1, 2 * half_px + 1), float32
        Grey levels.
    centre_px : ndarray of int, shape (2,)
        ``(u, v)`` of the patch's centre pixel in the image it was cut from.
    offset_px : ndarray, shape (2,)
        Tracked point minus ``centre_px`` (each within [-0.5, 0.5]).
    """

    pixels: np.ndarray
    centre_px: np.ndarray
    offset_px: np.ndarray

    @property
    def half_px(self) -> int:
        return self.pixels.shape[0] // 2

    @property
    def point_px(self) -> np.ndarray:
        return self.centre_px + self.offset_px


@dataclass(frozen=True)
class Texture:
    """How well a patch pins a point down (structure tensor of the patch).

    Attributes
    ----------
    weak, strong : float
        RMS grey-level gradients (grey levels per pixel) along the patch's weakest and
        strongest directions (square roots of the eigenvalues of the mean of ``grad grad^T``).
    normal : ndarray, shape (2,)
        The strongest direction (across an edge), a unit vector in pixels (u, v).
    kind : str
        ``"corner"`` (both directions textured: the point is pinned down), ``"edge"`` (only
        across one direction: it can slide along the edge, the aperture problem) or
        ``"featureless"``.
    """

    weak: float
    strong: float
    normal: np.ndarray
    kind: str


@dataclass(frozen=True)
class Match:
    """Result of looking for a template in a search window.

    Attributes
    ----------
    found : bool
        True when a peak was accepted.
    reason : str
        Otherwise why not (score too low, ambiguous, peak on the window border, window outside
        the image).
    uv : ndarray, shape (2,)
        Sub-pixel position of the template's reference point (SPEC pixels), NaN when not found.
    score : float
        The best normalised cross-correlation.
    second_score : float
        The best correlation away from the peak (NaN if none).
    """

    found: bool
    reason: str
    uv: np.ndarray
    score: float
    second_score: float


def cut_reference(image: np.ndarray, uv, half_px: int) -> ReferencePatch | None:
    """Cut the ``(2 half_px + 1)``-square patch centred on the pixel nearest ``uv``.

    Parameters
    ----------
    image : ndarray, shape (H, W), uint8 or float
    uv : (2,) pixel position of the point.
    half_px : half-side of the patch.

    Returns None when the patch does not lie wholly inside the image.
    """
    uv = np.asarray(uv, dtype=float)
    if uv.shape != (2,) or not np.all(np.isfinite(uv)):
        raise ValueError(f"uv must be two finite pixel coordinates, got {uv!r}")
    centre = np.floor(uv + 0.5).astype(int)
    u0, v0 = centre[0] - half_px, centre[1] - half_px
    u1, v1 = centre[0] + half_px + 1, centre[1] + half_px + 1
    height, width = image.shape[:2]
    if u0 < 0 or v0 < 0 or u1 > width or v1 > height:
        return None
    pixels = np.ascontiguousarray(image[v0:v1, u0:u1], dtype=np.float32)
    return ReferencePatch(pixels=pixels, centre_px=centre, offset_px=uv - centre)


def patch_texture(pixels: np.ndarray, min_texture: float, min_contrast: float) -> Texture:
    """Structure tensor of a patch and its kind (see :class:`Texture`).

    Gradients are central differences (grey levels per pixel) on the patch interior.

    Parameters
    ----------
    pixels : ndarray, shape (h, w), h and w >= 3
        The patch, grey levels.
    min_texture : float
        Weakest-direction gradient (grey levels per pixel) under which the patch is an edge.
    min_contrast : float
        Strongest-direction gradient under which it is featureless.

    Returns
    -------
    Texture
    """
    p = np.asarray(pixels, dtype=np.float64)
    if p.ndim != 2 or min(p.shape) < 3:
        raise ValueError(f"pixels must be a 2-D patch of at least 3x3, got shape {p.shape}")
    gu = 0.5 * (p[1:-1, 2:] - p[1:-1, :-2])
    gv = 0.5 * (p[2:, 1:-1] - p[:-2, 1:-1])
    tensor = np.array([[np.mean(gu * gu), np.mean(gu * gv)], [np.mean(gu * gv), np.mean(gv * gv)]])
    eigenvalues, eigenvectors = np.linalg.eigh(tensor)
    weak = math.sqrt(max(eigenvalues[0], 0.0))
    strong = math.sqrt(max(eigenvalues[1], 0.0))
    if strong < min_contrast:
        kind = "featureless"
    elif weak < min_texture:
        kind = "edge"
    else:
        kind = "corner"
    return Texture(weak=weak, strong=strong, normal=eigenvectors[:, 1].copy(), kind=kind)


def template_from_reference(reference: ReferencePatch, template_size: int,
                            A_reference_from_image: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The template to look for, and where the point sits in it.

    Without a warp the template is the reference's central ``template_size`` square and the
    point sits at its centre pixel plus ``reference.offset_px``. With a warp
    ``A_reference_from_image`` (2x2: a displacement in the current image maps to this
    displacement in the reference's image, the local linear map of the ground-plane motion),
    the template is resampled (bilinear) so that the point sits exactly at its centre.

    Parameters
    ----------
    reference : ReferencePatch
        The patch cut when the template was last updated (:func:`cut_reference`).
    template_size : int
        Side of the template, pixels (odd, at most the reference's side).
    A_reference_from_image : ndarray, shape (2, 2), optional
        The warp (none: the reference's central square as it is).

    Returns
    -------
    template : ndarray, shape (template_size, template_size), float32
    offset_px : ndarray, shape (2,)
        The point minus the template's centre pixel, in the current image.
    """
    half = template_size // 2
    big = reference.half_px
    if half > big:
        raise ValueError(f"template_size {template_size} is larger than the reference patch {2 * big + 1}")
    if A_reference_from_image is None:
        template = reference.pixels[big - half:big + half + 1, big - half:big + half + 1]
        return template, reference.offset_px.copy()
    A = np.asarray(A_reference_from_image, dtype=float)
    # template index (j, i) <-> current-image displacement (j - half, i - half) from the point;
    # reference index = big + offset + A @ displacement
    shift = big + reference.offset_px - A @ np.array([half, half], dtype=float)
    M = np.hstack([A, shift[:, None]]).astype(np.float64)
    template = cv2.warpAffine(reference.pixels, M, (template_size, template_size),
                              flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE)
    return template, np.zeros(2)


def _parabola_vertex(left: float, centre: float, right: float) -> float:
    """Sub-sample position of the vertex of the parabola through (-1, left), (0, centre), (1, right)."""
    curvature = left - 2.0 * centre + right
    if not curvature < 0.0:      # flat or not a maximum: stay on the sample
        return 0.0
    return float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))


def refine_translation(image: np.ndarray, template: np.ndarray, centre_uv, iterations: int = 6,
                       tolerance_px: float = 0.005) -> np.ndarray | None:
    """Sub-pixel position of a template's centre by Gauss-Newton on the normalised difference.

    Minimises ``sum_x (N[W_c](x) - N[T](x))^2`` over the centre ``c``, where
    ``W_c(x) = I(c + x)`` is the image resampled (bilinear) around ``c`` and ``N`` removes the
    mean and divides by the standard deviation (the same brightness and contrast invariance
    as the correlation score). Linearising ``W_{c+d} ~ W_c + grad(T) . d`` (the template's
    gradient stands for the window's: inverse-compositional Lucas-Kanade for a translation)
    gives ``(sum g g^T) d = sum g (N[T] - N[W_c])``. Directions the template does not
    constrain (along an edge) are left unchanged: the normal matrix is inverted on its
    well-conditioned eigen-directions only.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        The current frame, grey levels.
    template : ndarray, shape (T, T)
        The template, grey levels.
    centre_uv : array_like, shape (2,)
        Starting pixel position of the template's centre.
    iterations : int, default 6
        Most Gauss-Newton steps.
    tolerance_px : float, default 0.005
        Stop when a step is shorter than this, pixels.

    Returns
    -------
    ndarray, shape (2,) or None
        The refined centre, or None if it moved more than one pixel (diverged).
    """
    t = np.asarray(template, dtype=np.float32)
    size = t.shape[0]
    tn = (t - t.mean()) / max(float(t.std()), 1e-6)
    gu = np.zeros_like(tn)
    gv = np.zeros_like(tn)
    gu[:, 1:-1] = 0.5 * (tn[:, 2:] - tn[:, :-2])
    gv[1:-1, :] = 0.5 * (tn[2:, :] - tn[:-2, :])
    inner = (slice(1, -1), slice(1, -1))
    gu, gv, tn_in = gu[inner].ravel(), gv[inner].ravel(), tn[inner].ravel()
    normal = np.array([[gu @ gu, gu @ gv], [gu @ gv, gv @ gv]], dtype=np.float64)
    eigenvalues, eigenvectors = np.linalg.eigh(normal)
    if eigenvalues[1] <= 0:
        return None
    keep = eigenvalues > 1e-3 * eigenvalues[1]
    inverse = (eigenvectors[:, keep] / eigenvalues[keep]) @ eigenvectors[:, keep].T
    start = np.asarray(centre_uv, dtype=np.float64)
    centre = start.copy()
    for _ in range(iterations):
        window = cv2.getRectSubPix(image, (size, size), (float(centre[0]), float(centre[1])), patchType=cv2.CV_32F)
        wn = (window - window.mean()) / max(float(window.std()), 1e-6)
        residual = tn_in - wn[inner].ravel()
        step = inverse @ np.array([gu @ residual, gv @ residual], dtype=np.float64)
        centre = centre + step
        if np.max(np.abs(centre - start)) > 1.0:
            return None
        if np.max(np.abs(step)) < tolerance_px:
            break
    return centre


def match_in_window(image: np.ndarray, template: np.ndarray, offset_px, predicted_uv, search_radius_px: int,
                    min_score: float, ambiguity_margin: float, ambiguity_distance_px: float,
                    subpixel: str = "gradient") -> Match:
    """Find ``template`` near ``predicted_uv`` by normalised cross-correlation.

    Parameters
    ----------
    image : ndarray, shape (H, W), uint8 or float32
    template : ndarray, shape (T, T), float32, T odd.
    offset_px : (2,) the tracked point minus the template's centre pixel.
    predicted_uv : (2,) predicted pixel position of the tracked point.
    search_radius_px : the template centre is searched within this many pixels (each axis)
        of its predicted position.
    min_score, ambiguity_margin, ambiguity_distance_px : acceptance rules (see
        :class:`visland.tracking.TrackerParams`).
    subpixel : str, default "gradient"
        How the peak is refined below a pixel: ``"gradient"`` (Gauss-Newton on the template,
        :func:`refine_translation`) or ``"parabola"`` (a parabola through the scores).

    Returns
    -------
    Match
        The point's sub-pixel position when accepted. A peak on the window border is refused
        (the true maximum may lie outside: accepting it would let the point slide away).
    """
    nan2 = np.full(2, np.nan)
    template = np.asarray(template, dtype=np.float32)
    size = template.shape[0]
    half = size // 2
    offset = np.asarray(offset_px, dtype=float)
    centre = np.floor(np.asarray(predicted_uv, dtype=float) - offset + 0.5).astype(int)
    height, width = image.shape[:2]
    # window of template centres [c - r, c + r], clipped so the template stays in the image
    lo = np.maximum(centre - search_radius_px, half)
    hi = np.minimum(centre + search_radius_px, np.array([width - 1 - half, height - 1 - half]))
    if np.any(hi - lo < 2):
        return Match(False, "search window outside the image", nan2, math.nan, math.nan)
    window = image[lo[1] - half:hi[1] + half + 1, lo[0] - half:hi[0] + half + 1]
    if window.dtype != np.float32:
        window = window.astype(np.float32)
    scores = cv2.matchTemplate(window, template, cv2.TM_CCOEFF_NORMED)
    # a flat window (zero variance) has no defined correlation
    scores = np.nan_to_num(scores, nan=-1.0, posinf=-1.0, neginf=-1.0)
    _, best, _, (j, i) = cv2.minMaxLoc(scores)
    best = float(best)
    rows, cols = scores.shape
    radius = int(math.ceil(ambiguity_distance_px))
    masked = scores.copy()
    masked[max(i - radius, 0):i + radius + 1, max(j - radius, 0):j + radius + 1] = -np.inf
    second = float(masked.max()) if np.isfinite(masked).any() else math.nan
    if best < min_score:
        return Match(False, f"score {best:.2f} < {min_score:.2f}", nan2, best, second)
    on_border_u = (j == 0 and lo[0] > half) or (j == cols - 1 and hi[0] < width - 1 - half)
    on_border_v = (i == 0 and lo[1] > half) or (i == rows - 1 and hi[1] < height - 1 - half)
    if on_border_u or on_border_v:
        return Match(False, f"peak on the search-window border (score {best:.2f})", nan2, best, second)
    if j == 0 or j == cols - 1 or i == 0 or i == rows - 1:
        return Match(False, f"peak on the image border (score {best:.2f})", nan2, best, second)
    if math.isfinite(second) and second > best - ambiguity_margin:
        return Match(False, f"ambiguous (two peaks {best:.2f} and {second:.2f})", nan2, best, second)
    du = _parabola_vertex(float(scores[i, j - 1]), best, float(scores[i, j + 1]))
    dv = _parabola_vertex(float(scores[i - 1, j]), best, float(scores[i + 1, j]))
    centre_uv = np.array([lo[0] + j + du, lo[1] + i + dv], dtype=float)
    if subpixel == "gradient":
        refined = refine_translation(image, template, centre_uv)
        if refined is not None:
            centre_uv = refined
    elif subpixel != "parabola":
        raise ValueError(f"subpixel must be 'gradient' or 'parabola', got {subpixel!r}")
    return Match(True, "", centre_uv + offset, best, second)


def apply_homography(H: np.ndarray, uv) -> np.ndarray:
    """Map pixel points through a 3x3 homography.

    Parameters
    ----------
    H : ndarray, shape (3, 3)
        The homography, acting on homogeneous points ``(u, v, 1)``.
    uv : array_like, shape (..., 2)
        Points (pixels, or virtual coordinates for ``G^-1``).

    Returns
    -------
    ndarray, shape (..., 2)
    """
    uv = np.asarray(uv, dtype=float)
    w = H[2, 0] * uv[..., 0] + H[2, 1] * uv[..., 1] + H[2, 2]
    u = (H[0, 0] * uv[..., 0] + H[0, 1] * uv[..., 1] + H[0, 2]) / w
    v = (H[1, 0] * uv[..., 0] + H[1, 1] * uv[..., 1] + H[1, 2]) / w
    return np.stack([u, v], axis=-1)


def homography_jacobian(H: np.ndarray, uv) -> np.ndarray:
    """2x2 derivative of the homography map ``x -> H(x)`` at the point ``uv`` (2,).

    With ``[a, b, w] = H [u, v, 1]``: ``d(a/w) = (dA - (a/w) dW) / w`` where ``dA`` and ``dW``
    are the first two entries of H's first and third rows.

    Parameters
    ----------
    H : ndarray, shape (3, 3)
        The homography.
    uv : array_like, shape (2,)
        Where the derivative is taken.

    Returns
    -------
    ndarray, shape (2, 2)
        ``d H(x) / d x`` at ``uv``.
    """
    u, v = float(uv[0]), float(uv[1])
    a = H[0, 0] * u + H[0, 1] * v + H[0, 2]
    b = H[1, 0] * u + H[1, 1] * v + H[1, 2]
    w = H[2, 0] * u + H[2, 1] * v + H[2, 2]
    x, y = a / w, b / w
    return np.array([[H[0, 0] - x * H[2, 0], H[0, 1] - x * H[2, 1]],
                     [H[1, 0] - y * H[2, 0], H[1, 1] - y * H[2, 1]]]) / w
