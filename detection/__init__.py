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

Pixel lengths in :class:`DetectorParams` are for a 2048-pixel-wide frame and are rescaled to
the frame given, so the defaults serve every image size.
"""
from visland.detection.params import DetectorParams      # light: no OpenCV

__all__ = ["DetectorParams", "DetectionResult", "DetectionSequence", "detect_runway", "LINE_NAMES"]


def __getattr__(name):
    # the detector pulls in OpenCV: import it when asked for, so that ``visland`` commands of
    # other stages (which import visland.detection.cli) start fast
    if name == "detect_runway":
        from visland.detection.detector import detect_runway
        return detect_runway
    if name == "DetectionSequence":
        from visland.detection.sequence import DetectionSequence
        return DetectionSequence
    if name in ("DetectionResult", "LINE_NAMES"):
        from visland.detection import result
        return getattr(result, name)
    raise AttributeError(f"module 'visland.detection' has no attribute {name!r}")
