"""Each compiled helper of the average fusion against the numpy function it mirrors."""

import numpy as np
import pytest

from mimo_radar_env.core.compiled import HAVE_NUMBA
from mimo_radar_env.core.geometry import station_geometry
from mimo_radar_env.tracking.fusion.average import average_channels
from mimo_radar_env.tracking.imm import logsumexp
from mimo_radar_env.tracking.unscented import measurement_mean, measurement_residual, symmetrize

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed: only the numpy path exists")


@pytest.fixture(scope="module")
def kernels():
    from mimo_radar_env.tracking.fusion import _average_kernels

    return _average_kernels


def _sigmas(rng, S=9):
    sigmas = rng.normal(0.0, 1.0, size=(1, 1, 1, S, 4)) * [3e3, 10.0, 3e3, 10.0] + [4e4, 0, 5e4, 0]
    return sigmas


def test_geometry_mean_and_moments_mirror_the_unscented_update(kernels):
    rng = np.random.default_rng(0)
    sigmas = _sigmas(rng)
    tx, rx = np.array([1e4, 2e4]), np.array([7e4, 9e4])
    S = sigmas.shape[3]
    h0, h1, sn, cs = (np.empty(S) for _ in range(4))
    kernels.station_geometry(sigmas, 0, 0, 0, tx[0], tx[1], rx[0], rx[1], h0, h1, sn, cs)
    tx_range, rx_range, azimuth, sin, cos = station_geometry(sigmas[0, 0, 0], tx, rx)
    np.testing.assert_allclose(h0, tx_range + rx_range, rtol=1e-14)
    np.testing.assert_allclose(np.stack([h1, sn, cs]), np.stack([azimuth, sin, cos]), rtol=1e-14, atol=1e-15)
    wm = rng.dirichlet(np.ones(S))
    z = kernels.measurement_mean(wm, h0, sn, cs)
    expected = measurement_mean(np.stack([h0, h1], -1), wm, (sn[:, None], cs[:, None]))
    np.testing.assert_allclose(z, expected, rtol=1e-13)
    for angle in (0.3, 3.5, -7.0, 12.0):
        assert kernels.wrap_residual(angle) == pytest.approx(
            measurement_residual(np.array([0.0, angle]), 0.0)[1]
        )
    wc = rng.normal(0.1, 0.05, size=S)
    mean = sigmas[0, 0, 0].mean(axis=0)[None, None, None]
    p0, p1 = np.empty(4), np.empty(4)
    s00, s01, s11 = kernels.innovation_moments(sigmas, mean, 0, 0, 0, wc, h0, h1, z[0], z[1], p0, p1)
    dz = measurement_residual(np.stack([h0, h1], -1), np.array(z))
    dx = sigmas[0, 0, 0] - mean[0, 0, 0]
    np.testing.assert_allclose([[s00, s01], [s01, s11]], (dz * wc[:, None]).T @ dz, rtol=1e-12)
    np.testing.assert_allclose(np.stack([p0, p1], -1), dx.T @ (dz * wc[:, None]), rtol=1e-12)


def test_logsumexp_and_symmetrize_mirror_numpy(kernels):
    values = np.array([-1e3, -2.0, 0.5, -1e3 + 1])
    assert kernels.logsumexp(values) == pytest.approx(logsumexp(values, axis=0), rel=1e-15)
    a = np.random.default_rng(1).normal(size=(4, 4))
    expected = symmetrize(a.copy())
    kernels.symmetrize(a)
    np.testing.assert_allclose(a, expected, rtol=1e-15)


def test_average_channels_mirrors_numpy(kernels):
    rng = np.random.default_rng(2)
    C, R, n = 6, 3, 4
    root = rng.normal(size=(R, n, n))
    pred_covs = root @ np.swapaxes(root, -1, -2) + 5 * np.eye(n)
    means = rng.normal(size=(C, R, n))
    log_post = np.log(rng.dirichlet(np.ones(R), size=C))
    gain, cross = rng.normal(size=(C, R, n, 2)) * 0.1, rng.normal(size=(C, R, n, 2)) * 0.1
    out = (np.empty((R, n)), np.empty((R, n, n)), np.empty(R), np.empty(n), np.empty((n, n)))
    kernels.average_channels(pred_covs, means, log_post, gain, cross, *out, np.empty(n))
    model_means, model_covs, estimate, covariance = average_channels(
        pred_covs[None, None],
        means[None, None],
        np.exp(log_post)[None, None],
        gain[None, None],
        cross[None, None],
    )
    for mine, theirs in zip(
        (out[0], out[1], out[3], out[4]), (model_means, model_covs, estimate, covariance), strict=True
    ):
        np.testing.assert_allclose(mine, theirs[0, 0], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(out[2], logsumexp(log_post, axis=0) - np.log(C), rtol=1e-14)


def test_a_zero_divisor_gives_what_numpy_gives_not_an_exception(kernels):
    """A singular innovation covariance and a sigma point on the receiver divide by zero: the
    kernels give inf or NaN as the numpy path does (the update's finiteness check then falls
    back to the prediction in that trial); Python's error model raised ZeroDivisionError out of
    the env's step."""
    n = 4
    gain, cross, posterior = np.empty((1, 1, n, 2)), np.empty((1, 1, n, 2)), np.empty((1, 1, n))
    log_likelihood = kernels.kalman_update(
        np.zeros((1, 1, 1, n)), 0, 0, 0, np.ones(n), np.ones(n), 0.0, 0.0, 0.0, 1.0, 1.0, 0,
        gain, cross, posterior,
    )  # fmt: skip
    # S = 0: its closed-form inverse is 0 / 0
    assert np.isnan(log_likelihood) and np.isnan(gain).all() and np.isnan(posterior).all()
    on_receiver = np.array([7e4, 0.0, 9e4, 0.0])[None, None, None, None].repeat(3, axis=3)
    h0, h1, sn, cs = (np.empty(3) for _ in range(4))
    kernels.station_geometry(on_receiver, 0, 0, 0, 1e4, 2e4, 7e4, 9e4, h0, h1, sn, cs)
    with np.errstate(all="ignore"):
        _, _, _, sin, cos = station_geometry(on_receiver[0, 0, 0], np.array([1e4, 2e4]), np.array([7e4, 9e4]))
    np.testing.assert_array_equal(np.isnan(sn), np.isnan(sin))
    np.testing.assert_array_equal(np.isnan(cs), np.isnan(cos))
    assert np.isnan(sn).all()
