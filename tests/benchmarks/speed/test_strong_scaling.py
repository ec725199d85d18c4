"""The strong-scaling benchmark (``benchmarks/speed/strong_scaling.py``): its schedule against a
hand-worked one, its breakdown of a run's worker-seconds, and a tiny study measured whole."""

import pytest

from benchmarks.speed import strong_scaling
from benchmarks.speed.strong_scaling import Task


def test_list_scheduling_gives_each_task_to_the_first_free_worker():
    # 5, 4, 3 on two workers: 5 | 4 -> the 3 joins the 4 (free at 4): ends at 7
    assert strong_scaling.makespan([5.0, 4.0, 3.0], 2) == 7.0
    # the longest first is the harness's order; the other order ends later
    assert strong_scaling.makespan([3.0, 4.0, 5.0], 2) == 8.0
    assert strong_scaling.makespan([1.0] * 7, 3) == 3.0
    assert strong_scaling.makespan([2.0, 1.0], 4) == 2.0


def test_the_breakdown_splits_a_runs_worker_seconds():
    # two workers, a 10 s run: tasks of 4 s and 3 s ending at 5 s and 9 s, then 1 s of 3 s ending at 10 s
    tasks = [
        Task("r", "a", 0, 10, 5, 4.0, 5.0),
        Task("r", "b", 0, 10, 5, 3.0, 9.0),
        Task("r", "a", 1, 10, 5, 1.0, 10.0),
    ]
    parts = strong_scaling.breakdown(10.0, 2, tasks, {"a": 0.5, "b": 0.25})
    assert parts["task_fixed_s"] == 0.5 + 0.25 + 0.5
    assert parts["task_steps_s"] == 8.0 - 1.25
    assert parts["tail_idle_s"] == 10.0 - 9.0  # the other worker's last task ended at 9 s
    assert parts["outside_tasks_s"] == 20.0 - 8.0 - 1.0


@pytest.mark.filterwarnings("ignore")
def test_a_tiny_study_is_measured_and_modelled(tmp_path):
    study = ("claims", "--scenarios", "1", "--trials", "12", "--steps", "5")
    partial = []
    result = strong_scaling.measure(study, [1, 2], [4], measured_only=partial.append)
    # the measurements alone were handed over before the model's probes (a cut run keeps them)
    assert len(partial) == 1 and partial[0]["model"] == [] and partial[0]["measured"] == result["measured"]
    one, two = result["measured"]
    assert (one["tasks"], two["tasks"]) == (6, 6)  # six policies, one shard each at 1 and 2 workers
    for row in (one, two):
        parts = row["breakdown"]
        assert parts["task_steps_s"] > 0 and parts["task_fixed_s"] > 0
        assert parts["task_steps_s"] + parts["task_fixed_s"] <= parts["worker_seconds"]
    assert two["efficiency"] == pytest.approx(one["wall_s"] / (2 * two["wall_s"]))
    four = {m["schedule"]: m for m in result["model"] if m["workers"] == 4}
    assert (four["uniform"]["shard_size"], four["uniform"]["tasks"]) == (6, 12)  # 4 // gcd(6, 4) each
    by_cost = four["by cost"]["shard_sizes"]
    assert len(by_cost) == 6 and four["by cost"]["tasks"] == sum(-(-12 // n) for n in by_cost.values())
    for row in four.values():
        assert row["makespan_s"] >= row["task_seconds"] / 4
        assert row["wall_s"] == pytest.approx(result["outside_tasks_s"] + row["makespan_s"])


@pytest.mark.filterwarnings("ignore")
def test_without_the_model_only_the_runs_are_measured(tmp_path, monkeypatch):
    probed = []
    monkeypatch.setattr(strong_scaling, "predict", lambda *args: probed.append(args) or [])
    study = ("claims", "--scenarios", "1", "--trials", "6", "--steps", "3")
    result = strong_scaling.measure(study, [2], [4], model=False)
    assert result["model"] == [] and probed == [] and [r["workers"] for r in result["measured"]] == [2]


def test_repeated_runs_give_means_and_intervals_paired_by_repeat():
    """Two runs of a count: each figure is the mean of the runs' own; the efficiency is each
    repeat's against the base count's run of the same repeat, averaged, with its t interval."""

    def run(wall, last):  # one task of 3 s ending at ``last``
        return {"wall_s": wall, "tasks": [Task("r", "a", 0, 10, 5, 3.0, last)]}

    base_seconds = [1 * 10.0, 1 * 12.0]  # the 1-worker runs of repeats 0 and 1
    row = strong_scaling._row(2, [run(6.0, 5.5), run(8.0, 7.0)], base_seconds, {"a": 0.5})
    assert row["wall_s"] == 7.0 and row["wall_s_each"] == [6.0, 8.0]
    paired = [10.0 / (2 * 6.0), 12.0 / (2 * 8.0)]
    assert row["efficiency"] == pytest.approx(sum(paired) / 2)
    assert row["efficiency_ci"][0] < row["efficiency"] < row["efficiency_ci"][1]
    assert row["wall_s_ci"][0] < 7.0 < row["wall_s_ci"][1]
    assert row["after_last_task_s_each"] == [0.5, 1.0] and row["after_last_task_s"] == 0.75
    assert row["before_first_task_s"] == pytest.approx((2.5 + 4.0) / 2)
    once = strong_scaling._row(2, [run(6.0, 5.5)], base_seconds[:1], {"a": 0.5})
    assert once["efficiency"] == 10.0 / 12.0 and "wall_s_ci" not in once  # one run: no interval


def test_the_output_ends_with_the_last_counts_figures_as_one_json_line(monkeypatch, capsys):
    """What ``benchmarks.speed.across_commits --key`` reads from the command's last line."""
    import json

    figures = ("workers", "wall_s", "before_first_task_s", "after_last_task_s", "efficiency")
    rows = [
        dict(zip(figures, values, strict=True)) | {"tasks": 6}
        for values in [(1, 9.0, 0.5, 1.5, 1.0), (2, 5.0, 0.75, 1.25, 0.9)]
    ]
    monkeypatch.setattr(strong_scaling, "measure", lambda *args, **kwargs: {"measured": rows, "model": []})
    strong_scaling.main(["--workers", "1,2", "--predict", ""])
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert json.loads(last) == {key: rows[1][key] for key in figures}


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--repeats", "0"], "argument --repeats: must be an integer >= 1, got 0"),
        (["--model-from", "x"], "argument --model-from: must be an integer >= 1, got 'x'"),
        (["--json", "."], "argument --json: must be a file, and '.' is a folder"),
    ],
)
def test_bad_arguments_are_refused_in_one_line_before_any_run(argv, message, capsys):
    with pytest.raises(SystemExit):
        strong_scaling.main(argv)
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(message)
