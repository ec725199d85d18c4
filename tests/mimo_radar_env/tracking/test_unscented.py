"""The UKF's predict and update equal filterpy's."""

import numpy as np
import pytest

from mimo_radar_env.core.motion import process_covariance, transition_matrix
from mimo_radar_env.tracking import (
    robust_cholesky,
    sigma_points,
    unscented_update,
)
from mimo_radar_env.tracking.unscented import SigmaPointParameters
from tests.mimo_radar_env.tracking.filterpy_reference import make_reference_ukf, random_spd, wrap

RTOL = 1e-8


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


def test_the_covariance_guards_closed_forms_are_the_scalar_expansion_bit_for_bit():
    """The guard's determinant and conditioning test, formed in one gather of 2 x 2 minors, give
    the scalar Laplace expansion's bits (the compiled kernels write it out entry by entry), on
    numpy and on torch, and numpy's determinant to round-off."""
    pytest.importorskip("numba")
    from mimo_radar_env.tracking import _bound_kernels as scalar
    from mimo_radar_env.tracking import unscented

    rng = np.random.default_rng(1)
    root = rng.normal(size=(400, 4, 4))
    matrices = root @ np.swapaxes(root, -1, -2) + rng.random((400, 1, 1)) * np.eye(4)
    matrices[::7] *= -1  # negative definite: refused
    matrices[3] = np.diag([1.0, 1e-15, 1.0, 1.0])  # condition 1e15: refused
    det = unscented._det4(unscented._minors(matrices.reshape(-1, 16)))
    checked = unscented._certainly_conditioned(matrices, 1e12)
    expected_det = np.array([scalar.determinant.py_func(m) for m in matrices])
    expected = [
        scalar.certainly_conditioned.py_func(m, d, 1e12) for m, d in zip(matrices, expected_det, strict=True)
    ]
    np.testing.assert_array_equal(det, expected_det)
    assert checked.tolist() == expected and 0 < checked.sum() < len(matrices) - 50
    np.testing.assert_allclose(det, np.linalg.det(matrices), rtol=1e-10)
    torch = pytest.importorskip("torch")
    on_torch = torch.as_tensor(matrices)
    np.testing.assert_array_equal(unscented._det4(unscented._minors(on_torch.reshape(-1, 16))).numpy(), det)
    assert unscented._certainly_conditioned(on_torch, 1e12).tolist() == expected


def test_repairing_covariances_together_is_repairing_each_alone():
    """The step's model covariances and its fused covariance share one closed-form test: the
    same matrices and masks, bit for bit, as one repair each, whether every one passes the test,
    one of them needs its repair, or the checks are deferred (one flag for both, matrices kept)."""
    from mimo_radar_env.core.arrays import deferred_checks
    from mimo_radar_env.tracking import unscented

    rng = np.random.default_rng(2)
    root = rng.normal(size=(6, 1, 3, 4, 4))
    models = root @ np.swapaxes(root, -1, -2) + np.eye(4)
    fused = models[:, :, 0] * 2.0
    broken = fused.copy()
    broken[4, 0] = np.diag([1.0, -1e-3, 1.0, 1.0])  # not positive definite: repaired
    for pair in ([models, fused], [models, broken], [broken, models]):
        together = unscented.repair_covariances(pair)
        for (matrix, mask), alone in zip(together, map(unscented.repair_covariance, pair), strict=True):
            np.testing.assert_array_equal(matrix, alone[0])
            np.testing.assert_array_equal(mask, alone[1])
    assert unscented.repair_covariances([models, broken])[1][1].sum() == 1
    torch = pytest.importorskip("torch")
    with deferred_checks() as flags:
        kept = unscented.repair_covariances([torch.as_tensor(models), torch.as_tensor(broken)])
    assert len(flags) == 1 and not bool(flags[0])
    assert torch.equal(kept[1][0], torch.as_tensor(broken)) and not kept[1][1].any()
