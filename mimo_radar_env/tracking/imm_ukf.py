"""The batched IMM-UKF tracker of Section III-C.

One :class:`IMMUKFTracker` tracks the K targets of B trials at once. Its state is per
trial, target and model: means ``means`` (B, K, R, 4), covariances ``covs``
(B, K, R, 4, 4) and log model probabilities (B, K, R). One call of
:meth:`IMMUKFTracker.step` runs a whole IMM cycle as a few numpy computations, with no
Python loop over trials, targets, models or channels: mixing and per-model prediction
(:mod:`.imm`), sigma points of the prior (:mod:`.unscented`), the update of the selected
channels by a fusion (:mod:`.fusion`: the paper's ``"average"``, eq22, or
``"centralized"``), and the choice between update and prediction per trial.

A trial whose action was invalid (nothing probed) only predicts. A numerical failure (a
covariance that is not positive definite, a non-finite update) is repaired in that trial
alone and counted in :attr:`IMMUKFTracker.repairs`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import deferring, namespace
from ..core.model import RadarModel
from ..core.motion import transition_matrix
from . import imm
from .fusion import DEFAULT_FUSION, Posterior, Prior, make_fusion
from .unscented import SigmaPointParameters, repair_covariances, robust_cholesky, sigma_points

#: The tracker's models and Markov chain (docs/model.md): NCV, NCT(+3 deg/s), NCT(-3 deg/s).
DEFAULT_TURN_RATES_DEG = (0.0, 3.0, -3.0)
DEFAULT_INITIAL_PROBABILITIES = (0.8, 0.1, 0.1)
DEFAULT_STAY_PROBABILITY = 0.8


class IMMUKFTracker:
    """Batched IMM-UKF for B trials x K targets.

    Parameters
    ----------
    model : RadarModel
        Geometry, sample time, process noise and initial estimates.
    batch_size : int
    fusion : str
        A name of the fusion registry ``mimo_radar_env.tracking.FUSIONS``: ``"average"``
        (eq22, default) or ``"centralized"``.
    turn_rates_deg : sequence of float
        Turn rate of each model (0 = NCV). Default NCV, NCT(+3), NCT(-3) deg/s.
    initial_probabilities : sequence of float
    stay_probability : float
        Diagonal of the Markov matrix; the rest of each row is shared equally.
    sigma_point_parameters : SigmaPointParameters, optional
    use_numba : bool
        Run the fusion's compiled path when numba is installed (default); the numpy path
        gives the same numbers to round-off.
    """

    def __init__(
        self,
        model: RadarModel,
        batch_size: int,
        fusion: str = DEFAULT_FUSION,
        turn_rates_deg: tuple[float, ...] = DEFAULT_TURN_RATES_DEG,
        initial_probabilities: tuple[float, ...] = DEFAULT_INITIAL_PROBABILITIES,
        stay_probability: float = DEFAULT_STAY_PROBABILITY,
        sigma_point_parameters: SigmaPointParameters | None = None,
        use_numba: bool = True,
    ) -> None:
        if len(initial_probabilities) != len(turn_rates_deg):
            raise ValueError("initial_probabilities needs one entry per model (turn_rates_deg)")
        probs = np.asarray(initial_probabilities, dtype=np.float64)
        if np.any(probs <= 0) or not math.isclose(probs.sum(), 1.0, rel_tol=1e-9):
            raise ValueError(f"initial_probabilities must be > 0 and sum to 1, got {probs.tolist()}")
        if not 0.0 < stay_probability <= 1.0:
            raise ValueError(f"stay_probability must be in (0, 1], got {stay_probability}")
        self.model = model
        self.xp = xp = model.xp
        self.batch_size = batch_size
        # the compiled paths are numpy's; on torch the fusion's array path runs
        self.fusion = make_fusion(fusion, use_numba=use_numba and not xp.is_torch)
        self.num_models = len(turn_rates_deg)
        self.transitions = xp.asarray(
            transition_matrix(np.radians(turn_rates_deg), model.scenario.sample_time)
        )
        self.log_markov = xp.asarray(np.log(imm.markov_matrix(self.num_models, stay_probability)))
        self.log_initial = xp.asarray(np.log(probs))
        self.sigma_params = sigma_point_parameters or SigmaPointParameters()
        self.wm, self.wc = (xp.asarray(w) for w in self.sigma_params.weights(4))
        self.repairs = xp.zeros(batch_size, dtype=np.int64)
        self.reset()

    # ------------------------------------------------------------ state
    def reset(self, initial_estimates: NDArray[np.float64] | None = None) -> None:
        """Every trial back to its initial estimate (default ``X1_hat``; (B, K, 4)) with ``P1_hat``."""
        xp = self.xp
        B, K, R = self.batch_size, self.model.num_targets, self.num_models
        initial_cov = xp.asarray(np.stack([t.initial_covariance for t in self.model.scenario.targets]))
        start = self.model.initial_states if initial_estimates is None else xp.asarray(initial_estimates)
        start = xp.broadcast_to(start, (B, K, 4))
        self.means = xp.copy(xp.broadcast_to(start[:, :, None, :], (B, K, R, 4)))
        self.covs = xp.copy(xp.broadcast_to(initial_cov[None, :, None], (B, K, R, 4, 4)))
        self.log_probs = xp.copy(xp.broadcast_to(self.log_initial, (B, K, R)))
        self.estimate = xp.copy(start)
        self.covariance = xp.copy(xp.broadcast_to(initial_cov, (B, K, 4, 4)))
        #: the covariance of the last step's prediction (the IMM mixture), before its update
        self.prior_covariance = xp.copy(self.covariance)
        self.repairs[:] = 0

    @property
    def model_probabilities(self) -> NDArray[np.float64]:
        """Model probabilities (B, K, R)."""
        return self.xp.exp(self.log_probs)

    def predicted_state(self) -> NDArray[np.float64]:
        """eq24: ``sum_i u_i F_i(X_hat)``, the one-step prediction (B, K, 4)."""
        per_model = self.xp.einsum("rij,bkj->bkri", self.transitions, self.estimate)
        return self.xp.einsum("bkr,bkri->bki", self.model_probabilities, per_model)

    def predicted_covariance(self) -> NDArray[np.float64]:
        """``P_bar``: the covariance of the IMM mixture of the one-step predictions (B, K, 4, 4):
        each model's mixed posterior predicted exactly, combined with the predicted model
        probabilities ``c_j``. The tracker's state is unchanged."""
        return _mixture_covariance(*self._predict())

    # ------------------------------------------------------------ cycle
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
        prior = self._prior(*self._predict())
        self.prior_covariance = _mixture_covariance(prior.means, prior.covs, prior.log_c)
        posterior = self.fusion.update(prior, tx_positions, rx_positions, measurement, noise_variance)
        self._keep(posterior, prior, valid)

    def _predict(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Mixing and each model's exact prediction: means, covariances, log ``c_j``."""
        mixed_means, mixed_covs, log_c = imm.mix(self.log_probs, self.means, self.covs, self.log_markov)
        pred_means, pred_covs = imm.predict(mixed_means, mixed_covs, self.transitions, self.model.process_cov)
        return pred_means, pred_covs, log_c

    def _prior(
        self, means: NDArray[np.float64], covs: NDArray[np.float64], log_c: NDArray[np.float64]
    ) -> Prior:
        """Sigma points of the predicted models; a repaired covariance is also the prior of the update."""
        scale = self.sigma_params.scale(4)
        chol, repaired = robust_cholesky(scale * covs)
        self.repairs = self.repairs + repaired.reshape(self.batch_size, -1).sum(axis=1)
        if not deferring() and repaired.any():  # deferred: a failed factor fails the step's checks
            rebuilt = self.xp.matmul(chol, self.xp.swapaxes(chol, -1, -2)) / scale
            covs = self.xp.where(repaired[..., None, None], rebuilt, covs)
        return Prior(means, covs, log_c, sigma_points(means, chol), self.wm, self.wc)

    def _keep(self, posterior: Posterior, prior: Prior, valid: NDArray[np.bool_]) -> None:
        """The update where it is valid and finite, the prediction elsewhere (per trial and target)."""
        xp = self.xp
        finite = posterior.finite()  # (B, K)
        self.repairs = self.repairs + (~finite & valid[:, None]).sum(axis=1)
        use_update = finite & valid[:, None]
        log_pred = prior.log_c - imm.logsumexp(prior.log_c, axis=-1, keepdims=True)
        # the condition-number guard: a posterior that lost positive definiteness to rounding
        # (a prior far wider than the measurements) is repaired in its trial and target alone
        # (with deferred checks, the masked forms run always: the same numbers, no host read)
        everywhere = not deferring() and bool(use_update.all())
        covs, covariance = posterior.covs, posterior.covariance
        if not everywhere:  # the others are not used: keep their NaN out of the guard
            covs = xp.where(use_update[..., None, None, None], covs, xp.eye(4))
            covariance = xp.where(use_update[..., None, None], covariance, xp.eye(4))
        repaired = repair_covariances([covs, covariance])
        (posterior_covs, repaired_models), (covariance, repaired_fused) = repaired
        self.repairs = self.repairs + ((repaired_models.any(axis=-1) | repaired_fused) & use_update).sum(
            axis=1
        )
        self.means = xp.where(use_update[..., None, None], posterior.means, prior.means)
        self.covs = xp.where(use_update[..., None, None, None], posterior_covs, prior.covs)
        self.log_probs = xp.where(use_update[..., None], posterior.log_probs, log_pred)
        estimate = posterior.estimate
        if not everywhere:
            pred_est, pred_cov = imm.combine(prior.means, prior.covs, xp.exp(log_pred))
            estimate = xp.where(use_update[..., None], estimate, pred_est)
            covariance = xp.where(use_update[..., None, None], covariance, pred_cov)
        self.estimate = estimate
        self.covariance = covariance


def _mixture_covariance(
    means: NDArray[np.float64], covs: NDArray[np.float64], log_c: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The covariance of the IMM mixture of predicted models weighted by ``c_j``."""
    probs = namespace(log_c).exp(log_c - imm.logsumexp(log_c, axis=-1, keepdims=True))
    return imm.combine(means, covs, probs)[1]
