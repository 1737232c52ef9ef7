"""Independent models of grey-level profiles across rendered edges and markings, for tests of
the detector's one-dimensional readings."""

import numpy as np


def area_sampled_steps(offsets: np.ndarray, levels, steps_px, blur_px: float) -> np.ndarray:
    """Grey levels at ``offsets`` (pixels) across steps at ``steps_px`` between ``levels`` (one
    more level than steps), each pixel the mean over its width, after a Gaussian blur of
    ``blur_px`` (by a fine sum, 0.005 px): an independent model of a rendered edge, a stripe, a
    band of paint. The fine grid spans -12 to 12 px at least, and 3.5 px past the offsets."""
    lo, hi = min(-12.0, float(np.min(offsets)) - 3.5), max(12.0, float(np.max(offsets)) + 3.5)
    fine = np.linspace(lo, hi, int(round((hi - lo) / 0.005)) + 1)
    truth = np.full(fine.shape, float(levels[0]))
    for at, level in zip(steps_px, levels[1:]):
        truth[fine >= at] = level
    kernel_x = np.arange(-4.0 * blur_px, 4.0 * blur_px + 1e-9, fine[1] - fine[0])
    kernel = np.exp(-0.5 * (kernel_x / blur_px) ** 2)
    blurred = np.convolve(truth, kernel / kernel.sum(), mode="same")
    box = np.abs(fine[:, None] - offsets[None, :]) <= 0.5                 # a pixel's area around each sample
    return (blurred[:, None] * box).sum(axis=0) / box.sum(axis=0)
