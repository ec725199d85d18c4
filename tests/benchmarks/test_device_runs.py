"""The harness and the studies on the torch engine (``--device``, checked on CPU torch): the same
verdicts and estimates as on numpy, and the execution settings a device allows."""

import json
import re

import pytest

torch = pytest.importorskip("torch")
_HAS_CUDA = torch.cuda.is_available()

from benchmarks import backends, harness  # noqa: E402
from benchmarks.cli import main  # noqa: E402
from benchmarks.speed import device as device_bench  # noqa: E402


def test_the_claims_study_on_torch_gives_the_numpy_studys_verdicts_and_estimates(tmp_path, capsys):
    common = ["claims", "--trials", "6", "--steps", "10", "--quiet", "--no-figures"]
    assert main([*common, "--out", str(tmp_path / "numpy")]) == 0
    text_numpy = capsys.readouterr().out
    assert main([*common, "--out", str(tmp_path / "torch"), "--device", "cpu"]) == 0
    text_torch = capsys.readouterr().out
    assert text_torch.replace("torch", "numpy") == text_numpy  # the same tables, word for word
    numpy_claims = json.loads((tmp_path / "numpy" / "claims.json").read_text())
    torch_claims = json.loads((tmp_path / "torch" / "claims.json").read_text())
    assert [c["verdict"] for c in torch_claims] == [c["verdict"] for c in numpy_claims]
    compared = device_bench.study_differences(tmp_path / "numpy", tmp_path / "torch")
    assert {"claims.json", "paper-1-v1/summary.json", "paper-3-v1/summary.json"} <= set(compared["files"])
    assert not compared["differing"], compared["differing"][:5]
    assert 0 < compared["largest_relative"] <= device_bench.TOLERANCE  # rounding, not identity


def test_a_run_with_the_step_as_one_graph_gives_the_eager_runs_numbers(tmp_path):
    """``--device-mode graph`` through the harness: each policy's batch steps through the traced
    step (on CPU torch, the traced function), and every number of the run is the eager run's."""
    common = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,mg-crb-cl", "--trials", "4"]
    common += ["--steps", "12", "--quiet", "--no-figures", "--device", "cpu"]
    assert main([*common, "--out", str(tmp_path / "eager")]) == 0
    assert main([*common, "--out", str(tmp_path / "graph"), "--device-mode", "graph"]) == 0
    compared = device_bench.study_differences(tmp_path / "eager", tmp_path / "graph")
    assert "summary.json" in compared["files"]
    assert not compared["differing"] and compared["largest_relative"] == 0.0


def test_study_differences_find_a_changed_number_and_skip_the_times():
    a = {"x": [1.0, 2.0], "wall_s": 3.0, "v": "holds", "zero": 6.7e-16}
    assert not device_bench.json_differences(a, {**a, "wall_s": 9.0, "zero": 2.2e-16})
    assert device_bench.json_differences(a, {**a, "x": [1.0, 2.0 + 1e-8]}) == [(".x[1]", 2.0, 2.0 + 1e-8)]
    assert device_bench.json_differences(a, {**a, "v": "consistent"}) == [(".v", "holds", "consistent")]


def test_a_run_on_a_device_is_one_batch_per_policy_unless_told(tmp_path):
    common = ["run", "--scenario", "paper-1-v1", "--trials", "6", "--steps", "3", "--quiet", "--no-figures"]
    common += ["--device", "cpu"]
    assert main([*common, "--policies", "ucb1,random", "--out", str(tmp_path / "one")]) == 0
    assert harness.recorded_shard_size(tmp_path / "one") == 6
    assert main([*common, "--policies", "ucb1", "--out", str(tmp_path / "two"), "--shard-size", "4"]) == 0
    assert harness.recorded_shard_size(tmp_path / "two") == 4


def test_device_tasks_on_worker_processes_give_the_numbers_of_one_process(tmp_path, monkeypatch):
    """``--workers 2`` with ``--device``: the tasks run in two worker processes sharing the device
    (not in this process), one thread each, and every number is the one process's."""
    common = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,mg-crb-cl,random", "--trials", "5"]
    common += ["--steps", "8", "--quiet", "--no-figures", "--device", "cpu"]
    assert main([*common, "--out", str(tmp_path / "one")]) == 0
    pools = []
    original = backends.run_processes
    monkeypatch.setattr(backends, "run_inline", None)  # not one task in this process
    monkeypatch.setattr(backends, "run_processes", lambda *a, **k: pools.append(a[3:5]) or original(*a, **k))
    assert main([*common, "--out", str(tmp_path / "two"), "--workers", "2"]) == 0
    assert pools == [(2, 1)]  # two processes of one thread
    compared = device_bench.study_differences(tmp_path / "one", tmp_path / "two")
    assert "summary.json" in compared["files"]
    assert not compared["differing"], compared["differing"][:5]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            ["--backend", "ray"],
            r"--device 'cpu' runs on the local backend: the tasks in this process, or in --workers "
            r"processes sharing the device \(got backend='ray'\)$",
        ),
        (
            ["--device", "gpu"],
            r"--device must be 'cpu', 'cuda' or 'cuda:N', or no --device, got 'gpu'$",
        ),
        (
            ["--device", "cpu", "--policies", "ucb1,cts"],
            r"--device 'cpu': cts act\(s\) on numpy arrays only; run",
        ),
        pytest.param(
            ["--device", "cuda"],
            r"--device='cuda': torch sees no CUDA device here; use 'cpu' or no --device$",
            marks=pytest.mark.skipif(_HAS_CUDA, reason="a CUDA device is here"),
        ),
        (
            ["--device-mode", "graph"],
            r"--device-mode='graph' runs on torch: give a --device \('cpu', 'cuda'\)$",
        ),
    ],
)
def test_a_device_run_that_cannot_be_is_refused_in_one_line(tmp_path, capsys, extra, message):
    args = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "2", "--steps", "2"]
    args += ["--quiet", "--out", str(tmp_path / "r")]
    args += ["--device", "cpu", *extra] if extra[0] == "--backend" else extra
    with pytest.raises(SystemExit) as exit_info:
        main(args)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert len([line for line in err.splitlines() if line.strip()]) == 1
    assert re.search(message, err), err
    assert not (tmp_path / "r").exists()  # refused before anything is written
