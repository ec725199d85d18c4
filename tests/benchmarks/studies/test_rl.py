"""The RL study: across-seed statistics of learned policies beside the bandits, learning curves,
and a reduced run of the whole study (slow)."""

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks.studies.rl import COMPARED, flattened, judge_learners, rl_markdown


def _summary(armse: dict[str, float], trials: int = 4) -> dict:
    """A summary.json with the entries the study reads; paired differences equal the
    differences of the estimates (as they do for a mean over the same trials)."""
    policies = {
        p: {"armse": a, "final_regret": 10.0 * a, "ci": {"armse": [a - 0.1, a + 0.1], "final_regret": [0, 1]}}
        for p, a in armse.items()
    }
    names = list(armse)
    pairs = {
        f"{a} - {b}": {"armse": {"estimate": armse[a] - armse[b], "ci": [0, 0]}}
        for i, a in enumerate(names)
        for b in names[i + 1 :]
    }
    return {"trials": trials, "policies": policies, "paired_differences": pairs}


def test_learners_are_summarised_across_their_seeds_against_the_compared_policies():
    seeds = {0: 3.0, 1: 4.0, 2: 5.0}
    learned = {f"ppo:out/train/paper-1-v1/ppo-information/seed-{s}/model.zip": a for s, a in seeds.items()}
    other = {"ppo:out/train/paper-1-v1/ppo-sinr/seed-0/model.zip": 9.0}
    base = {"mg-crb-cl": 4.5, "best-tracking": 2.0, "tracking-ucb": 2.5}
    summaries = {
        (1, "average"): _summary({**base, **learned, **other}),
        (2, "average"): _summary({**base, **learned}),
    }
    judged = judge_learners(summaries, [("ppo", "information"), ("ppo", "sinr")])
    assert [(e["scenario"], e["fusion"]) for e in judged["scenarios"]] == [(1, "average"), (2, "average")]
    first = judged["scenarios"][0]["learners"]["ppo-information"]
    assert first["seeds"] == 3 and first["armse"]["mean"]["value"] == pytest.approx(4.0)
    assert first["armse"]["iqm"]["value"] == pytest.approx(4.0)  # the middle of 3, 4, 5 (trimmed)
    for name, value in base.items():  # mean over seeds of the paired differences
        assert first["minus"][name]["value"] == pytest.approx(4.0 - value)
    low, high = first["minus"]["best-tracking"]["ci"]
    assert 1.0 <= low < 2.0 < high <= 3.0  # over seeds: within the seeds' range
    assert judged["scenarios"][0]["learners"]["ppo-sinr"]["seeds"] == 1
    assert "ppo-sinr" not in judged["scenarios"][1]["learners"]
    # over scenarios: the IQM of ARMSE / best-tracking's, seeds of each scenario pooled
    ratio = judged["over_scenarios"]["average"]["ppo-information"]
    assert ratio["value"] == pytest.approx(2.0) and ratio["runs"] == 6
    assert set(judged["scenarios"][0]["compared"]) == set(COMPARED)
    text = rl_markdown(judged)
    assert "| `ppo-information` | 3 | 4.000 [" in text and "IQM of ARMSE / best-tracking's ARMSE" in text


def test_a_curve_is_flat_when_its_last_two_fifths_agree():
    steps = np.arange(1, 51, dtype=float)
    falling = {"timesteps": steps, "return": steps, "armse": 10.0 / steps}
    settled = {"timesteps": steps, "return": steps, "armse": 2.0 + np.exp(-steps / 3)}
    assert flattened([falling, falling])["flat"] is False
    result = flattened([settled, settled])
    assert result["flat"] is True and abs(result["change"]) < 0.02 and result["rollouts"] == 50
    assert flattened([{k: v[:3] for k, v in settled.items()}])["flat"] is None  # too short to tell


@pytest.mark.slow
def test_a_reduced_rl_study_trains_evaluates_and_reports(tmp_path):
    pytest.importorskip("sb3_contrib", reason="the RL study needs the rl extra")
    from benchmarks.cli import main

    out = tmp_path / "rl"
    argv = ["rl", "--scenarios", "1", "--timesteps", "16384", "--ppo-seeds", "2", "--contrib-seeds", "2"]
    argv += ["--trials", "6", "--steps", "20", "--workers", "2", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    judged = json.loads((out / "rl.json").read_text())
    learners = judged["scenarios"][0]["learners"]
    assert set(learners) == {
        "ppo-sinr",
        "ppo-information",
        "maskable-ppo-information",
        "recurrent-ppo-information",
    }
    assert all(row["seeds"] == 2 for row in learners.values())
    assert judged["training_worker_s"] > 0
    assert (out / "rl.md").read_text().startswith("# The RL study")
    assert (out / "curves_paper-1-average.png").stat().st_size > 0
    for key in learners:
        assert len(list((out / "train" / "paper-1-v1-average" / key).glob("seed-*/model.zip"))) == 2
        assert len(list((out / "train" / "paper-1-v1-average" / key).glob("seed-*/curve.csv"))) == 2
    # started again: every training and the run are kept, the report is the same
    first = (out / "rl.md").read_text()
    assert main(argv) == 0
    assert (out / "rl.md").read_text() == first


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--timesteps", "0"], "--timesteps: must be an integer >= 1"),
        (["--ppo-seeds", "0"], "--ppo-seeds: must be an integer >= 1"),
        (["--scenarios", "4"], "--scenarios must list paper scenarios 1, 2, 3"),
        (["--backend", "ray"], "the RL study trains in local worker processes"),
        (["--sweep", "0"], "--sweep must list positive timesteps, each once"),
        (["--sweep", "5,5"], "--sweep must list positive timesteps, each once"),
        (["--sweep", "lots"], "--sweep must list positive timesteps, each once"),
        (["--timesteps", "500", "--sweep", "500"], "--sweep lists --timesteps (500)"),
        (["--fusions", "average,mean"], "fusions must be among ['average', 'centralized']"),
        (["--fusions", "average", "--fusion", "average"], "--fusion does not apply"),
        (["--device-workers", "2"], "--device-workers needs --device"),
        (["--device", "cpu", "--device-workers", "0"], "--device-workers: must be an integer >= 1"),
    ],
)
def test_the_rl_study_refuses_bad_arguments_in_one_line(tmp_path, capsys, argv, message):
    from benchmarks.cli import main

    out = tmp_path / "rl"
    with pytest.raises(SystemExit) as exit_info:
        main(["rl", *argv, "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err
    assert not out.exists()


def test_the_docs_say_only_what_the_rl_tables_show(tmp_path):
    from benchmarks.docs_tooling.generators import rl_tables, rl_values

    learned = {
        f"ppo:t/paper-1-v1/ppo-information/seed-{s}/model.zip": a for s, a in enumerate((1.0, 1.2, 1.1))
    }
    worse = {
        f"recurrent-ppo:t/paper-1-v1/recurrent-ppo-information/seed-{s}/model.zip": 5.0 + s for s in range(3)
    }
    base = {"mg-crb-cl": 4.0, "best-tracking": 2.0, "tracking-ucb": 1.1}
    judged = judge_learners(
        {(1, "average"): _summary({**base, **learned, **worse})},
        [("ppo", "information"), ("recurrent-ppo", "information")],
    )
    steps = np.arange(1.0, 51.0)
    judged["scenarios"][0]["curves"] = {
        "ppo-information": flattened([{"timesteps": steps, "return": steps, "armse": 2.0 + np.exp(-steps)}]),
        "recurrent-ppo-information": flattened([{"timesteps": steps, "return": steps, "armse": 10 / steps}]),
    }
    judged["training_worker_s"] = 13000.0
    folder = tmp_path / "results" / "rl"
    folder.mkdir(parents=True)
    (folder / "rl.json").write_text(json.dumps(judged, default=float))
    timing = {"wall_s": 7200.0, "parts_s": {"training": 6600.0, "evaluation": 500.0}, "machine": {"cores": 2}}
    (folder / "timing.json").write_text(json.dumps(timing))
    table = rl_values(tmp_path)
    assert (table["wall"], table["cores"], table["training"], table["evaluation"]) == (
        "2.0 h",
        "2",
        "1.8 h",
        "8 min",
    )
    assert table["worker"] == "3.6 h"
    assert (table["best-tracking.better"], table["best-tracking.better.which"]) == (
        "1",
        "`ppo-information` in Scenario 1, average",
    )
    assert table["best-tracking.worse.which"] == "`recurrent-ppo-information` in Scenario 1, average"
    assert (table["best-tracking.same"], table["best-tracking.pairs"]) == ("0", "2")
    # against tracking-ucb (1.1): ppo's seeds 1.0, 1.2, 1.1 straddle it
    assert table["tracking-ucb.same.which"] == "`ppo-information` in Scenario 1, average"
    assert (table["flat"], table["curves"], table["flat.which"]) == (
        "1",
        "2",
        "`ppo-information` (Scenario 1, average)",
    )
    assert table["moving.which"].startswith("`recurrent-ppo-information` (Scenario 1, average, -")
    tables = rl_tables(tmp_path)
    assert (
        tables.startswith("Learned policies across their training seeds")
        and "## paper-1, average fusion" in tables
    )


def test_the_time_estimate_counts_only_the_trainings_still_to_do(tmp_path):
    import argparse

    from benchmarks.studies.rl import RLStudy, training_folder
    from benchmarks.training import seed_folder

    parser = argparse.ArgumentParser()
    RLStudy.add_arguments(parser)
    args = parser.parse_args(
        ["--scenarios", "1", "--timesteps", "3000", "--out", str(tmp_path), "--workers", "1"]
    )
    args.command = "rl"
    study = RLStudy(args)
    before = study.estimate_training_seconds()  # 10 PPO and 3 MaskablePPO at 3000/s, 3 RecurrentPPO at 1280/s
    assert before == pytest.approx(13 * 1.0 + 3 * 3000 / 1280)
    finished = seed_folder(training_folder(tmp_path, "paper-1-v1", "average", "ppo", "sinr"), 0)
    finished.mkdir(parents=True)
    (finished / "ppo.json").write_text(json.dumps({"job": {}, "train_wall_s": 1.0}))
    assert study.estimate_training_seconds() == pytest.approx(before - 1.0)


def test_on_a_device_the_time_estimate_reads_the_parallel_trials_of_the_device_entry(tmp_path):
    """torch-ppo reads PPO's hyperparameters: with no --n-envs, the estimate takes the device
    entry's parallel trials (4,096), or --hyperparams-key's entry's."""
    import argparse

    from benchmarks.studies.rl import RLStudy
    from benchmarks.training import estimate_training_seconds

    parser = argparse.ArgumentParser()
    RLStudy.add_arguments(parser)
    base = ["--scenarios", "1", "--timesteps", "40960", "--device", "cpu", "--out", str(tmp_path)]
    cases = (
        ([], 4096, 1),
        (["--hyperparams-key", "device-small"], 512, 1),
        (["--device-workers", "2"], 4096, 2),
    )
    for extra, n_envs, workers in cases:
        args = parser.parse_args([*base, *extra])
        args.command = "rl"
        study = RLStudy(args)
        trainings = len(study.trainings()) * 10  # 10 seeds each, --device-workers at once
        expected = trainings * estimate_training_seconds("torch-ppo", 40960, "cpu", n_envs) / workers
        assert study.estimate_training_seconds() == pytest.approx(expected)


def test_on_a_device_the_study_trains_torch_ppo_under_both_rewards_and_fusions_with_a_budget_sweep(
    tmp_path,
):
    """``rl --device cpu`` (CPU torch here; a GPU in .ci/device-check): torch-ppo under both
    rewards and both fusions with the device entry, each seed trained in this process, and
    with ``--sweep`` the information learner again at another budget; the evaluation runs the
    trained models beside the compared policies on numpy."""
    pytest.importorskip("torch", reason="torch-ppo needs the rl extra")
    from benchmarks.cli import main

    out = tmp_path / "rl"
    argv = "rl --scenarios 1 --device cpu --n-envs 4 --timesteps 128 --sweep 256 --ppo-seeds 2 --trials 6"
    argv = [*argv.split(), "--steps", "5", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    judged = json.loads((out / "rl.json").read_text())
    assert [(e["scenario"], e["fusion"]) for e in judged["scenarios"]] == [(1, "average"), (1, "centralized")]
    for entry in judged["scenarios"]:
        assert set(entry["learners"]) == {"torch-ppo-sinr", "torch-ppo-information"}
        assert all(row["seeds"] == 2 for row in entry["learners"].values())
    meta = json.loads(
        (out / "train/paper-1-v1-centralized/torch-ppo-information/seed-1/ppo.json").read_text()
    )
    assert (meta["device"], meta["n_envs"], meta["config"]["n_steps"]) == ("cpu", 4, 32)  # the device entry
    assert meta["env_options"]["reward"] == "information" and meta["env_options"]["fusion"] == "centralized"
    assert meta["trained_timesteps"] == 128
    # the sweep: the same learner at 256 steps, seed by seed against its 128-step seeds, same trials
    swept = json.loads(
        (out / "train/paper-1-v1-average/torch-ppo-information-256/seed-0/ppo.json").read_text()
    )
    assert swept["trained_timesteps"] == 256 and swept["env_options"]["fusion"] == "average"
    sweep = judged["sweep"]
    assert (sweep["learner"], sweep["scenario"], sweep["fusion"]) == ("torch-ppo-information", 1, "average")
    assert [row["timesteps"] for row in sweep["budgets"]] == [128, 256]
    rows = json.loads((out / "sweep-paper-1-v1-average-256/summary.json").read_text())["policies"]
    armse = {
        budget: [rows[p]["armse"] for p in sorted(rows) if f"/torch-ppo-information{tag}/" in p]
        for budget, tag in ((128, ""), (256, "-256"))
    }
    assert sweep["budgets"][1]["minus_study"]["value"] == pytest.approx(
        np.mean(armse[256]) - np.mean(armse[128])
    )
    # the study's own seeds score the same on the sweep's run as on the study's
    study_rows = json.loads((out / "paper-1-v1-average/summary.json").read_text())["policies"]
    assert sweep["budgets"][0]["armse"]["mean"]["value"] == pytest.approx(
        judged["scenarios"][0]["learners"]["torch-ppo-information"]["armse"]["mean"]["value"]
    )
    assert all(study_rows[p]["armse"] == rows[p]["armse"] for p in rows if p in study_rows)
    assert "## Budget sweep: `torch-ppo-information`, paper-1, average fusion" in (out / "rl.md").read_text()
    # the planning study finds the learners of the same scenario and fusion, and no other
    planning = tmp_path / "planning"
    argv = "planning --scenarios 1 --fusions centralized --trials 6 --steps 5 --workers 1 --quiet"
    argv += " --no-figures"
    assert main([*argv.split(), "--rl", str(out), "--out", str(planning)]) == 0
    (run,) = json.loads((planning / "planning.json").read_text())
    assert run["learners"]["seeds"] == {"torch-ppo-sinr": 2, "torch-ppo-information": 2}


def test_the_budget_sweep_pairs_each_seed_with_the_same_seed_at_the_study_budget():
    from benchmarks.studies.rl import Training, judge_sweep
    from benchmarks.study import Finished, Run

    def policy(tag, seed):
        return f"torch-ppo:o/train/paper-1-v1-average/{tag}/seed-{seed}/model.pt"

    study = {0: 3.0, 1: 5.0, 2: 4.0, 10: 6.0}  # seed 10 sorts between 1 and 2 as text
    longer = {0: 2.5, 1: 4.0, 2: 4.1, 10: 5.0}
    longest = {0: 2.0, 1: 4.5, 2: 3.0}  # a seed missing: only the seeds both have are paired
    finished, swept = {}, []
    for budget, scores in ((1000, longer), (5000, longest)):
        rows = {"best-tracking": 2.0}
        rows |= {policy("torch-ppo-information", s): a for s, a in study.items()}
        rows |= {policy(f"torch-ppo-information-{budget}", s): a for s, a in scores.items()}
        run = Run(("sweep", budget), "paper-1-v1", tuple(rows), Path("unused"))
        finished[budget] = Finished(run, None, _summary(rows))
        swept.append(
            Training(1, "paper-1-v1", "average", "torch-ppo", "information", 4, budget, Path("unused"))
        )
    judged = judge_sweep(finished, 100, swept)
    first, second, third = judged["budgets"]
    assert [row["timesteps"] for row in judged["budgets"]] == [100, 1000, 5000]
    assert (first["seeds"], second["seeds"], third["seeds"]) == (4, 4, 3)
    assert "minus_study" not in first
    assert first["armse"]["mean"]["value"] == pytest.approx(np.mean(list(study.values())))
    differences = [longer[s] - study[s] for s in study]  # -0.5, -1.0, 0.1, -1.0
    assert second["minus_study"]["value"] == pytest.approx(np.mean(differences))
    low, high = second["minus_study"]["ci"]
    assert min(differences) <= low < np.mean(differences) < high <= max(differences)
    assert third["minus_study"]["value"] == pytest.approx(np.mean([2.0 - 3.0, 4.5 - 5.0, 3.0 - 4.0]))
    assert second["minus_best_tracking"]["value"] == pytest.approx(np.mean(list(longer.values())) - 2.0)
    assert second["armse"]["iqm"]["value"] == pytest.approx(np.mean([4.0, 4.1]))  # 25 % trimmed each side


def test_a_figure_is_drawn_only_where_a_training_episode_ended_and_the_tables_count_the_points():
    from benchmarks.studies.rl import CURVE_POINTS, drawable, rl_markdown

    empty = {"timesteps": np.array([]), "return": np.array([]), "armse": np.array([])}
    one = {"timesteps": np.array([4096.0]), "return": np.array([9.0]), "armse": np.array([2.0])}
    figures = {"paper-1-average": {"a": [empty, empty]}, "paper-2-average": {"a": [empty], "b": [one]}}
    assert list(drawable(figures)) == ["paper-2-average"]
    judged = judge_learners(
        {
            (1, "average"): _summary(
                {
                    "mg-crb-cl": 3.0,
                    "best-tracking": 1.0,
                    "tracking-ucb": 1.5,
                    "ppo:t/x/ppo-sinr/seed-0/m": 2.0,
                }
            )
        },
        [("ppo", "sinr")],
    )
    judged["scenarios"][0]["curves"] = {"ppo-sinr": flattened([one, one])}
    text = rl_markdown(judged)
    assert "| paper-1 | average | `ppo-sinr` | 1 | - | - |" in text and CURVE_POINTS in text


def test_the_sweep_figures_count_the_steps_a_training_ran_whole_rollouts_of(tmp_path):
    """A budget is trained in whole rollouts (n_envs x the entry's n_steps): the docs give the
    steps trained, not the budget asked for."""
    from benchmarks.docs_tooling.generators import _rl_sweep
    from benchmarks.training import TORCH_PPO, load_hyperparams

    n_steps = load_hyperparams(None, "device", TORCH_PPO)["n_steps"]
    stat = {"value": -0.1, "ci": [-0.3, 0.2]}
    row = {
        "timesteps": 5_000_000,
        "minus_study": stat,
        "minus_best_tracking": {"value": 1.0, "ci": [0.8, 1.2]},
    }
    row["curve"] = {"change": None, "flat": None, "rollouts": 1}
    first = {"timesteps": 600_000, "curve": {"change": None, "flat": None, "rollouts": 0}}
    judged = {"sweep": {"budgets": [first, row], "learner": "torch-ppo-information"}}
    judged["training"] = {"n_envs": 4096, "hyperparams_key": "device"}
    table = _rl_sweep(judged)
    rollout = 4096 * n_steps
    trained = -(-5_000_000 // rollout) * rollout
    assert trained >= 5_000_000 and trained - 5_000_000 < rollout
    assert table["sweep.5000000.trained"] == f"{trained:,}"
    assert table["sweep.5000000.steps-per-trial"] == f"{trained // 4096:,}"
    assert (table["sweep.5000000.minus-study"], table["sweep.5000000.best-tracking"]) == (
        "not shown to differ",
        "worse",
    )


def test_the_trainings_busy_time_is_the_union_of_when_each_ran(tmp_path):
    """Overlapping trainings count once, the gap between invocations not at all; a training that
    does not record when it ran leaves the figure out."""
    from benchmarks.studies.rl import training_times

    def trained(name, seed, start, wall):
        folder = tmp_path / "train" / "paper-1-v1-average" / name / f"seed-{seed}"
        folder.mkdir(parents=True)
        meta = {"train_wall_s": wall} | ({} if start is None else {"trained_from_unix_s": start})
        (folder / "ppo.json").write_text(json.dumps(meta))

    assert training_times(tmp_path) == {"training_worker_s": 0.0}  # no training
    trained("torch-ppo-sinr", 0, 1000.0, 10.0)
    trained("torch-ppo-sinr", 1, 1005.0, 7.0)  # inside [1000, 1012]: adds 2
    trained("torch-ppo-information", 0, 1003.0, 2.0)  # inside the first
    trained("torch-ppo-information", 1, 5000.0, 5.0)  # a later invocation: the gap not counted
    assert training_times(tmp_path) == pytest.approx(
        {"training_worker_s": 24.0, "training_busy_s": 12.0 + 5.0}
    )
    trained("ppo-sinr", 0, None, 3.0)
    assert training_times(tmp_path) == pytest.approx({"training_worker_s": 27.0})
