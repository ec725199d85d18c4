"""The interacting-multiple-model pieces of the tracker (Section III-C): the Markov matrix,
mixing, per-model linear prediction, and the moment-matched combination of models.

Every function works on a batch with leading axes (B, K) and the model axis R next; model
probabilities are kept in log space.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import namespace
from .unscented import symmetrize


def logsumexp(values: NDArray[np.float64], axis: int, keepdims: bool = False) -> NDArray[np.float64]:
    """``log(sum(exp(values)))`` along an axis, stable for finite inputs."""
    xp = namespace(values)
    top = xp.max(values, axis=axis, keepdims=True)
    out = top + xp.log(xp.sum(xp.exp(values - top), axis=axis, keepdims=True))
    return out if keepdims else xp.squeeze(out, axis=axis)


def markov_matrix(num_models: int, stay_probability: float) -> NDArray[np.float64]:
    """``pi[i, j] = P(model j at t | model i at t-1)``: ``stay`` on the diagonal, the rest shared."""
    if num_models == 1:
        return np.ones((1, 1))
    off = (1.0 - stay_probability) / (num_models - 1)
    return np.full((num_models, num_models), off) + np.eye(num_models) * (stay_probability - off)


def mix(
    log_probs: NDArray[np.float64],
    means: NDArray[np.float64],
    covs: NDArray[np.float64],
    log_markov: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Interaction: the mixed initial conditions of every model.

    Parameters
    ----------
    log_probs : (B, K, R) log model probabilities of the last step
    means, covs : (B, K, R, n), (B, K, R, n, n) per-model posteriors of the last step
    log_markov : (R, R) log of the Markov matrix

    Returns
    -------
    mixed_means, mixed_covs : (B, K, R, n), (B, K, R, n, n)
    log_c : (B, K, R) log predicted model probabilities ``log c_j``
    """
    xp = namespace(means)
    joint = log_markov + log_probs[..., :, None]  # (B, K, i, j)
    log_c = logsumexp(joint, axis=-2)  # (B, K, j)
    mixing = xp.exp(joint - log_c[..., None, :])  # mu_{i|j}
    mixed_means = xp.einsum("bkij,bkid->bkjd", mixing, means)
    spread = means[..., None, :, :] - mixed_means[..., :, None, :]  # (B, K, j, i, d)
    outer = spread[..., :, None] * spread[..., None, :]
    mixed_covs = xp.einsum("bkij,bkjide->bkjde", mixing, covs[..., None, :, :, :] + outer)
    return mixed_means, mixed_covs, log_c


def predict(
    means: NDArray[np.float64],
    covs: NDArray[np.float64],
    transitions: NDArray[np.float64],
    process_cov: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Exact linear prediction of each model: ``F_r x``, ``F_r P F_r' + Q`` (transitions (R, n, n))."""
    xp = namespace(means)
    pred_means = xp.einsum("rij,bkrj->bkri", transitions, means)
    pred_covs = xp.matmul(xp.matmul(transitions, covs), xp.swapaxes(transitions, -1, -2))
    return pred_means, symmetrize(pred_covs + process_cov)


def combine(
    means: NDArray[np.float64], covs: NDArray[np.float64], probs: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Moment-matched mixture of per-model Gaussians along the model axis (-2 / -3)."""
    xp = namespace(means)
    mean = xp.einsum("...r,...ri->...i", probs, means)
    spread = means - mean[..., None, :]
    cov = xp.einsum("...r,...rij->...ij", probs, covs + spread[..., :, None] * spread[..., None, :])
    return mean, symmetrize(cov)
