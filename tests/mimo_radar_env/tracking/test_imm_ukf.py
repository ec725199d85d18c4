"""The batched IMM-UKF against filterpy filters (the reference implementation)."""

import copy

import numpy as np
import pytest
from filterpy.kalman import IMMEstimator, MerweScaledSigmaPoints, UnscentedKalmanFilter

from mimo_radar_env import RadarModel, load_scenario
from mimo_radar_env.core.motion import process_covariance, transition_matrix
from mimo_radar_env.tracking import (
    IMMUKFTracker,
    markov_matrix,
    robust_cholesky,
    sigma_points,
    unscented_update,
)
from mimo_radar_env.tracking.unscented import SigmaPointParameters

RTOL = 1e-8


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


def ours_predict_update(x0, P0, F, Q, tx, rx, z, variance):
    params = SigmaPointParameters()
    wm, wc = params.weights(4)
    x_pred = F @ x0
    P_pred = F @ P0 @ F.T + Q
    chol, _ = robust_cholesky(params.scale(4) * P_pred)
    sig = sigma_points(x_pred, chol)
    pos = sig[:, [0, 2]][:, None, :]
    h = np.concatenate(
        [
            np.linalg.norm(pos - tx, axis=-1) + np.linalg.norm(pos - rx, axis=-1),
            np.arctan2(pos[..., 1] - rx[:, 1], pos[..., 0] - rx[:, 0]),
        ],
        axis=-1,
    )
    C = len(tx)
    h = np.stack([h[:, :C], h[:, C:]], axis=-1).reshape(len(sig), 2 * C)  # interleave (range, azimuth)
    result = unscented_update(x_pred, P_pred, sig, h, z, variance, wm, wc)
    return x_pred, P_pred, result


@pytest.mark.parametrize("turn_deg", [0.0, 3.0, -3.0])
@pytest.mark.parametrize("num_channels", [1, 3])
def test_ukf_predict_and_update_equal_filterpy(turn_deg, num_channels):
    rng = np.random.default_rng(int(10 * turn_deg) + 100 + num_channels)
    F = transition_matrix(np.radians(turn_deg), 1.0)
    Q = process_covariance(1.0, 0.1)
    for trial in range(20):
        x0 = np.array(
            [rng.uniform(-5e4, 5e4), rng.normal(0, 100), rng.uniform(-5e4, 5e4), rng.normal(0, 100)]
        )
        P0 = random_spd(rng, rng.uniform(1, 50))
        tx = rng.uniform(-6e4, 6e4, size=(num_channels, 2))
        rx = rng.uniform(-6e4, 6e4, size=(num_channels, 2))
        if trial % 4 == 0:  # a receiver due east of the target: azimuths straddle +-pi
            rx[0] = [x0[0] + x0[1] + 3000.0, x0[2] + x0[3]]
        variance = np.tile([rng.uniform(2, 25), rng.uniform(0.001, 0.01)], num_channels)
        truth = F @ x0 + rng.normal(0, 3, size=4)
        pos = truth[[0, 2]]
        z = np.concatenate(
            [
                [np.linalg.norm(pos - t) + np.linalg.norm(pos - r), np.arctan2(pos[1] - r[1], pos[0] - r[0])]
                for t, r in zip(tx, rx, strict=True)
            ]
        )
        z += rng.normal(size=z.size) * np.sqrt(variance)
        z[1::2] = wrap(z[1::2])

        ukf = make_reference_ukf(F, Q, tx, rx)
        ukf.x, ukf.P = x0.copy(), P0.copy()
        ukf.predict()
        x_pred, P_pred, result = ours_predict_update(x0, P0, F, Q, tx, rx, z, variance)
        np.testing.assert_allclose(x_pred, ukf.x, rtol=RTOL)
        np.testing.assert_allclose(P_pred, ukf.P, rtol=RTOL, atol=1e-10 * np.abs(P_pred).max())
        ukf.update(z, R=np.diag(variance))
        np.testing.assert_allclose(result.mean, ukf.x, rtol=RTOL)
        np.testing.assert_allclose(result.covariance, ukf.P, rtol=1e-7, atol=1e-9 * np.abs(P_pred).max())
        np.testing.assert_allclose(result.log_likelihood, ukf.log_likelihood, rtol=RTOL)


def _reference_imm(model, means, covs, probs, tx, rx, R=None):
    Q = model.process_cov
    filters = []
    for r, rate in enumerate((0.0, 3.0, -3.0)):
        f = make_reference_ukf(transition_matrix(np.radians(rate), 1.0), Q, tx, rx)
        f.x, f.P = means[r].copy(), covs[r].copy()
        if R is not None:
            f.R = R.copy()
        filters.append(f)
    return IMMEstimator(filters, probs.copy(), markov_matrix(3, 0.8))


def _random_prior(rng, model):
    means = model.initial_states[0] + rng.normal(0, 20, size=(3, 4))
    covs = np.stack([random_spd(rng, 3.0) for _ in range(3)])
    probs = rng.dirichlet(np.ones(3) * 3)
    return means, covs, probs


def _set_prior(tracker, means, covs, probs):
    tracker.means[:] = means
    tracker.covs[:] = covs
    tracker.log_probs[:] = np.log(probs)


@pytest.mark.parametrize("fusion", ["average", "centralized"])
def test_one_imm_cycle_equals_filterpy_imm(fusion):
    """With one channel both fusions are one IMM-UKF cycle; compare to filterpy's IMMEstimator."""
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    rng = np.random.default_rng(7)
    for _ in range(10):
        means, covs, probs = _random_prior(rng, model)
        tx, rx = model.tx[[1]], model.rx[[2]]
        truth = means[0] + rng.normal(0, 2, 4)
        pos = truth[[0, 2]]
        variance = np.array([5.0, 0.002])
        z = np.array(
            [
                np.linalg.norm(pos - tx[0]) + np.linalg.norm(pos - rx[0]),
                np.arctan2(pos[1] - rx[0, 1], pos[0] - rx[0, 0]),
            ]
        )
        z += rng.normal(size=2) * np.sqrt(variance)

        imm = _reference_imm(model, means, covs, probs, tx, rx, R=np.diag(variance))
        imm.predict()
        imm.update(z)

        tracker = IMMUKFTracker(model, 1, fusion=fusion)
        _set_prior(tracker, means, covs, probs)
        tracker.step(tx[None], rx[None], z[None, None, None], variance[None, None, None], np.array([True]))
        np.testing.assert_allclose(tracker.means[0, 0], [f.x for f in imm.filters], rtol=RTOL)
        np.testing.assert_allclose(tracker.covs[0, 0], [f.P for f in imm.filters], rtol=1e-7, atol=1e-10)
        np.testing.assert_allclose(tracker.model_probabilities[0, 0], imm.mu, rtol=RTOL)
        np.testing.assert_allclose(tracker.estimate[0, 0], imm.x, rtol=RTOL)
        np.testing.assert_allclose(tracker.covariance[0, 0], imm.P, rtol=1e-7, atol=1e-10)


def test_average_fusion_is_the_mean_of_per_channel_imm_cycles():
    """eq22: every channel runs an IMM-UKF cycle from the fused prior; results are averaged."""
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    rng = np.random.default_rng(8)
    means, covs, probs = _random_prior(rng, model)
    tx_idx, rx_idx = np.array([0, 0, 0, 3, 3, 3]), np.array([1, 2, 4, 1, 2, 4])
    tx, rx = model.tx[tx_idx], model.rx[rx_idx]
    pos = means[0][[0, 2]] + 5.0
    z = np.stack(
        [
            [np.linalg.norm(pos - t) + np.linalg.norm(pos - r), np.arctan2(pos[1] - r[1], pos[0] - r[0])]
            for t, r in zip(tx, rx, strict=True)
        ]
    )
    variance = np.tile([5.0, 0.002], (6, 1)) * rng.uniform(1, 5, size=(6, 1))
    refs = []
    for c in range(6):
        imm = _reference_imm(model, means, covs, probs, tx[[c]], rx[[c]], R=np.diag(variance[c]))
        imm.predict()
        imm.update(z[c])
        refs.append(copy.deepcopy(imm))
    tracker = IMMUKFTracker(model, 1, fusion="average")
    _set_prior(tracker, means, covs, probs)
    # the tracker takes the selected stations; channels are their pairs, TX-major
    tx_stations, rx_stations = model.tx[[0, 3]], model.rx[[1, 2, 4]]
    tracker.step(tx_stations[None], rx_stations[None], z[None, None], variance[None, None], np.array([True]))
    np.testing.assert_allclose(tracker.estimate[0, 0], np.mean([r.x for r in refs], axis=0), rtol=RTOL)
    np.testing.assert_allclose(tracker.covariance[0, 0], np.mean([r.P for r in refs], axis=0), rtol=1e-7)
    np.testing.assert_allclose(
        tracker.model_probabilities[0, 0], np.mean([r.mu for r in refs], axis=0), rtol=RTOL
    )
    np.testing.assert_allclose(
        tracker.means[0, 0], np.mean([[f.x for f in r.filters] for r in refs], axis=0), rtol=RTOL
    )


def test_centralized_fusion_equals_filterpy_with_stacked_measurements():
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    rng = np.random.default_rng(9)
    means, covs, probs = _random_prior(rng, model)
    tx, rx = model.tx[[0, 0, 1, 1]], model.rx[[0, 5, 0, 5]]
    pos = means[1][[0, 2]] - 4.0
    z = np.stack(
        [
            [np.linalg.norm(pos - t) + np.linalg.norm(pos - r), np.arctan2(pos[1] - r[1], pos[0] - r[0])]
            for t, r in zip(tx, rx, strict=True)
        ]
    )
    variance = np.tile([5.0, 0.002], (4, 1))
    imm = _reference_imm(model, means, covs, probs, tx, rx, R=np.diag(variance.ravel()))
    imm.predict()
    imm.update(z.ravel())
    tracker = IMMUKFTracker(model, 1, fusion="centralized")
    _set_prior(tracker, means, covs, probs)
    tx_stations, rx_stations = model.tx[[0, 1]], model.rx[[0, 5]]  # channels 0-0, 0-5, 1-0, 1-5
    tracker.step(tx_stations[None], rx_stations[None], z[None, None], variance[None, None], np.array([True]))
    np.testing.assert_allclose(tracker.estimate[0, 0], imm.x, rtol=RTOL)
    np.testing.assert_allclose(tracker.model_probabilities[0, 0], imm.mu, rtol=RTOL)
    np.testing.assert_allclose(tracker.covariance[0, 0], imm.P, rtol=1e-7, atol=1e-10)


def test_predict_only_trials_and_eq24():
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    rng = np.random.default_rng(10)
    means, covs, probs = _random_prior(rng, model)
    tracker = IMMUKFTracker(model, 2)
    _set_prior(tracker, means, covs, probs)
    imm = _reference_imm(model, means, covs, probs, model.tx[[0]], model.rx[[0]])
    imm.predict()  # interaction + per-model prediction, no update
    tx = np.broadcast_to(model.tx[[0]], (2, 1, 2))
    rx = np.broadcast_to(model.rx[[0]], (2, 1, 2))
    tracker.step(tx, rx, np.zeros((2, 1, 1, 2)), np.ones((2, 1, 1, 2)), np.array([False, False]))
    np.testing.assert_allclose(tracker.means[0, 0], [f.x for f in imm.filters], rtol=RTOL)
    np.testing.assert_allclose(tracker.model_probabilities[0, 0], probs @ markov_matrix(3, 0.8), rtol=RTOL)
    # eq24: sum_i u_i F_i(X_hat)
    F = transition_matrix(np.radians([0.0, 3.0, -3.0]), 1.0)
    expected = sum(tracker.model_probabilities[0, 0, i] * F[i] @ tracker.estimate[0, 0] for i in range(3))
    np.testing.assert_allclose(tracker.predicted_state()[0, 0], expected, rtol=1e-12)


@pytest.mark.parametrize("fusion", ["average", "centralized"])
@pytest.mark.parametrize("scenario", ["paper-3", "large"])
def test_compiled_fusion_equals_the_numpy_path(scenario, fusion):
    """Each fusion's numba kernel against its numpy twin (the large layout's 16 channels stack
    a 32-dimensional measurement: below the Woodbury switch, so the kernel runs)."""
    from mimo_radar_env.core.compiled import HAVE_NUMBA
    from tests.helpers import large_scenario

    if not HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy path exists")
    sc = large_scenario(16, 16, 5, horizon=100) if scenario == "large" else load_scenario(scenario)
    model = RadarModel.from_scenario(sc)
    from mimo_radar_env.core.simulation import RadarSimulation
    from mimo_radar_env.core.streams import keys_from_generator

    batch = 7
    sim = RadarSimulation(model, batch)
    rng = np.random.default_rng(5)
    sim.reset(np.stack([keys_from_generator(rng) for _ in range(batch)]))
    trackers = [IMMUKFTracker(model, batch, fusion=fusion, use_numba=flag) for flag in (True, False)]
    for _ in range(40):
        sim.advance()
        tx = np.sort(np.argsort(rng.random((batch, sc.num_tx)), axis=1)[:, : sc.tx_per_step], axis=1)
        rx = np.sort(np.argsort(rng.random((batch, sc.num_rx)), axis=1)[:, : sc.rx_per_step], axis=1)
        valid = rng.random(batch) > 0.1
        obs = sim.observe(tx, rx, valid)
        for tracker in trackers:
            tracker.step(model.tx[tx], model.rx[rx], obs.measurement, obs.noise_variance, valid)
    fast, slow = trackers
    for name in ("estimate", "covariance", "means", "covs", "log_probs"):
        np.testing.assert_allclose(
            getattr(fast, name), getattr(slow, name), rtol=1e-10, atol=1e-10, err_msg=name
        )


def test_a_large_stacked_measurement_is_solved_through_woodbury_as_directly(monkeypatch):
    """From WOODBURY_MIN_DIMENSION on, the innovation covariance is inverted through the Woodbury
    identity; the update equals the direct inverse's (here 40 channels, 80 dimensions)."""
    from mimo_radar_env.tracking import unscented

    rng = np.random.default_rng(4)
    batch, n, d = 5, 4, 80
    params = unscented.SigmaPointParameters()
    wm, wc = params.weights(n)
    mean = rng.normal(size=(batch, n)) * 100
    root = rng.normal(size=(batch, n, n))
    cov = root @ np.swapaxes(root, -1, -2) + 10 * np.eye(n)
    chol, _ = unscented.robust_cholesky(params.scale(n) * cov)
    sigmas = unscented.sigma_points(mean, chol)
    lift = rng.normal(size=(n, d))
    sigmas_h = sigmas @ lift + rng.normal(size=(batch, 1, d))
    sigmas_h[..., 1::2] = np.arctan2(np.sin(sigmas_h[..., 1::2] / 100), np.cos(sigmas_h[..., 1::2] / 100))
    measurement = sigmas_h[:, 0] + rng.normal(size=(batch, d)) * 0.1
    noise = rng.uniform(0.5, 2.0, size=(batch, d))
    args = (mean, cov, sigmas, sigmas_h, measurement, noise, wm, wc)
    assert d >= unscented.WOODBURY_MIN_DIMENSION
    woodbury = unscented.unscented_update(*args)
    monkeypatch.setattr(unscented, "WOODBURY_MIN_DIMENSION", 10**9)
    direct = unscented.unscented_update(*args)
    for field in ("mean", "covariance", "log_likelihood", "gain"):
        np.testing.assert_allclose(
            getattr(woodbury, field), getattr(direct, field), rtol=1e-9, atol=1e-9, err_msg=field
        )
