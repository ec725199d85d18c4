"""A study's runs on one set of workers (harness.run_many): each run's tasks the longest first,
no barrier between runs, a run's outputs written as soon as its last task is saved."""

import numpy as np
import pytest

import agents
from benchmarks import harness
from benchmarks.harness import HarnessError, load_per_trial, make_config, run, run_many
from benchmarks.resources import task_seconds
from mimo_radar_env.envs.cost import seconds_per_trial_step


@pytest.fixture
def calls(monkeypatch):
    """The (scenario, policy, shard) of every task run in this process, in order, and the
    ``on_complete`` calls among them."""
    events = []
    task = harness.run_task

    def recording(payload, policy, shard):
        events.append((payload["scenario"]["name"], policy, shard))
        return task(payload, policy, shard)

    monkeypatch.setattr(harness, "run_task", recording)
    return events


def test_task_estimates_follow_the_declared_operations_and_the_shards_trials():
    config = make_config("paper-1", ["ucb1", "mg-crb-cl"], trials=5, steps=4, shard_size=2)
    cost = task_seconds(config)
    assert set(cost) == {(p, s) for p in config.policies for s in range(3)}
    env = seconds_per_trial_step(config.scenario_object, True, config.options.fusion)
    own = {
        p: agents.costs.seconds_per_trial_step(
            harness.make_policy(p, config.scenario_object, {}, seed=0, options=config.env_options)
        )
        for p in config.policies
    }
    assert own["mg-crb-cl"] > own["ucb1"]  # BPSO against the exact solver
    for p in config.policies:
        # a shard of 2 trials against one of 1: the per-trial part doubles, the per-step part stays
        per_trial = 4 * (env + own[p])
        assert cost[p, 0] == cost[p, 1]
        assert cost[p, 0] - cost[p, 2] == pytest.approx(per_trial, rel=1e-9)
    assert cost["mg-crb-cl", 2] > cost["ucb1", 0]


def test_a_runs_tasks_start_the_longest_first(tmp_path, calls):
    config = make_config("paper-1", ["ucb1", "mg-crb-cl"], trials=5, steps=4, shard_size=2)
    run(config, tmp_path, progress=False)
    cost = task_seconds(config)
    started = [(p, s) for _, p, s in calls]
    assert started == sorted(started, key=lambda task: -cost[task])
    assert started[:3] == [("mg-crb-cl", 0), ("mg-crb-cl", 1), ("mg-crb-cl", 2)]


def test_runs_share_the_workers_and_each_is_written_when_its_tasks_are_done(tmp_path, calls):
    configs = [
        make_config(name, ["fix1", "ucb1"], trials=3, steps=6, shard_size=2)
        for name in ("paper-1", "paper-2")
    ]
    folders = [tmp_path / "one", tmp_path / "two"]

    def complete(number, per_trial):
        assert harness._tasks_to_run(folders[number], configs[number], print) == []
        calls.append(("complete", number))

    assert run_many(list(zip(configs, folders, strict=True)), progress=False, on_complete=complete) == [
        True,
        True,
    ]
    names = [c[0] for c in calls]
    assert calls.index(("complete", 0)) == 4  # after run one's four tasks, before run two's
    assert names[:4] == ["paper-1"] * 4 and names[5:9] == ["paper-2"] * 4
    assert calls[-1] == ("complete", 1)
    for config, folder in zip(configs, folders, strict=True):  # the numbers of the run alone
        alone = run(config, folder.with_name(folder.name + "-alone"), progress=False)
        together = load_per_trial(folder, config)
        for policy in config.policies:
            for key, value in alone[policy].items():
                if key != "wall_s":
                    np.testing.assert_array_equal(together[policy][key], value)
    calls.clear()  # all complete: nothing runs, and each is reported complete again
    assert run_many(list(zip(configs, folders, strict=True)), progress=False, on_complete=complete) == [
        True,
        True,
    ]
    assert calls == [("complete", 0), ("complete", 1)]


def test_two_processes_give_the_numbers_of_one(tmp_path):
    configs = [
        make_config(n, ["mg-crb-cl", "fix2"], trials=3, steps=5, shard_size=1) for n in ("paper-1", "paper-3")
    ]
    one = [tmp_path / "a1", tmp_path / "b1"]
    two = [tmp_path / "a2", tmp_path / "b2"]
    assert run_many(list(zip(configs, one, strict=True)), progress=False) == [True, True]
    assert run_many(list(zip(configs, two, strict=True)), workers=2, progress=False) == [True, True]
    for config, a, b in zip(configs, one, two, strict=True):
        x, y = load_per_trial(a, config), load_per_trial(b, config)
        for policy in config.policies:
            np.testing.assert_array_equal(x[policy]["trial_expected"], y[policy]["trial_expected"])
            np.testing.assert_array_equal(x[policy]["trial_squared_error"], y[policy]["trial_squared_error"])


def test_max_tasks_leaves_later_runs_incomplete_and_two_runs_may_not_share_a_folder(tmp_path):
    configs = [make_config(n, ["fix1"], trials=2, steps=3, shard_size=1) for n in ("paper-1", "paper-2")]
    folders = [tmp_path / "one", tmp_path / "two"]
    assert run_many(list(zip(configs, folders, strict=True)), progress=False, max_tasks=3) == [True, False]
    assert run_many(list(zip(configs, folders, strict=True)), progress=False) == [True, True]
    with pytest.raises(HarnessError, match="two runs write into one folder"):
        run_many([(configs[0], tmp_path / "x"), (configs[1], tmp_path / "x" / ".." / "x")], progress=False)


@pytest.mark.parametrize(("scale", "said"), [(1e-9, True), (1e9, False)])
def test_a_run_far_slower_than_its_estimate_says_so_at_its_end(tmp_path, monkeypatch, capsys, scale, said):
    """The tasks' wall time against the sum of their estimates (task_seconds) over the workers:
    beyond SLOW_FACTOR times it, one line at the end says so; within it, nothing."""
    monkeypatch.setattr(harness, "SLOW_RUN_MIN_SECONDS", 0.0)
    real = harness.task_seconds
    monkeypatch.setattr(
        harness,
        "task_seconds",
        lambda config, threads=1: {k: v * scale for k, v in real(config, threads).items()},
    )
    config = make_config("paper-1", ["fix1", "random"], trials=2, steps=3, shard_size=1, say=lambda m: None)
    assert run_many([(config, tmp_path / "out")], progress=False) == [True]
    err = capsys.readouterr().err
    assert ("more than 2 times their estimate" in err) == said
    if said:
        assert "allow for that in --max-hours" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("budget", [harness.HELD_BYTES, 0])
def test_a_completed_run_is_joined_from_the_shards_it_wrote_or_checked(tmp_path, monkeypatch, budget):
    """``on_complete`` gets the run's shards joined: those this call wrote or checked from memory
    (none read back), the rest, beyond the held budget, from their files; the same arrays either
    way, those :func:`load_per_trial` reads from the folder."""
    monkeypatch.setattr(harness, "HELD_BYTES", budget)
    reads = []
    read = harness.read_shard
    monkeypatch.setattr(harness, "read_shard", lambda path, *a: reads.append(path) or read(path, *a))
    config = make_config("paper-1", ["fix1", "ucb1"], trials=3, steps=5, shard_size=2)
    folder = tmp_path / "run"
    joined = []

    def start(**kwargs):
        reads.clear()
        run_many([(config, folder)], progress=False, on_complete=lambda n, t: joined.append(t), **kwargs)

    start(max_tasks=3)  # three of four shards: incomplete, nothing joined
    assert joined == [] and reads == []
    first = sorted(folder.rglob("*.npz"))
    start()  # the three checked, the fourth written
    shards = sorted(folder.rglob("*.npz"))
    assert len(first) == 3 and len(shards) == 4 and len(joined) == 1
    assert sorted(reads) == (first if budget else sorted(first + shards))
    start()  # all four checked
    assert sorted(reads) == (shards if budget else sorted(shards + shards))
    fresh = tmp_path / "fresh"
    reads.clear()
    run_many([(config, fresh)], progress=False, on_complete=lambda n, t: joined.append(t))
    assert len(reads) == (0 if budget else 4)
    on_file = load_per_trial(folder, config)
    for per_trial in joined:
        assert per_trial.keys() == on_file.keys()
        for policy, fields in on_file.items():
            assert per_trial[policy].keys() == fields.keys()
            for key, value in fields.items():
                if key != "wall_s":  # a compute time: each run's own
                    np.testing.assert_array_equal(per_trial[policy][key], value, strict=True)


_PARENT = """
import sys
from benchmarks import backends, harness

seen = []
submit = backends.WorkerPool.submit

def recording(self, *args, **kwargs):
    seen.append("numba" in sys.modules)
    return submit(self, *args, **kwargs)

backends.WorkerPool.submit = recording
config = harness.make_config("paper-1-v1", ["mg-crb-cl", "ucb1"], trials=2, steps=2, shard_size=1)
assert harness.run_many([(config, sys.argv[1])], workers=2, progress=False) == [True]
print(seen[0], "numba" in sys.modules)
"""


def test_the_workers_start_before_this_process_imports_numba(tmp_path):
    """The run's configuration, costs and queue need no compiled kernel: this process imports
    numba (for its checks of the kernels' caches) only once the tasks are on their way, so that
    the workers' start does not wait for it."""
    pytest.importorskip("numba")
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-c", _PARENT, str(tmp_path / "out")], capture_output=True, text=True, check=True
    )
    assert done.stdout.split() == ["False", "True"]


@pytest.mark.parametrize("cached", [True, False])
def test_a_run_that_will_compile_kernels_says_so_on_its_progress_bar(tmp_path, monkeypatch, capsys, cached):
    pytest.importorskip("numba")
    monkeypatch.setattr(harness, "uncached", lambda kernels: [] if cached else list(kernels))
    config = make_config("paper-1", ["fix1"], trials=2, steps=3, shard_size=1, say=lambda m: None)
    assert run_many([(config, tmp_path / "out")]) == [True]
    assert ("compiling numba kernels (first run only" in capsys.readouterr().err) != cached


def test_each_policy_is_handed_over_as_soon_as_its_last_shard_is_saved(tmp_path, calls):
    """``on_policy`` comes after a policy's last task and before the next policy's first, with the
    policy's shards joined: the arrays ``on_complete`` then gets (the same objects) and those
    read from the folder. A resumed call hands over only the policies it completes."""
    config = make_config("paper-1", ["ucb1", "mg-crb-cl"], trials=5, steps=4, shard_size=2)
    given, first_call = {}, {}

    def policy_done(number, policy, joined):
        calls.append(("policy", policy))
        given[policy] = joined
        first_call.setdefault(policy, joined)

    def complete(number, per_trial):
        calls.append(("complete", number))
        for policy, joined in given.items():
            assert per_trial[policy] is joined
        given.clear()

    assert run_many([(config, tmp_path)], progress=False, on_complete=complete, on_policy=policy_done) == [
        True
    ]
    events = [c[1] if c[0] in ("policy", "complete") else c[1] for c in calls]
    assert events == ["mg-crb-cl"] * 4 + ["ucb1"] * 3 + ["ucb1", 0]  # three tasks each, longest first
    assert calls[3] == ("policy", "mg-crb-cl") and calls[-2:] == [("policy", "ucb1"), ("complete", 0)]
    fresh = load_per_trial(tmp_path, config)
    for policy in config.policies:
        assert set(first_call[policy]) == set(fresh[policy])
        for key, value in fresh[policy].items():
            np.testing.assert_array_equal(first_call[policy][key], value)
    calls.clear()
    harness.shard_path(tmp_path, "ucb1", 1).unlink()
    assert run_many([(config, tmp_path)], progress=False, on_complete=complete, on_policy=policy_done) == [
        True
    ]
    assert calls == [("paper-1", "ucb1", 1), ("policy", "ucb1"), ("complete", 0)]


def test_a_policy_handed_over_is_no_longer_held_shard_by_shard():
    held = harness._Held(1 << 20)
    data = {key: np.zeros(3) for key in harness.DATA_FIELDS}
    for policy, shard in (("a", 0), ("a", 1), ("b", 0)):
        held.add(0, policy, shard, data)
    each = sum(a.nbytes for a in data.values())
    assert held.nbytes == 3 * each
    assert sorted(held.pop_policy(0, "a")) == [("a", 0), ("a", 1)]
    assert held.nbytes == each and list(held.shards[0]) == [("b", 0)]
