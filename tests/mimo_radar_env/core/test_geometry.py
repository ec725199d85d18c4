"""The bistatic geometry (eq6) and its Jacobian."""

import numpy as np

from mimo_radar_env.core.geometry import bistatic_measurement, measurement_jacobian


def test_measurement_jacobian_matches_finite_differences():
    rng = np.random.default_rng(1)
    p, tx, rx = rng.uniform(0, 1e5, (5, 2)), rng.uniform(0, 1e5, (4, 2)), rng.uniform(0, 1e5, (6, 2))
    shape = (5, 4, 6, 2)
    points = np.broadcast_to(p[:, None, None], shape)
    tx_b, rx_b = np.broadcast_to(tx[None, :, None], shape), np.broadcast_to(rx[None, None], shape)
    numeric = np.zeros((5, 4, 6, 2, 2))
    for i, step in enumerate(np.eye(2) * 1e-2):
        h_plus, h_minus = (
            bistatic_measurement(points + step, tx_b, rx_b),
            bistatic_measurement(points - step, tx_b, rx_b),
        )
        numeric[..., i] = (h_plus - h_minus) / 2e-2
    np.testing.assert_allclose(measurement_jacobian(p, tx, rx), numeric, rtol=1e-6, atol=1e-10)
