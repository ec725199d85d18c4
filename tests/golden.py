"""Reference numbers of MimoRadarSelect-v0 and -v1 (docs/performance.md, "No result changes").

``python -m tests.golden`` rewrites tests/data/golden.npz (v0) and golden_v1.npz (v1); only do
that for an intended change of results, never to make a fast path pass (and never for v0,
whose numbers are a promise).
"""

from pathlib import Path

import numpy as np

import agents
import mimo_radar_env
from benchmarks.settings import paper_study_params
from tests.helpers import vector_env

GOLDEN = Path(__file__).with_name("data") / "golden.npz"
GOLDEN_V1 = Path(__file__).with_name("data") / "golden_v1.npz"


def record() -> dict[str, np.ndarray]:
    out = {}
    for scenario, fusion in (("paper-3", "average"), ("paper-2", "centralized")):
        venv = vector_env(
            "MimoRadarSelect-v0",
            6,
            scenario=scenario,
            fusion=fusion,
        )
        for name in ("mg-crb-cl", "ucb1"):
            agent = agents.make_agent(name, venv.scenario, seed=4)
            tracks, rewards, actions = [], [], []
            for step in agents.Rollout(agent, venv, seed=11).run(120):
                tracks.append(step.obs["track"])
                rewards.append(step.reward)
                actions.append(step.action)
            key = f"{scenario}_{fusion}_{name}"
            out[f"{key}_track"] = np.array(tracks)
            out[f"{key}_reward"] = np.array(rewards)
            out[f"{key}_action"] = np.array(actions)
    return out


def record_v1() -> dict[str, np.ndarray]:
    """v1 (its calibrated layout, dB eq32, shared truth) with its paper-study agent parameters,
    both fusions, and the per-step position bound."""
    version = mimo_radar_env.VERSIONS["v1"]
    out = {}
    for scenario, fusion in (("paper-1-v1", "centralized"), ("paper-3-v1", "average")):
        venv = vector_env(
            version.env_id,
            5,
            scenario=scenario,
            fusion=fusion,
        )
        params = paper_study_params("v1")
        for name in ("mg-crb-cl", "epsilon-greedy"):
            agent = agents.make_agent(name, venv.scenario, seed=7, **params.get(name, {}))
            recorded: dict[str, list] = {"track": [], "reward": [], "action": [], "bound": []}
            for step in agents.Rollout(agent, venv, seed=3).run(80):
                recorded["track"].append(step.obs["track"])
                recorded["reward"].append(step.reward)
                recorded["action"].append(step.action)
                recorded["bound"].append(step.info["position_bound"])
            for key, values in recorded.items():
                out[f"{scenario}_{fusion}_{name}_{key}"] = np.array(values)
    return out


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **record())
    np.savez_compressed(GOLDEN_V1, **record_v1())
    print(f"wrote {GOLDEN} and {GOLDEN_V1}")
