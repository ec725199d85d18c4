"""Rendering: the scene drawn as an image, and the human mode without a display."""

import gymnasium as gym
import numpy as np
import pytest


def test_rgb_array_rendering_draws_the_scene():
    env = gym.make("MimoRadarSelect-v0", scenario="paper-3", render_mode="rgb_array")
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.unwrapped.oracle_action())
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 10  # not a blank canvas
    # the selected channels are drawn: the frame changes with the selection
    env2 = gym.make("MimoRadarSelect-v0", scenario="paper-3", render_mode="rgb_array")
    env2.reset(seed=0)
    for _ in range(3):
        env2.step(np.array([0, 0, 1, 1, 0, 0, 0, 1, 1, 1], dtype=np.int8))
    assert not np.array_equal(env2.render(), frame)


def test_human_rendering_runs_headless_and_says_it_shows_nothing():
    env = gym.make("MimoRadarSelect-v0", render_mode="human")  # Agg in tests: draws, shows nothing
    with pytest.warns(UserWarning, match="render_mode='human' shows nothing here"):
        env.reset(seed=0)
    env.step(env.unwrapped.oracle_action())
    assert env.unwrapped._figure is not None
    env.close()
    assert env.unwrapped._figure is None


def test_an_unknown_render_mode_is_named_with_the_allowed_ones():
    with pytest.raises(
        ValueError, match=r"render_mode must be one of \['human', 'rgb_array'\] or None, got 'ansi'"
    ):
        gym.make("MimoRadarSelect-v1", render_mode="ansi")
