"""One definition per env version, read by registration, the harness and the command line."""

import gymnasium as gym
import pytest

import mimo_radar_env
from benchmarks.cli import build_parser
from benchmarks.studies.settings import study_agent_params
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
    assert EnvOptions.for_version("v1") == VERSIONS["v1"].options()
    assert VERSIONS["v1"].options(truth="per-trial").truth == "per-trial"


def test_the_paper_study_parameters_come_from_the_version_and_are_copies():
    assert study_agent_params("v1", []) == {"mg-crb-cl": {"solver_params": {"rule": "set"}}}
    assert study_agent_params("v0", []) == {}
    merged = study_agent_params("v1", ["mg-crb-cl.beta=1.5"])
    assert merged == {"mg-crb-cl": {"solver_params": {"rule": "set"}, "beta": 1.5}}
    assert dict(VERSIONS["v1"].paper_agent_params["mg-crb-cl"]) == {"solver_params": {"rule": "set"}}


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
