"""Reference numbers of MimoRadarSelect-v0 (docs/performance.md, "No result changes").

``python -m tests.golden`` rewrites tests/data/golden.npz; only do that for an intended
change of results, never to make a fast path pass.
"""

from pathlib import Path

import gymnasium as gym
import numpy as np

import agents
import mimo_radar_env  # noqa: F401

GOLDEN = Path(__file__).with_name("data") / "golden.npz"


def record() -> dict[str, np.ndarray]:
    out = {}
    for scenario, fusion in (("paper-3", "average"), ("paper-2", "centralized")):
        venv = gym.make_vec(
            "MimoRadarSelect-v0",
            num_envs=6,
            vectorization_mode="vector_entry_point",
            scenario=scenario,
            fusion=fusion,
        )
        for name in ("mg-crb-cl", "ucb1"):
            agent = agents.make_agent(name, venv.scenario, seed=4)
            obs, _ = venv.reset(seed=11)
            agent.reset(obs)
            tracks, rewards, actions = [], [], []
            for _ in range(120):
                action = agent.act(obs)
                obs, reward, _, _, info = venv.step(action)
                agent.update(obs, reward)
                tracks.append(obs["track"])
                rewards.append(reward)
                actions.append(action)
            key = f"{scenario}_{fusion}_{name}"
            out[f"{key}_track"] = np.array(tracks)
            out[f"{key}_reward"] = np.array(rewards)
            out[f"{key}_action"] = np.array(actions)
    return out


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **record())
    print(f"wrote {GOLDEN}")
