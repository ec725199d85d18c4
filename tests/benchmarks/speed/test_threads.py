"""The threads benchmark (``benchmarks/speed/threads.py``): a tiny run measured on one thread and
on the threads the harness chooses, with the same numbers."""

import pytest

from benchmarks.speed import threads
from mimo_radar_env.core.compiled import CHUNK, HAVE_NUMBA


@pytest.mark.skipif(not HAVE_NUMBA, reason="threads inside a task are numba's")
def test_a_tiny_run_is_measured_on_one_thread_and_on_the_chosen_threads(tmp_path, monkeypatch):
    tiny = ("run", "--scenario", "paper-1-v1", "--policies", "mg-crb-cl", "--trials", str(CHUNK + 6),
            "--shard-size", str(CHUNK + 6), "--steps", "3")  # fmt: skip
    monkeypatch.setattr(threads, "RUN", tiny)
    row = threads.measure_fusion("average", 2, tmp_path)
    one, chosen = row["runs"]["one thread"], row["runs"]["chosen"]
    assert row["predicted"]["threads"] == 2 and row["predicted"]["speedup"] > 1
    assert one["said"] == [] and chosen["said"] and chosen["said"][0].startswith("1 worker of 2 threads:")
    assert row["measured_task_speedup"] == pytest.approx(one["task_s"] / chosen["task_s"])
    assert row["same_numbers"]
    assert one["wall_s"] > one["task_s"] > 0
