"""The posterior Cramer-Rao bound against the covariance-form recursion, a closed form and a tracker."""

import numpy as np
import pytest

from mimo_radar_env.core.geometry import bistatic_measurement


def test_position_bound_equals_the_covariance_form_riccati_recursion():
    """The information recursion of the PCRB against the Kalman covariance recursion with
    finite-difference Jacobians at the true states (the linear-Gaussian closed form)."""
    import gymnasium as gym

    from tests.helpers import random_valid_actions

    env = gym.make("MimoRadarSelect-v1", scenario="paper-2-v1").unwrapped
    env.reset(seed=4)
    sc, model = env.scenario, env.engine.model
    cov = sc.targets[0].initial_covariance.copy()
    rng = np.random.default_rng(1)
    for t, action in enumerate(
        random_valid_actions(rng, 450, 4, 6, 2, 3), start=1
    ):  # through the 3 deg/s turn
        _, _, _, _, info = env.step(action)
        f = model.transitions[0, t - 1]
        cov = f @ cov @ f.T + model.process_cov
        state = info["true_state"][0]
        lam = np.clip(
            np.log10(info["mean_sinr"][0] / model.min_sinr[0]) / np.log10(sc.peak_sinr / model.min_sinr[0])
            + 0.2,
            0.2,
            1.2,
        )
        info_sum = np.zeros((4, 4))
        for m in np.flatnonzero(action[:4]):
            for n in np.flatnonzero(action[4:]):
                jac = np.zeros((2, 4))
                for i in (0, 2):
                    step = np.zeros(4)
                    step[i] = 1e-3
                    up = bistatic_measurement((state + step)[[0, 2]], sc.tx_positions[m], sc.rx_positions[n])
                    down = bistatic_measurement(
                        (state - step)[[0, 2]], sc.tx_positions[m], sc.rx_positions[n]
                    )
                    jac[:, i] = (up - down) / 2e-3
                r = np.diag([sc.range_variance, sc.azimuth_variance]) / lam[m, n]
                info_sum += jac.T @ np.linalg.inv(r) @ jac
        cov = np.linalg.inv(np.linalg.inv(cov) + info_sum)
        if t % 50 == 0:
            expected = np.sqrt(cov[0, 0] + cov[2, 2])
            assert info["position_bound"][0] == pytest.approx(expected, rel=1e-5)


def test_the_bound_is_below_the_rmse_of_a_centralised_tracker_with_true_noise():
    from benchmarks.docs_tooling.model_figures import error_and_bound

    squared, bounds = error_and_bound(200, 300)
    rmse = np.sqrt(np.mean(squared, axis=1))  # per step, over trials
    bound = np.sqrt(np.mean(bounds, axis=1))
    later = slice(50, None)  # past the start-up transient
    assert np.mean(rmse[later]) >= 0.97 * np.mean(bound[later])
    assert np.mean(rmse[later]) <= 2.0 * np.mean(bound[later])  # and the tracker is not far from it
    print(f"time-averaged RMSE {np.mean(rmse[later]):.3f} m, bound {np.mean(bound[later]):.3f} m")


def test_bound_of_a_static_target_is_the_closed_form_posterior():
    """Linear case: a target that does not move (F = I, Q = 0) measured with the same position
    information I at every step has J_t = P0^-1 + t E' I E, so the position block of J_t^-1 is
    the Schur-complement closed form, and with a diagonal P0 it is (S0^-1 + t I)^-1."""
    from mimo_radar_env.tracking.bound import bound_step, position_bound

    rng = np.random.default_rng(8)
    variances = rng.uniform(10, 400, (2, 3, 4))
    prior = np.zeros((2, 3, 4, 4))
    prior[..., np.arange(4), np.arange(4)] = variances
    root = rng.normal(size=(2, 3, 2, 2))
    measured = root @ np.swapaxes(root, -1, -2) + 0.1 * np.eye(2)
    covariance = prior
    for t in range(1, 6):
        covariance = bound_step(covariance, np.broadcast_to(np.eye(4), (3, 4, 4)), np.zeros((4, 4)), measured)
        position_prior = prior[..., [0, 2], :][..., [0, 2]]
        expected = np.linalg.inv(np.linalg.inv(position_prior) + t * measured)
        np.testing.assert_allclose(covariance[..., [0, 2], :][..., [0, 2]], expected, rtol=1e-9)
        np.testing.assert_allclose(
            position_bound(covariance), np.sqrt(np.trace(expected, axis1=-2, axis2=-1)), rtol=1e-9
        )


@pytest.mark.parametrize("scenario", ["paper-1-v1", "paper-3-v1"])
def test_the_compiled_bound_step_is_the_numpy_paths(scenario, monkeypatch):
    """Over a whole episode (best-tracking's selections), the compiled step's position bound
    equals the numpy path's to round-off; the numpy path is LAPACK's, unchanged."""
    from mimo_radar_env import MimoRadarSelectVectorEnv
    from mimo_radar_env.core.compiled import HAVE_NUMBA
    from mimo_radar_env.envs import engine
    from mimo_radar_env.tracking import bound

    if not HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy path exists")
    bounds = {}
    for flag in (True, False):
        monkeypatch.setattr(engine, "bound_step", lambda *a, flag=flag: bound.bound_step(*a, use_numba=flag))
        env = MimoRadarSelectVectorEnv(num_envs=6, scenario=scenario)
        env.reset(seed=3)
        out = []
        for _ in range(1000):
            *_, terminated, truncated, info = env.step(env.tracking_oracle_action())
            out.append(info["position_bound"])
            if (terminated | truncated).any():
                break
        bounds[flag] = np.array(out)
    np.testing.assert_allclose(bounds[True], bounds[False], rtol=1e-12)


def test_a_matrix_the_compiled_check_refuses_takes_the_numpy_path_and_its_repair():
    from mimo_radar_env.core.compiled import HAVE_NUMBA
    from mimo_radar_env.tracking import bound

    if not HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy path exists")
    covariance = np.broadcast_to(np.diag([1e14, 1.0, 1.0, 1.0]), (2, 1, 4, 4)).copy()  # condition 1e14
    args = (covariance, np.eye(4)[None], np.zeros((4, 4)), np.zeros((2, 1, 2, 2)))
    _, healthy = bound._compiled_step(*args, 1e12)
    assert not healthy
    np.testing.assert_array_equal(bound.bound_step(*args), bound.bound_step(*args, use_numba=False))
    assert np.linalg.cond(bound.bound_step(*args)[0, 0]) < 1.01e12  # repaired


def test_a_one_trial_env_passes_the_bound_kernel_what_a_batch_passes(monkeypatch):
    """A one-trial env's initial bound is a read-only broadcast: passed as it is, numba would
    compile the kernel again for a read-only signature. Every call gets writable C arrays."""
    from mimo_radar_env import MimoRadarSelectVectorEnv
    from mimo_radar_env.core.compiled import HAVE_NUMBA
    from mimo_radar_env.tracking import bound

    if not HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy path exists")
    calls = []
    compiled = bound._compiled_step

    def recording(*args):
        calls.append([(a.flags.writeable, a.flags.c_contiguous) for a in args[:4]])
        return compiled(*args)

    monkeypatch.setattr(bound, "_compiled_step", recording)
    for trials in (1, 3):
        env = MimoRadarSelectVectorEnv(num_envs=trials, scenario="paper-1-v1")
        env.reset(seed=0)
        for _ in range(2):
            env.step(env.tracking_oracle_action())
    assert len(calls) == 4
    assert all(flags == [(True, True)] * 4 for flags in calls)


def test_a_singular_matrix_is_refused_by_the_compiled_check_not_divided_by():
    """A zero determinant: the closed-form inverse divides by it (inf, NaN under numpy's error
    model, where Python's raised ZeroDivisionError out of the env's step); the check refuses
    the result and the numpy path repairs it."""
    from mimo_radar_env.core.compiled import HAVE_NUMBA
    from mimo_radar_env.tracking import bound

    if not HAVE_NUMBA:
        pytest.skip("numba is not installed: only the numpy path exists")
    singular = np.zeros((2, 1, 4, 4))  # F P F' + Q = 0
    args = (singular, np.eye(4)[None], np.zeros((4, 4)), np.zeros((2, 1, 2, 2)))
    _, healthy = bound._compiled_step(*args, 1e12)
    assert not healthy
    finite = np.broadcast_to(np.eye(4), (2, 1, 4, 4)).copy()
    overflow = (finite * 1e200, np.eye(4)[None], np.eye(4) * 1e200, np.zeros((2, 1, 2, 2)))
    _, healthy = bound._compiled_step(*overflow, 1e12)  # a determinant of inf
    assert not healthy
    assert np.isfinite(bound.bound_step(*args)).all()
