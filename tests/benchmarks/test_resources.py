"""Resources are known before a run starts: each policy declares its memory per trial, the
harness lowers the shard size to what fits the machine (and says so) or refuses."""

import json

import pytest

import agents
from benchmarks.cli import main
from benchmarks.harness import HarnessError, fit_shard_size
from mimo_radar_env import load_scenario
from mimo_radar_env.envs.cost import memory_parts

PAPER = load_scenario("paper-1-v1")


def test_the_shard_size_is_lowered_to_fit_or_the_run_refused():
    fixed, env = memory_parts(PAPER)
    per_trial = env + 1000
    said = []
    room = int((fixed + 10 * per_trial) * 2 * 2)  # two workers, half the memory: ten trials each
    assert fit_shard_size(PAPER, {"a": 1000, "b": 10}, 50, 2, said.append, available=room) == 10
    assert "shards of 10 trials instead of 50: 'a' needs about" in said[0]
    assert fit_shard_size(PAPER, {"a": 1000}, 5, 2, said.append, available=room) == 5 and len(said) == 1
    with pytest.raises(HarnessError, match=r"one trial of .a. on .paper-1-v1. .* use fewer workers"):
        fit_shard_size(PAPER, {"a": 1000}, 50, 2, said.append, available=int(fixed + per_trial))


def test_a_run_too_large_for_the_machine_is_refused_before_anything_is_written(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("benchmarks.harness.machine_memory", lambda: 2**18)  # a 256 KiB machine
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "mg-crb-cl", "--trials", "2", "--steps", "2"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    assert "one trial of 'mg-crb-cl' on 'paper-1-v1'" in capsys.readouterr().err
    assert not out.exists()


def test_a_smaller_shard_that_fits_is_chosen_and_recorded(tmp_path, capsys, monkeypatch):
    fixed, env = memory_parts(PAPER)
    agent = agents.costs.memory_per_trial(agents.make_agent("ucb1", PAPER))
    monkeypatch.setattr("benchmarks.harness.machine_memory", lambda: int((fixed + 3 * (env + agent)) * 2))
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "7", "--steps", "3"]
    assert main([*argv, "--workers", "1", "--out", str(out), "--quiet", "--no-figures"]) == 0
    assert "shards of 3 trials instead of 7" in capsys.readouterr().err  # 7 trials, one worker
    assert json.loads((out / "config.json").read_text())["shard_size"] == 3
    assert len(list((out / "shards" / "ucb1").glob("*.npz"))) == 3  # 3 + 3 + 1 trials


# ---------------------------------------------------------------- time
def test_the_time_estimate_counts_every_task_and_the_tasks_at_once():
    from benchmarks.harness import STEP_OVERHEAD_SECONDS, estimate_seconds
    from mimo_radar_env import VERSIONS
    from mimo_radar_env.envs.cost import seconds_per_trial_step

    options = VERSIONS["v1"].options()
    env = seconds_per_trial_step(PAPER, options.tracking, options.fusion)
    own = {"a": 1e-4, "b": 3e-5}  # each policy's seconds per trial-step
    # 120 trials in shards of 50: three shards per policy, six tasks, two at once
    by_hand = sum(10 * (3 * STEP_OVERHEAD_SECONDS + 120 * (env + o)) for o in own.values())
    assert estimate_seconds(PAPER, options, own, 120, 10, 50, parallel=2) == pytest.approx(by_hand / 2)
    # one task: more workers do not make it faster
    one = estimate_seconds(PAPER, options, {"a": 1e-4}, 20, 10, 50, parallel=1)
    assert estimate_seconds(PAPER, options, {"a": 1e-4}, 20, 10, 50, parallel=4) == one


def test_a_run_estimated_beyond_max_hours_is_refused_before_anything_is_written(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "mg-crb-cl", "--trials", "5000"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--max-hours", "0.01", "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert (
        "5000 trials x 1000 steps of 1 policy on 'paper-1-v1'" in err and "more than --max-hours 0.01" in err
    )
    assert not out.exists()


def test_a_long_run_says_its_estimate(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("benchmarks.harness.STEP_OVERHEAD_SECONDS", 100.0)  # a very slow machine
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "random", "--trials", "2", "--steps", "2"]
    assert (
        main([*argv, "--workers", "1", "--max-hours", "none", "--out", str(out), "--quiet", "--no-figures"])
        == 0
    )
    assert (
        "2 trials x 2 steps of 1 policy on 'paper-1-v1', 1 task(s) at once: about" in capsys.readouterr().err
    )


@pytest.mark.parametrize("value", ["0", "-1", "inf", "nan", "soon"])
def test_max_hours_takes_a_positive_number_or_none(tmp_path, capsys, value):
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exit_info:
        main(
            ["run", "--scenario", "paper-1", "--policies", "random", "--max-hours", value, "--out", str(out)]
        )
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--max-hours" in err and "number of hours > 0 or 'none'" in err
    assert not out.exists()
