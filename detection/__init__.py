"""visland.detection: find the runway in a frame, its corners, and the d_F heading measurement.

Public API (stable)::

    from visland.detection import DetectorParams, detect_runway, DetectionResult
    result = detect_runway(image_gray_uint8, camera, roll_rad, pitch_rad,
                           params=DetectorParams(), previous=None)

Modules, in pipeline order (each holds one idea):

- :mod:`~visland.detection.params`: :class:`DetectorParams`, the stage's one parameter set.
- :mod:`~visland.detection.horizon`: horizon coordinates (s, d), vanishing points.
- :mod:`~visland.detection.candidates`: Canny + Hough candidate lines in a region of interest,
  each checked and re-fitted on the frame.
- :mod:`~visland.detection.pencil`: the frame resampled on the lines through one horizon point.
- :mod:`~visland.detection.trapezoid`: the symmetry/trapezoid model picking left and right edges.
- :mod:`~visland.detection.refine`: sub-pixel refinement of a line against the image gradient.
- :mod:`~visland.detection.transverse`: the runway's surface extent, threshold and runway-end
  lines, corners.
- :mod:`~visland.detection.detector`: :func:`detect_runway`, tying the above together
  (tracking from the previous result, acquisition on the whole ground otherwise).
- :mod:`~visland.detection.result`: :class:`DetectionResult`.
- :mod:`~visland.detection.sequence`: :class:`DetectionSequence`, frame after frame (the last
  good detection as the prior through short losses; re-acquisitions checked against it).
- :mod:`~visland.detection.run`, :mod:`~visland.detection.bench`, :mod:`~visland.detection.cli`:
  ``visland detect`` and ``visland bench detect``.

- :mod:`~visland.detection.accuracy`: errors against exact labels, per distance band.

Pixel lengths in :class:`DetectorParams` are for the SPEC camera (2048 px, focal length 2472 px)
and are rescaled to the camera given (resolution lengths with the frame's side, angles seen
through the lens with its focal length), so the defaults serve every image size and lens.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from visland.exports import lazy_exports

# Exports load on first use (visland.exports, PEP 562): every ``visland`` command imports this
# package to register ``visland.detection.cli``, and the detector pulls in OpenCV and SciPy
# (0.3-0.4 s, median of 7 cold imports on the reference machine, against 0.23 s for a whole
# ``visland scenarios``), DetectorParams NumPy. The imports below are the same names for
# readers and editors ("go to definition"); they are not executed.
if TYPE_CHECKING:
    from visland.detection.detector import detect_runway
    from visland.detection.params import DetectorParams
    from visland.detection.result import LINE_NAMES, DetectionResult
    from visland.detection.sequence import DetectionSequence

_EXPORTS = {
    "DetectorParams": "visland.detection.params",
    "detect_runway": "visland.detection.detector",
    "DetectionResult": "visland.detection.result", "LINE_NAMES": "visland.detection.result",
    "DetectionSequence": "visland.detection.sequence",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
