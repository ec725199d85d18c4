"""Batched unscented transform pieces: sigma points and the measurement update.

Conventions follow filterpy 2.x (``MerweScaledSigmaPoints`` and
``UnscentedKalmanFilter.update``) so that the two can be compared number for
number: sigma points ``x, x + U_k, x - U_k`` with ``U`` the Cholesky factor of
``(n + lambda) P``; weights of van der Merwe's scaled transform; the update uses
the sigma points of the prior. Every function works on arbitrary leading batch
axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import defer, deferring, namespace

_LOG_2PI = float(np.log(2.0 * np.pi))
_TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class SigmaPointParameters:
    """Van der Merwe's scaled sigma points (alpha, beta, kappa).

    The default ``alpha = 1, beta = 2, kappa = 0`` gives non-negative weights
    (``Wm0 = 0``, ``Wc0 = 2``, the others ``1/(2n)``), so every unscented
    covariance is positive semi-definite by construction.
    """

    alpha: float = 1.0
    beta: float = 2.0
    kappa: float = 0.0

    def scale(self, n: int) -> float:
        """``n + lambda = alpha^2 (n + kappa)``."""
        return self.alpha**2 * (n + self.kappa)

    def weights(self, n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Mean and covariance weights ``Wm``, ``Wc`` (2n + 1,)."""
        scale = self.scale(n)
        lam = scale - n
        wm = np.full(2 * n + 1, 0.5 / scale)
        wc = wm.copy()
        wm[0] = lam / scale
        wc[0] = lam / scale + (1.0 - self.alpha**2 + self.beta)
        return wm, wc


def symmetrize(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    xp = namespace(matrix)
    return 0.5 * (matrix + xp.swapaxes(matrix, -1, -2))


#: The condition-number guard: a covariance whose eigenvalues spread more than this (estimated
#: from its Cholesky factor) or that is not positive definite is repaired.
MAX_CONDITION = 1e12


def _floor_eigenvalues(
    matrix: NDArray[np.float64], relative_floor: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """``(symmetrised, rebuilt, low)``: the re-symmetrised matrices (non-finite entries zeroed),
    the same with eigenvalues raised to ``relative_floor * max(|eigenvalue|)`` (at least a tiny
    absolute jitter), and where an eigenvalue was below that floor."""
    xp = namespace(matrix)
    sym = symmetrize(matrix)
    sym = xp.where(xp.isfinite(sym), sym, 0.0)
    eigenvalues, eigenvectors = xp.linalg.eigh(sym)
    top = xp.max(xp.abs(eigenvalues), axis=-1, keepdims=True)
    floor = xp.maximum(relative_floor * top, 1e-12)
    low = xp.any(eigenvalues < floor, axis=-1)
    clipped = xp.maximum(eigenvalues, floor)
    rebuilt = symmetrize(xp.einsum("...ij,...j,...kj->...ik", eigenvectors, clipped, eigenvectors))
    return sym, rebuilt, low


def _certainly_conditioned(matrix: NDArray[np.float64], max_condition: float) -> NDArray[np.bool_]:
    """True where a symmetric 4 x 4 matrix is certainly positive definite with a condition number
    at most ``max_condition``: its leading principal minors are positive (Sylvester) and
    ``trace^4 / det``, an upper bound of the condition number, is within it. Closed forms, no
    factorisation; False only says "look closer"."""
    xp = namespace(matrix)
    entries = matrix.reshape(*matrix.shape[:-2], 16)
    with xp.errstate(all="ignore"):
        minors = _minors(entries)
        cofactors = entries[..., 0:3] * minors[..., 12:15]  # a00 cof0, a01 cof1, a02 cof2
        minor3 = cofactors[..., 0] - cofactors[..., 1] + cofactors[..., 2]
        det = _det4(minors)
        trace = xp.trace(matrix, axis1=-2, axis2=-1)
        return (
            (entries[..., 0] > 0)
            & (minors[..., 0] > 0)  # the leading 2 x 2 minor
            & (minor3 > 0)
            & (det > 0)
            & (trace**4 <= max_condition * det)
        )


def _minor_entries(rows: tuple[int, int], pairs: tuple[tuple[int, int], ...]) -> list[list[int]]:
    """The flat entries ``[A, B, C, D]`` of the 2 x 2 minors ``a[r][i] a[s][j] - a[s][i] a[r][j]``
    of ``rows`` (r, s) and column ``pairs`` (i, j) of a 4 x 4 matrix."""
    r, s = rows
    return [[4 * first + column[k] for column in pairs] for first, k in ((r, 0), (s, 1), (s, 0), (r, 1))]


_PAIRS = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
#: The entries of the 15 minors :func:`_minors` forms: ``s0 .. s5`` of rows 0-1 and ``c5 .. c0``
#: of rows 2-3 (the Laplace expansion's, :func:`_det4`), then the cofactors of ``a00``, ``a01``
#: and ``a02`` in the leading 3 x 3 block (rows 1-2, columns (1, 2), (0, 2), (0, 1)).
_MINOR_ENTRIES = tuple(
    tuple(a + b + c)
    for a, b, c in zip(
        _minor_entries((0, 1), _PAIRS),
        _minor_entries((2, 3), _PAIRS[::-1]),
        _minor_entries((1, 2), ((1, 2), (0, 2), (0, 1))),
        strict=True,
    )
)


def _minors(entries: NDArray[np.float64]) -> NDArray[np.float64]:
    """The 15 2 x 2 minors of :data:`_MINOR_ENTRIES` of 4 x 4 matrices given by their 16 entries
    (..., 16), in one gather: each ``A B - C D`` as the scalar expansion writes it, bit for bit."""
    xp = namespace(entries)
    gathered = entries[..., xp.constant(_MINOR_ENTRIES)]  # (..., 4, 15)
    return gathered[..., 0, :] * gathered[..., 1, :] - gathered[..., 2, :] * gathered[..., 3, :]


def _det4(minors: NDArray[np.float64]) -> NDArray[np.float64]:
    """Determinants of 4 x 4 matrices from their :func:`_minors`, by the Laplace expansion in
    2 x 2 minors, ``s0 c5 - s1 c4 + s2 c3 + s3 c2 - s4 c1 + s5 c0`` summed left to right."""
    terms = minors[..., 0:6] * minors[..., 6:12]
    det = terms[..., 0] - terms[..., 1]
    det = det + terms[..., 2]
    det = det + terms[..., 3]
    det = det - terms[..., 4]
    return det + terms[..., 5]


def repair_covariance(
    matrix: NDArray[np.float64], relative_floor: float = 1.0 / MAX_CONDITION
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Covariances made usable, and a mask (batch shape) of those repaired.

    A matrix that is not numerically positive definite, or whose condition number (estimated
    from its Cholesky factor's diagonal) exceeds ``1 / relative_floor``, gets its eigenvalues
    raised to ``relative_floor`` times the largest; the others are returned as given.
    """
    xp = namespace(matrix)
    if _left_as_given([matrix], relative_floor):  # the fast path of every healthy step
        return matrix, xp.zeros(matrix.shape[:-2], dtype=bool)
    try:
        diagonal = xp.diagonal(xp.linalg.cholesky(matrix), axis1=-2, axis2=-1)
        with xp.errstate(divide="ignore", invalid="ignore"):
            spread = (xp.max(diagonal, axis=-1) / xp.min(diagonal, axis=-1)) ** 2
        wanted = ~(spread <= 1.0 / relative_floor)
        if not wanted.any():
            return matrix, wanted
    except xp.linalg.LinAlgError:
        wanted = xp.zeros(matrix.shape[:-2], dtype=bool)
    _, rebuilt, low = _floor_eigenvalues(matrix, relative_floor)
    repaired = low | wanted
    return xp.where(repaired[..., None, None], rebuilt, matrix), repaired


def repair_covariances(
    matrices: Sequence[NDArray[np.float64]], relative_floor: float = 1.0 / MAX_CONDITION
) -> list[tuple[NDArray[np.float64], NDArray[np.bool_]]]:
    """:func:`repair_covariance` of each of ``matrices`` (4 x 4 covariances, of any batch shapes)
    with one closed-form test of the healthy ones over all of them (a step's model covariances
    and its fused covariance): the same results as one call each, in one pass where every one
    passes (the others are repaired one by one, as alone)."""
    xp = namespace(matrices[0])
    if _left_as_given(matrices, relative_floor):
        return [(m, xp.zeros(m.shape[:-2], dtype=bool)) for m in matrices]
    return [repair_covariance(m, relative_floor) for m in matrices]


def _left_as_given(matrices: Sequence[NDArray[np.float64]], relative_floor: float) -> bool:
    """Whether every one of ``matrices`` (4 x 4) is certainly healthy by the closed-form test
    (:func:`_certainly_conditioned`, one pass over all of them), so is returned as given; with
    deferred checks the test is left to the caller
    (:func:`~mimo_radar_env.core.arrays.deferred_checks`) and this is True.
    Other sizes: False (factorised)."""
    if not all(m.shape[-2:] == (4, 4) for m in matrices):
        return False
    xp = namespace(matrices[0])
    together = matrices[0] if len(matrices) == 1 else xp.concatenate([m.reshape(-1, 4, 4) for m in matrices])
    passed = _certainly_conditioned(together, 1.0 / relative_floor)
    if deferring():
        defer(passed)
        return True
    return bool(xp.all(passed))


def robust_cholesky(
    matrix: NDArray[np.float64], relative_floor: float = 1e-12
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Lower Cholesky factors of a batch of symmetric matrices, repairing failures.

    A matrix that is not numerically positive definite is re-symmetrised and its
    eigenvalues are raised to ``relative_floor * max(|eigenvalue|)`` (at least a
    tiny absolute jitter); only the failing matrices are touched.

    Returns the factors and a mask (batch shape) of the repaired matrices.
    """
    xp = namespace(matrix)
    try:
        return xp.linalg.cholesky(matrix), xp.zeros(matrix.shape[:-2], dtype=bool)
    except xp.linalg.LinAlgError:
        pass
    sym, rebuilt, repaired = _floor_eigenvalues(matrix, relative_floor)
    return xp.linalg.cholesky(xp.where(repaired[..., None, None], rebuilt, sym)), repaired


def sigma_points(mean: NDArray[np.float64], chol_scaled: NDArray[np.float64]) -> NDArray[np.float64]:
    """Sigma points (..., 2n + 1, n) from a mean (..., n) and the lower Cholesky
    factor of ``(n + lambda) P`` (..., n, n)."""
    xp = namespace(mean)
    offsets = xp.swapaxes(chol_scaled, -1, -2)  # rows = columns of L = rows of filterpy's U
    return xp.concatenate(
        [mean[..., None, :], mean[..., None, :] + offsets, mean[..., None, :] - offsets], axis=-2
    )


def measurement_mean(
    sigmas_h: NDArray[np.float64],
    wm: NDArray[np.float64],
    azimuth_sin_cos: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> NDArray[np.float64]:
    """Weighted mean of measurement sigma points (..., S, d).

    Measurements are (range sum, azimuth) pairs: even components are averaged
    linearly, odd ones (azimuths) as circular means. ``azimuth_sin_cos`` may give
    the sines and cosines of the azimuths (..., S, d/2) when they are at hand.
    """
    xp = namespace(sigmas_h)
    mean = xp.empty(sigmas_h.shape[:-2] + sigmas_h.shape[-1:])
    mean[..., 0::2] = xp.einsum("s,...sd->...d", wm, sigmas_h[..., 0::2])
    if azimuth_sin_cos is None:
        angles = sigmas_h[..., 1::2]
        azimuth_sin_cos = (xp.sin(angles), xp.cos(angles))
    sin, cos = azimuth_sin_cos
    mean[..., 1::2] = xp.arctan2(xp.einsum("s,...sd->...d", wm, sin), xp.einsum("s,...sd->...d", wm, cos))
    return mean


def measurement_residual(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a - b`` for (range sum, azimuth) pairs, azimuths wrapped into [-pi, pi]."""
    xp = namespace(a)
    diff = a - b
    angles = diff[..., 1::2]
    angles -= _TWO_PI * xp.rint(angles / _TWO_PI)
    return diff


def _inverse_and_logdet(
    matrix: NDArray[np.float64], allow_indefinite: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Inverse and log-determinant of symmetric positive definite matrices (..., d, d)
    (``allow_indefinite``: of any invertible symmetric matrix, ``log |det|``)."""
    xp = namespace(matrix)
    if matrix.shape[-1] == 2 and not allow_indefinite:  # closed form: the paper fusion's channels
        a, b, c = matrix[..., 0, 0], matrix[..., 0, 1], matrix[..., 1, 1]
        det = a * c - b * b
        inverse = xp.stack([xp.stack([c, -b], -1), xp.stack([-b, a], -1)], -2) / det[..., None, None]
        return inverse, xp.log(det)
    sign, logdet = xp.linalg.slogdet(matrix)
    try:
        return xp.linalg.inv(matrix), logdet
    except xp.linalg.LinAlgError:  # singular in some trials: those get NaN, and the tracker
        pass  # keeps their prediction (IMMUKFTracker counts it as a repair)
    singular = ~((sign != 0) if allow_indefinite else (sign > 0)) | ~xp.isfinite(logdet)
    inverse = xp.linalg.inv(xp.where(singular[..., None, None], xp.eye(matrix.shape[-1]), matrix))
    return xp.where(singular[..., None, None], xp.nan, inverse), xp.where(singular, xp.nan, logdet)


@dataclass
class UpdateResult:
    """Posterior of an unscented update.

    ``covariance`` is ``None`` when the update was asked not to form it; the
    posterior covariance is then ``prior_cov - gain @ cross_cov'``.
    """

    mean: NDArray[np.float64]
    covariance: NDArray[np.float64] | None
    log_likelihood: NDArray[np.float64]
    gain: NDArray[np.float64]
    cross_cov: NDArray[np.float64]


def unscented_update(
    prior_mean: NDArray[np.float64],
    prior_cov: NDArray[np.float64],
    sigmas: NDArray[np.float64],
    sigmas_h: NDArray[np.float64],
    measurement: NDArray[np.float64],
    noise_variance: NDArray[np.float64],
    wm: NDArray[np.float64],
    wc: NDArray[np.float64],
    azimuth_sin_cos: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    with_covariance: bool = True,
) -> UpdateResult:
    """One unscented measurement update, batched over leading axes.

    Parameters
    ----------
    prior_mean, prior_cov : (..., n), (..., n, n)
    sigmas : (..., S, n) sigma points of the prior
    sigmas_h : (..., S, d) the sigma points through the measurement function
    measurement : (..., d)
        (range sum, azimuth) pairs, stacked when several channels are fused.
    noise_variance : (..., d) diagonal of the measurement covariance R
    azimuth_sin_cos : optional sines and cosines of the sigma azimuths (..., S, d/2)
    with_covariance : bool
        False skips forming the posterior covariances (callers that only need
        sums of them fold the correction ``gain @ cross_cov'`` themselves).
    """
    xp = namespace(prior_mean)
    z_pred = measurement_mean(sigmas_h, wm, azimuth_sin_cos)
    dz = measurement_residual(sigmas_h, z_pred[..., None, :])
    dx = sigmas - prior_mean[..., None, :]
    weighted_dz = dz * wc[:, None]
    d = dz.shape[-1]
    cross_cov = xp.matmul(xp.swapaxes(dx, -1, -2), weighted_dz)
    residual = measurement_residual(measurement, z_pred)
    if d >= WOODBURY_MIN_DIMENSION and xp.all(wc != 0):
        gain, mahalanobis, logdet = _woodbury(dz, wc, noise_variance, cross_cov, residual)
    else:
        innovation_cov = xp.matmul(xp.swapaxes(weighted_dz, -1, -2), dz)
        diag = xp.arange(d)
        innovation_cov[..., diag, diag] += noise_variance
        innovation_inv, logdet = _inverse_and_logdet(innovation_cov)
        gain = xp.matmul(cross_cov, innovation_inv)
        mahalanobis = xp.matmul(xp.matmul(residual[..., None, :], innovation_inv), residual[..., None])[
            ..., 0, 0
        ]
    mean = prior_mean + xp.matmul(gain, residual[..., None])[..., 0]
    # K S K' = K Pxz' (as K S = Pxz); symmetric up to rounding: callers symmetrise what they keep
    cov = prior_cov - xp.matmul(gain, xp.swapaxes(cross_cov, -1, -2)) if with_covariance else None
    log_likelihood = -0.5 * (mahalanobis + logdet + d * _LOG_2PI)
    return UpdateResult(mean, cov, log_likelihood, gain, cross_cov)


#: From this stacked measurement dimension on (32 channels), the innovation covariance is
#: inverted through the Woodbury identity: it is the diagonal ``R`` plus a rank-``S`` term
#: (``S`` sigma points), so an ``S x S`` system replaces a ``d x d`` one. The paper's sizes (at
#: most 12 dimensions) keep the direct inverse.
WOODBURY_MIN_DIMENSION = 64


def _woodbury(
    dz: NDArray[np.float64],
    wc: NDArray[np.float64],
    noise_variance: NDArray[np.float64],
    cross_cov: NDArray[np.float64],
    residual: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Gain, Mahalanobis distance and log-determinant of ``S = dz' Wc dz + R`` (``R`` diagonal)
    by ``S^-1 = R^-1 - R^-1 dz' M^-1 dz R^-1`` with ``M = Wc^-1 + dz R^-1 dz'`` and
    ``det S = det R det Wc det M``. A singular ``M`` gives NaN in that trial (the tracker keeps
    its prediction there and counts it)."""
    xp = namespace(dz)
    inv_noise = 1.0 / noise_variance  # (..., d)
    scaled = dz * inv_noise[..., None, :]  # dz R^-1, (..., S, d)
    inner = xp.matmul(scaled, xp.swapaxes(dz, -1, -2))  # (..., S, S)
    points = xp.arange(wc.shape[0])
    inner[..., points, points] += 1.0 / wc
    inner_inv, inner_logdet = _inverse_and_logdet(inner, allow_indefinite=True)
    # K = Pxz R^-1 - (Pxz R^-1 dz') M^-1 (dz R^-1)
    cross_scaled = cross_cov * inv_noise[..., None, :]  # (..., n, d)
    gain = cross_scaled - xp.matmul(
        xp.matmul(xp.matmul(cross_scaled, xp.swapaxes(dz, -1, -2)), inner_inv), scaled
    )
    projected = xp.matmul(scaled, residual[..., None])[..., 0]  # dz R^-1 r, (..., S)
    mahalanobis = xp.einsum("...d,...d->...", residual * inv_noise, residual) - xp.einsum(
        "...s,...st,...t->...", projected, inner_inv, projected
    )
    logdet = xp.log(noise_variance).sum(axis=-1) + xp.log(xp.abs(wc)).sum() + inner_logdet
    return gain, mahalanobis, logdet
