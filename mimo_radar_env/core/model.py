"""The radar model of a scenario: every constant the simulation needs, computed once.

:class:`RadarModel` turns a :class:`~mimo_radar_env.scenarios.scenario.Scenario` into
arrays: station positions, the per-channel SINR gain including the scenario
constant ``C`` (docs/model.md, section 4), the per-target minimum SINR of eq32, the maneuver
transition matrices and the noise-free nominal trajectories.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..scenarios import Scenario, ScenarioError, turn_rate_schedule
from .arrays import NUMPY, NumpyNamespace, TorchNamespace
from .geometry import squared_range_products
from .motion import noise_gain, nominal_trajectories, positions, process_covariance, transition_matrix

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
    straight : array (4, 4)
        ``F`` of straight motion (NCV), the truth's motion past the schedule.
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
    straight: NDArray[np.float64]
    nominal: NDArray[np.float64]
    process_cov: NDArray[np.float64]
    noise_gain: NDArray[np.float64]
    initial_states: NDArray[np.float64]
    initial_cov_sqrt: NDArray[np.float64]
    #: the targets' weights ``Omega_k`` (K,) and the diagonal of ``Sigma0`` (2,) of eq32
    weights: NDArray[np.float64]
    measurement_diagonal: NDArray[np.float64]
    #: the array namespace its arrays live in (:mod:`.arrays`): numpy, or torch on a device
    xp: NumpyNamespace | TorchNamespace = NUMPY

    def to(self, xp: NumpyNamespace | TorchNamespace) -> RadarModel:
        """The same model with its arrays in namespace ``xp`` (torch on a device, say)."""
        arrays = {
            f.name: xp.asarray(getattr(self, f.name))
            for f in dataclasses.fields(self)
            if isinstance(getattr(self, f.name), np.ndarray)
        }
        return dataclasses.replace(self, xp=xp, **arrays)

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
            straight=transition_matrix(0.0, sc.sample_time),
            nominal=nominal,
            process_cov=process_covariance(sc.sample_time, sc.process_noise),
            noise_gain=noise_gain(sc.sample_time),
            initial_states=initial_states,
            initial_cov_sqrt=np.stack([np.linalg.cholesky(t.initial_covariance) for t in sc.targets]),
            weights=np.asarray(sc.weights, dtype=np.float64),
            measurement_diagonal=np.diagonal(sc.measurement_covariance).copy(),
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

    def transition_at(self, step: Any) -> NDArray[np.float64]:
        """``F`` (K, 4, 4) of the truth's step ``step -> step + 1``; past the schedule, straight
        motion. ``step`` is an integer, or on torch a 0-d ``int64`` tensor read on the device."""
        xp, last = self.xp, self.transitions.shape[1] - 1
        if xp.is_torch and isinstance(step, xp.torch.Tensor):
            scheduled = self.transitions.index_select(1, xp.minimum(step, last).reshape(1))[:, 0]
            return xp.where(step <= last, scheduled, self.straight)
        if step <= last:
            return self.transitions[:, step]
        return xp.broadcast_to(self.straight, (self.num_targets, 4, 4))

    @property
    def nominal_positions(self) -> NDArray[np.float64]:
        """The targets' noise-free positions at each step, (T+1, K, 2)."""
        return self.xp.moveaxis(positions(self.nominal), 1, 0)

    def nominal_channel_weights(self) -> NDArray[np.float64]:
        """Each channel's expected reward on the noise-free tracks (:meth:`channel_weights` at
        :attr:`nominal_positions`), (T+1, M, N)."""
        return self.channel_weights(self.mean_sinr(self.nominal_positions))

    # ---------------------------------------------------------- physics
    def mean_sinr(self, positions: NDArray[np.float64]) -> NDArray[np.float64]:
        """Mean SINR ``S[k, m, n]`` (eq5) for positions (..., K, 2): shape (..., K, M, N)."""
        return self.gain / squared_range_products(positions, self.tx, self.rx)

    def measurement_variance(self, quality: NDArray[np.float64]) -> NDArray[np.float64]:
        """eq32: the diagonal of ``Sigma0 / lambda`` for qualities ``lambda`` (...): shape (..., 2)."""
        return self.measurement_diagonal / quality[..., None]

    def channel_weights(self, mean_sinr: NDArray[np.float64]) -> NDArray[np.float64]:
        """``sum_k Omega_k S[k, m, n]``: the expected reward of each channel, (..., M, N)."""
        return self.xp.einsum("k,...kmn->...mn", self.weights, mean_sinr)

    def quality(
        self, sinr: NDArray[np.float64], target_axis: int = -3, scale: str = "linear"
    ) -> NDArray[np.float64]:
        """``lambda`` of eq32 from the SINR, clipped into [0.2, 1.2] (docs/model.md, section 5).

        ``target_axis`` is the axis of ``sinr`` that indexes targets. ``scale="linear"`` applies
        eq32 to linear SINRs (reading 0); ``"db"`` to SINRs in dB,
        ``(S_dB - S_min,dB) / (S_max,dB - S_min,dB) + 0.2`` (reading 1).
        """
        xp = self.xp
        shape = [1] * sinr.ndim
        shape[target_axis] = self.num_targets
        s_min = self.min_sinr.reshape(shape)
        peak = float(self.scenario.peak_sinr)
        if scale == "db":
            with np.errstate(divide="ignore"):
                sinr, s_min, peak = 10 * xp.log10(sinr), 10 * xp.log10(s_min), float(10 * np.log10(peak))
        elif scale != "linear":
            raise ValueError(f"scale must be 'linear' or 'db', got {scale!r}")
        lam = (sinr - s_min) / (peak - s_min) + LAMBDA_FLOOR
        return xp.clip(lam, LAMBDA_FLOOR, 1.0 + LAMBDA_FLOOR)


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
        where = positions(nominal[:, start : start + chunk])  # (K, c, 2)
        sinr = raw_gain[:, None] / squared_range_products(where, tx, rx)
        highest = np.maximum(highest, sinr.max(axis=(1, 2, 3)))
        lowest = np.minimum(lowest, sinr.min(axis=(1, 2, 3)))
    return highest, lowest
