"""Env options: one typed set, settable everywhere, checked before anything is written."""

import dataclasses
import json

import gymnasium as gym
import numpy as np
import pytest

import agents
import mimo_radar_env
from benchmarks.cli import main
from mimo_radar_env import VERSIONS, EnvOptions, MimoRadarSelectVectorEnv
from mimo_radar_env.envs.options import option_choices, option_names
from mimo_radar_env.tracking import FUSIONS

#: A value other than the default for every option, with its CLI flag(s).
NON_DEFAULT = {
    "fusion": ("centralized", ["--fusion", "centralized"]),
    "tracking": (False, ["--no-tracking"]),
    "filter_noise": ("estimated", ["--filter-noise", "estimated"]),
    "measurement_quality": (0.5, ["--measurement-quality", "0.5"]),
    "invalid_action": ("raise", ["--invalid-action", "raise"]),
    "oracle_solver": ("alternating", ["--oracle-solver", "alternating"]),
    "lambda_scale": ("db", ["--lambda-scale", "db"]),
    "truth": ("shared", ["--truth", "shared"]),
    "measurements": (True, ["--measurements"]),
    "reward": ("information", ["--reward", "information"]),
    "prediction_covariance": (True, ["--prediction-covariance"]),
}
#: A bad value of every option, as a CLI argument and as a Python value.
BAD = {
    "fusion": ("--fusion", "median", "median"),
    "tracking": (None, None, "yes"),  # a switch (--tracking/--no-tracking): no bad CLI value
    "filter_noise": ("--filter-noise", "guess", "guess"),
    "measurement_quality": ("--measurement-quality", "-1", -1.0),
    "invalid_action": ("--invalid-action", "ignore", "ignore"),
    "oracle_solver": ("--oracle-solver", "local-search", "local-search"),
    "lambda_scale": ("--lambda-scale", "log", "log"),
    "truth": ("--truth", "per-run", "per-run"),
    "measurements": (None, None, 1),  # a switch: no bad CLI value
    "reward": ("--reward", "regret", "regret"),
    "prediction_covariance": (None, None, "no"),  # a switch: no bad CLI value
}


def test_the_tables_above_cover_every_option_and_choices_come_from_their_registries():
    assert set(NON_DEFAULT) == set(BAD) == set(option_names())
    assert option_choices()["fusion"] == tuple(FUSIONS)
    assert option_choices()["oracle_solver"] == ("auto", "exact", "alternating")


def test_the_option_docs_are_generated_from_the_fields():
    """One home: the env's Arguments, EnvOptions' docstring and the command line's help all read
    the fields' metadata."""
    from mimo_radar_env.envs.options import option_docs, option_help

    flat = " ".join(gym.make("MimoRadarSelect-v1").unwrapped.__class__.__doc__.split())
    options_doc = " ".join(EnvOptions.__doc__.split())
    for name, doc in option_docs().items():
        assert f"* ``{name}``: {doc}" in flat, name
        assert f"{name} : " in options_doc and doc in options_doc, name
        assert option_help()[name]
    for version in mimo_radar_env.VERSIONS.values():
        assert f"``{version.env_id}`` ({version.summary})" in flat


def test_the_env_docstring_lists_every_option():
    doc = gym.make("MimoRadarSelect-v0").unwrapped.__class__.__doc__
    arguments = doc[doc.index("## Arguments") : doc.index("## Seeding")]
    for name in option_names():
        assert f"``{name}``" in arguments, name
    for name, choices in option_choices().items():
        for choice in choices:
            assert f'"{choice}"' in arguments, (name, choice)


@pytest.mark.parametrize("name", list(NON_DEFAULT))
def test_every_option_round_trips_from_the_cli_to_the_env(name, tmp_path, monkeypatch):
    value, flags = NON_DEFAULT[name]
    built = []

    class Spy(MimoRadarSelectVectorEnv):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            built.append(self.options)

    monkeypatch.setattr(agents.rollout, "MimoRadarSelectVectorEnv", Spy)  # where every run builds its envs
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1", "--policies", "ucb1", "--trials", "2", "--steps", "3"]
    argv += ["--workers", "1", "--no-figures", "--quiet", "--out", str(out), "--env-version", "v0", *flags]
    assert main(argv) == 0
    recorded = json.loads((out / "config.json").read_text())["env_options"]
    assert recorded == {**EnvOptions().to_dict(), name: value}
    assert json.loads((out / "summary.json").read_text())["env_options"][name] == value
    # every env of the run (the check before writing, then the worker's) got the option
    assert built and all(getattr(options, name) == value for options in built)


def test_a_worker_process_builds_the_env_with_the_recorded_options(tmp_path):
    """Same numbers in a spawned worker as in process; different from the default fusion."""
    base = ["run", "--scenario", "paper-3-v1", "--policies", "ucb1", "--trials", "2", "--steps", "30"]
    base += ["--no-figures", "--quiet", "--shard-size", "1"]
    summaries = {}
    for label, extra in (
        ("process", ["--workers", "2", "--fusion", "centralized"]),
        ("inline", ["--workers", "1", "--fusion", "centralized"]),
        ("default", ["--workers", "1"]),
    ):
        assert main([*base, *extra, "--out", str(tmp_path / label)]) == 0
        summaries[label] = json.loads((tmp_path / label / "summary.json").read_text())["policies"]["ucb1"]
    assert summaries["process"]["armse"] == summaries["inline"]["armse"]
    assert summaries["process"]["armse"] != summaries["default"]["armse"]


@pytest.mark.parametrize("name", list(BAD))
def test_a_bad_option_is_refused_before_anything_is_written(name, tmp_path, capsys):
    flag, text, value = BAD[name]
    out = tmp_path / "run"
    if flag is not None:
        argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--out", str(out), flag, text]
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 2
        last = capsys.readouterr().err.strip().splitlines()[-1]  # after argparse's usage
        assert last.startswith("mimo-radar-bench run: error: argument " + flag) and repr(text) in last
        assert not out.exists()
    with pytest.raises(ValueError, match=name):
        EnvOptions(**{name: value})
    with pytest.raises(ValueError, match=name):
        gym.make("MimoRadarSelect-v0", **{name: value})


def _bad_parameter_values():
    """(agent, parameter, bad value) for every parameter of every registered agent."""
    cases = []
    for name in agents.available_agents():
        for parameter in agents.agent_parameters(name):
            if name in agents.learned_agents() and parameter != "path":
                continue  # needs a trained model: tests/agents/test_ppo.py, test_learners.py
            bad = {"solver": "nosuch", "path": "/nonexistent/model.zip", "tx": "a", "rx": "a"}
            cases.append((name, parameter, bad.get(parameter, -1 if parameter == "seed" else "x")))
    return cases


@pytest.mark.parametrize(("agent", "parameter", "value"), _bad_parameter_values())
def test_a_bad_agent_parameter_is_refused_before_anything_is_written(
    agent, parameter, value, tmp_path, capsys
):
    out = tmp_path / "run"
    params = {"fixed": ["fixed.tx=[0, 1]", "fixed.rx=[0, 1, 2]"]}.get(agent, [])
    params = [p for p in params if not p.startswith(f"{agent}.{parameter}=")]
    learned = agent in agents.learned_agents()
    if learned:
        for module in ("stable_baselines3", "sb3_contrib", "torch"):
            pytest.importorskip(module, reason="the learned agents need the rl extra")
    policy = f"{agent}:/nonexistent/model.zip" if learned else agent
    argv = ["run", "--scenario", "paper-1-v1", "--policies", policy, "--out", str(out), "--quiet"]
    if not learned:
        params.append(f"{agent}.{parameter}={json.dumps(value)}")
    for item in params:
        argv += ["--agent-param", item]
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("mimo-radar-bench: error: ")
    named = {"solver": "solver", "solver_params": "solver_params", "path": "ppo model"}.get(
        parameter, parameter
    )
    assert named in err
    assert not out.exists()


def test_options_are_typed_and_frozen():
    options = EnvOptions(measurement_quality=2)
    assert options.measurement_quality == 2.0 and isinstance(options.measurement_quality, float)
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.fusion = "centralized"
    assert EnvOptions(fusion="centralized").changed() == {"fusion": "centralized"}
    with pytest.raises(ValueError, match="measurement_quality"):
        EnvOptions(measurement_quality=True)
    with pytest.raises(ValueError, match="measurement_quality"):
        EnvOptions(measurement_quality=np.inf)


def test_the_cli_starts_from_the_chosen_versions_defaults(tmp_path):
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    argv += ["--workers", "1", "--no-figures", "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "v1")]) == 0  # v1 is the default
    v1 = json.loads((tmp_path / "v1" / "config.json").read_text())["env_options"]
    assert v1 == VERSIONS["v1"].options().to_dict() and v1["truth"] == "shared"
    assert main([*argv, "--env-version", "v1", "--truth", "per-trial", "--out", str(tmp_path / "mix")]) == 0
    mixed = json.loads((tmp_path / "mix" / "config.json").read_text())["env_options"]
    assert mixed == {**v1, "truth": "per-trial"}
    argv[2] = "paper-1"  # v0's name of the scenario
    assert main([*argv, "--env-version", "v0", "--out", str(tmp_path / "v0")]) == 0
    v0 = json.loads((tmp_path / "v0" / "config.json").read_text())["env_options"]
    assert v0 == EnvOptions().to_dict()
