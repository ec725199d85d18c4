"""The posterior Cramer-Rao bound of the position for the selections made (docs/model.md,
section 14): the information recursion of Tichavsky et al. (1998) along the true trajectory."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..core.arrays import namespace
from ..core.compiled import HAVE_NUMBA, LazyKernels
from ..core.motion import POSITION
from .unscented import MAX_CONDITION, repair_covariance


def bound_step(
    covariance: NDArray[np.float64],
    transition: NDArray[np.float64],
    process_cov: NDArray[np.float64],
    measured: NDArray[np.float64],
    use_numba: bool = True,
) -> NDArray[np.float64]:
    """One step of the posterior Cramer-Rao bound's information recursion (linear Gaussian
    motion, Tichavsky et al. 1998): ``J' = (Q + F J^-1 F')^-1 + E' I E``; returns ``J'^-1``.

    ``covariance`` (B, K, 4, 4) the last step's ``J^-1``; ``transition`` (K, 4, 4) the true
    ``F`` of each target's step; ``process_cov`` (4, 4) ``Q``; ``measured`` (B, K, 2, 2) the
    position information ``I`` of the channels probed, at the true state with the true ``R``
    (0 when nothing was probed). ``E`` picks the position (state ``[x, vx, y, vy]``). The
    information form is kept for its numerical robustness: channel information can be huge
    near a station. Both covariances pass the tracker's condition-number guard
    (:func:`~mimo_radar_env.tracking.unscented.repair_covariance`), which changes nothing unless
    a prior is many orders of magnitude wider than the measurements. With numba
    (``use_numba``) a compiled twin (:mod:`._bound_kernels`: closed-form 4 x 4 inverses where
    this path calls LAPACK, agreeing to round-off) runs while every matrix passes the guard's
    closed-form test, and this numpy path otherwise.
    """
    xp = namespace(covariance, measured)
    if use_numba and HAVE_NUMBA and not xp.is_torch:
        # writable C arrays always: numba compiles a read-only array (a one-trial env's
        # broadcast initial bound) as another signature, a second compilation of the same kernel
        out, healthy = _KERNELS.for_batch("_compiled_step", len(covariance))(
            *(np.require(a, np.float64, ["C", "W"]) for a in (covariance, transition, process_cov, measured)),
            MAX_CONDITION,
        )
        if healthy:
            return out
    prior, _ = repair_covariance(
        xp.matmul(xp.matmul(transition, covariance), xp.swapaxes(transition, -1, -2)) + process_cov
    )
    information = xp.linalg.inv(prior)
    information[..., POSITION, POSITION] += measured
    return repair_covariance(xp.linalg.inv(information))[0]


def position_bound(covariance: NDArray[np.float64]) -> NDArray[np.float64]:
    """``sqrt(trace)`` of the position block of the bound's ``J^-1`` (m): (B, K) from (B, K, 4, 4)."""
    return namespace(covariance).sqrt(covariance[..., 0, 0] + covariance[..., 2, 2])


_KERNELS = LazyKernels(
    __name__,
    _compiled_step="._bound_kernels:bound_step",
    _compiled_step_threaded="._bound_kernels:bound_step_threaded",
)
__getattr__ = _KERNELS.module_getattr
