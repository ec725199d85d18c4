"""Scenario validation at the edges: every bad field, file and fuzzed mutation refused by name, or
run finite."""

import dataclasses
import pickle
import re
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mimo_radar_env import Maneuver, RadarModel, Scenario, ScenarioError, Target, load_scenario
from mimo_radar_env.core.geometry import MIN_RANGE
from tests.helpers import vector_env

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


def test_a_track_through_a_station_is_refused_and_the_sinr_model_is_finite():
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
        ({"sample_time": 1e300}, r"sample_time must be in \[0.001, 1e\+06\] \(s\), got 1e\+300"),
        ({"horizon": 10**12}, "horizon must be between 1 and 1000000"),
        ({"tx_power": True}, "tx_power must be numbers, got booleans"),
        ({"tx_power": ["1000", "1000", "1000", "1000"]}, "tx_power must be numbers, got strings"),
        ({"horizon": True}, "horizon must be an integer"),
    ],
)
def test_extreme_and_nonsense_values_are_named(changes, message):
    data = {**PAPER, **changes}
    with pytest.raises(ScenarioError, match=message):
        RadarModel.from_scenario(Scenario.from_dict(data))


def test_maneuvers_not_a_list_and_non_utf8_files(tmp_path):
    data = {**PAPER, "targets": [{"initial_state": [5, 100, 5, 100], "maneuvers": 5}]}
    with pytest.raises(ScenarioError, match=r"targets\[0\].maneuvers must be a list"):
        Scenario.from_dict(data)
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: caf\xe9\n".encode("latin-1"))
    with pytest.raises(ScenarioError, match="is not UTF-8 text"):
        load_scenario(path)


def test_yaml_duplicate_keys_are_refused(tmp_path):
    path = tmp_path / "dup.yaml"
    path.write_text("horizon: 10\nhorizon: 20\n")
    with pytest.raises(ScenarioError, match="duplicate key 'horizon' at line 2"):
        load_scenario(path)


def test_an_alias_bomb_is_refused_quickly(tmp_path):
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


@settings(
    max_examples=100,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(st.fixed_dictionaries({}, optional=_FIELDS))
def test_fuzzed_scenarios_are_refused_by_name_or_run_finite(changes):
    data = {**PAPER, "horizon": 60, **changes}
    try:
        env = vector_env(
            "MimoRadarSelect-v0",
            2,
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


@pytest.mark.parametrize("field", ["horizon", "tx_per_step", "truth_seed"])
def test_an_integral_float_is_not_taken_as_an_integer(field):
    with pytest.raises(ScenarioError, match=rf"{field} must be an integer, got 1\.0"):
        Scenario.from_dict(_layout(**{field: 1.0}))


def test_make_refuses_a_float_horizon():
    import gymnasium as gym

    with pytest.raises(ScenarioError, match=r"horizon must be an integer, got 5\.0"):
        gym.make("MimoRadarSelect-v1", horizon=5.0)


@pytest.mark.parametrize("name", ["", "../escape", "a/b", "a\\b", ".hidden", " padded", "x" * 101, 5, None])
def test_a_name_no_folder_can_carry_is_refused(name):
    """A study writes a scenario's run into OUT/<name> (claims.paper_runs): a name with a separator, a
    leading dot, a space or nothing at all would put it elsewhere, and a non-string is not made one."""
    with pytest.raises(
        ScenarioError, match=f"name must be a string of 1 to 100 letters.*got {re.escape(repr(name))}"
    ):
        Scenario.from_dict({**PAPER, "name": name})


@pytest.mark.parametrize("name", ["paper-1-v1-search5", "random-6x8-K2", "caf\xe9", "v1+jitter.2", "x" * 100])
def test_names_of_letters_digits_and_marks_are_kept(name):
    assert Scenario.from_dict({**PAPER, "name": name}).name == name


@pytest.mark.parametrize(
    "changes",
    [
        {"tx_per_step": 99},
        {"horizon": -3},
        {"sample_time": 0.0},
        {"weights": [float("nan")]},
        {"name": "../escape"},
        {"tx_positions": [[0.0, 0.0]] * 4},
        {"targets": [{"initial_state": [5, 100, 5], "initial_covariance": [20.0] * 4}]},
        {
            "targets": [
                {
                    "initial_state": [5, 100, 5, 100],
                    "maneuvers": [{"turn_rate_deg": 0.0, "start": 1, "stop": 9}],
                }
            ]
        },
    ],
)
def test_a_scenario_built_directly_is_checked_as_from_dict_checks_it(changes):
    """``Scenario(...)`` and ``dataclasses.replace`` refuse what ``from_dict`` refuses, with its message: a
    scenario built so ran before with a zero sample time, coincident stations or NaN weights."""
    with pytest.raises(ScenarioError) as expected:
        Scenario.from_dict({**PAPER, **changes})
    paper = Scenario.from_dict(PAPER)
    fields = dict(changes)
    if "targets" in fields:  # built directly, as the dataclasses
        (raw,) = fields["targets"]
        maneuvers = tuple(Maneuver(**m) for m in raw.get("maneuvers", []))
        cov = np.diag(raw.get("initial_covariance", [20.0] * 4))
        fields["targets"] = (Target(np.array(raw["initial_state"], float), cov, maneuvers),)
    with pytest.raises(ScenarioError, match=re.escape(str(expected.value))):
        dataclasses.replace(paper, **fields)
    with pytest.raises(ScenarioError, match=re.escape(str(expected.value))):
        Scenario(**{**{f.name: getattr(paper, f.name) for f in dataclasses.fields(paper)}, **fields})


def test_a_scenario_built_directly_holds_what_from_dict_makes_of_its_fields():
    paper = Scenario.from_dict(PAPER)
    shorter = dataclasses.replace(paper, horizon=50, tx_power=2000.0, tx_positions=PAPER["tx_positions"])
    assert shorter == Scenario.from_dict({**PAPER, "horizon": 50, "tx_power": 2000.0})
    assert isinstance(shorter.tx_positions, np.ndarray) and shorter.tx_power.shape == (paper.num_tx,)
    assert pickle.loads(pickle.dumps(shorter)) == shorter
