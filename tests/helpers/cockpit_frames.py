"""A synthetic cockpit sequence with known structure pixels, for the structure-mask tests.

Drawn here, independently of the code under test: a textured ground (smoothed seeded noise)
sliding across the view frame after frame, a static bright sky above a static horizon (steady
flight: the hard case, both are as steady as the structure), and the aircraft's structure drawn
over it: a dark windshield frame along the bottom and both sides, and a static wiper bar. Each
frame gets seeded sensor noise and a small exposure flicker.
"""
import cv2
import numpy as np

SIZE = (640, 480)
HORIZON_V = 110


def structure_truth(size=SIZE):
    """Boolean (H, W): True on the drawn structure (frame and wiper)."""
    width, height = size
    canvas = np.zeros((height, width), np.uint8)
    glare_shield = np.array([[0, 392], [200, 404], [440, 404], [width - 1, 388], [width - 1, height - 1],
                             [0, height - 1]], np.int32)
    left_pillar = np.array([[0, 0], [48, 0], [92, height - 1], [0, height - 1]], np.int32)
    right_pillar = np.array([[width - 40, 0], [width - 1, 0], [width - 1, height - 1], [width - 75, height - 1]],
                            np.int32)
    for polygon in (glare_shield, left_pillar, right_pillar):
        cv2.fillPoly(canvas, [polygon], 1)
    cv2.line(canvas, (430, 470), (515, 180), 2, thickness=14)
    return canvas


def cockpit_frames(n_frames=30, seed=0, size=SIZE, exposure_swing=0.02, shake_px=0):
    """``n_frames`` grey uint8 frames and the structure truth (bool, of the unshaken frame).

    ``exposure_swing``: relative amplitude of the automatic exposure's swing over the frames;
    ``shake_px``: the whole frame shifted by a random whole number of pixels in
    ``[-shake_px, shake_px]`` each way (a hand-held camera).
    """
    rng = np.random.default_rng(seed)
    width, height = size
    step = np.array([11, 6])
    big = rng.normal(0.0, 1.0, (height + n_frames * step[1] + 40, width + n_frames * step[0] + 40))
    ground = cv2.GaussianBlur(big.astype(np.float32), (0, 0), 3.0)
    ground = 120.0 + 38.0 * ground / ground.std()
    canvas = structure_truth(size)
    frame_part, wiper = canvas == 1, canvas == 2
    v = np.arange(height)[:, None] * np.ones((1, width))
    frames = []
    for k in range(n_frames):
        du, dv = k * step + (np.array([7, 4]) * np.sin(0.7 * k)).astype(int) + 20
        image = ground[dv:dv + height, du:du + width].copy()
        image[v < HORIZON_V] = 215.0 - 0.15 * v[v < HORIZON_V]              # sky: bright, smooth gradient
        image[frame_part] = 32.0
        image[wiper] = 58.0
        image *= 1.0 + exposure_swing * np.sin(1.3 * k)                        # automatic exposure
        image += rng.normal(0.0, 2.0, image.shape)
        if shake_px:
            du, dv = rng.integers(-shake_px, shake_px + 1, 2)
            image = cv2.warpAffine(image, np.float32([[1, 0, du], [0, 1, dv]]), (width, height),
                                   borderMode=cv2.BORDER_REPLICATE)
        frames.append(np.clip(np.round(image), 0, 255).astype(np.uint8))
    return frames, canvas > 0
