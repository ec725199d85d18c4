"""The fusion interface's contract, for every registered fusion: its super-arm posterior from the
channels' summed terms is the one its planning gain gives through Woodbury's identity; and the
pieces the base shares (finite flags, the path layout, the numba switch)."""

import numpy as np
import pytest

from mimo_radar_env.core.compiled import HAVE_NUMBA
from mimo_radar_env.tracking.fusion import FUSIONS, fusion_class
from mimo_radar_env.tracking.fusion.base import Posterior, Prior
from mimo_radar_env.tracking.information import inverse_2x2


def _spd(rng, shape, n):
    root = rng.normal(size=(*shape, n, n))
    return root @ np.swapaxes(root, -1, -2) + 0.5 * np.eye(n)


@pytest.mark.parametrize("name", sorted(FUSIONS))
def test_the_super_arm_posterior_is_the_planning_gains(name):
    fusion = fusion_class(name)
    rng = np.random.default_rng(0)
    S, K, M, N = 4, 2, 3, 4
    P = _spd(rng, (S, K), 4)
    information = _spd(rng, (S, K, M, N), 2) * 0.1
    selected = np.zeros((S, M, N))
    selected[:, :2, 1:4] = 1.0  # 2 x 3 channels
    selected[1] = 0.0
    selected[1, 0, 0] = 1.0  # one channel
    prior_info, _ = inverse_2x2(P[..., 0::2, 0::2])
    terms = fusion.channel_terms(prior_info, information)  # (S, K, M, N, 2, 2)
    total = np.einsum("skmnij,smn->skij", terms, selected)
    count = selected.sum(axis=(1, 2))[:, None, None, None]
    from_sum = fusion.posterior_from_sum(prior_info, total, count)
    G = fusion.planning_gain(information, P[..., 0::2, 0::2], selected)
    E = np.zeros((4, 2))
    E[0, 0] = E[2, 1] = 1.0
    from_gain = P - P @ E @ G @ E.T @ P
    np.testing.assert_allclose(from_sum, from_gain[..., 0::2, 0::2], rtol=1e-9)


def test_posterior_finite_flags_each_target_whose_update_failed():
    means, covs, log_probs = np.zeros((2, 3, 3, 4)), np.ones((2, 3, 3, 4, 4)), np.zeros((2, 3, 3))
    covs[0, 1, 2, 3, 3] = np.nan
    log_probs[1, 2, 0] = np.inf
    posterior = Posterior(means, covs, log_probs, means[:, :, 0], covs[:, :, 0])
    np.testing.assert_array_equal(posterior.finite(), [[True, False, True], [True, True, False]])


def test_run_path_passes_the_priors_arrays_then_the_channels_in_order():
    arrays = [np.full(1, float(i)) for i in range(6)]
    prior = Prior(*arrays)
    seen = []

    def path(*args):
        seen.extend(float(a[0]) if isinstance(a, np.ndarray) else a for a in args)
        return tuple(np.zeros(1) for _ in range(5))

    fusion = next(iter(FUSIONS.values()))
    assert isinstance(fusion.run_path(path, prior, "tx", "rx", "z", "r"), Posterior)
    assert seen == [3.0, 0.0, 1.0, 2.0, 4.0, 5.0, "tx", "rx", "z", "r"]  # sigmas, means, covs, log_c, wm, wc


def test_the_compiled_path_is_taken_only_where_numba_is_installed_and_asked_for():
    for cls in FUSIONS.values():
        assert cls(use_numba=False).use_numba is False
        assert cls().use_numba is HAVE_NUMBA


def test_an_unknown_fusion_is_named_with_the_choices():
    with pytest.raises(ValueError, match=r"fusion must be one of \['average', 'centralized'"):
        fusion_class("median")
