"""The IMM-UKF tracker against filterpy: one IMM cycle under each fusion, average fusion as the mean of
per-channel cycles, centralised fusion as stacked measurements, predict-only trials, the compiled
fusions and Woodbury's solve."""

import copy

import numpy as np
import pytest
from filterpy.kalman import IMMEstimator

from mimo_radar_env import RadarModel, load_scenario
from mimo_radar_env.core.motion import transition_matrix
from mimo_radar_env.tracking import (
    IMMUKFTracker,
    markov_matrix,
)
from tests.helpers import reset_simulation
from tests.mimo_radar_env.tracking.filterpy_reference import make_reference_ukf, random_spd

RTOL = 1e-8


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


def _assert_fused_as_filterpy(tracker, imm):
    """Trial 0, target 0 of ``tracker``: filterpy's fused estimate, model probabilities and
    covariance."""
    np.testing.assert_allclose(tracker.estimate[0, 0], imm.x, rtol=RTOL)
    np.testing.assert_allclose(tracker.model_probabilities[0, 0], imm.mu, rtol=RTOL)
    np.testing.assert_allclose(tracker.covariance[0, 0], imm.P, rtol=1e-7, atol=1e-10)


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
        _assert_fused_as_filterpy(tracker, imm)


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
    _assert_fused_as_filterpy(tracker, imm)


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

    batch = 7
    rng = np.random.default_rng(5)
    sim = reset_simulation(model, batch, rng)
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
