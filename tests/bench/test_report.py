"""Reports: the table's cells and marks, and the summary against the curves."""

import csv
import json

import numpy as np
import pytest

from benchmarks import report
from benchmarks.cli import main


def test_cells_carry_the_interval_and_its_method_mark():
    assert report.format_estimate(1.23456, [1.2, 1.3], "{:.3f}") == "1.235 [1.200, 1.300]"
    assert report.format_estimate(0.5, [0.4, 0.6], "{:.2f}", 100, "percentile") == "50.00 [40.00, 60.00]†"
    assert (
        report.format_estimate(2.0, [2.0, 2.0], "{:.1f}", method="constant over trials") == "2.0 [2.0, 2.0]‡"
    )
    assert report.format_estimate(-0.0001, None, "{:.1f}") == "0.0"  # never -0.0
    assert report.format_estimate(None, None, "{:.1f}") == "—"


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    argv = [
        "run",
        "--scenario",
        "paper-3-v1",
        "--policies",
        "mg-crb-cl,fix2",
        "--trials",
        "5",
        "--steps",
        "12",
    ]
    assert main([*argv, "--workers", "1", "--quiet", "--out", str(out)]) == 0
    return out


def test_the_summary_follows_from_the_curves(small_run):
    summary = json.loads((small_run / "summary.json").read_text())
    with open(small_run / "curves.csv") as handle:
        rows = list(csv.DictReader(handle))
    for policy, row in summary["policies"].items():
        mine = [r for r in rows if r["policy"] == policy]
        rmse = np.array([[float(r[f"rmse_target{k}"]) for k in (1, 2)] for r in mine])
        assert row["armse_per_target"] == pytest.approx(list(rmse.mean(axis=0)), rel=1e-9)
        assert row["final_regret"] == pytest.approx(float(mine[-1]["cumulative_regret"]), rel=1e-9)
        assert row["asr"] == pytest.approx(np.mean([float(r["asr"]) for r in mine]), abs=1e-12)
        linear = np.mean([10 ** (float(r["mean_sinr_db"]) / 10) for r in mine])
        assert row["mean_sinr_db"] == pytest.approx(10 * np.log10(linear), rel=1e-9)
        assert row["method"]["armse"] == "percentile"  # 5 trials: below BCa's minimum


def test_the_table_shows_the_summary_with_marks(small_run):
    summary = json.loads((small_run / "summary.json").read_text())
    table = (small_run / "table.md").read_text()
    row = summary["policies"]["fix2"]
    assert f"{row['bound']:.3f} [{row['ci']['bound'][0]:.3f}, {row['ci']['bound'][1]:.3f}]‡" in table
    assert report.METHOD_LEGEND in table
