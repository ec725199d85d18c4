"""Bistatic geometry: ranges and the range-sum/azimuth measurement function (eq6)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .arrays import namespace


def wrap_angle(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Wrap angles to (-pi, pi]."""
    xp = namespace(angle)
    wrapped = xp.mod(angle + xp.pi, 2.0 * xp.pi) - xp.pi
    return xp.where(wrapped == -xp.pi, xp.pi, wrapped)


def station_ranges(positions: NDArray[np.float64], stations: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distances from positions (..., 2) to every station (S, 2): shape (..., S)."""
    xp = namespace(positions)
    delta = positions[..., None, :] - stations
    return xp.sqrt(xp.einsum("...i,...i->...", delta, delta))


#: Ranges below this (m) count as this in the SINR model, which stays finite by construction
#: (scenarios keep their tracks 10 m or more from every station; a trial may stray closer).
MIN_RANGE = 1.0


def squared_range_products(
    positions: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(R_tx[m] R_rx[n])^2`` for positions (..., 2) and stations (M, 2), (N, 2): shape (..., M, N).

    The one home of eq5's range dependence: the mean SINR is ``gain / (R_tx R_rx)^2``.
    """
    xp = namespace(positions)
    tx_sq = xp.maximum(station_ranges(positions, tx), MIN_RANGE) ** 2
    rx_sq = xp.maximum(station_ranges(positions, rx), MIN_RANGE) ** 2
    return tx_sq[..., :, None] * rx_sq[..., None, :]


def path_gain(
    positions: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``L = (R_tx R_rx)^-2`` (eq5, eq16) of every channel, shape (..., M, N)."""
    return 1.0 / squared_range_products(positions, tx, rx)


def bistatic_measurement(
    positions: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``h_mn`` of eq6: ``[R_tx + R_rx, atan2(y - y_rx, x - x_rx)]``.

    ``positions``, ``tx`` and ``rx`` broadcast against each other, last axis (x, y).
    Returns shape (..., 2).
    """
    xp = namespace(positions)
    to_tx = positions - tx
    to_rx = positions - rx
    range_sum = xp.hypot(to_tx[..., 0], to_tx[..., 1]) + xp.hypot(to_rx[..., 0], to_rx[..., 1])
    azimuth = xp.arctan2(to_rx[..., 1], to_rx[..., 0])
    return xp.stack([range_sum, azimuth], axis=-1)


def station_geometry(
    points: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> tuple[
    NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]
]:
    """eq6 per station: ranges to the transmitters, and ranges, azimuths, sines and cosines
    of the azimuths to the receivers.

    ``points`` (..., 4) are states ``[x, vx, y, vy]`` (sigma points); they broadcast against
    the station positions (..., 2). A channel's range sum is ``tx_range + rx_range`` and its
    azimuth the receiver's: computing per station and broadcasting over channels saves the
    work of ``Ms * Ns`` channels on ``Ms + Ns`` stations.
    """
    xp = namespace(points)
    tx_dx, tx_dy = points[..., 0] - tx[..., 0], points[..., 2] - tx[..., 1]
    rx_dx, rx_dy = points[..., 0] - rx[..., 0], points[..., 2] - rx[..., 1]
    tx_range = xp.sqrt(tx_dx * tx_dx + tx_dy * tx_dy)
    rx_range = xp.sqrt(rx_dx * rx_dx + rx_dy * rx_dy)
    return tx_range, rx_range, xp.arctan2(rx_dy, rx_dx), rx_dy / rx_range, rx_dx / rx_range


def channel_jacobian(
    positions: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``d h / d(x, y)`` of eq6 for positions and stations that broadcast (last axis (x, y)):
    shape (..., 2, 2).

    Row 0 is the range sum's gradient, the sum of the unit vectors from the TX and the RX to
    the target; row 1 the azimuth's, ``(-dy, dx) / R_rx^2`` from the RX.
    """
    xp = namespace(positions)
    to_tx, to_rx = positions - tx, positions - rx
    tx_range = xp.maximum(xp.linalg.norm(to_tx, axis=-1, keepdims=True), MIN_RANGE)
    rx_range = xp.maximum(xp.linalg.norm(to_rx, axis=-1, keepdims=True), MIN_RANGE)
    range_sum = to_tx / tx_range + to_rx / rx_range
    azimuth = xp.stack([-to_rx[..., 1], to_rx[..., 0]], axis=-1) / rx_range**2
    return xp.stack(xp.broadcast_arrays(range_sum, azimuth), axis=-2)


def measurement_jacobian(
    positions: NDArray[np.float64], tx: NDArray[np.float64], rx: NDArray[np.float64]
) -> NDArray[np.float64]:
    """:func:`channel_jacobian` of every channel: positions (..., 2), stations (M, 2), (N, 2);
    shape (..., M, N, 2, 2)."""
    return channel_jacobian(positions[..., None, None, :], tx[:, None, :], rx[None, :, :])
