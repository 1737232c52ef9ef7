"""Row statistics of pencil images against their definitions, row by row in plain Python."""
import math

import numpy as np

from visland.detection.pencil import row_quantile, row_quantiles


def test_row_quantiles_are_the_nearest_order_statistics_of_each_rows_finite_values():
    rng = np.random.default_rng(7)
    values = rng.normal(100.0, 20.0, (40, 17)).astype(np.float32)
    values[3, :5] = np.nan                      # a row partly outside the frame
    values[8] = np.nan                          # a row wholly outside
    values[12, -1] = np.nan
    qs = (0.25, 0.75, 0.5, 0.0, 1.0)
    together = row_quantiles(values, qs)
    for q, column in zip(qs, together):
        np.testing.assert_array_equal(column, row_quantile(values, q))
        for row, got in zip(values, column):
            finite = sorted(float(x) for x in row if math.isfinite(x))
            if not finite:
                assert math.isnan(got)
                continue
            assert got == finite[int(math.floor(q * (len(finite) - 1) + 0.5))]


def _pencil_frame():
    """A textured 2048 px-like grey frame (smaller) and a horizon through its upper third."""
    from visland.camera import CameraModel
    from visland.detection.horizon import horizon_frame
    camera = CameraModel.default(512)
    rng = np.random.default_rng(11)
    image = rng.integers(0, 256, (512, 512), dtype=np.uint8)
    return image, horizon_frame(camera, 0.05, math.radians(-8.0))


def test_rectify_reads_the_whole_frames_values_by_bands_and_through_a_float_frame():
    """Each band of rows read from its own crop, or every read through one FloatFrame, gives
    the very float32 values cv2.remap reads off the whole frame converted to float32, samples
    outside the frame NaN; a narrow wedge and one wider than the frame."""
    import cv2

    from visland.detection.pencil import FloatFrame, rectify
    image, horizon = _pencil_frame()
    whole = image.astype(np.float32)
    shared = FloatFrame(image, margin_px=8)
    outside_seen = False
    for s0, k_range, d_range, geometric in ((10.0, (-0.2, 0.25), (1.0, 300.0), True),
                                             (-30.0, (-1.5, 1.4), (1.0, 400.0), True),
                                             (5.0, (-0.4, 0.3), (20.0, 200.0), False)):
        q, t, n = horizon.q_uv, horizon.t_uv, horizon.n_uv
        for source in (image, shared):
            rect = rectify(source, horizon, s0, k_range, d_range, max_rows=250, max_columns=90, pixel_step=2.0,
                           geometric_rows=geometric)
            d32, k32 = rect.d.astype(np.float32)[:, None], rect.k.astype(np.float32)[None, :]
            u = np.float32(q[0] + s0 * t[0]) + (d32 * np.float32(t[0])) * k32 + d32 * np.float32(n[0])
            v = np.float32(q[1] + s0 * t[1]) + (d32 * np.float32(t[1])) * k32 + d32 * np.float32(n[1])
            inside = (u >= 0) & (u <= 511) & (v >= 0) & (v <= 511)
            expected = cv2.remap(whole, u, v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            assert inside.any()
            outside_seen |= not inside.all()
            np.testing.assert_array_equal(rect.values[inside], expected[inside])
            assert np.isnan(rect.values[~inside]).all()
    assert outside_seen


def test_float_frame_converts_a_region_once():
    from visland.detection.pencil import FloatFrame
    image, _ = _pencil_frame()
    frame = FloatFrame(image, margin_px=16)
    first = frame.crop(100, 200, 300, 400)
    np.testing.assert_array_equal(first, image[200:400, 100:300].astype(np.float32))
    inner = frame.crop(90, 190, 310, 410)                      # within the margin: a view of the same conversion
    assert np.shares_memory(first, inner) and inner.dtype == np.float32
    np.testing.assert_array_equal(inner, image[190:410, 90:310].astype(np.float32))
    outer = frame.crop(0, 0, 512, 100)                         # elsewhere: converted anew
    assert not np.shares_memory(first, outer)
    np.testing.assert_array_equal(outer, image[:100].astype(np.float32))
