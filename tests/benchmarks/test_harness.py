"""The Monte-Carlo harness and its CLI on small runs."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import benchmarks
from benchmarks import harness
from benchmarks.cli import main
from benchmarks.harness import HarnessError, load_per_trial, make_config, run, run_many, shard_path
from benchmarks.report import write_outputs
from mimo_radar_env import load_scenario
from tests.helpers import SUMMARY_KEYS


def test_run_subcommand_with_agent_params_and_a_scenario_file(tmp_path, capsys):
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(
        "tx_positions: [[0, 0], [20000, 0], [0, 20000]]\n"
        "rx_positions: [[20000, 20000], [10000, 0], [0, 10000]]\n"
        "tx_per_step: 2\nrx_per_step: 2\nhorizon: 40\ntargets:\n  - initial_state: [5000, 50, 7000, 20]\n"
    )
    out = tmp_path / "run"
    main(
        [
            "run",
            "--scenario",
            str(scenario),
            "--policies",
            "mg-crb-cl,discounted-thompson,random",
            "--agent-param",
            "mg-crb-cl.solver=exact",
            "--agent-param",
            "discounted-thompson.discount=0.95",
            "--trials",
            "3",
            "--seed",
            "7",
            "--fusion",
            "centralized",
            "--workers",
            "1",
            "--no-figures",
            "--out",
            str(out),
            "--quiet",
        ]
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"] == "tiny" and summary["seed"] == 7 and summary["steps"] == 40
    assert list(summary["policies"]) == ["mg-crb-cl", "discounted-thompson", "random"]
    config = json.loads((out / "config.json").read_text())
    assert config["agent_params"] == {
        "mg-crb-cl": {"solver": "exact"},
        "discounted-thompson": {"discount": 0.95},
    }
    assert not (out / "sinr.png").exists()


def test_a_changed_configuration_in_the_same_dir_is_refused(tmp_path):
    config = make_config("paper-1", ["fix1"], trials=2, steps=5, shard_size=1)
    run(config, tmp_path, progress=False)
    other = make_config("paper-1", ["fix1"], trials=2, steps=6, shard_size=1)
    with pytest.raises(HarnessError, match=r"different configuration \(differs in \['steps'\]\)"):
        run(other, tmp_path, progress=False)


def test_resume_after_a_partial_run_gives_the_same_numbers(tmp_path):
    config = make_config("paper-3", ["mg-crb-cl", "epsilon-greedy"], trials=6, steps=20, shard_size=2)
    whole = run(config, tmp_path / "whole", progress=False)
    assert run(config, tmp_path / "part", progress=False, max_tasks=3) is None  # stops after 3 of 6 tasks
    assert len(list((tmp_path / "part" / "shards").rglob("*.npz"))) == 3
    resumed = run(config, tmp_path / "part", progress=False)
    for policy in config.policies:
        for key, value in whole[policy].items():
            if key != "wall_s":
                np.testing.assert_array_equal(resumed[policy][key], value)


def test_a_killed_run_restarted_gives_exactly_the_uninterrupted_numbers(tmp_path):
    args = [
        "run",
        "--scenario",
        "paper-1-v1",
        "--policies",
        "ucb1,fix1",
        "--trials",
        "8",
        "--shard-size",
        "1",
        "--steps",
        "300",
        "--workers",
        "1",
        "--no-figures",
        "--quiet",
    ]
    killed = tmp_path / "killed"
    proc = subprocess.Popen(
        [sys.executable, "-m", "benchmarks", *args, "--out", str(killed)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.time() + 120
    while time.time() < deadline and len(list(killed.glob("shards/*/*.npz"))) < 3:
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done = len(list(killed.glob("shards/*/*.npz")))
    assert 3 <= done < 16, "the run must be killed part-way"
    assert main([*args, "--out", str(killed)]) == 0
    assert main([*args, "--out", str(tmp_path / "whole")]) == 0
    a = json.loads((killed / "summary.json").read_text())["policies"]
    b = json.loads((tmp_path / "whole" / "summary.json").read_text())["policies"]
    for policy in a:
        for key in SUMMARY_KEYS - {"wall_s"}:
            assert a[policy][key] == b[policy][key], (policy, key)


def test_outputs_regenerate_from_saved_shards(tmp_path):
    config = make_config("paper-1", ["fix1", "best"], trials=2, steps=10, shard_size=1)
    totals = run(config, tmp_path, progress=False)
    first = write_outputs(config, totals, tmp_path, figures=False)
    again = write_outputs(config, None, tmp_path, figures=False)
    assert first == again
    assert shard_path(tmp_path, "fix1", 1).exists()


@pytest.mark.parametrize(
    ("kwargs", "python", "flag"),
    [
        ({"trials": 0}, "trials must be an integer >= 1, got 0", "--trials must be"),
        ({"seed": -1}, "seed must be an integer >= 0, got -1", "--seed must be"),
        ({"steps": 5000}, "steps must be between 1 and the scenario horizon", "--steps must be"),
        ({"shard_size": 0}, "shard_size must be an integer >= 1", "--shard-size must be"),
        (
            {"agent_params": {"ucb1": {"seed": 3}}},
            "agent_params ucb1.seed: agents' seeds are set by the run (seed)",
            "--agent-param ucb1.seed",
        ),
        (
            {"agent_params": {"cts": {}}},
            "agent_params names policy 'cts', which is not in the run",
            "--agent-param names",
        ),
        (
            {"max_hours": 1e-9, "trials": 500},
            "more than max_hours 1e-09: use fewer trials or steps, more workers",
            "more than --max-hours",
        ),
        (
            {"max_hours": 0},
            "max_hours must be a number of hours > 0 or None (no limit), got 0",
            "--max-hours must",
        ),
        ({"max_hours": float("nan")}, "max_hours must be a number of hours > 0", "--max-hours must"),
        (
            {"max_hours": "2"},
            "max_hours must be a number of hours > 0 or None (no limit), got '2'",
            "--max-hours",
        ),
        ({"workers": 0}, "workers must be an integer >= 1, got 0", "--workers must be"),
        ({"workers": 2.5}, "workers must be an integer >= 1, got 2.5", "--workers must be"),
        ({"parallel": -1}, "parallel must be an integer >= 1, got -1", "parallel must be"),
        (
            {"options": [("fusion", "centralized")]},
            "options must be an EnvOptions or a mapping",
            "options must",
        ),
        (
            {"options": {"fusion": "x"}},
            "options: fusion must be one of ['average', 'centralized']",
            "options:",
        ),
    ],
)
def test_the_library_api_names_its_arguments_and_the_command_line_its_flags(kwargs, python, flag):
    """make_config's refusals speak Python (its arguments); the command line translates them to
    its flags, and nothing else in the message changes."""
    given = {"trials": 2, **kwargs}
    with pytest.raises(HarnessError) as caught:
        make_config("paper-1-v1", ["ucb1"], say=lambda message: None, **given)
    assert python in str(caught.value) and "--" not in str(caught.value)
    assert flag in caught.value.for_command_line()


def test_an_agent_parameter_named_after_an_env_option_must_be_the_runs():
    """tracking-ucb's ``fusion`` defaults to the run's; one given otherwise is refused in the
    words of the API or of the command line (not with the Python fix the rollout suggests)."""
    given = {"agent_params": {"tracking-ucb": {"fusion": "average"}}, "options": {"fusion": "centralized"}}
    with pytest.raises(HarnessError) as caught:
        make_config("paper-1-v1", ["tracking-ucb"], 6, steps=3, say=lambda message: None, **given)
    said = "tracking-ucb.fusion='average' differs from the run's fusion='centralized'; leave it out"
    assert str(caught.value) == f"policy 'tracking-ucb': agent_params {said} (the agent takes the run's)"
    assert caught.value.for_command_line().startswith(f"policy 'tracking-ucb': --agent-param {said}")
    given["agent_params"]["tracking-ucb"]["fusion"] = "centralized"  # the run's: taken
    make_config("paper-1-v1", ["tracking-ucb"], 6, steps=3, say=lambda message: None, **given)


def test_the_env_options_default_to_the_scenarios_version_and_a_mapping_goes_over_them():
    """A run of v1's paper scenario without options is v1's (as ``gym.make`` and the command line
    make it), not :class:`EnvOptions`' own defaults, which are v0's readings."""
    from mimo_radar_env import EnvOptions
    from mimo_radar_env.envs.versions import VERSIONS

    def options(scenario, given):
        config = make_config(scenario, ["ucb1"], trials=2, steps=3, options=given, say=lambda m: None)
        return config.env_options

    v1, v0 = VERSIONS["v1"].options(), VERSIONS["v0"].options()
    assert v1 != v0 == EnvOptions()
    for scenario, version in (("paper-1-v1", v1), ("paper-2-v1-search5", v1), ("paper-1", v0)):
        assert options(scenario, None) == options(scenario, {}) == version.to_dict()
        assert options(scenario, {"fusion": "centralized"}) == {**version.to_dict(), "fusion": "centralized"}
        assert options(scenario, EnvOptions()) == EnvOptions().to_dict()  # an EnvOptions is taken as it is
    assert options(load_scenario("paper-1"), None) == v1.to_dict()  # an object or a file: v1's, the default
    with pytest.raises(TypeError, match="unexpected keyword argument 'bogus'"):  # as in Gymnasium
        options("paper-1-v1", {"bogus": 1})


def test_per_policy_shards_cover_every_trial_once_and_give_the_same_numbers(tmp_path):
    kinds = dict(steps=6, say=lambda _: None)
    uniform = make_config("paper-1-v1", ["ucb1", "fix1"], 7, shard_size=7, **kinds)
    mixed = make_config("paper-1-v1", ["ucb1", "fix1"], 7, shard_size={"ucb1": 3, "fix1": 7}, **kinds)
    assert mixed.shard_size == 7 and mixed.shard_sizes == {"ucb1": 3}
    assert mixed.tasks() == [("ucb1", 0), ("fix1", 0), ("ucb1", 1), ("ucb1", 2)]
    for policy in mixed.policies:
        covered = [t for s in range(mixed.shards_of(policy)) for t in mixed.shard_trials(policy, s)]
        assert covered == list(range(7))
    assert "shard_sizes" not in uniform.to_json() and mixed.to_json()["shard_sizes"] == {"ucb1": 3}
    for config, name in ((uniform, "uniform"), (mixed, "mixed")):
        run(config, tmp_path / name, progress=False)
    a, b = load_per_trial(tmp_path / "uniform", uniform), load_per_trial(tmp_path / "mixed", mixed)
    for policy in ("ucb1", "fix1"):
        for key in ("trial_expected", "trial_squared_error", "trial_bound_squared", "trial_matches"):
            np.testing.assert_allclose(b[policy][key], a[policy][key], rtol=1e-12, atol=0)
    # resumed without a shard size, the run keeps each policy's
    assert harness.recorded_shard_size(tmp_path / "mixed") == {"ucb1": 3, "fix1": 7}
    assert harness.recorded_shard_size(tmp_path / "uniform") == 7
    # a study resuming the folder with other policies gets none: its configuration differs anyway
    assert harness.recorded_shard_size(tmp_path / "mixed", ["ucb1"]) is None
    assert harness.recorded_shard_size(tmp_path / "mixed", ["fix1", "ucb1"]) == {"ucb1": 3, "fix1": 7}
    with pytest.raises(HarnessError, match=r"`?shard_size`? names \['a'\], not the run's policies"):
        make_config("paper-1-v1", ["ucb1"], 7, shard_size={"a": 3}, **kinds)


def test_a_run_planned_by_cost_says_its_shards(capsys):
    six = ["best", "mg-crb-cl", "ucb1", "epsilon-greedy", "fix1", "fix2"]
    config = make_config("paper-1-v1", six, 500, 10, workers=1, parallel=8, say=print)
    said = capsys.readouterr().out
    assert config.shard_sizes and "shards by cost: " in said
    assert f"mg-crb-cl {config.shards_of('mg-crb-cl')} of {config.size_of('mg-crb-cl')} trials" in said
    assert config.size_of("mg-crb-cl") < config.size_of("fix1")


def test_each_policys_shard_size_is_checked_like_one_for_all():
    with pytest.raises(HarnessError, match=r"`?shard_size`? must be an integer >= 1, got 0"):
        make_config(
            "paper-1-v1", ["ucb1", "fix1"], 7, 6, shard_size={"ucb1": 0, "fix1": 7}, say=lambda _: None
        )


def test_the_largest_seed_a_run_takes_runs_every_shard_and_one_more_is_refused(tmp_path):
    """Trial i's agent is seeded seed + i, at most 2**63 - 1: the run's seed was checked only
    for >= 0, so a seed near the top was taken, wrote its folder and failed in its second shard."""
    top = 2**63 - 4
    config = make_config("paper-1-v1", ["ucb1"], 4, 2, seed=top, shard_size=2, say=lambda _: None)
    joined = run(config, tmp_path / "top", progress=False)
    assert joined is not None and joined["ucb1"]["trial_expected"].shape == (4, 2)
    with pytest.raises(HarnessError, match=r"`?seed`? must be at most 2\*\*63 - 4 for 4 trials"):
        make_config("paper-1-v1", ["ucb1"], 4, 2, seed=top + 1, shard_size=2, say=lambda _: None)


def test_policies_given_as_one_string_are_refused_not_read_letter_by_letter():
    with pytest.raises(HarnessError, match=r"policies must be a list of policy names, got the string 'ucb1'"):
        make_config("paper-1-v1", "ucb1", trials=2, say=lambda message: None)


def test_runs_that_are_not_a_config_and_a_folder_are_refused_before_a_folder_is_made(tmp_path):
    config = make_config("paper-1-v1", ["fix1"], trials=2, steps=3, say=lambda m: None)
    out = tmp_path / "out"
    with pytest.raises(TypeError, match="a run's out must be a folder's path, got int"):
        run(config, 5, progress=False)
    with pytest.raises(
        TypeError, match="a run's config must be a RunConfig .make_config builds one., got str"
    ):
        run("paper-1-v1", out, progress=False)
    for runs in ([config], (config, out)):
        with pytest.raises(TypeError, match=r"runs must be a list of \(RunConfig, folder\) pairs"):
            run_many(runs, progress=False)
    assert not out.exists()


def test_an_output_folder_is_made_or_refused_in_the_apis_words(tmp_path):
    """``output_folder``, which every command calls before its work: a file, a path under a file,
    or a folder that cannot be made is one HarnessError naming ``out`` (``--out`` on the command
    line); a new folder is made and nothing is left in it."""
    (tmp_path / "file").write_text("x")
    with pytest.raises(HarnessError) as caught:
        harness.output_folder(tmp_path / "file")
    assert str(caught.value).startswith(f"out {tmp_path / 'file'} is a file, not a folder")
    assert caught.value.for_command_line().startswith("--out ")
    with pytest.raises(HarnessError, match="cannot write into out .*file/run: Not a directory"):
        harness.output_folder(tmp_path / "file" / "run")
    made = harness.output_folder(tmp_path / "new" / "run")
    assert made.is_dir() and list(made.iterdir()) == []


@pytest.mark.parametrize("empty", ["", "  "])
def test_an_empty_out_is_refused_not_read_as_the_current_folder(tmp_path, monkeypatch, empty):
    """``Path("")`` is the current folder: an empty ``out`` (an unset shell variable, say) is refused by
    ``output_folder``, ``run``, ``run_many`` and ``benchmarks.run`` as the command line refuses
    ``--out ''``, and nothing is written where the call was made."""
    monkeypatch.chdir(tmp_path)
    config = make_config("paper-1-v1", ["ucb1"], 2, 3)
    calls = [
        lambda: harness.output_folder(empty),
        lambda: run(config, empty, progress=False),
        lambda: run_many([(config, empty)], progress=False),
        lambda: benchmarks.run("paper-1-v1", ["ucb1"], trials=2, steps=3, out=empty, progress=False),
    ]
    for call in calls:
        with pytest.raises(HarnessError, match=f"out must name a folder, got {empty!r}") as caught:
            call()
        assert caught.value.for_command_line().startswith("--out must name a folder")
    assert list(tmp_path.iterdir()) == []
