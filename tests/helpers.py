"""Helpers shared by the tests."""

import re
from pathlib import Path

import numpy as np

from mimo_radar_env import random_scenario
from mimo_radar_env.core.superarm import random_super_arms


def needs_torch_compiler():
    """A mark that skips a test of the compiled form where this torch's compiler cannot keep eager's
    numbers, as that form then refuses (``mimo_radar_env.envs.device_forms.COMPILE_TORCH``)."""
    import pytest

    from mimo_radar_env.envs.device_forms import COMPILE_TORCH, missing_compile_options

    missing = missing_compile_options()
    return pytest.mark.skipif(bool(missing), reason=f"the compiled form needs torch {COMPILE_TORCH} or later")


def random_valid_actions(rng: np.random.Generator, batch: int, num_tx: int, num_rx: int, ms: int, ns: int):
    """Uniformly random valid super arms as (B, M + N) int8 actions."""
    return random_super_arms(rng, batch, num_tx, num_rx, ms, ns)


def large_scenario(num_tx=16, num_rx=16, num_targets=5, tx_per_step=4, rx_per_step=4, horizon=1000, seed=0):
    """A random layout of ``num_tx`` x ``num_rx`` stations and ``num_targets`` targets in 100 km x 100 km."""
    return random_scenario(num_tx, num_rx, num_targets, tx_per_step, rx_per_step, horizon=horizon, seed=seed)


def vector_env(env_id: str, num_envs: int, **kwargs):
    """``gym.make_vec`` of a registered id through its native vector entry point (B trials as
    one batch)."""
    import gymnasium as gym

    return gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs)


def bandit_obs(sinr, probed, track=None, track_pred=None):
    """An agent's observation written by hand: the SINR, the probed mask and, where given, the
    tracks and their predictions."""
    obs = {"sinr": np.asarray(sinr, dtype=float), "probed": np.asarray(probed, dtype=np.int8)}
    if track is not None:
        obs["track"] = np.asarray(track, dtype=float)
        obs["track_pred"] = np.asarray(track_pred, dtype=float)
    return obs


#: The keys of every policy's row of a run's summary.json.
SUMMARY_KEYS = {
    "ci",
    "tracker_repairs",
    "method",
    "armse",
    "armse_per_target",
    "bound",
    "bound_per_target",
    "armse_over_bound",
    "asr",
    "final_regret",
    "mean_sinr_db",
    "wall_s",
}


def reset_simulation(model, batch: int, rng: np.random.Generator, **options):
    """A RadarSimulation of ``batch`` trials of ``model``, reset with keys drawn from ``rng``."""
    from mimo_radar_env.core.simulation import RadarSimulation
    from mimo_radar_env.core.streams import keys_from_generator

    sim = RadarSimulation(model, batch, **options)
    sim.reset(np.stack([keys_from_generator(rng) for _ in range(batch)]))
    return sim


def simulation(scenario, batch: int, seed: int = 0, **options):
    """The model of ``scenario`` (a name or a Scenario) and a simulation of ``batch`` trials of it,
    reset with keys drawn from ``seed`` (:func:`reset_simulation`)."""
    from mimo_radar_env import RadarModel, load_scenario

    model = RadarModel.from_scenario(load_scenario(scenario))
    return model, reset_simulation(model, batch, np.random.default_rng(seed), **options)


class StandInGraph:
    """What a CUDA graph does, on the CPU (``device_forms.cuda_graph``'s contract): capturing runs
    only the warm-up; each replay runs the body and leaves its outputs in the same tensors as the
    first replay (a graph's fixed buffers)."""

    def __init__(self, body, warm_up):
        warm_up()
        self.body = body
        self.outputs = None

    def replay(self):
        import torch

        fresh = self.body()
        if self.outputs is None:
            self.outputs = fresh
        else:
            torch.utils._pytree.tree_map(lambda old, new: old.copy_(new), self.outputs, fresh)
        return self.outputs


def readme_demo_table() -> str:
    """The table the README shows ``mimo-radar-bench demo`` printing."""
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    return re.search(r"mimo-radar-bench demo\n```\n.*?```text\n(.*?)```", text, re.DOTALL).group(1).strip()
