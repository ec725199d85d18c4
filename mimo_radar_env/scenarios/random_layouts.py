"""Random layouts, for studies beyond the paper's arrays."""

from __future__ import annotations

import numpy as np

from . import validation as check
from .scenario import MAX_HORIZON, MAX_POSITION, MAX_STATIONS, Scenario
from .validation import ScenarioError

#: The most targets of a random layout.
MAX_RANDOM_TARGETS = 100


def random_scenario(
    num_tx: int,
    num_rx: int,
    num_targets: int,
    tx_per_step: int,
    rx_per_step: int,
    horizon: int = 1000,
    seed: int = 0,
    extent: float = 100e3,
) -> Scenario:
    """A random layout for studies beyond the paper's arrays.

    Stations uniform in an ``extent`` x ``extent`` square (metres), targets starting in its
    central 60 % with random headings and speeds of 50-150 m/s; every other target (the
    1st, 3rd...) turns at -3 deg/s for 30 steps from ``horizon // 3`` when the horizon
    allows. Every other field keeps the paper's value. A draw whose track passes too close to
    a station (``MIN_STATION_DISTANCE``) is replaced by the generator's next draw. At most
    ``MAX_STATIONS`` transmitters and receivers and ``MAX_RANDOM_TARGETS`` targets.
    """
    for name, value, high, what in (
        ("num_tx", num_tx, MAX_STATIONS, "transmitters"),
        ("num_rx", num_rx, MAX_STATIONS, "receivers"),
        ("num_targets", num_targets, MAX_RANDOM_TARGETS, "targets"),
        ("horizon", horizon, MAX_HORIZON, "steps"),
    ):
        check.integer_in(name, value, 1, high, f"a number of {what}")
    check.integer_in("seed", seed, 0, 2**63 - 1, "a seed")
    if not 0 < check.number("extent", extent) <= MAX_POSITION:
        raise ScenarioError(f"extent must be in (0, {MAX_POSITION:g}] m, got {extent!r}")
    rng = np.random.default_rng(seed)
    for _ in range(100):
        try:
            return _draw(rng, num_tx, num_rx, num_targets, tx_per_step, rx_per_step, horizon, extent)
        except ScenarioError as exc:
            if "from every station" not in str(exc):
                raise
    raise ScenarioError(
        f"no random layout in 100 draws keeps every track away from the stations (seed {seed})"
    )


def _draw(
    rng: np.random.Generator,
    num_tx: int,
    num_rx: int,
    num_targets: int,
    tx_per_step: int,
    rx_per_step: int,
    horizon: int,
    extent: float,
) -> Scenario:
    start = horizon // 3
    targets = []
    for k in range(num_targets):
        heading, speed = rng.uniform(0, 2 * np.pi), rng.uniform(50, 150)
        turn = k % 2 == 0 and start + 30 <= horizon
        targets.append(
            {
                "initial_state": [
                    rng.uniform(0.2 * extent, 0.8 * extent),
                    speed * np.cos(heading),
                    rng.uniform(0.2 * extent, 0.8 * extent),
                    speed * np.sin(heading),
                ],
                "maneuvers": [{"turn_rate_deg": -3.0, "start": start, "stop": start + 30}] if turn else [],
            }
        )
    return Scenario.from_dict(
        {
            "name": f"random-{num_tx}x{num_rx}-K{num_targets}",
            "tx_positions": rng.uniform(0, extent, (num_tx, 2)).tolist(),
            "rx_positions": rng.uniform(0, extent, (num_rx, 2)).tolist(),
            "tx_per_step": tx_per_step,
            "rx_per_step": rx_per_step,
            "targets": targets,
            "horizon": horizon,
        }
    )
