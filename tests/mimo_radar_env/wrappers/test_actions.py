"""The Flat env's actions, single and vector, Discrete and per-station scores (hypothesis): a
valid action steps; anything else is refused by one ``ValueError`` of one line that shows the
value as given, and the env is unchanged (the next valid step gives what it would have)."""

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mimo_radar_env  # noqa: F401  (registers the envs)

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
