"""The env benchmark: its numpy reference computes what the compiled path does, and leaves the env
as it found it."""

import numpy as np

from benchmarks.speed import env_throughput
from mimo_radar_env.core.superarm import random_super_arms
from mimo_radar_env.envs import engine as engine_module
from tests.helpers import vector_env


def _episode(venv, steps=4):
    sc = venv.scenario
    rng = np.random.default_rng(1)
    obs, _ = venv.reset(seed=3)
    out = []
    for _ in range(steps):
        action = random_super_arms(rng, 3, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        obs, reward, *_, info = venv.step(action)
        out.append((obs["track"].copy(), info["position_bound"].copy(), reward.copy()))
    return out


def test_the_numpy_reference_is_the_same_computation_and_is_undone():
    for fusion in ("average", "centralized"):
        venv = vector_env("MimoRadarSelect-v1", 3, fusion=fusion)
        compiled = _episode(venv)
        bound_step, use_numba = engine_module.bound_step, venv.engine.tracker.fusion.use_numba
        with env_throughput.numpy_paths(venv):
            assert venv.engine.tracker.fusion.use_numba is False
            reference = _episode(venv)
        assert engine_module.bound_step is bound_step
        assert venv.engine.tracker.fusion.use_numba is use_numba
        for (track, bound, reward), (track_np, bound_np, reward_np) in zip(compiled, reference, strict=True):
            np.testing.assert_allclose(track, track_np, rtol=1e-9)
            np.testing.assert_allclose(bound, bound_np, rtol=1e-9)
            np.testing.assert_array_equal(reward, reward_np)


def test_a_rate_is_trial_steps_over_the_timed_steps(monkeypatch):
    clock = iter([10.0, 12.0])  # two seconds for the timed steps
    monkeypatch.setattr(env_throughput.time, "perf_counter", lambda: next(clock))
    rate = env_throughput.measure("paper-1-v1", trials=5, steps=9, tracking=True)
    assert rate == 5 * 8 / 2.0  # the first step is a warm-up, not timed
