"""Batched IMM-UKF tracker with the paper's distributed fusion and a centralised one.

One :class:`IMMUKFTracker` tracks the K targets of B trials at once. Its state is
per trial, target and model: means ``x`` (B, K, R, 4), covariances
``P`` (B, K, R, 4, 4) and log model probabilities (B, K, R). One call of
:meth:`IMMUKFTracker.step` runs a whole IMM cycle (Section III-C) as a few numpy
computations, with no Python loop over trials, targets, models or channels:

1. interaction (mixing) with the Markov matrix, in log space;
2. exact linear prediction per model (NCV, NCT(+w), NCT(-w));
3. unscented update with the bistatic range-sum/azimuth model (eq6);
4. model-probability update, in log space;
5. combination, and fusion over the selected channels:

   * ``fusion="average"`` (the paper, eq22): every selected channel runs steps
     3-4 from the common fused prior with its own measurement; the fused
     per-model means, covariances and model probabilities are the means over
     channels, and the fused estimate is the mean of the channels' combined
     estimates (eq22);
   * ``fusion="centralized"``: one update with the stacked measurements of all
     selected channels.

A trial whose action was invalid (nothing probed) only predicts. A numerical
failure (a covariance that is not positive definite, a non-finite update) is
repaired in that trial alone and counted in :attr:`IMMUKFTracker.repairs`.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from ..core.model import RadarModel
from ..core.motion import transition_matrix
from . import _average_kernel
from .unscented import (
    SigmaPointParameters,
    robust_cholesky,
    sigma_points,
    symmetrize,
    unscented_update,
)

Fusion = Literal["average", "centralized"]
FUSIONS: tuple[str, ...] = ("average", "centralized")

#: SPEC 5 defaults.
DEFAULT_TURN_RATES_DEG = (0.0, 3.0, -3.0)
DEFAULT_INITIAL_PROBABILITIES = (0.8, 0.1, 0.1)
DEFAULT_STAY_PROBABILITY = 0.8


def logsumexp(values: NDArray[np.float64], axis: int, keepdims: bool = False) -> NDArray[np.float64]:
    """``log(sum(exp(values)))`` along an axis, stable for finite inputs."""
    top = np.max(values, axis=axis, keepdims=True)
    out = top + np.log(np.sum(np.exp(values - top), axis=axis, keepdims=True))
    return out if keepdims else np.squeeze(out, axis=axis)


def markov_matrix(num_models: int, stay_probability: float) -> NDArray[np.float64]:
    """``pi[i, j] = P(model j at t | model i at t-1)``: ``stay`` on the diagonal, the rest shared."""
    if num_models == 1:
        return np.ones((1, 1))
    off = (1.0 - stay_probability) / (num_models - 1)
    return np.full((num_models, num_models), off) + np.eye(num_models) * (stay_probability - off)


def combine(
    means: NDArray[np.float64], covs: NDArray[np.float64], probs: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Moment-matched mixture of per-model Gaussians along the model axis (-2 / -3)."""
    mean = np.einsum("...r,...ri->...i", probs, means)
    spread = means - mean[..., None, :]
    cov = np.einsum("...r,...rij->...ij", probs, covs + spread[..., :, None] * spread[..., None, :])
    return mean, symmetrize(cov)


def average_channels(
    prior_covs: NDArray[np.float64],
    means: NDArray[np.float64],
    probs: NDArray[np.float64],
    gain: NDArray[np.float64],
    cross_cov: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """eq22 fusion of per-channel IMM posteriors that share one prior.

    Parameters
    ----------
    prior_covs : (B, K, R, n, n) the common predicted covariances
    means : (B, K, C, R, n) per-channel, per-model posterior means
    probs : (B, K, C, R) per-channel model probabilities
    gain, cross_cov : (B, K, C, R, n, d) per-channel Kalman gains and cross covariances;
        channel c's posterior covariance is ``prior_covs - gain_c @ cross_cov_c'``.

    Returns
    -------
    model_means, model_covs : (B, K, R, n), (B, K, R, n, n) means over channels
    estimate, covariance : (B, K, n), (B, K, n, n) the mean over channels of each
        channel's combined estimate and covariance

    The channel axis is folded into the inner dimension of one matrix product, so
    no per-channel (n, n) covariance is ever formed.
    """
    B, K, C, R, n = means.shape
    d = gain.shape[-1]

    def fold(a: NDArray[np.float64]) -> NDArray[np.float64]:  # (B, K, C, R, n, d) -> (B, K, R, n, C*d)
        return np.moveaxis(a, 2, -2).reshape(B, K, R, n, C * d)

    folded_cross_t = np.swapaxes(fold(cross_cov), -1, -2)
    model_covs = symmetrize(prior_covs - (fold(gain) @ folded_cross_t) / C)
    weights = probs / C  # each channel's combined estimate enters the mean with 1/C
    channel_mean = np.einsum("bkcr,bkcri->bkci", probs, means)
    spread = (means - channel_mean[..., None, :]).reshape(B, K, C * R, n)
    weighted_spread = spread * weights.reshape(B, K, C * R, 1)
    covariance = np.einsum("bkr,bkrij->bkij", weights.sum(axis=2), prior_covs)
    covariance -= (fold(gain * weights[..., None, None]) @ folded_cross_t).sum(axis=2)
    covariance += np.swapaxes(weighted_spread, -1, -2) @ spread
    return means.mean(axis=2), model_covs, channel_mean.mean(axis=2), symmetrize(covariance)


def _station_geometry(
    sigmas: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> tuple[
    NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]
]:
    """Ranges to the transmitters, and ranges, azimuths (eq6), sines and cosines to the receivers.

    ``sigmas`` (..., 4) broadcasts against the station positions (..., 2). A channel's range
    sum is ``tx_range + rx_range`` and its azimuth the receiver's: computing per station and
    broadcasting over channels saves the work of ``Ms * Ns`` channels on ``Ms + Ns`` stations.
    """
    tx_dx, tx_dy = sigmas[..., 0] - tx[..., 0], sigmas[..., 2] - tx[..., 1]
    rx_dx, rx_dy = sigmas[..., 0] - rx[..., 0], sigmas[..., 2] - rx[..., 1]
    tx_range = np.sqrt(tx_dx * tx_dx + tx_dy * tx_dy)
    rx_range = np.sqrt(rx_dx * rx_dx + rx_dy * rx_dy)
    return tx_range, rx_range, np.arctan2(rx_dy, rx_dx), rx_dy / rx_range, rx_dx / rx_range


class IMMUKFTracker:
    """Batched IMM-UKF for B trials x K targets.

    Parameters
    ----------
    model : RadarModel
        Geometry, sample time, process noise and initial estimates.
    batch_size : int
    fusion : {"average", "centralized"}
    turn_rates_deg : sequence of float
        Turn rate of each model (0 = NCV). Default NCV, NCT(+3), NCT(-3) deg/s.
    initial_probabilities : sequence of float
    stay_probability : float
        Diagonal of the Markov matrix; the rest of each row is shared equally.
    sigma_points : SigmaPointParameters
    use_numba : bool
        Run the average fusion's update in the compiled kernel when numba is installed
        (default); the numpy path gives the same numbers to round-off.
    """

    def __init__(
        self,
        model: RadarModel,
        batch_size: int,
        fusion: Fusion = "average",
        turn_rates_deg: tuple[float, ...] = DEFAULT_TURN_RATES_DEG,
        initial_probabilities: tuple[float, ...] = DEFAULT_INITIAL_PROBABILITIES,
        stay_probability: float = DEFAULT_STAY_PROBABILITY,
        sigma_point_parameters: SigmaPointParameters | None = None,
        use_numba: bool = True,
    ) -> None:
        if fusion not in FUSIONS:
            raise ValueError(f"fusion must be one of {FUSIONS}, got {fusion!r}")
        if len(initial_probabilities) != len(turn_rates_deg):
            raise ValueError("initial_probabilities needs one entry per model (turn_rates_deg)")
        probs = np.asarray(initial_probabilities, dtype=np.float64)
        if np.any(probs <= 0) or not math.isclose(probs.sum(), 1.0, rel_tol=1e-9):
            raise ValueError(f"initial_probabilities must be > 0 and sum to 1, got {probs.tolist()}")
        if not 0.0 < stay_probability <= 1.0:
            raise ValueError(f"stay_probability must be in (0, 1], got {stay_probability}")
        self.model = model
        self.batch_size = batch_size
        self.fusion: Fusion = fusion
        self.num_models = len(turn_rates_deg)
        self.transitions = transition_matrix(np.radians(turn_rates_deg), model.scenario.sample_time)
        self.log_markov = np.log(markov_matrix(self.num_models, stay_probability))
        self.log_initial = np.log(probs)
        self.sigma_params = sigma_point_parameters or SigmaPointParameters()
        self.wm, self.wc = self.sigma_params.weights(4)
        self.repairs = np.zeros(batch_size, dtype=np.int64)
        self.use_numba = use_numba and _average_kernel.HAVE_NUMBA
        self.reset()

    # ------------------------------------------------------------ state
    def reset(self) -> None:
        """Every trial back to the initial estimate ``X1_hat, P1_hat`` of each target."""
        B, K, R = self.batch_size, self.model.num_targets, self.num_models
        initial_cov = np.stack([t.initial_covariance for t in self.model.scenario.targets])
        self.means = np.broadcast_to(self.model.initial_states[None, :, None, :], (B, K, R, 4)).copy()
        self.covs = np.broadcast_to(initial_cov[None, :, None], (B, K, R, 4, 4)).copy()
        self.log_probs = np.broadcast_to(self.log_initial, (B, K, R)).copy()
        self.estimate = np.broadcast_to(self.model.initial_states, (B, K, 4)).copy()
        self.covariance = np.broadcast_to(initial_cov, (B, K, 4, 4)).copy()
        self.repairs[:] = 0

    @property
    def model_probabilities(self) -> NDArray[np.float64]:
        """Model probabilities (B, K, R)."""
        return np.exp(self.log_probs)

    def predicted_state(self) -> NDArray[np.float64]:
        """eq24: ``sum_i u_i F_i(X_hat)``, the one-step prediction (B, K, 4)."""
        per_model = np.einsum("rij,bkj->bkri", self.transitions, self.estimate)
        return np.einsum("bkr,bkri->bki", self.model_probabilities, per_model)

    # ------------------------------------------------------------ cycle
    def mix_and_predict(
        self,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Interaction and per-model prediction.

        Returns predicted means (B, K, R, 4), covariances (B, K, R, 4, 4) and the
        log predicted model probabilities ``log c_j`` (B, K, R).
        """
        joint = self.log_markov + self.log_probs[..., :, None]  # (B, K, i, j)
        log_c = logsumexp(joint, axis=-2)  # (B, K, j)
        mixing = np.exp(joint - log_c[..., None, :])  # mu_{i|j}
        mixed_means = np.einsum("bkij,bkid->bkjd", mixing, self.means)
        spread = self.means[..., None, :, :] - mixed_means[..., :, None, :]  # (B, K, j, i, d)
        outer = spread[..., :, None] * spread[..., None, :]
        mixed_covs = np.einsum("bkij,bkjide->bkjde", mixing, self.covs[..., None, :, :, :] + outer)
        pred_means = np.einsum("rij,bkrj->bkri", self.transitions, mixed_means)
        pred_covs = self.transitions @ mixed_covs @ np.swapaxes(self.transitions, -1, -2)
        pred_covs = symmetrize(pred_covs + self.model.process_cov)
        return pred_means, pred_covs, log_c

    def _average_numpy(
        self,
        sigmas: NDArray[np.float64],
        pred_means: NDArray[np.float64],
        pred_covs: NDArray[np.float64],
        log_c: NDArray[np.float64],
        tx_positions: NDArray[np.float64],
        rx_positions: NDArray[np.float64],
        measurement: NDArray[np.float64],
        noise_variance: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], ...]:
        """The paper's average fusion with numpy arrays (the reference of the numba kernel)."""
        B, K = self.batch_size, self.model.num_targets
        num_tx, num_rx = tx_positions.shape[1], rx_positions.shape[1]
        # (B, K, C, R, S): every channel updates the common prior on its own; geometry is
        # computed per station, then laid out per channel (contiguous arrays are fastest)
        tx_range, rx_range, azimuth, sin, cos = _station_geometry(
            sigmas[:, :, None, None],
            tx_positions[:, None, :, None, None, None],
            rx_positions[:, None, None, :, None, None],
        )
        R, S = sigmas.shape[2], sigmas.shape[3]
        C = num_tx * num_rx
        full = (B, K, num_tx, num_rx, R, S)

        def per_channel(a: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.broadcast_to(a, full).reshape(B, K, C, R, S)

        h = np.stack([per_channel(tx_range + rx_range), per_channel(azimuth)], axis=-1)
        result = unscented_update(
            pred_means[:, :, None],
            pred_covs[:, :, None],
            sigmas[:, :, None],
            h,
            measurement[:, :, :, None],
            noise_variance[:, :, :, None],
            self.wm,
            self.wc,
            (per_channel(sin)[..., None], per_channel(cos)[..., None]),
            with_covariance=False,
        )
        log_post = result.log_likelihood + log_c[:, :, None]
        log_post -= logsumexp(log_post, axis=-1, keepdims=True)  # (B, K, C, R)
        post_means, post_covs, estimate, covariance = average_channels(
            pred_covs, result.mean, np.exp(log_post), result.gain, result.cross_cov
        )
        log_post = logsumexp(log_post, axis=2) - np.log(log_post.shape[2])
        return post_means, post_covs, log_post, estimate, covariance

    def step(
        self,
        tx_positions: NDArray[np.float64],
        rx_positions: NDArray[np.float64],
        measurement: NDArray[np.float64],
        noise_variance: NDArray[np.float64],
        valid: NDArray[np.bool_],
    ) -> None:
        """One IMM-UKF cycle with the measurements of the selected channels.

        Parameters
        ----------
        tx_positions, rx_positions : (B, Ms, 2), (B, Ns, 2)
            Positions of the selected transmitters and receivers; every pair is a
            channel, ordered TX-major (channel ``i * Ns + j``).
        measurement : (B, K, Ms * Ns, 2)
            Range sum and azimuth of each target on each channel.
        noise_variance : (B, K, Ms * Ns, 2)
            Diagonal measurement covariance the filter uses.
        valid : (B,) bool
            False for trials that probed nothing: those only predict.
        """
        pred_means, pred_covs, log_c = self.mix_and_predict()
        scale = self.sigma_params.scale(4)
        chol, repaired = robust_cholesky(scale * pred_covs)
        self.repairs += repaired.reshape(self.batch_size, -1).sum(axis=1)
        if repaired.any():  # the update must start from the repaired prior its sigma points describe
            rebuilt = chol @ np.swapaxes(chol, -1, -2) / scale
            pred_covs = np.where(repaired[..., None, None], rebuilt, pred_covs)
        sigmas = sigma_points(pred_means, chol)  # (B, K, R, S, 4)
        B, K = self.batch_size, self.model.num_targets
        num_tx, num_rx = tx_positions.shape[1], rx_positions.shape[1]
        if self.fusion == "centralized":
            # (B, K, R, S, Ms, Ns): channels innermost, stacked TX-major into one 2C measurement
            tx_range, rx_range, azimuth, sin, cos = _station_geometry(
                sigmas[..., None, None, :],
                tx_positions[:, None, None, None, :, None],
                rx_positions[:, None, None, None, None, :],
            )
            range_sum = tx_range + rx_range
            full = range_sum.shape
            h = np.stack([range_sum, np.broadcast_to(azimuth, full)], axis=-1)
            R, S = h.shape[2], h.shape[3]
            C = num_tx * num_rx
            result = unscented_update(
                pred_means,
                pred_covs,
                sigmas,
                h.reshape(B, K, R, S, 2 * C),
                measurement.reshape(B, K, 1, 2 * C),
                noise_variance.reshape(B, K, 1, 2 * C),
                self.wm,
                self.wc,
                (
                    np.broadcast_to(sin, full).reshape(B, K, R, S, C),
                    np.broadcast_to(cos, full).reshape(B, K, R, S, C),
                ),
            )
            log_post = result.log_likelihood + log_c
            log_post -= logsumexp(log_post, axis=-1, keepdims=True)
            post_means, post_covs = result.mean, symmetrize(result.covariance)
            estimate, covariance = combine(post_means, post_covs, np.exp(log_post))
        else:
            if self.use_numba:
                post_means, post_covs, log_post, estimate, covariance = _average_kernel.average_fusion_update(
                    sigmas,
                    pred_means,
                    pred_covs,
                    log_c,
                    self.wm,
                    self.wc,
                    tx_positions,
                    rx_positions,
                    measurement,
                    noise_variance,
                )
            else:
                post_means, post_covs, log_post, estimate, covariance = self._average_numpy(
                    sigmas,
                    pred_means,
                    pred_covs,
                    log_c,
                    tx_positions,
                    rx_positions,
                    measurement,
                    noise_variance,
                )

        # predict-only trials and numerically failed updates keep the prediction
        finite = (
            np.isfinite(post_means).all(axis=(-1, -2))
            & np.isfinite(post_covs).all(axis=(-1, -2, -3))
            & np.isfinite(log_post).all(axis=-1)
        )  # (B, K)
        self.repairs += (~finite & valid[:, None]).sum(axis=1)
        use_update = finite & valid[:, None]
        log_pred = log_c - logsumexp(log_c, axis=-1, keepdims=True)
        self.means = np.where(use_update[..., None, None], post_means, pred_means)
        self.covs = np.where(use_update[..., None, None, None], post_covs, pred_covs)
        self.log_probs = np.where(use_update[..., None], log_post, log_pred)
        if not use_update.all():
            pred_est, pred_cov = combine(pred_means, pred_covs, np.exp(log_pred))
            estimate = np.where(use_update[..., None], estimate, pred_est)
            covariance = np.where(use_update[..., None, None], covariance, pred_cov)
        self.estimate = estimate
        self.covariance = covariance
