"""The predicted information of a super arm against direct computations."""

import itertools

import numpy as np
import pytest

from mimo_radar_env import RadarModel, load_scenario
from mimo_radar_env.core.geometry import bistatic_measurement
from mimo_radar_env.core.superarm import subset_masks
from mimo_radar_env.tracking import IMMUKFTracker
from mimo_radar_env.tracking.information import channel_information, super_arm_criterion


def _super_arms(num_tx, num_rx, ms, ns):
    tx, rx = subset_masks(num_tx, ms), subset_masks(num_rx, ns)
    pairs = list(itertools.product(range(len(tx)), range(len(rx))))
    return tx[[p[0] for p in pairs]], rx[[p[1] for p in pairs]]


def _random_case(rng, batch=3, targets=2, num_tx=3, num_rx=4):
    tx, rx = rng.uniform(0, 5e4, (num_tx, 2)), rng.uniform(0, 5e4, (num_rx, 2))
    states = np.concatenate(
        [rng.uniform(0, 5e4, (batch, targets, 1)), rng.normal(0, 50, (batch, targets, 1))], -1
    )
    states = np.concatenate(
        [states, rng.uniform(0, 5e4, (batch, targets, 1)), rng.normal(0, 50, (batch, targets, 1))], -1
    )
    root = rng.normal(0, 3, (batch, targets, 4, 4))
    cov = root @ np.swapaxes(root, -1, -2) + np.eye(4)
    variance = np.stack(
        [
            rng.uniform(1, 25, (batch, targets, num_tx, num_rx)),
            rng.uniform(1e-4, 1e-2, (batch, targets, num_tx, num_rx)),
        ],
        -1,
    )
    weights = rng.dirichlet(np.ones(targets))
    return tx, rx, states, cov, variance, weights


def _direct(tx, rx, state, cov, variance, tx_mask, rx_mask, criterion):
    """Explicit 4 x 4 information filter with finite-difference Jacobians, one trial and target."""
    info = np.linalg.inv(cov)
    for m in np.flatnonzero(tx_mask):
        for n in np.flatnonzero(rx_mask):
            jac = np.zeros((2, 4))
            for i in range(4):
                step = np.zeros(4)
                step[i] = 1e-3
                up = bistatic_measurement((state + step)[[0, 2]], tx[m], rx[n])
                down = bistatic_measurement((state - step)[[0, 2]], tx[m], rx[n])
                jac[:, i] = (up - down) / 2e-3
            info += jac.T @ np.linalg.inv(np.diag(variance[m, n])) @ jac
    position = np.linalg.inv(info)[np.ix_([0, 2], [0, 2])]
    return np.trace(position) if criterion == "trace" else np.log(np.linalg.det(position))


@pytest.mark.parametrize("criterion", ["trace", "logdet"])
def test_criterion_equals_the_explicit_information_filter(criterion):
    rng = np.random.default_rng(11)
    tx, rx, states, cov, variance, weights = _random_case(rng)
    tx_masks, rx_masks = _super_arms(3, 4, 2, 2)
    info = channel_information(states[..., [0, 2]], tx, rx, variance)
    position_cov = cov[..., [0, 2], :][..., [0, 2]]
    mine = super_arm_criterion(position_cov, info, tx_masks, rx_masks, weights, criterion)
    assert mine.shape == (3, len(tx_masks))
    for b in range(3):
        for a in range(len(tx_masks)):
            direct = sum(
                weights[k]
                * _direct(
                    tx, rx, states[b, k], cov[b, k], variance[b, k], tx_masks[a], rx_masks[a], criterion
                )
                for k in range(2)
            )
            assert mine[b, a] == pytest.approx(direct, rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("criterion", ["trace", "logdet"])
def test_adding_a_channel_never_increases_the_criterion(criterion):
    rng = np.random.default_rng(5)
    for _ in range(20):
        tx, rx, states, cov, variance, weights = _random_case(rng, num_tx=4, num_rx=5)
        info = channel_information(states[..., [0, 2]], tx, rx, variance)
        position_cov = cov[..., [0, 2], :][..., [0, 2]]
        small_tx, small_rx = _super_arms(4, 5, 2, 2)
        extra = rng.integers(0, 5, len(small_rx))
        big_rx = small_rx.copy()
        big_rx[np.arange(len(big_rx)), extra] = True  # one more receiver (or the same super arm)
        before = super_arm_criterion(position_cov, info, small_tx, small_rx, weights, criterion)
        after = super_arm_criterion(position_cov, info, small_tx, big_rx, weights, criterion)
        assert np.all(after <= before + 1e-12 * np.abs(before))


def test_predicted_covariance_is_the_mixture_of_the_models_predictions():
    model = RadarModel.from_scenario(load_scenario("paper-2-v1"))
    tracker = IMMUKFTracker(model, batch_size=2)
    rng = np.random.default_rng(0)
    tracker.log_probs = np.log(rng.dirichlet(np.ones(3), size=(2, 1)))
    tracker.means = tracker.means + rng.normal(0, 10, tracker.means.shape)
    pbar = tracker.predicted_covariance()
    markov = np.exp(tracker.log_markov)
    for b in range(2):
        mu = np.exp(tracker.log_probs[b, 0])
        c = mu @ markov
        means, covs = [], []
        for j in range(3):
            w = mu * markov[:, j] / c[j]
            x0 = sum(w[i] * tracker.means[b, 0, i] for i in range(3))
            p0 = sum(
                w[i]
                * (tracker.covs[b, 0, i] + np.outer(tracker.means[b, 0, i] - x0, tracker.means[b, 0, i] - x0))
                for i in range(3)
            )
            f = tracker.transitions[j]
            means.append(f @ x0)
            covs.append(f @ p0 @ f.T + model.process_cov)
        x = sum(c[j] * means[j] for j in range(3))
        p = sum(c[j] * (covs[j] + np.outer(means[j] - x, means[j] - x)) for j in range(3))
        np.testing.assert_allclose(pbar[b, 0], p, rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(tracker.predicted_covariance(), pbar)  # a pure query
