"""One definition per env version, read by registration, the harness and the command line."""

import gymnasium as gym
import pytest

import mimo_radar_env
from benchmarks.cli import build_parser
from benchmarks.settings import study_agent_params
from mimo_radar_env import VERSIONS, EnvOptions, default_config, env_version


@pytest.mark.parametrize("name", sorted(VERSIONS))
def test_registration_reads_the_version(name):
    version = VERSIONS[name]
    for env_id in (version.env_id, version.flat_env_id):
        spec = gym.spec(env_id)
        assert spec.kwargs == version.registration_kwargs()
    env = gym.make(version.env_id)
    config = default_config(name)
    assert env.unwrapped.options == EnvOptions(**{k: v for k, v in config.items() if k != "scenario"})
    assert env.unwrapped.scenario.name == config["scenario"] == version.paper_scenarios[0]
    env.close()


def test_the_views_are_derived_from_the_versions():
    assert mimo_radar_env.ENV_IDS == {n: v.env_id for n, v in VERSIONS.items()}
    assert mimo_radar_env.FLAT_ENV_IDS == {n: v.flat_env_id for n, v in VERSIONS.items()}
    assert mimo_radar_env.PAPER_SCENARIOS == {n: v.paper_scenarios for n, v in VERSIONS.items()}
    assert mimo_radar_env.ENV_ID == VERSIONS[mimo_radar_env.DEFAULT_VERSION].env_id == "MimoRadarSelect-v1"
    assert VERSIONS["v1"].options(truth="per-trial").truth == "per-trial"


def test_the_paper_study_owns_its_parameters_and_hands_out_copies():
    from benchmarks.settings import PAPER_AGENT_PARAMS

    assert study_agent_params("v1", []) == {"mg-crb-cl": {"solver_params": {"rule": "set"}}}
    assert study_agent_params("v0", []) == {}
    merged = study_agent_params("v1", ["mg-crb-cl.beta=1.5"])
    assert merged == {"mg-crb-cl": {"solver_params": {"rule": "set"}, "beta": 1.5}}
    assert PAPER_AGENT_PARAMS["v1"]["mg-crb-cl"] == {"solver_params": {"rule": "set"}}
    assert set(PAPER_AGENT_PARAMS) == set(VERSIONS)
    # the env versions hold no agent parameters
    assert not any("agent" in name for version in VERSIONS.values() for name in vars(version))
    with pytest.raises(ValueError, match="env version must be one of"):
        study_agent_params("v9", [])


def test_the_command_line_offers_every_version_and_its_defaults():
    parser = build_parser()
    args = parser.parse_args(["paper", "--scenario", "1", "--out", "x"])
    assert args.env_version == mimo_radar_env.DEFAULT_VERSION
    with pytest.raises(SystemExit):
        parser.parse_args(["paper", "--scenario", "1", "--out", "x", "--env-version", "v9"])


def test_a_bad_version_is_named():
    with pytest.raises(ValueError, match=r"env version must be one of \['v0', 'v1'\], got 'v9'"):
        env_version("v9")
    with pytest.raises(ValueError, match="lambda_scale must be one of"):
        mimo_radar_env.EnvVersion("v9", "bad", option_defaults={"lambda_scale": "log"})


#: Layout 5 of the global layout search (search-layouts, seed 0), km: 4 TX then 6 RX.
SEARCH_5_KM = [42.441, 7.232, 31.58, 16.659, 71.48, 82.425, 79.092, 61.507, 49.467, 8.597, 51.486, 41.422]
SEARCH_5_KM += [15.811, 59.904, 69.484, 49.032, 54.065, 82.58, 86.783, 16.473]


@pytest.mark.parametrize("number", [1, 2, 3])
def test_a_scenario_set_is_its_versions_scenario_with_other_stations(number):
    import numpy as np

    from mimo_radar_env import SCENARIO_SETS, load_scenario
    from mimo_radar_env.envs.versions import paper_key

    chosen = SCENARIO_SETS["search-5"]
    name = chosen.paper_scenario(number)
    own = load_scenario(env_version(chosen.version).paper_scenario(number)).to_dict()
    shipped = load_scenario(name).to_dict()
    km = np.array(SEARCH_5_KM).reshape(10, 2)
    assert np.array_equal(shipped["tx_positions"], km[:4] * 1e3)
    assert np.allclose(shipped["rx_positions"], km[4:] * 1e3, rtol=0, atol=1e-9)
    for key in set(own) - {"name", "tx_positions", "rx_positions"}:
        assert shipped[key] == own[key], key
    assert paper_key(name) == f"paper-{number}"
    with pytest.raises(ValueError, match="paper scenarios are 1, 2 and 3"):
        chosen.paper_scenario(4)


def test_the_claims_study_runs_a_scenario_set_and_refuses_another_version(tmp_path, capsys):
    import json

    from benchmarks.cli import main

    args = ["claims", "--scenario-set", "search-5", "--scenarios", "2", "--trials", "6", "--steps", "3"]
    args += ["--quiet", "--no-figures", "--workers", "1"]
    assert main([*args, "--out", str(tmp_path / "set")]) == 0
    config = json.loads((tmp_path / "set" / "paper-2-v1-search5" / "config.json").read_text())
    assert config["scenario"]["name"] == "paper-2-v1-search5"
    with pytest.raises(SystemExit) as exit_info:
        main([*args, "--env-version", "v0", "--out", str(tmp_path / "v0")])
    assert exit_info.value.code == 2
    assert "made for env version v1, not v0" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("make", "scenario", "message"),
    [
        (
            "MimoRadarSelect-v1",
            "paper-3",
            r"'paper-3' is MimoRadarSelect-v0's paper Scenario 3; MimoRadarSelect-v1's is 'paper-3-v1'",
        ),
        ("MimoRadarSelectFlat-v1", "paper-1", r"MimoRadarSelect-v1's is 'paper-1-v1'"),
        ("MimoRadarSelect-v0", "paper-2-v1", r"MimoRadarSelect-v0's is 'paper-2'"),
        ("MimoRadarSelect-v0", "paper-1-v1-search5", r"scenario set 'search-5' of MimoRadarSelect-v1"),
    ],
)
def test_another_versions_scenario_name_is_refused_with_this_versions_name(make, scenario, message):
    import gymnasium as gym

    for build in (
        lambda: gym.make(make, scenario=scenario),
        lambda: gym.make_vec(make, 2, vectorization_mode="vector_entry_point", scenario=scenario),
    ):
        with pytest.raises(ValueError, match=message):
            build()


def test_a_scenario_object_runs_under_any_version_as_given():
    import gymnasium as gym

    from mimo_radar_env import load_scenario

    env = gym.make("MimoRadarSelect-v1", scenario=load_scenario("paper-3"))
    assert env.unwrapped.scenario.name == "paper-3" and env.unwrapped.options.lambda_scale == "db"
    env.reset(seed=0)
    assert gym.make("MimoRadarSelect-v1", scenario="paper-3-v1").unwrapped.scenario.name == "paper-3-v1"


def test_the_command_line_refuses_another_versions_scenario_name(capsys):
    from benchmarks.cli import main

    with pytest.raises(SystemExit):
        main(["run", "--scenario", "paper-2", "--policies", "ucb1", "--out", "never-written"])
    assert "use 'paper-2-v1' or --env-version v0" in capsys.readouterr().err


def test_the_version_and_scenario_set_tables_refuse_two_entries_of_one_name():
    from mimo_radar_env.envs.versions import SCENARIO_SETS, EnvVersion, by_name

    assert list(VERSIONS) == ["v0", "v1"] and list(SCENARIO_SETS) == ["search-5"]
    assert all(name == entry.name for name, entry in {**VERSIONS, **SCENARIO_SETS}.items())
    with pytest.raises(ValueError, match="two entries are called 'v1'"):
        by_name(EnvVersion("v1", "one"), EnvVersion("v1", "another"))


def test_a_shipped_scenario_names_its_version_and_anything_else_the_default():
    from mimo_radar_env import load_scenario
    from mimo_radar_env.envs.versions import DEFAULT_VERSION, SCENARIO_SETS, scenario_version

    for version in VERSIONS.values():
        assert {scenario_version(name) for name in version.paper_scenarios} == {version.name}
    for scenario_set in SCENARIO_SETS.values():
        assert {scenario_version(name) for name in scenario_set.paper_scenarios} == {scenario_set.version}
    for other in ("my-layout.toml", "paper-4", load_scenario("paper-1"), None):
        assert scenario_version(other) == DEFAULT_VERSION
