"""The scaling benchmark measures a small layout, and its growth fit is a log-log slope."""

import pytest


def test_the_scaling_rows_measure_a_small_layout_and_the_growth_fit_is_a_slope():
    from benchmarks.speed import scaling

    row = scaling.measure(5, 6, 2, 2, 3, trials=4, steps=2)
    assert (row["M"], row["N"], row["K"], row["B"], row["solver"]) == (5, 6, 2, 4, "exact")
    assert row["ms_per_step"] > 0 and row["peak_mib"] > 0
    assert row["us_per_trial_step"] == pytest.approx(1e3 * row["ms_per_step"] / 4)
    assert scaling.growth([1, 2, 4, 8], [3, 6, 12, 24]) == pytest.approx(1.0)
    assert scaling.growth([1, 2, 4], [1, 4, 16]) == pytest.approx(2.0)
