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


def test_the_device_benchmark_keeps_each_row_as_it_comes_and_runs_the_fusions_asked(tmp_path, monkeypatch):
    path = tmp_path / "device.json"
    seen = []
    real = device_bench.measure

    def measure_then_stop(*args, **kwargs):  # a run stopped by a time limit in its third row
        seen.append(json.loads(path.read_text())["speed"] if path.exists() else None)
        if len(seen) == 5:  # the probe and the timing of each row: rows 1 and 2 done
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(device_bench, "measure", measure_then_stop)
    arguments = ["--device", "cpu", "--sizes", "20,40", "--skip-equality", "--target-seconds", "0.02"]
    with pytest.raises(KeyboardInterrupt):
        device_bench.main([*arguments, "--fusions", "centralized", "--json", str(path)])
    kept = json.loads(path.read_text())["speed"]
    assert [(r["fusion"], r["trials"]) for r in kept] == [("centralized", 20), ("centralized", 40)]
    assert seen[2] == kept[:1]  # the first row was on disk before the second was measured
    with pytest.raises(SystemExit, match="unknown fusion 'eq22' in --fusions; allowed: average, centralized"):
        device_bench.main([*arguments, "--fusions", "average,eq22", "--json", str(tmp_path / "no.json")])
    assert not (tmp_path / "no.json").exists()


@pytest.mark.parametrize(("device", "measured"), [(None, [500]), ("cuda:0", [500, 50_000, 1_000_000])])
def test_rows_stop_growing_linearly_on_a_cpu_and_after_a_slow_step_on_a_gpu(monkeypatch, device, measured):
    """A step of 20 ms at B = 500: on a CPU B = 50,000 would take 2 s (linear), so the rows stop;
    on a GPU, launch-bound at small B, they go on until a step itself took longer than the limit."""
    seconds = {500: 0.02, 50_000: 0.03, 1_000_000: 0.5}
    monkeypatch.setattr(device_bench, "_engine", lambda *args: args[2])
    monkeypatch.setattr(device_bench, "_free", lambda device: None)

    def measure(fusion, trials, device, keys, steps, mode="eager", engine=None):
        rate = trials / seconds[trials]
        return {
            "trials": trials,
            "seconds_per_step": seconds[trials],
            "trial_steps_per_s": rate,
            "first_step_s": 0,
        }

    monkeypatch.setattr(device_bench, "measure", measure)
    rows = list(device_bench.speed_rows("b", device, tuple(seconds), None, 1.9, 1.0, fusions=("average",)))
    assert [r["trials"] for r in rows if "skipped" not in r] == measured
    assert [r["skipped"] for r in rows if "skipped" in r] == (["too slow"] if device is None else [])


def test_the_profile_gives_each_operations_calls_per_step_as_counted_apart(tmp_path, capsys):
    """The profile's calls of a library kernel in a step are those a dispatch mode counts in the
    same step, and its times add up to no more than the step's wall time (on the CPU)."""
    from torch.utils._python_dispatch import TorchDispatchMode

    path = tmp_path / "device.json"
    arguments = ["--device", "cpu", "--skip-equality", "--skip-speed", "--fusions", "centralized"]
    device_bench.main([*arguments, "--profile-sizes", "8", "--json", str(path)])
    (row,) = json.loads(path.read_text())["profile"]
    for bad in ("5,x", "0", "8,"):
        with pytest.raises(SystemExit):  # argparse's one line, before anything runs
            device_bench.main([*arguments, "--profile-sizes", bad, "--json", str(tmp_path / "bad.json")])
        assert f"--profile-sizes: must be positive trial counts, comma-separated, got {bad!r}" in (
            capsys.readouterr().err
        )
    assert not (tmp_path / "bad.json").exists()
    assert (row["fusion"], row["trials"], row["time"]) == ("centralized", 8, "cpu")
    assert 0 < sum(op["ms_per_step"] for op in row["ops"]) <= row["ms_per_step"] <= row["wall_ms_per_step"]

    keys = device_bench._keys(8)
    one = device_bench.profile_row("centralized", 8, "cpu", keys, steps=1, top=10_000)
    engine = device_bench._engine("v1", "centralized", 8, "cpu")
    engine.reset_from_keys(keys)
    first, second = device_bench._random_actions(engine, 2)  # the actions the profile played
    engine.step(first)
    calls: dict[str, int] = {}

    class Calls(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            name = "aten::" + func.__name__.split(".")[0]
            calls[name] = calls.get(name, 0) + 1
            return func(*args, **(kwargs or {}))

    with Calls():
        engine.step(second)
    profiled = {op["op"]: op["calls_per_step"] for op in one["ops"]}
    # (the profiler also records composite operations and their parts, where a dispatch mode sees
    # the parts alone: compared here are library kernels called directly)
    for name in ("aten::linalg_cholesky_ex", "aten::sort"):
        assert profiled[name] == calls[name] >= 1, name


def test_the_forms_asked_are_also_timed_with_torchs_library_products(monkeypatch, capsys):
    """``--library-products graph``: the graph form's rows again, labelled and marked, with
    torch's batched matrix products (the CPU's choice) where the device computes elementwise;
    the other forms once. A bad form is refused in argparse's one line."""
    import argparse

    import torch

    from mimo_radar_env.core.arrays import TorchNamespace

    def rows(backend, where, sizes, *rest):
        yield {"backend": backend, "elementwise": TorchNamespace("cuda").elementwise}

    monkeypatch.setattr(device_bench, "speed_rows", rows)
    monkeypatch.setattr(torch, "get_num_threads", lambda: 2)
    args = argparse.Namespace(sizes="500", compiled_sizes="500", library_products="graph",
                              max_step_seconds=1.0, target_seconds=1.0)  # fmt: skip
    made = list(device_bench._speed(args, "cuda:0", ("eager", "graph"), ("float64",)))
    assert made[2:] == [
        {"backend": "torch cuda:0 eager", "elementwise": True},
        {"backend": "torch cuda:0 graph", "elementwise": True},
        {"backend": "torch cuda:0 graph library products", "elementwise": False, "products": "library"},
    ]
    with pytest.raises(SystemExit):
        device_bench.main(["--device", "cpu", "--library-products", "graph,jit"])
    assert (
        "argument --library-products: must be forms of the step (eager, graph, compiled), got 'graph,jit'"
        in (capsys.readouterr().err)
    )
