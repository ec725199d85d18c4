"""What an env costs before it runs: its memory and arithmetic per trial, roughly (upper
estimates the harness sizes shards and estimates times with), and the check that refuses an
env larger than the machine."""

from __future__ import annotations

import math

from ..core.superarm import AUTO_EXACT_SUBSETS, search_operations
from ..scenarios import Scenario
from ..tracking.fusion import DEFAULT_FUSION, fusion_class
from ..tracking.fusion.base import MODELS


def memory_estimate(scenario: Scenario, batch_size: int) -> int:
    """Bytes an env of ``batch_size`` trials of ``scenario`` needs, roughly (an upper estimate).

    The model keeps per-step matrices (K, T, 4, 4) and trajectories; each trial keeps channel
    arrays (K, M, N) and the tracker's per-target, per-model sigma points and covariances.
    """
    model, per_trial = memory_parts(scenario)
    return model + batch_size * per_trial


def memory_parts(scenario: Scenario) -> tuple[int, int]:
    """Bytes an env of ``scenario`` needs, roughly (upper estimates): once (the model's per-step
    arrays) and per trial (channel arrays, the tracker's sigma points and covariances)."""
    sc = scenario
    K, M, N, T = sc.num_targets, sc.num_tx, sc.num_rx, sc.horizon
    channels = sc.tx_per_step * sc.rx_per_step
    model = 8 * K * (T + 1) * (16 + 4)
    per_trial = 8 * K * (12 * M * N + 3 * (9 * 4 + 4 * 4) * (channels + 2) * 4)
    subsets = min(math.comb(M, sc.tx_per_step), math.comb(N, sc.rx_per_step))
    if subsets <= AUTO_EXACT_SUBSETS:  # the oracle's exact search of every step (info["optimal_reward"])
        per_trial += 8 * 3 * subsets * max(M, N)
    return model, per_trial


def operations_per_trial_step(
    scenario: Scenario, tracking: bool = True, fusion: str = DEFAULT_FUSION
) -> float:
    """Arithmetic operations one trial of an env of ``scenario`` does per step, roughly (an
    upper estimate, to size runs in time as :func:`memory_parts` sizes them in memory): the
    channel draws and SINR of all ``K M N`` target-channels, the oracle's search of the
    optimal super arm, and, with ``tracking``, the IMM-UKF's update of the ``Ms Ns`` probed
    channels by ``fusion`` (:meth:`~mimo_radar_env.tracking.fusion.Fusion.update_operations`)
    and the bound's recursion."""
    sc = scenario
    K, M, N = sc.num_targets, sc.num_tx, sc.num_rx
    channels = sc.tx_per_step * sc.rx_per_step
    operations = 60.0 * K * M * N + search_operations(M, N, sc.tx_per_step, sc.rx_per_step)
    if not tracking:
        return operations
    update = fusion_class(fusion).update_operations(channels)
    bound = channels * 200 + 2000
    return operations + K * (MODELS * (update + 3000) + bound)


def machine_memory() -> int | None:
    """This machine's physical memory in bytes (None where the platform does not say)."""
    import os

    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return None


def check_memory(scenario: Scenario, batch_size: int, fraction: float = 0.5) -> None:
    """Refuse, before allocating, an env that needs more than ``fraction`` of this machine's memory."""
    available = machine_memory()
    if available is None:  # pragma: no cover - not POSIX
        return
    need = memory_estimate(scenario, batch_size)
    if need > fraction * available:
        raise ValueError(
            f"{batch_size} trials of scenario {scenario.name!r} (horizon {scenario.horizon}, "
            f"{scenario.num_tx} x {scenario.num_rx} stations, {scenario.num_targets} targets) need about "
            f"{need / 2**30:.1f} GiB; this machine has {available / 2**30:.1f} GiB: use fewer trials, "
            "a shorter horizon or a smaller layout"
        )
