"""The Flat env's actions, single and vector, Discrete and per-station scores (hypothesis): a
valid action steps; anything else is refused by one ``ValueError`` of one line that shows the
value as given, and the env is unchanged (the next valid step gives what it would have)."""

import math
from itertools import combinations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mimo_radar_env  # noqa: F401  (registers the envs)
from mimo_radar_env.wrappers import StationScoreAction, SuperArmDiscreteAction, make_ppo_env
from tests.helpers import large_scenario

ODD = [
    3.0, "3", True, False, None, np.nan, np.inf, -np.inf, -1, 120, 10**20, 2.5, [3], (3,), [], "x",
    np.float32(3.0), np.bool_(True), np.array(3.0), np.array([3, 4]), b"3", complex(3, 0),
]  # fmt: skip
SCALARS = st.one_of(
    st.sampled_from(ODD),
    st.integers(-200, 200),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=4),
)


def _valid_discrete(action) -> bool:
    return (
        isinstance(action, int | np.integer) and not isinstance(action, bool | np.bool_) and 0 <= action < 120
    )


def _one_line_refusal(excinfo, action) -> None:
    message = str(excinfo.value)
    assert "\n" not in message, message
    assert repr(action)[:20] in message or str(action)[:20] in message or "shape" in message, message


@settings(max_examples=80, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(SCALARS)
def test_a_discrete_action_steps_or_is_refused_in_one_line(action):
    env = gym.make("MimoRadarSelectFlat-v1")
    env.reset(seed=0)
    if _valid_discrete(action):
        env.step(action)
        return
    with pytest.raises(ValueError) as excinfo:
        env.step(action)
    _one_line_refusal(excinfo, action)
    # refused before anything moved: the next valid step is the first step of the episode
    reference = gym.make("MimoRadarSelectFlat-v1")
    reference.reset(seed=0)
    assert np.array_equal(env.step(7)[0], reference.step(7)[0])


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(SCALARS, min_size=0, max_size=4))
def test_a_vector_of_discrete_actions_steps_or_is_refused_in_one_line(actions):
    envs = gym.make_vec("MimoRadarSelectFlat-v1", num_envs=3, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    if len(actions) == 3 and all(_valid_discrete(a) for a in actions):
        envs.step(np.array(actions))
        return
    with pytest.raises(ValueError) as excinfo:
        envs.step(actions)
    assert "\n" not in str(excinfo.value), str(excinfo.value)


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=32), min_size=10, max_size=10))
def test_station_scores_outside_the_box_are_refused_showing_the_value(scores):
    env = gym.make("MimoRadarSelectFlat-v1", action="scores")
    env.reset(seed=0)
    action = np.array(scores, dtype=np.float32)
    if np.all(np.isfinite(action)) and np.all(np.abs(action) <= 1):
        env.step(action)
        return
    with pytest.raises(ValueError) as excinfo:
        env.step(action)
    message = str(excinfo.value)
    assert "\n" not in message
    bad = action[~(np.isfinite(action) & (np.abs(action) <= 1))][0]
    assert str(bad) in message or repr(float(bad)) in message or "nan" in message or "inf" in message, message


def test_discrete_super_arm_index_is_a_bijection():
    env = SuperArmDiscreteAction(gym.make("MimoRadarSelect-v0", scenario="paper-1"))
    assert env.action_space.n == math.comb(4, 2) * math.comb(6, 3) == 120
    actions = env.index.to_action(np.arange(120))
    assert (actions[:, :4].sum(axis=1) == 2).all() and (actions[:, 4:].sum(axis=1) == 3).all()
    every = {(t, r) for t in combinations(range(4), 2) for r in combinations(range(6), 3)}
    seen = {(tuple(np.flatnonzero(a[:4])), tuple(np.flatnonzero(a[4:]))) for a in actions}
    assert seen == every  # onto and, with 120 distinct images of 120 indices, one-to-one
    env.reset(seed=0)
    for i in (0, 57, 119):
        _, _, _, _, info = env.step(i)
        assert info["action_valid"]
    with pytest.raises(ValueError, match=r"super-arm index must be in \[0, 120\)"):
        env.index.to_action(120)


def test_station_scores_give_valid_selections_on_paper_and_16x16_layouts():
    rng = np.random.default_rng(0)
    for scenario in ("paper-3", large_scenario(16, 16, 5)):
        env = StationScoreAction(gym.make("MimoRadarSelect-v0", scenario=scenario))
        sc = env.unwrapped.scenario
        env.reset(seed=1)
        for _ in range(20):
            scores = rng.uniform(-1, 1, size=sc.num_tx + sc.num_rx).astype(np.float32)
            action = env.action(scores)
            assert action[: sc.num_tx].sum() == sc.tx_per_step and action[sc.num_tx :].sum() == sc.rx_per_step
            top_tx = np.argsort(-scores[: sc.num_tx])[: sc.tx_per_step]
            assert set(np.flatnonzero(action[: sc.num_tx])) == set(top_tx)
            assert env.step(scores)[4]["action_valid"]
        env.step(np.zeros(sc.num_tx + sc.num_rx, dtype=np.float32))  # ties resolve to a valid selection
    with pytest.raises(ValueError, match="use StationScoreAction"):
        SuperArmDiscreteAction(gym.make("MimoRadarSelect-v0", scenario=large_scenario(16, 16, 5)))
    assert isinstance(make_ppo_env(large_scenario(16, 16, 5)).env, StationScoreAction)
    assert isinstance(make_ppo_env("paper-1-v1").env, SuperArmDiscreteAction)


def test_make_ppo_env_takes_only_the_env_ids_it_wraps():
    """Another id failed inside its env's constructor (CartPole: "unexpected keyword argument
    'scenario'"), and a Flat id would have wrapped the learning wrappers twice."""
    for other in ("CartPole-v1", "MimoRadarSelectFlat-v1"):
        with pytest.raises(
            ValueError,
            match=rf"env_id must be one of \['MimoRadarSelect-v0', 'MimoRadarSelect-v1'\], got '{other}'",
        ):
            make_ppo_env(env_id=other)
    assert make_ppo_env(env_id="MimoRadarSelect-v0").unwrapped.options.lambda_scale == "linear"
