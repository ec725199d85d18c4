"""The information pieces against numpy's linear algebra: each channel's H' R^-1 H, the 2 x 2
determinants and inverses, and Woodbury's gain against the 4 x 4 inverse it replaces."""

import numpy as np

from mimo_radar_env.core.geometry import measurement_jacobian
from mimo_radar_env.tracking import information as info


def _spd(rng, shape, n=2):
    root = rng.normal(size=(*shape, n, n))
    return root @ np.swapaxes(root, -1, -2) + 0.5 * np.eye(n)


def test_channel_information_is_h_transpose_r_inverse_h():
    rng = np.random.default_rng(0)
    positions = rng.uniform(2e4, 8e4, size=(3, 2, 2))  # (B, K, 2)
    tx, rx = rng.uniform(0, 1e5, size=(4, 2)), rng.uniform(0, 1e5, size=(5, 2))
    variance = rng.uniform(1.0, 10.0, size=(3, 2, 4, 5, 2))
    J = info.channel_information(positions, tx, rx, variance)
    H = measurement_jacobian(positions, tx, rx)
    for index in np.ndindex(*J.shape[:-2]):
        expected = H[index].T @ np.linalg.inv(np.diag(variance[index])) @ H[index]
        np.testing.assert_allclose(J[index], expected, rtol=1e-12)


def test_closed_form_determinants_and_inverses_are_numpys():
    a = _spd(np.random.default_rng(1), (6, 3))
    inverse, det = info.inverse_2x2(a)
    np.testing.assert_allclose(det, np.linalg.det(a), rtol=1e-12)
    np.testing.assert_allclose(inverse, np.linalg.inv(a), rtol=1e-12)
    covariance = _spd(np.random.default_rng(2), (6,), n=4)
    np.testing.assert_allclose(
        info.position_determinant(covariance), np.linalg.det(covariance[:, 0::2, 0::2]), rtol=1e-12
    )


def test_woodburys_gain_gives_the_posterior_of_the_four_by_four_inverse():
    rng = np.random.default_rng(3)
    P = _spd(rng, (5,), n=4)  # prior state covariances [x, vx, y, vy]
    J = _spd(rng, (5,))
    J[0] = [[2.0, 0.0], [0.0, 0.0]]  # a singular information: one direction observed only
    G = info.woodbury_gain(J, P[:, 0::2, 0::2])
    E = np.zeros((4, 2))
    E[0, 0] = E[2, 1] = 1.0
    for s in range(5):
        direct = np.linalg.inv(np.linalg.inv(P[s]) + E @ J[s] @ E.T)
        woodbury = P[s] - P[s] @ E @ G[s] @ E.T @ P[s]
        np.testing.assert_allclose(woodbury, direct, rtol=1e-10, atol=1e-12)
        np.testing.assert_array_equal(G[s], G[s].T)
