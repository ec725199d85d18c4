"""What an env costs before it runs: its memory and arithmetic per trial, roughly (upper
estimates the harness sizes shards and estimates times with), and the check that refuses an
env larger than the machine."""

from __future__ import annotations

import math

from ..core.superarm import AUTO_EXACT_SUBSETS, search_operations, search_seconds
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


#: Seconds per declared operation of the channel draws and of the tracker (its compiled update
#: and bound) on the developers' machine, fitted to ``benchmarks.speed.policy_cost``'s
#: measurements at 4 and 50 trials; the oracle's search runs at its method's
#: (:data:`~mimo_radar_env.core.superarm.SEARCH_SECONDS_PER_OPERATION`).
SECONDS_PER_OPERATION = {"channels": 1.6e-10, "tracker": 4.3e-10}
#: Of the tracker's time, seconds per declared operation of the fusion's compiled update (its
#: kernel alone runs faster than the tracker's numpy parts): the average fusion's kernel on one
#: thread, ``paper-1-v1`` at 500 trials, on the developers' machine.
COMPILED_UPDATE_SECONDS_PER_OPERATION = 2.7e-10


def operation_parts(
    scenario: Scenario, tracking: bool = True, fusion: str = DEFAULT_FUSION
) -> dict[str, float]:
    """Arithmetic operations one trial of an env of ``scenario`` does per step, roughly (upper
    estimates), by part: ``"channels"``, the channel draws and SINR of all ``K M N``
    target-channels; ``"search"``, the oracle's search of the optimal super arm; ``"tracker"``,
    with ``tracking``, the IMM-UKF's update of the ``Ms Ns`` probed channels by ``fusion``
    (:meth:`~mimo_radar_env.tracking.fusion.Fusion.update_operations`) and the bound's
    recursion (0 without)."""
    sc = scenario
    K, M, N = sc.num_targets, sc.num_tx, sc.num_rx
    channels = sc.tx_per_step * sc.rx_per_step
    tracker = 0.0
    if tracking:
        update = fusion_class(fusion).update_operations(channels)
        tracker = K * (MODELS * (update + 3000) + channels * 200 + 2000)
    return {
        "channels": 60.0 * K * M * N,
        "search": float(search_operations(M, N, sc.tx_per_step, sc.rx_per_step)),
        "tracker": float(tracker),
    }


def operations_per_trial_step(
    scenario: Scenario, tracking: bool = True, fusion: str = DEFAULT_FUSION
) -> float:
    """Arithmetic operations one trial of an env of ``scenario`` does per step, roughly: the sum
    of :func:`operation_parts` (sizes runs in time as :func:`memory_parts` sizes them in
    memory)."""
    return sum(operation_parts(scenario, tracking, fusion).values())


def seconds_per_trial_step(scenario: Scenario, tracking: bool = True, fusion: str = DEFAULT_FUSION) -> float:
    """One trial's share of a step's time on the developers' machine, roughly: each part of
    :func:`operation_parts` at its rate (:data:`SECONDS_PER_OPERATION`, the search's
    :func:`~mimo_radar_env.core.superarm.search_seconds`)."""
    parts = operation_parts(scenario, tracking, fusion)
    sc = scenario
    search = search_seconds(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
    return search + sum(SECONDS_PER_OPERATION[part] * parts[part] for part in ("channels", "tracker"))


def threaded_seconds_per_trial_step(
    scenario: Scenario, tracking: bool = True, fusion: str = DEFAULT_FUSION
) -> float:
    """The part of :func:`seconds_per_trial_step` that a task's threads share: the fusion's
    compiled update, whose kernel spreads chunks of trials over numba's threads (0 without the
    tracker or where the fusion's update is not compiled)."""
    if not tracking:
        return 0.0
    sc = scenario
    channels = sc.tx_per_step * sc.rx_per_step
    kind = fusion_class(fusion)
    if not kind.compiled_update(channels):
        return 0.0
    operations = sc.num_targets * MODELS * kind.update_operations(channels)
    return min(
        COMPILED_UPDATE_SECONDS_PER_OPERATION * operations, seconds_per_trial_step(sc, tracking, fusion)
    )


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
