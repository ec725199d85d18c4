"""Batch-first simulation of targets, channels and measurements.

:class:`RadarSimulation` holds the truth of B Monte-Carlo trials and draws what
the radar observes. Every array has the trial axis first. The single env is the
B = 1 case of this class.

Time: reset puts the targets at step 0 (``X_0 ~ N(X1_hat, P1_hat)``); each
:meth:`advance` moves them from ``t`` to ``t + 1`` with the transition of step
``t`` (docs/model.md, section 3). Observations at step ``t`` use the state at ``t``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import motion
from .counter_hash import Stream
from .geometry import bistatic_measurement, wrap_angle
from .model import RadarModel
from .streams import TrialStreams, full_index, shared_truth_key


@dataclass
class ChannelObservations:
    """What the selected channels of one step observe, for B trials.

    ``C = Ms * Ns`` channels per trial, ordered TX-major. For trials whose action
    was invalid the arrays hold placeholder channels and ``valid`` is False.

    Attributes
    ----------
    tx_index, rx_index : int arrays (B, C)
        Transmitter and receiver of each channel.
    tx_stations, rx_stations : int arrays (B, Ms), (B, Ns)
        The selected stations; channel ``i * Ns + j`` is ``tx_stations[i]``-``rx_stations[j]``.
    valid : bool array (B,)
    mean_sinr : (B, K, C) true mean SINR of the probed channels
    sinr : (B, K, C) Swerling-I samples, Exponential with mean ``mean_sinr``
    measurement : (B, K, C, 2) range sum (m) and azimuth (rad, wrapped)
    noise_variance : (B, K, C, 2) the true variances ``diag(Sigma0) / lambda``
    """

    tx_index: NDArray[np.int64]
    rx_index: NDArray[np.int64]
    tx_stations: NDArray[np.int64]
    rx_stations: NDArray[np.int64]
    valid: NDArray[np.bool_]
    mean_sinr: NDArray[np.float64]
    sinr: NDArray[np.float64]
    measurement: NDArray[np.float64]
    noise_variance: NDArray[np.float64]


class RadarSimulation:
    """Truth and observations of B trials of one scenario.

    Parameters
    ----------
    model : RadarModel
    batch_size : int
        Number of trials B.
    measurement_quality : float, optional
        Replace eq32's SINR-driven ``lambda`` by this constant on every channel
        (an ablation that decouples measurement accuracy from the selection).
    lambda_scale : {"linear", "db"}
        The scale eq32 is applied on (:meth:`RadarModel.quality`).
    truth : {"per-trial", "shared"}
        A true trajectory per trial drawn from ``N(X1_hat, P1_hat)``, or one shared by every
        trial (see :meth:`reset`).
    """

    def __init__(
        self,
        model: RadarModel,
        batch_size: int,
        measurement_quality: float | None = None,
        lambda_scale: str = "linear",
        truth: str = "per-trial",
    ) -> None:
        if batch_size < 1:
            raise ValueError(f"batch_size must be >= 1, got {batch_size}")
        if measurement_quality is not None and not measurement_quality > 0:
            raise ValueError(f"measurement_quality must be > 0 or None, got {measurement_quality}")
        self.model = model
        self.batch_size = batch_size
        self.measurement_quality = measurement_quality
        self.lambda_scale = lambda_scale
        if truth not in ("per-trial", "shared"):
            raise ValueError(f"truth must be 'per-trial' or 'shared', got {truth!r}")
        self.truth = truth
        self.xp = xp = model.xp
        shape = (batch_size, model.num_targets, 4)
        self.initial_estimates = xp.copy(xp.broadcast_to(model.initial_states, shape))
        self.step_index = 0
        #: on torch, the step also as a 0-d tensor on the device, which the draws and the motion
        #: read there (a CUDA graph of the step replays with it); on numpy, the step itself
        self.clock: Any = xp.zeros((), dtype=np.int64) if xp.is_torch else 0
        self.state = xp.zeros((batch_size, model.num_targets, 4))
        self._streams: TrialStreams | None = None
        self._upcoming: NDArray[np.float64] | None = None
        self._mean_sinr: NDArray[np.float64] | None = None
        self._process_std = float(np.sqrt(model.scenario.process_noise))

    # -------------------------------------------------------------- truth
    def reset(self, keys: NDArray[np.uint64]) -> None:
        """Start B new trials; ``keys`` (B, 2) from :func:`keys_from_generator`.

        With ``truth="shared"`` every trial's truth key is the scenario's ``truth_seed`` key:
        one true trajectory, started at ``X1_hat``, the same in every trial; each trial's
        initial *estimate* is then ``X1_hat + N(0, P1_hat)``, drawn from the trial's own key.
        """
        keys = np.array(keys, dtype=np.uint64)
        if self.truth == "shared":
            keys[:, 0] = shared_truth_key(self.model.scenario.truth_seed)
        xp = self.xp
        self._streams = TrialStreams(keys, xp)
        if self._streams.batch_size != self.batch_size:
            raise ValueError(f"expected keys for {self.batch_size} trials, got {self._streams.batch_size}")
        model = self.model
        draws = self._streams.normal(
            Stream.INITIAL_STATE, 0, full_index(self.batch_size, (model.num_targets, 4), xp)
        )
        offset = xp.einsum("kij,bkj->bki", model.initial_cov_sqrt, draws)
        if self.truth == "shared":
            estimate_draws = self._streams.normal(
                Stream.INITIAL_ESTIMATE, 0, full_index(self.batch_size, (model.num_targets, 4), xp)
            )
            self.state = xp.copy(xp.broadcast_to(model.initial_states, offset.shape))
            self.initial_estimates = model.initial_states + xp.einsum(
                "kij,bkj->bki", model.initial_cov_sqrt, estimate_draws
            )
        else:
            self.state = model.initial_states + offset
            self.initial_estimates = xp.copy(xp.broadcast_to(model.initial_states, offset.shape))
        self.step_index = 0
        self.clock = xp.zeros((), dtype=np.int64) if xp.is_torch else 0
        self.forget()

    @property
    def streams(self) -> TrialStreams:
        if self._streams is None:
            raise RuntimeError("call reset() before stepping the simulation")
        return self._streams

    def upcoming_state(self) -> NDArray[np.float64]:
        """The true state at step ``t + 1`` (B, K, 4), without advancing.

        The truth does not depend on the radar's actions, so the oracle may look
        one step ahead; steps past the horizon continue with NCV.
        """
        if self._upcoming is None:
            self._upcoming = self._next_state(self.state, self.clock)
        return self._upcoming

    def _next_state(self, state: NDArray[np.float64], t: int) -> NDArray[np.float64]:
        """The true state after step ``t`` from ``state`` (the step's transition and its draw of
        the process noise)."""
        model, xp = self.model, self.xp
        F = model.transition_at(t)
        noise = self._process_std * self.streams.normal(
            Stream.PROCESS_NOISE, t, full_index(self.batch_size, (model.num_targets, 2), xp)
        )
        return xp.einsum("kij,bkj->bki", F, state) + xp.matmul(noise, model.noise_gain.T)

    def future_states(self, horizon: int) -> NDArray[np.float64]:
        """The true states at steps ``t + 1 .. t + horizon`` (B, H, K, 4), without advancing:
        each step's process noise comes from the counter-based stream of that step, so these
        are the states :meth:`advance` will reach (planning oracles read them)."""
        if horizon < 1:
            raise ValueError(f"horizon must be >= 1, got {horizon}")
        states = [self.upcoming_state()]
        for h in range(1, horizon):
            states.append(self._next_state(states[-1], self.step_index + h))
        return self.xp.stack(states, axis=1)

    def advance(self) -> None:
        """Move every trial's targets from step ``t`` to ``t + 1``."""
        self.state = self.upcoming_state()
        self.step_index += 1
        self.clock = self.clock + 1
        self.forget()

    def forget(self) -> None:
        """Drop the values kept for the current step (the coming state, the mean SINR)."""
        self._upcoming = None
        self._mean_sinr = None

    @property
    def positions(self) -> NDArray[np.float64]:
        """True positions (B, K, 2)."""
        return motion.positions(self.state)

    def mean_sinr(self) -> NDArray[np.float64]:
        """True mean SINR at the current step, (B, K, M, N)."""
        if self._mean_sinr is None:
            self._mean_sinr = self.model.mean_sinr(self.positions)
        return self._mean_sinr

    # ------------------------------------------------------- observations
    def sinr_samples_all(self) -> NDArray[np.float64]:
        """Swerling-I SINR samples of every channel at the current step, (B, K, M, N).

        Used for the reset probe of Algorithm 1's initialisation.
        """
        model = self.model
        shape = (model.num_targets, model.num_tx, model.num_rx)
        draws = self.streams.exponential(Stream.SINR, self.clock, full_index(self.batch_size, shape, self.xp))
        return self.mean_sinr() * draws

    def quality(self, mean_sinr: NDArray[np.float64], target_axis: int = -3) -> NDArray[np.float64]:
        """eq32's ``lambda`` of channels with mean SINR ``mean_sinr`` on this run's scale, or the
        constant ``measurement_quality`` when it is set."""
        if self.measurement_quality is None:
            return self.model.quality(mean_sinr, target_axis=target_axis, scale=self.lambda_scale)
        return self.xp.full_like(mean_sinr, self.measurement_quality)

    def observe(
        self, tx_index: NDArray[np.int64], rx_index: NDArray[np.int64], valid: NDArray[np.bool_]
    ) -> ChannelObservations:
        """Observe the channels ``tx_index x rx_index`` (B, Ms), (B, Ns) at the current step.

        The draw of channel ``(k, m, n)`` depends only on the trial key, the step
        and ``(k, m, n)``, never on which other channels are probed.
        """
        model, xp = self.model, self.xp
        num_targets, num_tx, num_rx = model.num_targets, model.num_tx, model.num_rx
        batch = xp.arange(self.batch_size)[:, None, None]
        channel_tx = xp.repeat(tx_index, rx_index.shape[1], axis=1)  # (B, C)
        channel_rx = xp.tile(rx_index, (1, tx_index.shape[1]))  # (B, C)
        targets = xp.arange(num_targets)[None, :, None]
        mean = self.mean_sinr()[batch, targets, channel_tx[:, None, :], channel_rx[:, None, :]]
        flat = (targets * num_tx + channel_tx[:, None, :]) * num_rx + channel_rx[:, None, :]  # (B, K, C)
        sinr = mean * self.streams.exponential(Stream.SINR, self.clock, flat)
        lam = self.quality(mean, target_axis=1)
        variance = model.measurement_variance(lam)  # (B, K, C, 2)
        clean = bistatic_measurement(
            self.positions[:, :, None, :], model.tx[channel_tx][:, None], model.rx[channel_rx][:, None]
        )
        noise_index = flat[..., None] * 2 + xp.arange(2)
        noise = xp.sqrt(variance) * self.streams.normal(Stream.MEASUREMENT, self.clock, noise_index)
        measurement = clean + noise
        measurement[..., 1] = wrap_angle(measurement[..., 1])
        return ChannelObservations(
            tx_index=channel_tx,
            rx_index=channel_rx,
            tx_stations=tx_index,
            rx_stations=rx_index,
            valid=valid,
            mean_sinr=mean,
            sinr=sinr,
            measurement=measurement,
            noise_variance=variance,
        )
