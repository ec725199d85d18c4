"""Resources are known before a run starts (benchmarks.resources): each policy declares its
memory per trial, the harness lowers the shard size to what fits the machine (and says so) or
refuses; the time is estimated from the declared costs, which also size the shards, order the
tasks and choose the threads per worker."""

import json

import pytest

import agents
from benchmarks.cli import main
from benchmarks.errors import HarnessError
from benchmarks.harness import make_config
from benchmarks.resources import fit_shard_size
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
    monkeypatch.setattr("benchmarks.resources.machine_memory", lambda: 2**18)  # a 256 KiB machine
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
    monkeypatch.setattr("benchmarks.resources.machine_memory", lambda: int((fixed + 3 * (env + agent)) * 2))
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "7", "--steps", "3"]
    assert main([*argv, "--workers", "1", "--out", str(out), "--quiet", "--no-figures"]) == 0
    assert "shards of 3 trials instead of 7" in capsys.readouterr().err  # 7 trials, one worker
    assert json.loads((out / "config.json").read_text())["shard_size"] == 3
    assert len(list((out / "shards" / "ucb1").glob("*.npz"))) == 3  # 3 + 3 + 1 trials


# ---------------------------------------------------------------- time
def test_the_time_estimate_counts_every_task_and_the_tasks_at_once():
    from benchmarks.resources import STEP_OVERHEAD_SECONDS, estimate_seconds
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
    monkeypatch.setattr("benchmarks.resources.STEP_OVERHEAD_SECONDS", 100.0)  # a very slow machine
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


# ---------------------------------------------------------------- the cost-aware schedule
def _model_makespan(costs, sizes, trials, parallel):
    """The makespan of the tasks of ``sizes`` by the cost model, queued the longest first (written
    out apart from the module's)."""
    tasks = []
    for policy, size in sizes.items():
        fixed, per_trial, _ = costs[policy]
        for start in range(0, trials, size):
            tasks.append(fixed + (min(start + size, trials) - start) * per_trial)
    loads = [0.0] * parallel
    for seconds in sorted(tasks, reverse=True):
        loads[loads.index(min(loads))] += seconds
    return max(loads)


def test_the_costliest_policy_gets_the_smallest_shards_and_the_run_ends_sooner():
    from benchmarks.resources import auto_shard_size, plan_shard_sizes

    # one policy ten times the others' per trial (MG-CRB-CL's BPSO beside the index policies)
    costs = {"costly": (2e-3, 150e-6, 0.0), **{f"cheap{i}": (2e-3, 15e-6, 0.0) for i in range(5)}}
    for parallel in (1, 2, 4, 8, 16):
        sizes = plan_shard_sizes(costs, 500, parallel)
        uniform = dict.fromkeys(costs, auto_shard_size(500, parallel, len(costs)))
        assert sizes["costly"] == min(sizes.values())
        planned = _model_makespan(costs, sizes, 500, parallel)
        assert planned <= _model_makespan(costs, uniform, 500, parallel) * (1 + 1e-12)
        assert planned <= _model_makespan(costs, dict.fromkeys(costs, 500), 500, parallel) * (1 + 1e-12)
    assert plan_shard_sizes(costs, 500, 1) == dict.fromkeys(costs, 500)  # one worker: whole batches
    assert plan_shard_sizes(costs, 500, 16)["cheap0"] > plan_shard_sizes(costs, 500, 16)["costly"]
    # equal policies and as many workers: one shard each, as the uniform schedule
    assert plan_shard_sizes(dict.fromkeys("abcd", (1e-3, 1e-5, 0.0)), 100, 4) == dict.fromkeys("abcd", 100)


# ---------------------------------------------------------------- threads inside a task
def test_a_steps_threaded_part_is_spread_over_the_threads_by_whole_chunks():
    from benchmarks.resources import step_seconds
    from mimo_radar_env.core.compiled import CHUNK

    fixed, serial, threaded = 1e-3, 4e-6, 6e-6
    cost = (fixed, serial + threaded, threaded)
    trials = 3 * CHUNK + 8  # four chunks, the last of 8 trials
    # the slowest thread's chunks, counted by hand: 4 chunks over 2 or 3 threads leave one thread two
    for threads, slowest in [(1, trials), (2, 2 * CHUNK), (3, 2 * CHUNK), (4, CHUNK), (16, CHUNK)]:
        expected = fixed + serial * trials + threaded * slowest
        assert step_seconds(cost, trials, threads) == pytest.approx(expected, rel=1e-12)
    assert step_seconds(cost, CHUNK, 8) == step_seconds(cost, CHUNK, 1)  # one chunk: one thread


def _by_hand(configs, todo, workers):
    """Every thread count's makespan of ``todo`` on ``workers // threads`` processes, each task's
    seconds summed from its policy's declared parts (apart from the module's own)."""
    from mimo_radar_env.core.compiled import CHUNK

    spans = {}
    for threads in range(1, workers + 1):
        loads = [0.0] * (workers // threads)
        for number, policy, shard in todo:
            config = configs[number]
            fixed, per_trial, threaded = config.step_costs[policy]
            n = len(config.shard_trials(policy, shard))
            chunks = -(-n // CHUNK)
            slowest = n if threads == 1 or n <= CHUNK else min(n, CHUNK * -(-chunks // threads))
            seconds = config.steps * (fixed + (per_trial - threaded) * n + threaded * slowest)
            loads[loads.index(min(loads))] += seconds
        spans[threads] = max(loads)
    return spans


@pytest.mark.parametrize(
    ("policies", "workers", "chosen"),
    [
        (["mg-crb-cl"], 2, 2),  # one task: both cores on it
        (["ucb1", "fix1"], 2, 1),  # two alike tasks, one per core: threads would idle in their serial part
        (["mg-crb-cl", "ucb1"], 2, None),  # BPSO's threads against the second core: by the costs
        (["mg-crb-cl"], 5, 5),  # five chunks of trials, one per thread
    ],
)
def test_the_threads_chosen_are_those_whose_tasks_end_soonest_by_the_declared_costs(
    policies, workers, chosen, monkeypatch
):
    from benchmarks import machine_rate, resources

    monkeypatch.setattr(machine_rate, "factor", lambda: None)
    config = make_config("paper-1-v1", policies, 300, 4, shard_size=300, say=lambda message: None)
    todo = [(0, policy, 0) for policy in policies]
    threads, seconds, one_each = resources.choose_threads([config], todo, workers)
    spans = _by_hand([config], todo, workers)
    assert threads == min(spans, key=lambda t: (round(spans[t] / spans[1], 9), t))
    assert chosen is None or threads == chosen
    assert seconds == pytest.approx(spans[threads], rel=1e-9)
    assert one_each == pytest.approx(spans[1], rel=1e-9)
    assert all(0 < config.step_costs[p][2] < config.step_costs[p][1] for p in policies)
