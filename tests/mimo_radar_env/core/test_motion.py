"""The truth follows the motion model."""

import numpy as np

from tests.helpers import simulation


def test_truth_follows_the_motion_model():
    """Increments of the truth have the process-noise covariance Q = G diag(Qs, Qs) G'."""
    batch = 4000
    _, sim = simulation("paper-1", batch, seed=2)
    start = sim.state.copy()
    np.testing.assert_allclose(
        np.cov(start[:, 0].T), np.diag([20.0] * 4), atol=1.5
    )  # 4.7 sigma of a sample covariance
    sim.advance()
    F = np.array([[1, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1.0]])
    noise = sim.state[:, 0] - start[:, 0] @ F.T
    Q = 0.1 * np.array([[0.25, 0.5, 0, 0], [0.5, 1, 0, 0], [0, 0, 0.25, 0.5], [0, 0, 0.5, 1]])
    np.testing.assert_allclose(np.cov(noise.T), Q, atol=0.012)
