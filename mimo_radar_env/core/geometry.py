"""Bistatic geometry: ranges and the range-sum/azimuth measurement function (eq6)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def wrap_angle(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Wrap angles to (-pi, pi]."""
    wrapped = np.mod(angle + np.pi, 2.0 * np.pi) - np.pi
    return np.where(wrapped == -np.pi, np.pi, wrapped)


def station_ranges(positions: NDArray[np.float64], stations: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distances from positions (..., 2) to every station (S, 2): shape (..., S)."""
    delta = positions[..., None, :] - stations
    return np.sqrt(np.einsum("...i,...i->...", delta, delta))


def bistatic_measurement(
    positions: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``h_mn`` of eq6: ``[R_tx + R_rx, atan2(y - y_rx, x - x_rx)]``.

    ``positions``, ``tx`` and ``rx`` broadcast against each other, last axis (x, y).
    Returns shape (..., 2).
    """
    to_tx = positions - tx
    to_rx = positions - rx
    range_sum = np.hypot(to_tx[..., 0], to_tx[..., 1]) + np.hypot(to_rx[..., 0], to_rx[..., 1])
    azimuth = np.arctan2(to_rx[..., 1], to_rx[..., 0])
    return np.stack([range_sum, azimuth], axis=-1)
