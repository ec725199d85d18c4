"""Physical ranges of the scenario fields, and the tracker at their edges: every accepted input
gives finite outputs on both fusions; what lies beyond is refused with the range allowed."""

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mimo_radar_env  # noqa: F401
from mimo_radar_env import Scenario, ScenarioError, load_scenario
from mimo_radar_env.core.superarm import random_super_arms
from mimo_radar_env.tracking.unscented import repair_covariance
from tests.helpers import vector_env

BASE = load_scenario("paper-1-v1")
EXTENT = BASE.extent


def _episode(scenario: Scenario, fusion: str, steps: int = 40, trials: int = 6, **options) -> dict:
    """A short episode of random selections; every output array of every step."""
    env = vector_env(
        "MimoRadarSelect-v1",
        trials,
        scenario=scenario,
        fusion=fusion,
        horizon=steps,
        **options,
    )
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    seen: dict[str, list] = {}
    for _ in range(steps):
        action = random_super_arms(rng, trials, scenario.num_tx, scenario.num_rx, 2, 3)
        obs, reward, _, _, info = env.step(action)
        for key, value in {"reward": reward, **obs, **info}.items():
            seen.setdefault(key, []).append(np.asarray(value, dtype=np.float64))
    env.close()
    return {key: np.array(values) for key, values in seen.items()}


def _all_finite(outputs: dict) -> list[str]:
    return [key for key, value in outputs.items() if not np.isfinite(value).all()]


def test_the_scene_extent_and_the_measurement_quality_range():
    points = np.concatenate([BASE.tx_positions, BASE.rx_positions, [BASE.targets[0].initial_state[[0, 2]]]])
    spread = max(np.linalg.norm(a - b) for a in points for b in points)
    assert EXTENT == pytest.approx(spread)
    low, high = BASE.measurement_quality_range()
    assert high == pytest.approx(min(5.0 / 1e-6, 0.002 / 1e-12))  # Sigma0 / lambda >= 1 mm^2, 1 urad^2
    assert low == pytest.approx(max(5.0 / EXTENT**2, 0.002 / np.pi**2))
    with pytest.raises(ValueError, match=r"measurement_quality=1e\+16 puts .* allowed: \[0.000203, 5e\+06\]"):
        gym.make("MimoRadarSelect-v1", measurement_quality=1e16)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"range_variance": 1e-7}, r"range_variance must be in \[1e-06, "),
        ({"range_variance": 2 * EXTENT**2}, r"range_variance must be in \[1e-06, "),
        ({"azimuth_variance": 10.0}, r"azimuth_variance must be in \[1e-12, 9.87\]"),
        ({"process_noise": 1e30}, r"process_noise must be in \[0, "),
        ({"sample_time": 1e-4}, r"sample_time must be in \[0.001, 1e\+06\] \(s\), got 0.0001"),
        ({"sample_time": 1e5, "process_noise": 0.0}, r"moves 1.41e\+07 m in one sample_time of 100000 s"),
        ({"tx_positions": [[1e200, 0.0], [0, 1], [1, 0], [1, 1]]}, r"tx_positions must lie within 1e\+08 m"),
    ],
)
def test_fields_beyond_their_physical_range_are_refused(changes, message):
    with pytest.raises(ScenarioError, match=message):
        BASE.replace(**changes)


def test_an_initial_covariance_beyond_its_range_is_refused():
    for variances in ([1e-21] * 4, [EXTENT**3] * 4):
        targets = BASE.to_dict()["targets"]
        targets[0]["initial_covariance"] = variances
        with pytest.raises(ScenarioError, match=r"initial_covariance must have eigenvalues in \[1e-06, "):
            BASE.replace(targets=targets)
    targets[0]["initial_covariance"] = [1e-6, 1.0, 1.0, 1e7]
    with pytest.raises(ScenarioError, match=r"from 1e-06 to 1e\+07: a condition number above 1e\+12"):
        BASE.replace(targets=targets)


def test_the_guard_repairs_only_what_is_broken():
    rng = np.random.default_rng(0)
    root = rng.normal(size=(5, 4, 4))
    healthy = root @ np.swapaxes(root, -1, -2) + np.eye(4)
    broken = healthy.copy()
    broken[1] -= 2 * np.linalg.eigvalsh(healthy[1])[0] * np.eye(4)  # one negative eigenvalue
    broken[3] = np.diag([1.0, 1e-15, 1.0, 1.0])  # positive definite, condition 1e15
    fixed, repaired = repair_covariance(broken)
    assert repaired.tolist() == [False, True, False, True, False]
    np.testing.assert_array_equal(fixed[~repaired], broken[~repaired])  # untouched, bit for bit
    for matrix in fixed[repaired]:
        eigenvalues = np.linalg.eigvalsh(matrix)
        # the floor is 1e-12 of the largest eigenvalue, up to the rounding of rebuilding the matrix
        assert eigenvalues.min() > 0 and eigenvalues.max() / eigenvalues.min() <= 1.01e12
    same, none = repair_covariance(healthy)
    assert not none.any() and same is healthy


@pytest.mark.parametrize("fusion", ["average", "centralized"])
def test_a_healthy_run_repairs_nothing(fusion):
    outputs = _episode(BASE, fusion)
    assert _all_finite(outputs) == [] and outputs["tracker_repairs"].max() == 0


@pytest.mark.parametrize("fusion", ["average", "centralized"])
@pytest.mark.parametrize(
    "edge",
    ["measurement_quality", "process_noise", "initial_covariance", "range_variance"],
)
def test_the_edges_of_the_ranges_give_finite_outputs(edge, fusion):
    """Where the previous tracker failed (a prior far wider than the measurements): the guard
    repairs in the trial and target alone, counts it, and nothing non-finite comes out."""
    scenario, options = BASE, {}
    if edge == "measurement_quality":
        options["measurement_quality"] = BASE.measurement_quality_range()[1]
    elif edge == "process_noise":
        scenario = BASE.replace(process_noise=3 * EXTENT**2)
    elif edge == "range_variance":
        scenario = BASE.replace(range_variance=1e-6)
    else:
        targets = BASE.to_dict()["targets"]
        targets[0]["initial_covariance"] = [EXTENT**2] * 4
        scenario = BASE.replace(targets=targets)
    outputs = _episode(scenario, fusion, **options)
    assert _all_finite(outputs) == []
    assert np.all(np.diff(outputs["tracker_repairs"], axis=0) >= 0)  # a count per episode


def _edge(low: float, high: float) -> st.SearchStrategy[float]:
    """The ends of a range, and values spread log-uniformly between them (``10**log10(x)`` can
    round one ulp past an end: such a value is the end itself)."""
    inner = st.floats(np.log10(low), np.log10(high)).map(lambda e: min(max(float(10.0**e), low), high))
    return st.one_of(st.sampled_from([low, high]), inner)


@st.composite
def edge_scenarios(draw):
    step = draw(_edge(1e-3, 10.0))
    changes = {
        "sample_time": step,
        "range_variance": draw(_edge(1e-6, EXTENT**2)),
        "azimuth_variance": draw(_edge(1e-12, float(np.pi**2))),
        "process_noise": draw(st.one_of(st.just(0.0), _edge(1e-9, 3 * EXTENT**2 / step**3))),
    }
    targets = BASE.to_dict()["targets"]
    smallest = draw(_edge(1e-6, EXTENT**2))  # and the others within the condition number allowed
    variances = [draw(_edge(smallest, min(EXTENT**2, 1e12 * smallest))) for _ in range(3)]
    targets[0]["initial_covariance"] = [smallest, *variances]
    return BASE.replace(targets=targets, **changes)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(edge_scenarios(), st.sampled_from(["average", "centralized"]))
def test_scenarios_at_the_edges_of_their_ranges_run_finite(scenario, fusion):
    assert _all_finite(_episode(scenario, fusion, steps=25, trials=3)) == []


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(edge_scenarios(), st.sampled_from(["average", "centralized"]))
def test_scenarios_at_the_edges_of_their_ranges_run_finite_many(scenario, fusion):
    assert _all_finite(_episode(scenario, fusion, steps=60, trials=4)) == []


def test_an_edge_scenario_whose_bound_once_divided_by_zero_runs_finite():
    """Found by the slow test's random examples: the compiled bound divided by a zero
    determinant (ZeroDivisionError out of the env's step) instead of handing the matrix to the
    numpy path's repair."""
    targets = BASE.to_dict()["targets"]
    targets[0]["initial_covariance"] = [1e-6] * 4
    scenario = BASE.replace(
        targets=targets,
        sample_time=6.493816315762113,
        process_noise=130100273.37380923,
        range_variance=1e-6,
        azimuth_variance=1e-12,
    )
    assert _all_finite(_episode(scenario, "average", steps=60, trials=4)) == []
