"""The perf command's quick mode: every figure is produced, as a positive number."""

import json

import pytest

from benchmarks.cli import main

FIGURES = {
    "tracker_speedup_vs_filterpy",
    "exact_vs_bpso_speedup",
    "bpso_optimality_rate",
    "env_trial_steps_per_s",
    "repro_wall_s_exact",
    "repro_wall_s_paper",
}


def test_perf_quick_writes_every_figure(tmp_path, capsys):
    assert main(["perf", "--quick", "--workers", "1", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "perf.json").read_text())
    assert FIGURES <= set(result) and result["quick"] is True
    for key in FIGURES:
        assert result[key] > 0, key
    assert 0 <= result["bpso_optimality_rate"] <= 1
    assert "tracker_speedup_vs_filterpy" in capsys.readouterr().out


def test_the_scaling_rows_measure_a_small_layout_and_the_growth_fit_is_a_slope():
    from benchmarks.speed import scaling

    row = scaling.measure(5, 6, 2, 2, 3, trials=4, steps=2)
    assert (row["M"], row["N"], row["K"], row["B"], row["solver"]) == (5, 6, 2, 4, "exact")
    assert row["ms_per_step"] > 0 and row["peak_mib"] > 0
    assert row["us_per_trial_step"] == pytest.approx(1e3 * row["ms_per_step"] / 4)
    assert scaling.growth([1, 2, 4, 8], [3, 6, 12, 24]) == pytest.approx(1.0)
    assert scaling.growth([1, 2, 4], [1, 4, 16]) == pytest.approx(2.0)
