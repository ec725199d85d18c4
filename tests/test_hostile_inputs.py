"""Issue 15's hostile-test findings, each as a regression test (items 1, 9-12 and the fuzz)."""

import subprocess
import sys
import time

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmarks.cli import main
from mimo_radar_env import EnvOptions, RadarModel, Scenario, ScenarioError, load_scenario
from mimo_radar_env.core.geometry import MIN_RANGE

PAPER = load_scenario("paper-1").to_dict()


def _layout(**changes):
    data = {
        "tx_positions": [[0, 0], [0, 1e4]],
        "rx_positions": [[1e4, 0], [1e4, 1e4]],
        "tx_per_step": 1,
        "rx_per_step": 1,
        "targets": [{"initial_state": [-1000, 100, 0, 0]}],
        "horizon": 200,
    }
    data.update(changes)
    return data


def test_1_a_track_through_a_station_is_refused_and_the_sinr_model_is_finite():
    with pytest.raises(ScenarioError, match=r"targets\[0\]'s noise-free track passes 0 m from TX1 .*10 m"):
        Scenario.from_dict(_layout())
    sc = Scenario.from_dict(_layout(targets=[{"initial_state": [-1000, 100, 50, 0]}]))  # 50 m off TX1
    model = RadarModel.from_scenario(sc)
    at_station = model.mean_sinr(np.array([[0.0, 0.0]]))  # a trial may stray onto a station
    assert np.all(np.isfinite(at_station))
    point = np.array([MIN_RANGE / 2, 0.0])  # ranges below MIN_RANGE count as MIN_RANGE
    near = model.mean_sinr(point[None])
    rx_range = np.linalg.norm(sc.rx_positions - point, axis=1)
    np.testing.assert_allclose(near[0, 0], model.gain[0, 0] / (MIN_RANGE**2 * rx_range**2), rtol=1e-12)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"tx_power": 1e300, "rcs": 1e300}, "the SINR constant C"),
        ({"sample_time": 1e300}, "leaves the finite numbers"),
        ({"horizon": 10**12}, "horizon must be between 1 and 1000000"),
        ({"tx_power": True}, "tx_power must be numbers, got booleans"),
        ({"tx_power": ["1000", "1000", "1000", "1000"]}, "tx_power must be numbers, got strings"),
        ({"horizon": True}, "horizon must be an integer"),
    ],
)
def test_9_10_11_extreme_and_nonsense_values_are_named(changes, message):
    data = {**PAPER, **changes}
    with pytest.raises(ScenarioError, match=message):
        RadarModel.from_scenario(Scenario.from_dict(data))


def test_10_maneuvers_not_a_list_and_non_utf8_files(tmp_path):
    data = {**PAPER, "targets": [{"initial_state": [5, 100, 5, 100], "maneuvers": 5}]}
    with pytest.raises(ScenarioError, match=r"targets\[0\].maneuvers must be a list"):
        Scenario.from_dict(data)
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: caf\xe9\n".encode("latin-1"))
    with pytest.raises(ScenarioError, match="is not UTF-8 text"):
        load_scenario(path)


def test_11_yaml_duplicate_keys_are_refused(tmp_path):
    path = tmp_path / "dup.yaml"
    path.write_text("horizon: 10\nhorizon: 20\n")
    with pytest.raises(ScenarioError, match="duplicate key 'horizon' at line 2"):
        load_scenario(path)


def test_12_an_alias_bomb_is_refused_quickly(tmp_path):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 9)]
    path = tmp_path / "bomb.yaml"
    path.write_text("\n".join(lines) + "\n")
    assert path.stat().st_size < 1500
    start = time.perf_counter()
    with pytest.raises(ScenarioError, match="expands to more than 100000 YAML nodes"):
        load_scenario(path)
    assert time.perf_counter() - start < 1.0
    many = tmp_path / "aliases.yaml"
    many.write_text("a: &a 1\nb: [" + ", ".join(["*a"] * 101) + "]\n")
    with pytest.raises(ScenarioError, match="more than 100 YAML aliases"):
        load_scenario(many)
    deep = tmp_path / "deep.yaml"
    deep.write_text("x: " + "[" * 40 + "]" * 40 + "\n")
    with pytest.raises(ScenarioError, match="nests deeper than 32"):
        load_scenario(deep)
    big = tmp_path / "big.yaml"
    big.write_text("# " + "x" * (1 << 20) + "\n")
    with pytest.raises(ScenarioError, match="the limit is 1048576"):
        load_scenario(big)


def test_10_11_bad_env_arguments_are_named():
    with pytest.raises(ValueError, match="measurement_quality must be None or a number > 0, got 'high'"):
        gym.make("MimoRadarSelect-v0", measurement_quality="high")
    with pytest.raises(ValueError, match="measurement_quality"):
        EnvOptions(measurement_quality=True)
    with pytest.raises(ValueError, match="num_envs must be an integer >= 1, got 2.5"):
        gym.make_vec("MimoRadarSelect-v0", num_envs=2.5, vectorization_mode="vector_entry_point")
    venv = gym.make_vec("MimoRadarSelect-v0", num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match="seed must be an integer >= 0"):
        venv.reset(seed=1.5)
    with pytest.raises(ValueError, match=r"need about .* GiB; this machine has"):
        gym.make_vec("MimoRadarSelect-v0", num_envs=10**7, vectorization_mode="vector_entry_point")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["demo", "--steps", "-4"], "argument --steps: must be an integer >= 1, got -4"),
        (["train-ppo", "--timesteps", "0", "--out", "X"], "argument --timesteps: must be an integer >= 1"),
        (["train-ppo", "--timesteps", "-5", "--out", "X"], "argument --timesteps: must be an integer >= 1"),
        (
            ["run", "--scenario", "paper-1", "--policies", "ucb1", "--workers", "0", "--out", "X"],
            "argument --workers: must be an integer >= 1, got 0",
        ),
        (
            ["run", "--scenario", "paper-1", "--policies", "ucb1", "--seed", "-1", "--out", "X"],
            "argument --seed: must be an integer >= 0, got -1",
        ),
    ],
)
def test_11_cli_numbers_out_of_range(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err.strip().splitlines()[-1]
    assert not (tmp_path / "X").exists()


@pytest.mark.parametrize(
    ("param", "message"),
    [
        ("mg-crb-cl.alpha=-1", "policy 'mg-crb-cl': alpha must be in [0, 1], got -1"),
        ("mg-crb-cl.alpha=[1,2", "--agent-param 'mg-crb-cl.alpha=[1,2': the value is"),
        ("mg-crb-cl.seed=5", "agents' seeds are set by the run (--seed)"),
    ],
)
def test_6_bad_values_fail_before_config_json_is_written(param, message, tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1", "--policies", "mg-crb-cl", "--agent-param", param]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("policies", "message"),
    [
        ("ppo:/etc", "PPO model /etc/model.zip does not exist"),
        ("fixed", "needs the parameter(s) ['rx', 'tx']"),
    ],
)
def test_6_models_and_missing_parameters(policies, message, tmp_path, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit):
        main(["run", "--scenario", "paper-1", "--policies", policies, "--out", str(out), "--quiet"])
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_10_an_unusable_out_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    argv = ["run", "--scenario", "paper-1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(blocker / "out"), "--quiet", "--no-figures"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write into --out" in err[0]


def test_13_an_unreachable_ray_address_fails_within_seconds(tmp_path, capsys):
    pytest.importorskip("ray", reason="the ray extra")
    import socket

    with socket.socket() as probe:  # a loopback port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    argv = ["run", "--scenario", "paper-1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    start = time.perf_counter()
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--backend", "ray", "--address", f"127.0.0.1:{port}", "--out", str(tmp_path / "o")])
    assert time.perf_counter() - start < 10
    assert exit_info.value.code == 2
    assert f"cannot reach the Ray cluster at '127.0.0.1:{port}'" in capsys.readouterr().err


# ------------------------------------------------------------------ fuzz
_FIELDS = {
    "tx_per_step": st.one_of(
        st.integers(-2, 6), st.floats(allow_nan=True), st.booleans(), st.text(max_size=3)
    ),
    "horizon": st.one_of(st.integers(-5, 300), st.floats(-10, 1e13), st.booleans()),
    "sample_time": st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 10)),
    "process_noise": st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=2)),
    "tx_power": st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.lists(st.floats(-1e300, 1e300), min_size=1, max_size=5),
        st.booleans(),
    ),
    "noise_power": st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.none()),
    "range_variance": st.floats(-1, 1e300),
    "peak_sinr": st.one_of(st.floats(-1, 1e300), st.text(max_size=2)),
    "weights": st.one_of(st.lists(st.floats(-1, 5), max_size=3), st.just("x")),
    "tx_positions": st.one_of(
        st.lists(st.lists(st.floats(-2e5, 2e5), min_size=2, max_size=2), min_size=1, max_size=6),
        st.just([[0, 0]]),
        st.just("abc"),
    ),
    "targets": st.one_of(
        st.lists(
            st.fixed_dictionaries(
                {"initial_state": st.lists(st.floats(-1e5, 1e5), min_size=3, max_size=5)},
                optional={"maneuvers": st.one_of(st.integers(), st.just([]))},
            ),
            max_size=2,
        ),
        st.just(5),
    ),
}


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.fixed_dictionaries({}, optional=_FIELDS))
def test_fuzzed_scenarios_are_refused_by_name_or_run_finite(changes):
    data = {**PAPER, "horizon": 60, **changes}
    try:
        env = gym.make_vec(
            "MimoRadarSelect-v0",
            num_envs=2,
            vectorization_mode="vector_entry_point",
            scenario=Scenario.from_dict(data),
        )
    except ScenarioError as exc:
        assert any(name in str(exc) for name in (*data, "track", "SINR constant", "targets")), str(exc)
        return
    sc = env.scenario
    rng = np.random.default_rng(0)
    obs, info = env.reset(seed=0)
    from mimo_radar_env.core.superarm import random_super_arms

    for _ in range(min(50, sc.horizon)):
        obs, reward, _, _, info = env.step(
            random_super_arms(rng, 2, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        )
        assert np.all(np.isfinite(reward))
        for key in ("sinr", "track", "track_pred", "track_pos_cov"):
            assert np.all(np.isfinite(obs[key])), key
        assert np.isfinite(info["optimal_reward"]).all() and np.isfinite(info["expected_reward"]).all()


def test_subprocess_cli_scenario_errors_are_one_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(
        "tx_positions: [[0, 0]]\nrx_positions: [[1, 1]]\ntx_per_step: 1\nrx_per_step: 1\n"
        "targets: [{initial_state: [5, 1, 5, 1], maneuvers: 5}]\n"
    )
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks",
            "run",
            "--scenario",
            str(path),
            "--policies",
            "fix1",
            "--out",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "maneuvers must be a list" in result.stderr
