"""Target motion: NCV and NCT transition matrices (eq1, eq3) and trajectories.

State ``X = [x, vx, y, vy]'`` in metres and metres per second.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .arrays import namespace

#: The positions x and y of a state ``[x, vx, y, vy]``, and its velocities: every other entry. A
#: slice, where a list of indices would, on a device, first be copied there from the host's
#: memory, which torch does synchronously.
POSITION = slice(0, None, 2)
VELOCITY = slice(1, None, 2)


def positions(states: NDArray[np.float64]) -> NDArray[np.float64]:
    """The positions (..., 2) of states (..., 4): a new array, as indexing with ``[0, 2]`` gives."""
    return namespace(states).ascontiguousarray(states[..., POSITION])


def position_block(covariance: NDArray[np.float64]) -> NDArray[np.float64]:
    """The position block (..., 2, 2) of covariances (..., 4, 4): a new array."""
    return namespace(covariance).ascontiguousarray(covariance[..., POSITION, POSITION])


def transition_matrix(turn_rate: ArrayLike, sample_time: float) -> NDArray[np.float64]:
    """NCT transition matrix for turn rate(s) ``w`` (rad/s); ``w = 0`` gives NCV.

    Positive ``w`` turns counter-clockwise. Vectorised: the result has
    shape ``np.shape(turn_rate) + (4, 4)``.
    """
    w = np.asarray(turn_rate, dtype=np.float64)
    wt = w * sample_time
    straight = np.abs(wt) < 1e-12
    safe_w = np.where(straight, 1.0, w)
    sin_wt, cos_wt = np.sin(wt), np.cos(wt)
    a = np.where(straight, sample_time, sin_wt / safe_w)  # sin(wT)/w
    b = np.where(straight, 0.0, (1.0 - cos_wt) / safe_w)  # (1-cos(wT))/w
    F = np.zeros(w.shape + (4, 4))
    F[..., 0, 0] = 1.0
    F[..., 0, 1] = a
    F[..., 0, 3] = -b
    F[..., 1, 1] = cos_wt
    F[..., 1, 3] = -sin_wt
    F[..., 2, 1] = b
    F[..., 2, 2] = 1.0
    F[..., 2, 3] = a
    F[..., 3, 1] = sin_wt
    F[..., 3, 3] = cos_wt
    return F


def noise_gain(sample_time: float) -> NDArray[np.float64]:
    """``G`` of eq3, shape (4, 2)."""
    ts = sample_time
    return np.array([[ts**2 / 2, 0.0], [ts, 0.0], [0.0, ts**2 / 2], [0.0, ts]])


def process_covariance(sample_time: float, process_noise: float) -> NDArray[np.float64]:
    """``Q = G diag(Qs, Qs) G'``, shape (4, 4)."""
    G = noise_gain(sample_time)
    return process_noise * G @ G.T


def nominal_trajectories(
    initial_states: NDArray[np.float64], transitions: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Noise-free trajectories: ``initial_states`` (K, 4), ``transitions`` (K, T, 4, 4).

    Returns (K, T+1, 4), the state at steps 0..T.
    """
    num_targets, horizon = transitions.shape[:2]
    out = np.empty((num_targets, horizon + 1, 4))
    out[:, 0] = initial_states
    for t in range(horizon):  # sequential in time by nature; vectorised over targets
        out[:, t + 1] = np.einsum("kij,kj->ki", transitions[:, t], out[:, t])
    return out
