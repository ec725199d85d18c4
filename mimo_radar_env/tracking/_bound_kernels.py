"""The compiled (numba) twin of :func:`mimo_radar_env.tracking.bound.bound_step`'s healthy path.

For every trial and target, :func:`bound_step` predicts the bound's covariance
(``F P F' + Q``), checks it with the closed-form condition test of
:func:`~mimo_radar_env.tracking.unscented.repair_covariance`'s fast path, inverts it in closed
form (the adjugate from the Laplace expansion in 2 x 2 minors, where the numpy path calls
LAPACK), adds the measured position information, and checks and inverts the result the same
way; the two paths agree to round-off (tested at 1e-12 over whole episodes). A matrix that
fails a check is flagged and the caller runs the numpy path (which repairs it) for the whole
batch. Importing this module needs numba (the ``fast`` extra).
"""

from __future__ import annotations

import numpy as np

from ..core.compiled import CHUNK, numba, twins

# numpy's error model: a division by a zero determinant gives inf or NaN, which the condition
# checks refuse (the numpy path then repairs the matrix), where Python's would raise
njit = numba.njit(cache=True, error_model="numpy")


@njit
def certainly_conditioned(a, det, max_condition):
    """``unscented._certainly_conditioned`` of one symmetric 4 x 4 matrix of determinant
    ``det`` (:func:`determinant`'s), and False unless ``det`` and the trace are finite (an
    inverse by a zero determinant is not a covariance to go on with)."""
    minor2 = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    cof0 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    cof1 = a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0]
    cof2 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    minor3 = a[0, 0] * cof0 - a[0, 1] * cof1 + a[0, 2] * cof2
    trace = a[0, 0] + a[1, 1] + a[2, 2] + a[3, 3]
    if not (np.isfinite(det) and np.isfinite(trace)):
        return False
    return a[0, 0] > 0 and minor2 > 0 and minor3 > 0 and det > 0 and trace**4 <= max_condition * det


@njit
def minors(a):
    """The 2 x 2 minors of rows 0-1 (``s0 .. s5``) and rows 2-3 (``c0 .. c5``) of ``a``, as
    ``unscented._det4`` forms them."""
    s0 = a[0, 0] * a[1, 1] - a[1, 0] * a[0, 1]
    s1 = a[0, 0] * a[1, 2] - a[1, 0] * a[0, 2]
    s2 = a[0, 0] * a[1, 3] - a[1, 0] * a[0, 3]
    s3 = a[0, 1] * a[1, 2] - a[1, 1] * a[0, 2]
    s4 = a[0, 1] * a[1, 3] - a[1, 1] * a[0, 3]
    s5 = a[0, 2] * a[1, 3] - a[1, 2] * a[0, 3]
    c5 = a[2, 2] * a[3, 3] - a[3, 2] * a[2, 3]
    c4 = a[2, 1] * a[3, 3] - a[3, 1] * a[2, 3]
    c3 = a[2, 1] * a[3, 2] - a[3, 1] * a[2, 2]
    c2 = a[2, 0] * a[3, 3] - a[3, 0] * a[2, 3]
    c1 = a[2, 0] * a[3, 2] - a[3, 0] * a[2, 2]
    c0 = a[2, 0] * a[3, 1] - a[3, 0] * a[2, 1]
    return s0, s1, s2, s3, s4, s5, c0, c1, c2, c3, c4, c5


@njit
def determinant(a):
    """``unscented._det4``: the Laplace expansion in 2 x 2 minors."""
    s0, s1, s2, s3, s4, s5, c0, c1, c2, c3, c4, c5 = minors(a)
    return s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0


@njit
def inverse(a, out):
    """The inverse of one 4 x 4 matrix in closed form (its adjugate over its determinant), into
    ``out``; returns the determinant (:func:`determinant`'s, from the same minors). For the
    guard's well-conditioned matrices it agrees with LAPACK's to round-off."""
    s0, s1, s2, s3, s4, s5, c0, c1, c2, c3, c4, c5 = minors(a)
    det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0
    a00, a01, a02, a03 = a[0, 0], a[0, 1], a[0, 2], a[0, 3]
    a10, a11, a12, a13 = a[1, 0], a[1, 1], a[1, 2], a[1, 3]
    a20, a21, a22, a23 = a[2, 0], a[2, 1], a[2, 2], a[2, 3]
    a30, a31, a32, a33 = a[3, 0], a[3, 1], a[3, 2], a[3, 3]
    out[0, 0] = (a11 * c5 - a12 * c4 + a13 * c3) / det
    out[0, 1] = (-a01 * c5 + a02 * c4 - a03 * c3) / det
    out[0, 2] = (a31 * s5 - a32 * s4 + a33 * s3) / det
    out[0, 3] = (-a21 * s5 + a22 * s4 - a23 * s3) / det
    out[1, 0] = (-a10 * c5 + a12 * c2 - a13 * c1) / det
    out[1, 1] = (a00 * c5 - a02 * c2 + a03 * c1) / det
    out[1, 2] = (-a30 * s5 + a32 * s2 - a33 * s1) / det
    out[1, 3] = (a20 * s5 - a22 * s2 + a23 * s1) / det
    out[2, 0] = (a10 * c4 - a11 * c2 + a13 * c0) / det
    out[2, 1] = (-a00 * c4 + a01 * c2 - a03 * c0) / det
    out[2, 2] = (a30 * s4 - a31 * s2 + a33 * s0) / det
    out[2, 3] = (-a20 * s4 + a21 * s2 - a23 * s0) / det
    out[3, 0] = (-a10 * c3 + a11 * c1 - a12 * c0) / det
    out[3, 1] = (a00 * c3 - a01 * c1 + a02 * c0) / det
    out[3, 2] = (-a30 * s3 + a31 * s1 - a32 * s0) / det
    out[3, 3] = (a20 * s3 - a21 * s1 + a22 * s0) / det
    return det


def _bound_step(covariance, transition, process_cov, measured, max_condition):
    """Returns ``(next covariance (B, K, 4, 4), healthy)``: ``healthy`` is False when a matrix
    failed a condition check (the result is then not to be used). A chunk of trials stops at its
    first failure; the others go on (their work is thrown away with the result)."""
    B, K = covariance.shape[:2]
    out = np.empty((B, K, 4, 4))
    chunks = (B + CHUNK - 1) // CHUNK
    healthy = np.ones(chunks, dtype=np.bool_)
    for chunk in numba.prange(chunks):
        prior = np.empty((4, 4))
        temp = np.empty((4, 4))
        information = np.empty((4, 4))
        for b in range(chunk * CHUNK, min(B, (chunk + 1) * CHUNK)):
            if not healthy[chunk]:
                break
            for k in range(K):
                F = transition[k]
                P = covariance[b, k]
                # F P F' + Q, as (F @ P) @ F' + Q
                for i in range(4):
                    for j in range(4):
                        acc = 0.0
                        for p in range(4):
                            acc += F[i, p] * P[p, j]
                        temp[i, j] = acc
                for i in range(4):
                    for j in range(4):
                        acc = 0.0
                        for p in range(4):
                            acc += temp[i, p] * F[j, p]
                        prior[i, j] = acc + process_cov[i, j]
                det = inverse(prior, information)  # used only if the prior passes the check
                if not certainly_conditioned(prior, det, max_condition):
                    healthy[chunk] = False
                    break
                for i in range(2):
                    for j in range(2):
                        information[2 * i, 2 * j] += measured[b, k, i, j]
                inverse(information, out[b, k])
                if not certainly_conditioned(out[b, k], determinant(out[b, k]), max_condition):
                    healthy[chunk] = False
                    break
    return out, healthy.all()


#: The kernel, serial and over threads (:func:`~mimo_radar_env.core.compiled.twins`).
bound_step, bound_step_threaded = twins(_bound_step, error_model="numpy")
