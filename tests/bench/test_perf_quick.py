"""The perf command's quick mode: every figure is produced, as a positive number."""

import json

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
