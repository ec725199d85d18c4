"""The IMM pieces against the textbook formulas written out per trial and model (Bar-Shalom, Li and
Kirubarajan, Section 11.6.6): the Markov matrix, mixing, prediction and the moment-matched
combination."""

import numpy as np
import pytest
from scipy.special import logsumexp as scipy_logsumexp

from mimo_radar_env.tracking import imm


def _random_state(rng, B=3, K=2, R=3, n=4):
    means = rng.normal(size=(B, K, R, n))
    root = rng.normal(size=(B, K, R, n, n))
    covs = root @ np.swapaxes(root, -1, -2) + n * np.eye(n)
    probs = rng.dirichlet(np.ones(R), size=(B, K))
    return means, covs, probs


def test_logsumexp_is_scipys_and_stable_where_exp_overflows():
    values = np.random.default_rng(0).normal(size=(4, 5)) * 50
    np.testing.assert_allclose(imm.logsumexp(values, axis=1), scipy_logsumexp(values, axis=1), rtol=1e-14)
    assert imm.logsumexp(np.array([[1000.0, 1000.0]]), axis=1)[0] == pytest.approx(1000 + np.log(2))


def test_the_markov_matrix_stays_on_the_diagonal_and_shares_the_rest():
    pi = imm.markov_matrix(3, 0.8)
    np.testing.assert_allclose(pi, [[0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8]])
    np.testing.assert_array_equal(imm.markov_matrix(1, 0.8), [[1.0]])


def test_mixing_is_the_textbooks_interaction_step():
    rng = np.random.default_rng(1)
    means, covs, probs = _random_state(rng)
    pi = imm.markov_matrix(3, 0.7)
    mixed_means, mixed_covs, log_c = imm.mix(np.log(probs), means, covs, np.log(pi))
    B, K, R, n = means.shape
    for b in range(B):
        for k in range(K):
            mu = probs[b, k]
            c = pi.T @ mu  # c_j = sum_i pi_ij mu_i
            np.testing.assert_allclose(np.exp(log_c[b, k]), c, rtol=1e-13)
            for j in range(R):
                weights = pi[:, j] * mu / c[j]  # mu_{i|j}
                x0 = sum(weights[i] * means[b, k, i] for i in range(R))
                P0 = sum(
                    weights[i] * (covs[b, k, i] + np.outer(means[b, k, i] - x0, means[b, k, i] - x0))
                    for i in range(R)
                )
                np.testing.assert_allclose(mixed_means[b, k, j], x0, rtol=1e-12, atol=1e-14)
                np.testing.assert_allclose(mixed_covs[b, k, j], P0, rtol=1e-12)


def test_prediction_is_each_models_linear_prediction():
    rng = np.random.default_rng(2)
    means, covs, _ = _random_state(rng)
    transitions = np.eye(4) + 0.1 * rng.normal(size=(3, 4, 4))
    q = np.diag([1.0, 2.0, 3.0, 4.0])
    pred_means, pred_covs = imm.predict(means, covs, transitions, q)
    for b, k, r in np.ndindex(*means.shape[:3]):
        F = transitions[r]
        np.testing.assert_allclose(pred_means[b, k, r], F @ means[b, k, r], rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(pred_covs[b, k, r], F @ covs[b, k, r] @ F.T + q, rtol=1e-12)
        np.testing.assert_array_equal(pred_covs[b, k, r], pred_covs[b, k, r].T)


def test_combination_matches_the_mixtures_first_two_moments():
    rng = np.random.default_rng(3)
    means, covs, probs = _random_state(rng)
    mean, cov = imm.combine(means, covs, probs)
    # the moments of the Gaussian mixture, by sampling it: a seeded statistical check
    b, k = 1, 0
    draws = 400_000
    models = rng.choice(3, size=draws, p=probs[b, k])
    roots = np.linalg.cholesky(covs[b, k])
    samples = means[b, k, models] + np.einsum("sij,sj->si", roots[models], rng.normal(size=(draws, 4)))
    np.testing.assert_allclose(samples.mean(0), mean[b, k], atol=0.03)
    np.testing.assert_allclose(np.cov(samples.T), cov[b, k], rtol=0.03, atol=0.05)
    # and exactly: the law of total covariance
    x = probs[b, k] @ means[b, k]
    total = sum(
        probs[b, k, r] * (covs[b, k, r] + np.outer(means[b, k, r] - x, means[b, k, r] - x)) for r in range(3)
    )
    np.testing.assert_allclose(cov[b, k], total, rtol=1e-12)
