"""Track MimoRadarSelect's targets with Stone Soup, from the measurements the env puts in ``info``.

The env is made with ``measurements=True``: after each step ``info["measurement"]`` holds the
range sum and azimuth of every target on every selected channel, ``info["measurement_covariance"]``
their covariances and ``info["measurement_tx"]``/``["measurement_rx"]`` the channels' stations.
Stone Soup (``pip install stonesoup``; not a dependency of mimo-radar-env) runs an unscented
Kalman filter on them: the bistatic measurement (eq6) is a small measurement model class, the
motion is the scenario's nearly-constant-velocity model, and each step's channels update the
track one after the other (centralised fusion). The script prints the Stone Soup UKF's ARMSE
beside the env's own IMM-UKF with centralised fusion on the same measurements.

    python docs/examples/stone_soup_tracker.py [--steps 1000] [--seed 0]
"""

from __future__ import annotations

import argparse
from datetime import datetime, timedelta

import gymnasium as gym
import numpy as np
from stonesoup.base import Property
from stonesoup.models.measurement.nonlinear import NonLinearGaussianMeasurement
from stonesoup.models.transition.linear import LinearGaussianTimeInvariantTransitionModel
from stonesoup.predictor.kalman import UnscentedKalmanPredictor
from stonesoup.types.angle import Bearing
from stonesoup.types.array import StateVector, StateVectors
from stonesoup.types.detection import Detection
from stonesoup.types.hypothesis import SingleHypothesis
from stonesoup.types.state import GaussianState
from stonesoup.updater.kalman import UnscentedKalmanUpdater

import mimo_radar_env  # noqa: F401  (registers the envs)
from mimo_radar_env import RadarModel


class BistaticRangeSumAzimuth(NonLinearGaussianMeasurement):
    """eq6: ``[|p - tx| + |p - rx|, atan2(y - y_rx, x - x_rx)]`` of the position ``p``."""

    tx: np.ndarray = Property(doc="transmitter position (x, y), m")
    rx: np.ndarray = Property(doc="receiver position (x, y), m")

    @property
    def ndim_meas(self) -> int:
        return 2

    def function(self, state, noise=False, **kwargs):
        if isinstance(noise, bool) or noise is None:
            noise = self.rvs(num_samples=state.state_vector.shape[1], **kwargs) if noise else 0
        x = np.asarray(state.state_vector[self.mapping[0], :], dtype=float)
        y = np.asarray(state.state_vector[self.mapping[1], :], dtype=float)
        range_sum = np.hypot(x - self.tx[0], y - self.tx[1]) + np.hypot(x - self.rx[0], y - self.rx[1])
        azimuth = [Bearing(a) for a in np.arctan2(y - self.rx[1], x - self.rx[0])]
        return StateVectors([range_sum, azimuth]) + noise


def run(steps: int | None = None, seed: int = 0) -> dict[str, float]:
    """One episode with the Best selections; the ARMSE (m) of Stone Soup's UKF and the env's."""
    env = gym.make("MimoRadarSelect-v1", measurements=True, fusion="centralized")
    sc = env.unwrapped.scenario
    model = RadarModel.from_scenario(sc)
    steps = sc.horizon if steps is None else min(steps, sc.horizon)
    # the scenario's NCV motion: F and Q = G diag(Qs, Qs) G' (eq1, eq3)
    transition = LinearGaussianTimeInvariantTransitionModel(
        transition_matrix=model.transitions[0, 0],
        covariance_matrix=model.process_cov,
    )
    predictor = UnscentedKalmanPredictor(transition)
    updater = UnscentedKalmanUpdater(measurement_model=None)

    obs, info = env.reset(seed=seed)
    start = datetime(2026, 1, 1)
    # start where the env's tracker starts: its initial estimate and P1_hat
    tracks = [
        GaussianState(obs["track"][k].reshape(4, 1), target.initial_covariance, timestamp=start)
        for k, target in enumerate(sc.targets)
    ]
    ours, theirs = [], []
    for step in range(1, steps + 1):
        _, _, _, _, info = env.step(env.unwrapped.oracle_action())
        when = start + timedelta(seconds=step * sc.sample_time)
        errors = []
        for k in range(sc.num_targets):
            state = predictor.predict(tracks[k], timestamp=when)
            for c, (m, n) in enumerate(zip(info["measurement_tx"], info["measurement_rx"], strict=True)):
                measurement_model = BistaticRangeSumAzimuth(
                    ndim_state=4,
                    mapping=(0, 2),
                    noise_covar=info["measurement_covariance"][k, c],
                    tx=sc.tx_positions[m],
                    rx=sc.rx_positions[n],
                )
                z = info["measurement"][k, c]
                detection = Detection(
                    StateVector([z[0], Bearing(z[1])]), timestamp=when, measurement_model=measurement_model
                )
                prediction = updater.predict_measurement(state, measurement_model)
                state = updater.update(SingleHypothesis(state, detection, measurement_prediction=prediction))
            tracks[k] = state
            truth = info["true_state"][k, [0, 2]]
            errors.append(np.sum((np.asarray(state.state_vector[[0, 2], 0], float) - truth) ** 2))
        theirs.append(errors)
        ours.append(info["position_error"] ** 2)
    rmse = {
        "stone_soup_ukf": float(np.mean(np.sqrt(np.mean(theirs, axis=0)))),
        "env_imm_ukf": float(np.mean(np.sqrt(np.mean(ours, axis=0)))),
    }
    return rmse


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=None, help="steps (default: the horizon)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    result = run(args.steps, args.seed)
    print(
        f"ARMSE over one episode (Best's selections, v1, paper-1-v1): Stone Soup UKF "
        f"{result['stone_soup_ukf']:.2f} m, the env's IMM-UKF (centralised) {result['env_imm_ukf']:.2f} m"
    )


if __name__ == "__main__":
    main()
