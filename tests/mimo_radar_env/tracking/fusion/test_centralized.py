"""The centralised fusion's compiled helpers against numpy's linear algebra (the whole kernel
against the numpy path is in test_imm_ukf_reference)."""

import numpy as np
import pytest

from mimo_radar_env.core.compiled import HAVE_NUMBA

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed: only the numpy path exists")


def _kernels():
    from mimo_radar_env.tracking.fusion import _centralized_kernels as kernels

    return kernels


@pytest.mark.parametrize("size", [1, 2, 18, 40])
def test_the_cholesky_factor_and_solves_are_numpys(size):
    kernels = _kernels()
    rng = np.random.default_rng(size)
    root = rng.normal(size=(size, size))
    matrix = root @ root.T + size * np.eye(size)
    factor = matrix.copy()
    logdet = kernels.cholesky(factor)
    lower = np.tril(factor)
    np.testing.assert_allclose(lower, np.linalg.cholesky(matrix), rtol=1e-12, atol=1e-12)
    assert logdet == pytest.approx(np.linalg.slogdet(matrix)[1], rel=1e-12)
    x = rng.normal(size=size)
    forward, both = x.copy(), x.copy()
    kernels.forward(factor, forward)
    kernels.forward(factor, both)
    kernels.backward(factor, both)
    np.testing.assert_allclose(forward, np.linalg.solve(lower, x), rtol=1e-10)
    np.testing.assert_allclose(both, np.linalg.solve(matrix, x), rtol=1e-10)


def test_a_covariance_that_is_not_positive_definite_gives_nan():
    kernels = _kernels()
    indefinite = np.array([[1.0, 2.0], [2.0, 1.0]])
    assert np.isnan(kernels.cholesky(indefinite.copy()))
    assert np.isnan(kernels.cholesky(np.zeros((3, 3))))
