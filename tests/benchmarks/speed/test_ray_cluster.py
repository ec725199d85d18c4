"""The Ray-against-local benchmark (``benchmarks/speed/ray_cluster.py``): its runs alternate the
backends, the order reversed every other repeat, a run whose numbers differ from the first
one's is caught, and each run's time before its first task and after its last is read from its
shards (no cluster started)."""

import numpy as np
import pytest

from benchmarks.speed import ray_cluster


def _shard(folder, values, seconds):
    path = folder / "run" / "shards" / "fix1" / "shard_0.npz"
    path.parent.mkdir(parents=True)
    (folder / "run" / "config.json").write_text('{"steps": 5}')
    np.savez(
        path, trial_expected=np.asarray(values), wall_s=np.array(seconds), checksum=np.array(str(seconds))
    )


def test_the_backends_alternate_and_a_changed_number_is_caught(tmp_path, monkeypatch):
    commands, runs = [], []

    def study(arguments, workers, out, python):
        assert python == ("-m", "benchmarks")
        runs.append(("ray" if "ray" in arguments else "local", workers))
        changed = len(runs) == 4  # the last run (the second repeat's local one) writes another number
        _shard(out, [1.0, np.nan, 3.0 + changed], seconds=len(runs))
        return 10.0 + len(runs)

    monkeypatch.setattr(ray_cluster, "run_study", study)
    monkeypatch.setattr(ray_cluster, "ray", lambda *arguments, check=True: commands.append(arguments[0]))
    result = ray_cluster.measure(("claims",), 2, repeats=2)
    assert commands == ["start", "stop"]
    # the order reversed every other repeat
    assert runs == [("local", 2), ("ray", 2), ("ray", 2), ("local", 2)]
    assert [r["wall_s"] for r in result["runs"]] == [11.0, 12.0, 13.0, 14.0]
    # NaN equals NaN; the compute time and its checksum differ in every run and are left out
    assert [r["same_numbers"] for r in result["runs"]] == [True, True, True, False]
    # the shard was written as the fake run returned: its task started its compute seconds
    # before, and the run's wall time ends at once after it
    for number, run in enumerate(result["runs"], start=1):
        assert run["before_first_task_s"] == pytest.approx(-number, abs=0.5)
        assert run["after_last_task_s"] == pytest.approx(run["wall_s"], abs=0.5)
