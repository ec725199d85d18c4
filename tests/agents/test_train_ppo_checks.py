"""train-ppo checks everything before it writes: the hyperparameter entry, the folder (locked,
and never holding a stale normalisation of an earlier model)."""

import json
import threading
from pathlib import Path

import pytest

from benchmarks.cli import main
from benchmarks.harness import output_lock

ENTRY = """MimoRadarSelectFlat-v1:
  n_envs: 2
  n_steps: 64
  batch_size: 64
  n_epochs: 1
{extra}
"""


def _train(tmp_path: Path, extra: str, *more: str) -> list[str]:
    path = tmp_path / "hp.yml"
    path.write_text(
        ENTRY.format(extra=extra) if extra.startswith("  ") else extra
    )  # an entry's line, or a file
    argv = ["train-ppo", "--scenario", "paper-1-v1", "--timesteps", "128", "--hyperparams", str(path)]
    return [*argv, "--out", str(tmp_path / "model"), "--quiet", *more]


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("  n_epoch: 3", "unknown hyperparameter(s) ['n_epoch']"),
        (
            "  learning_rate: lin_3e-4",
            "learning_rate must be a number in (0, 1], got 'lin_3e-4' (rl-zoo3's 'lin_'",
        ),
        ("  gamma: 1.5", "gamma must be in (0, 1], got 1.5"),
        ("  n_envs: 0", "n_envs must be in [1, 1,048,576], got 0"),
        ("  n_envs: 2.5", "n_envs must be an integer in [1, 1,048,576], got 2.5"),
        ("  batch_size: 1000", "batch_size 1000 is more than a rollout's n_steps x n_envs = 128"),
        ("  policy: CnnPolicy", "policy must be one of ['MlpPolicy'] for ppo, got 'CnnPolicy'"),
        ("  normalize: 'dict(norm_obs=True, clip=3)'", "normalize has unknown key(s) ['clip']"),
        ("  normalize: 'dict(norm_obs=True'", "normalize must look like dict(key=value, ...)"),
        ("  policy_kwargs: 'dict(net_arch=[0])'", "net_arch must be a list of layer sizes in [1, 4096]"),
        ("MimoRadarSelectFlat-v1: [1, 2]", "entry 'MimoRadarSelectFlat-v1' must be a mapping"),
        ("MimoRadarSelectFlat-v1: {a: [1, 2}", "is not YAML"),
    ],
)
def test_a_bad_hyperparameter_file_is_one_line_and_writes_nothing(extra, message, tmp_path, capsys):
    pytest.importorskip("stable_baselines3", reason="train-ppo needs the rl extra")
    with pytest.raises(SystemExit) as exit_info:
        main(_train(tmp_path, extra))
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "model").exists()


@pytest.mark.parametrize("kind", ["missing", "folder", "binary"])
def test_a_hyperparameter_file_that_cannot_be_read_is_named_in_one_line(kind, tmp_path, capsys):
    pytest.importorskip("stable_baselines3", reason="train-ppo needs the rl extra")
    path = tmp_path / "hp.yml"
    if kind == "folder":
        path.mkdir()
    elif kind == "binary":
        path.write_bytes(bytes(range(128, 256)))
    argv = ["train-ppo", "--timesteps", "128", "--hyperparams", str(path), "--out", str(tmp_path / "model")]
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        f"mimo-radar-bench: error: cannot read the hyperparameters {path}: "
    )
    assert not (tmp_path / "model").exists()


def test_the_folder_is_locked_and_an_old_model_is_replaced_only_when_asked(tmp_path, capsys):
    pytest.importorskip("stable_baselines3", reason="train-ppo needs the rl extra")
    normalised = "  normalize: 'dict(norm_obs=True, norm_reward=False)'"
    assert main(_train(tmp_path, normalised)) == 0
    folder = tmp_path / "model"
    assert (folder / "vecnormalize.npz").exists()
    with pytest.raises(SystemExit):  # a model is there: refused, untouched
        main(_train(tmp_path, "  normalize: false"))
    assert "already holds a trained model" in capsys.readouterr().err
    assert (folder / "vecnormalize.npz").exists()
    with output_lock(folder), pytest.raises(SystemExit):  # another training holds the folder
        main(_train(tmp_path, "  normalize: false", "--overwrite"))
    assert "another run is writing into" in capsys.readouterr().err
    assert main(_train(tmp_path, "  normalize: false", "--overwrite")) == 0
    assert (folder / "model.zip").exists() and not (folder / "vecnormalize.npz").exists()  # no stale file


def test_ctrl_c_during_one_training_says_nothing_of_it_was_saved(tmp_path, monkeypatch, capsys):
    """Ctrl-C during a single training: the command says that a training is saved only at its end
    and how to train it again (exit 130), and the same command then trains it."""
    pytest.importorskip("torch", reason="torch-ppo needs the rl extra")
    from benchmarks import training

    def interrupted(*arguments, **keywords):
        raise KeyboardInterrupt

    argv = ["train-ppo", "--algo", "torch-ppo", "--device", "cpu", "--timesteps", "64", "--quiet"]
    with monkeypatch.context() as patch:
        patch.setattr(training, "_train_torch", interrupted)
        with pytest.raises(SystemExit) as exit_info:
            main([*argv, "--out", str(tmp_path / "t")])
    assert exit_info.value.code == 130
    assert capsys.readouterr().err.strip() == (
        f"mimo-radar-bench: interrupted: the training into {tmp_path / 't'} had not finished, and a "
        "training is saved only at its end; run the same command again to train it from its first step"
    )
    assert main([*argv, "--out", str(tmp_path / "t")]) == 0
    assert (tmp_path / "t" / training.META_FILE).is_file()


def test_ctrl_c_between_seeds_says_what_was_saved_and_how_to_resume(tmp_path, monkeypatch, capsys):
    """Ctrl-C during a several-seed training: the finished seeds stay, and the command says how
    many and how to resume (exit 130), as an interrupted benchmark run does."""
    pytest.importorskip("torch", reason="torch-ppo needs the rl extra")
    from benchmarks import training

    trained = []

    def one_seed(job, out, seed, device=None, device_mode="eager", in_worker=False):
        if trained:
            raise KeyboardInterrupt
        trained.append(seed)
        return {"job": job}

    monkeypatch.setattr(training, "_train_one_seed", one_seed)
    argv = ["train-ppo", "--algo", "torch-ppo", "--device", "cpu", "--seeds", "3", "--timesteps", "64"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(tmp_path / "t"), "--quiet"])
    assert exit_info.value.code == 130
    err = capsys.readouterr().err.strip()
    assert err == (
        f"mimo-radar-bench: interrupted: 1 of 3 trainings finished and saved in {tmp_path / 't'} "
        "(an unfinished one is trained again); run the same command again to resume"
    )
    # main() called from Python leaves its caller's process alone: only the program bounds its
    # teardown after an interrupt (that limit, armed here, ended a pytest worker 5 s later)
    assert "teardown-limit" not in [thread.name for thread in threading.enumerate()]


def test_a_training_estimated_beyond_max_hours_is_refused_before_anything_is_written(tmp_path, capsys):
    """train-ppo estimates its trainings (timesteps at each learner's rate, seeds --workers at a
    time) and refuses beyond --max-hours in one line, as the studies do; below, it says the
    estimate when it is a minute or more."""
    pytest.importorskip("torch", reason="torch-ppo needs the rl extra")
    from benchmarks.training import TRAINING_STEPS_PER_S, estimate_training_seconds

    assert estimate_training_seconds("recurrent-ppo", 1280) == pytest.approx(1.0)
    assert estimate_training_seconds("ppo", 3000) == pytest.approx(3000 / TRAINING_STEPS_PER_S["ppo"])
    assert estimate_training_seconds("ppo", 3000, "cpu", n_envs=512) == pytest.approx(1.0)  # B: torch-ppo's
    # trainings at once: on the CPU each on its own core, as fast as alone; sharing a CUDA device,
    # each slower than alone but k of them sooner than k one after another
    alone = estimate_training_seconds("torch-ppo", 10**6, "cpu", 512)
    assert estimate_training_seconds("torch-ppo", 10**6, "cpu", 512, at_once=4) == alone
    for trials in (8, 4096):
        alone = estimate_training_seconds("torch-ppo", 10**6, "cuda", trials)
        shared = estimate_training_seconds("torch-ppo", 10**6, "cuda", trials, at_once=4)
        assert alone < shared < 4 * alone
    # torch-ppo's speed grows with its parallel trials: within 15 % of the training benchmark's
    # rates, the H200's rows as committed and CPU torch's on the developers' two cores
    perf = json.loads((Path(__file__).parents[2] / "docs/results/perf/training.json").read_text())
    rows = [r for r in perf["rows"] if r["device"] == "cuda"]
    measured = [(r["device"], r["trials"], r["env_steps_per_s"]) for r in rows]
    for device, trials, rate in [*measured, ("cpu", 8, 800), ("cpu", 64, 3_735), ("cpu", 512, 7_669)]:
        estimate = 1e6 / estimate_training_seconds("torch-ppo", 1_000_000, device, n_envs=trials)
        assert estimate == pytest.approx(rate, rel=0.15), (device, trials)
    # eight trainings sharing an H200 (the RL study there): each one's rate within 15 % of theirs
    shared = json.loads((Path(__file__).parents[2] / "docs/results/perf/device-checks.json").read_text())
    study = shared["rl_study"]
    each = 1e6 / estimate_training_seconds("torch-ppo", 10**6, "cuda", 4096, study["trainings_at_once"])
    assert each == pytest.approx(study["rate_per_training"], rel=0.15)
    out = tmp_path / "model"
    argv = ["train-ppo", "--timesteps", "2147483647", "--out", str(out), "--quiet"]
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "1 training(s) of 2,147,483,647 --timesteps of ppo would take about" in err[0]
    assert "more than --max-hours 24" in err[0] and not out.exists()
    # four seeds, two at a time, at 3000 steps/s: two rounds of 36,000 / 3000 = 12 s
    with pytest.raises(SystemExit):
        main(["train-ppo", "--timesteps", "36000", "--seeds", "4", "--workers", "2", "--out", str(out),
              "--max-hours", str(23 / 3600), "--quiet"])  # fmt: skip
    assert "4 training(s) of 36,000 --timesteps of ppo would take about 24 s" in capsys.readouterr().err
    assert not out.exists()


def test_a_folder_holding_a_benchmark_run_is_refused_before_anything_is_written(tmp_path, capsys):
    """train-ppo wrote its model beside a run's config.json, shards and tables."""
    pytest.importorskip("stable_baselines3", reason="train-ppo needs the rl extra")
    run = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "random", "--trials", "2", "--steps", "2"]
    assert main([*argv, "--workers", "1", "--quiet", "--no-figures", "--out", str(run)]) == 0
    before = sorted(p.name for p in run.iterdir())
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(["train-ppo", "--timesteps", "128", "--out", str(run), "--overwrite"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{run} holds a benchmark run (its config.json or shards/)" in err[0]
    assert sorted(p.name for p in run.iterdir()) == before
