"""Helpers shared by the tests."""

import numpy as np


def random_valid_actions(rng: np.random.Generator, batch: int, num_tx: int, num_rx: int, ms: int, ns: int):
    """Uniformly random valid super arms as (B, M + N) int8 actions."""
    tx = np.argsort(rng.random((batch, num_tx)), axis=1)[:, :ms]
    rx = np.argsort(rng.random((batch, num_rx)), axis=1)[:, :ns]
    action = np.zeros((batch, num_tx + num_rx), dtype=np.int8)
    np.put_along_axis(action, tx, 1, axis=1)
    np.put_along_axis(action, num_tx + rx, 1, axis=1)
    return action


def large_scenario(
    num_tx: int = 16,
    num_rx: int = 16,
    num_targets: int = 5,
    tx_per_step: int = 4,
    rx_per_step: int = 4,
    horizon: int = 1000,
    seed: int = 0,
):
    """A random layout of ``num_tx`` x ``num_rx`` stations and ``num_targets`` targets in 100 km x 100 km."""
    from mimo_radar_env import Scenario

    rng = np.random.default_rng(seed)
    targets = []
    for k in range(num_targets):
        heading = rng.uniform(0, 2 * np.pi)
        speed = rng.uniform(50, 150)
        maneuvers = (
            [{"turn_rate_deg": 3.0 if k % 2 else -3.0, "start": horizon // 3, "stop": horizon // 3 + 30}]
            if k % 2 == 0 or k == 1
            else []
        )
        targets.append(
            {
                "initial_state": [
                    rng.uniform(20e3, 80e3),
                    speed * np.cos(heading),
                    rng.uniform(20e3, 80e3),
                    speed * np.sin(heading),
                ],
                "initial_covariance": [20.0] * 4,
                "maneuvers": maneuvers if horizon > horizon // 3 + 30 else [],
            }
        )
    return Scenario.from_dict(
        {
            "name": f"random-{num_tx}x{num_rx}-K{num_targets}",
            "tx_positions": rng.uniform(0, 100e3, size=(num_tx, 2)).tolist(),
            "rx_positions": rng.uniform(0, 100e3, size=(num_rx, 2)).tolist(),
            "tx_per_step": tx_per_step,
            "rx_per_step": rx_per_step,
            "targets": targets,
            "weights": (np.ones(num_targets) / num_targets).tolist(),
            "horizon": horizon,
        }
    )
