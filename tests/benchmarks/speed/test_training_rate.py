"""The training-rate benchmark times the rollouts after the first, for both learners."""

import pytest

torch = pytest.importorskip("torch", reason="torch-ppo needs the rl extra")


@pytest.mark.parametrize("learner", ["sb3", "torch-ppo"])
def test_the_training_rate_times_the_rollouts_after_the_first(learner):
    """A row's rate is the env steps of its rollouts after the first over their time, each
    rollout with its update: it counts (rollouts - 1) n_steps B steps, and cannot exceed
    those steps over the whole call's time."""
    import time

    from benchmarks.speed import training_rate

    start = time.perf_counter()
    row = training_rate.training_rate(learner, 4, None if learner == "sb3" else "cpu", rollouts=3, n_steps=8)
    wall = time.perf_counter() - start
    assert row["timed_steps"] == 2 * 8 * 4 and row["batch_size"] == 8 * 4 // 8
    assert row["timed_steps"] / wall < row["env_steps_per_s"] < float("inf")


def test_the_device_rows_come_in_each_form_of_the_step_asked(tmp_path, capsys):
    import json

    from benchmarks.speed import training_rate

    path = tmp_path / "training.json"
    arguments = ["--device", "cpu", "--sizes", "4", "--cpu-sizes", "", "--n-steps", "4", "--json", str(path)]
    training_rate.main([*arguments, "--device-modes", "eager,graph"])
    rows = json.loads(path.read_text())["rows"]
    assert [(r["learner"], r["device"], r["device_mode"], r["trials"]) for r in rows] == [
        ("torch-ppo", "cpu", "eager", 4),
        ("torch-ppo", "cpu", "graph", 4),
    ]
    with pytest.raises(SystemExit):
        training_rate.main([*arguments, "--device-modes", "eager,fused"])
    assert (
        "--device-modes: device_mode must be one of eager, graph, compiled; got 'fused'"
        in capsys.readouterr().err
    )


def test_trainings_sharing_a_device_count_their_steps_over_their_span(tmp_path, capsys):
    """--processes 2: two trainings at once, one worker process each, in a row whose rate is all
    their timed steps over the span of their timed windows: at most the sum of their own rates
    (equal only if the windows coincide); a count below one is refused."""
    import json

    from benchmarks.speed import training_rate

    path = tmp_path / "training.json"
    arguments = ["--device", "cpu", "--sizes", "4", "--cpu-sizes", "", "--n-steps", "4", "--json", str(path)]
    training_rate.main([*arguments, "--processes", "2"])
    (two,) = json.loads(path.read_text())["rows"]
    assert two["processes"] == 2 and len(two["per_process_steps_per_s"]) == 2
    assert two["timed_steps"] == 2 * 4 * 4  # each: the rollouts after the first, n_steps x B
    windows = two["per_process_windows_s"]
    span = max(end for _, end in windows) - min(start for start, _ in windows)
    assert two["env_steps_per_s"] == pytest.approx(2 * two["timed_steps"] / span, rel=1e-12)
    assert 0 < two["env_steps_per_s"] <= sum(two["per_process_steps_per_s"]) * (1 + 1e-12)
    with pytest.raises(SystemExit):
        training_rate.main([*arguments, "--processes", "0"])
    assert "--processes must list whole numbers >= 1, got '0'" in capsys.readouterr().err
