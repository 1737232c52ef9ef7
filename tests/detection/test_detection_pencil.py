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
