"""The filterpy references the tracker tests share: an angle wrap, a random covariance and
filterpy's UKF set up as the tracker's."""

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def make_reference_ukf(F, Q, tx_list, rx_list):
    """A filterpy UKF with the stacked bistatic measurement of the given channels."""

    def hx(x):
        out = []
        for tx, rx in zip(tx_list, rx_list, strict=True):
            p = np.array([x[0], x[2]])
            out += [np.linalg.norm(p - tx) + np.linalg.norm(p - rx), np.arctan2(p[1] - rx[1], p[0] - rx[0])]
        return np.array(out)

    def z_mean(sigmas, wm):
        z = wm @ sigmas
        z[1::2] = np.arctan2(wm @ np.sin(sigmas[:, 1::2]), wm @ np.cos(sigmas[:, 1::2]))
        return z

    def residual_z(a, b):
        d = np.asarray(a - b, dtype=float)
        d[1::2] = wrap(d[1::2])
        return d

    points = MerweScaledSigmaPoints(4, alpha=1.0, beta=2.0, kappa=0.0)
    ukf = UnscentedKalmanFilter(
        dim_x=4,
        dim_z=2 * len(tx_list),
        dt=1.0,
        hx=hx,
        fx=lambda x, dt: F @ x,
        points=points,
        z_mean_fn=z_mean,
        residual_z=residual_z,
    )
    ukf.Q = Q.copy()
    return ukf


def random_spd(rng, scale):
    A = rng.normal(size=(4, 4))
    return scale * (A @ A.T + 4 * np.eye(4))
