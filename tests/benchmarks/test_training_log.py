"""The training's progress line: the steps, the last episodes, the rate and the time left."""

import pytest

torch = pytest.importorskip("torch", reason="torch-ppo needs the rl extra")


def test_the_progress_line_says_the_steps_the_last_episodes_the_rate_and_the_time_left(capsys):
    from benchmarks.training_log import LearningCurve

    log = LearningCurve(progress=True, every=0.0, name="torch-ppo")
    log.start(4000)
    log.add_episodes([10.0, 20.0], [2.0, 4.0])
    log._start -= 2.0  # two seconds ago
    log.close_rollout(1000)
    line = capsys.readouterr().out.strip()
    assert line.startswith("torch-ppo: 1,000/4,000 steps (25 %) · return 15.0 · ARMSE 3.00 m · ")
    rate = int(line.split(" · ")[3].split()[0].replace(",", ""))
    assert 400 <= rate <= 500  # about 1,000 steps in 2 s
    assert line.endswith("s left") and log.rows == [
        {"timesteps": 1000, "episodes": 2, "return": 15.0, "armse": 3.0}
    ]
