"""The device benchmark: the normwise difference it reports, and the rows it writes (on CPU torch)."""

import json

import numpy as np
import pytest

pytest.importorskip("torch")

from benchmarks.speed import device as device_bench  # noqa: E402


def test_the_relative_difference_is_normwise_per_trial():
    a = np.array([[1e3, 1e-6], [1.0, 0.0]])
    b = a + np.array([[1e-9, 1e-9], [0.0, 0.0]])
    assert device_bench.relative_difference(a, b) == pytest.approx(1e-12)  # 1e-9 on 1e3, not on 1e-6
    assert device_bench.relative_difference(a, a + [[0, 0], [0, 1e-3]]) == pytest.approx(1e-3)
    nan = np.array([[np.nan, 1.0]])
    assert device_bench.relative_difference(nan, nan) == 0
    assert device_bench.relative_difference(nan, np.array([[1.0, 1.0]])) == np.inf


def test_the_device_benchmark_writes_its_rows(tmp_path):
    path = tmp_path / "device.json"
    device_bench.main(
        [
            "--device",
            "cpu",
            "--sizes",
            "20,40",
            "--equality-trials",
            "2",
            "--equality-steps",
            "3",
            "--target-seconds",
            "0.05",
            "--modes",
            "eager,graph",
            "--form-equality-steps",
            "3",
            "--json",
            str(path),
        ]
    )
    result = json.loads(path.read_text())
    runs = [(e["version"], e["fusion"], e["mode"], e["precision"]) for e in result["equality"]]
    eager = [(v, f, "eager") for v in ("v1", "v0") for f in ("average", "centralized")]
    assert runs == [
        *((*run, "float64") for run in eager),
        *((*run, "float32") for run in eager),  # both precisions by default
        ("v1", "average", "graph", "float64"),
        ("v1", "centralized", "graph", "float64"),
    ]
    for e in result["equality"]:
        assert "oracle_action" not in e["largest_entry"]  # the actions' share apart from the numbers
        if e["precision"] == "float64":
            assert e["largest"] <= device_bench.TOLERANCE
        else:  # float32: not the same numbers, and not float64's either
            assert device_bench.TOLERANCE < e["largest"] <= 5e-2
    rows = [r for r in result["speed"] if "skipped" not in r]
    assert {(r["backend"].split(" (")[0], r["fusion"], r["trials"]) for r in rows} == {
        (b, f, t)
        for b in ("numpy + numba, 1 core", "torch cpu")
        for f in ("average", "centralized")
        for t in (20, 40)
    }
    for r in rows:
        assert r["trial_steps_per_s"] == pytest.approx(r["trials"] / r["seconds_per_step"])
