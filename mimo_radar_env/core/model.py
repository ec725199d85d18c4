"""The radar model of a scenario: every constant the simulation needs, computed once.

:class:`RadarModel` turns a :class:`~mimo_radar_env.scenario.Scenario` into
arrays: station positions, the per-channel SINR gain including the scenario
constant ``C`` (docs/model.md, section 4), the per-target minimum SINR of eq32, the maneuver
transition matrices and the noise-free nominal trajectories.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..scenarios import Scenario, ScenarioError, turn_rate_schedule
from .geometry import squared_range_products
from .motion import noise_gain, nominal_trajectories, process_covariance, transition_matrix
from .superarm import AUTO_EXACT_SUBSETS, search_operations

#: eq32: the lower end of the measurement-quality factor lambda.
LAMBDA_FLOOR = 0.2


@dataclass(frozen=True)
class RadarModel:
    """Constants of a scenario's radar model (all lengths in metres).

    Attributes
    ----------
    tx, rx : arrays (M, 2), (N, 2)
    gain : array (K, M, N)
        ``C * psi * P_m / (sigma_noise^2 + sigma_int_n^2)``: the mean SINR is
        ``gain / (R_tx R_rx)^2`` (eq5 with the scenario constant ``C``).
    sinr_constant : float
        the scenario constant ``C``: the largest noise-free mean SINR is ``S_max``.
    min_sinr : array (K,)
        ``S_min_k`` of eq32, from the nominal trajectory of target k.
    transitions : array (K, T, 4, 4)
        ``F`` of the transition ``t -> t+1`` for each target.
    nominal : array (K, T+1, 4)
        Noise-free trajectories from the initial estimates.
    """

    scenario: Scenario
    tx: NDArray[np.float64]
    rx: NDArray[np.float64]
    gain: NDArray[np.float64]
    sinr_constant: float
    min_sinr: NDArray[np.float64]
    transitions: NDArray[np.float64]
    nominal: NDArray[np.float64]
    process_cov: NDArray[np.float64]
    noise_gain: NDArray[np.float64]
    initial_states: NDArray[np.float64]
    initial_cov_sqrt: NDArray[np.float64]

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> RadarModel:
        sc = scenario
        transitions = transition_matrix(turn_rate_schedule(sc), sc.sample_time)
        initial_states = np.stack([t.initial_state for t in sc.targets])
        nominal = nominal_trajectories(initial_states, transitions)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            raw_gain = (
                sc.rcs * sc.tx_power[None, :, None] / (sc.noise_power + sc.interference_power[None, None, :])
            )
            raw_max, raw_min = _sinr_extremes(raw_gain, sc.tx_positions, sc.rx_positions, nominal)
            constant = sc.peak_sinr / raw_max.max()
            scaled_gain = constant * raw_gain
        if not (np.isfinite(constant) and constant > 0 and np.all(np.isfinite(scaled_gain))):
            raise ScenarioError(
                f"the SINR constant C = {constant:g} of scenario {sc.name!r} is not a finite positive "
                "number: tx_power, rcs, noise_power, interference_power or the ranges are too extreme"
            )
        return cls(
            scenario=sc,
            tx=sc.tx_positions,
            rx=sc.rx_positions,
            gain=constant * raw_gain,
            sinr_constant=float(constant),
            min_sinr=constant * raw_min,
            transitions=transitions,
            nominal=nominal,
            process_cov=process_covariance(sc.sample_time, sc.process_noise),
            noise_gain=noise_gain(sc.sample_time),
            initial_states=initial_states,
            initial_cov_sqrt=np.stack([np.linalg.cholesky(t.initial_covariance) for t in sc.targets]),
        )

    # ----------------------------------------------------------- sizes
    @property
    def num_tx(self) -> int:
        return self.tx.shape[0]

    @property
    def num_rx(self) -> int:
        return self.rx.shape[0]

    @property
    def num_targets(self) -> int:
        return self.gain.shape[0]

    @property
    def weights(self) -> NDArray[np.float64]:
        return self.scenario.weights

    # ---------------------------------------------------------- physics
    def mean_sinr(self, positions: NDArray[np.float64]) -> NDArray[np.float64]:
        """Mean SINR ``S[k, m, n]`` (eq5) for positions (..., K, 2): shape (..., K, M, N)."""
        return self.gain / squared_range_products(positions, self.tx, self.rx)

    def measurement_variance(self, quality: NDArray[np.float64]) -> NDArray[np.float64]:
        """eq32: the diagonal of ``Sigma0 / lambda`` for qualities ``lambda`` (...): shape (..., 2)."""
        return np.diagonal(self.scenario.measurement_covariance) / quality[..., None]

    def channel_weights(self, mean_sinr: NDArray[np.float64]) -> NDArray[np.float64]:
        """``sum_k Omega_k S[k, m, n]``: the expected reward of each channel, (..., M, N)."""
        return np.einsum("k,...kmn->...mn", self.weights, mean_sinr)

    def quality(
        self, sinr: NDArray[np.float64], target_axis: int = -3, scale: str = "linear"
    ) -> NDArray[np.float64]:
        """``lambda`` of eq32 from the SINR, clipped into [0.2, 1.2] (docs/model.md, section 5).

        ``target_axis`` is the axis of ``sinr`` that indexes targets. ``scale="linear"`` applies
        eq32 to linear SINRs (reading 0); ``"db"`` to SINRs in dB,
        ``(S_dB - S_min,dB) / (S_max,dB - S_min,dB) + 0.2`` (reading 1).
        """
        shape = [1] * sinr.ndim
        shape[target_axis] = self.num_targets
        s_min = self.min_sinr.reshape(shape)
        peak = self.scenario.peak_sinr
        if scale == "db":
            with np.errstate(divide="ignore"):
                sinr, s_min, peak = 10 * np.log10(sinr), 10 * np.log10(s_min), 10 * np.log10(peak)
        elif scale != "linear":
            raise ValueError(f"scale must be 'linear' or 'db', got {scale!r}")
        lam = (sinr - s_min) / (peak - s_min) + LAMBDA_FLOOR
        return np.clip(lam, LAMBDA_FLOOR, 1.0 + LAMBDA_FLOOR)


def _sinr_extremes(
    raw_gain: NDArray[np.float64],
    tx: NDArray[np.float64],
    rx: NDArray[np.float64],
    nominal: NDArray[np.float64],
    chunk_elements: int = 4_000_000,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per-target max and min over channels and steps of ``raw_gain / (R_tx R_rx)^2``.

    Processed in chunks of steps so that large layouts do not build the whole
    (K, T+1, M, N) array at once.
    """
    num_targets, num_steps = nominal.shape[:2]
    per_step = num_targets * raw_gain.shape[1] * raw_gain.shape[2]
    chunk = max(1, chunk_elements // per_step)
    highest = np.full(num_targets, -np.inf)
    lowest = np.full(num_targets, np.inf)
    for start in range(0, num_steps, chunk):
        positions = nominal[:, start : start + chunk][..., [0, 2]]  # (K, c, 2)
        sinr = raw_gain[:, None] / squared_range_products(positions, tx, rx)
        highest = np.maximum(highest, sinr.max(axis=(1, 2, 3)))
        lowest = np.minimum(lowest, sinr.min(axis=(1, 2, 3)))
    return highest, lowest


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


#: Models of the IMM (constant velocity and the two coordinated turns), sigma points of a
#: 4-state unscented transform, and the stacked measurement size beyond which the centralised
#: update inverts through Woodbury's identity (as ``tracking.unscented`` does).
_MODELS, _SIGMA_POINTS, _WOODBURY_FROM = 3, 9, 64


def operations_per_trial_step(scenario: Scenario, tracking: bool = True, fusion: str = "average") -> float:
    """Arithmetic operations one trial of an env of ``scenario`` does per step, roughly (an
    upper estimate, to size runs in time as :func:`memory_parts` sizes them in memory): the
    channel draws and SINR of all ``K M N`` target-channels, the oracle's search of the
    optimal super arm, and, with ``tracking``, the IMM-UKF's update of the ``Ms Ns`` probed
    channels by ``fusion`` and the bound's recursion."""
    sc = scenario
    K, M, N = sc.num_targets, sc.num_tx, sc.num_rx
    channels = sc.tx_per_step * sc.rx_per_step
    operations = 60.0 * K * M * N + search_operations(M, N, sc.tx_per_step, sc.rx_per_step)
    if not tracking:
        return operations
    per_channel = _SIGMA_POINTS * 2 * 40 + 400  # measurement model, 2 x 2 innovation and gain
    if fusion == "centralized":
        size = 2 * channels  # range and azimuth of every probed channel, stacked
        inverse = _SIGMA_POINTS**2 * size if size >= _WOODBURY_FROM else size**3 / 3
        # twice the arithmetic: it runs as many small numpy calls (the average fusion is compiled)
        update = 2 * (channels * per_channel + _SIGMA_POINTS * size**2 + 8 * size**2 + inverse)
    else:
        update = channels * (per_channel + 300)  # one update per channel, then eq22's average
    bound = channels * 200 + 2000
    return operations + K * (_MODELS * (update + 3000) + bound)


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
