"""Batched IMM-UKF vs filterpy filters looped in Python, on the same inputs.

Run: ``python -m benchmarks.speed.tracker_speed [--trials 500] [--steps 20] [--reference-trials 10]``.

Both sides run the paper's average fusion on ``paper-1`` with 6 channels and 3 models:
every (trial, channel) pair is one IMM-UKF cycle (interaction, 3 UKF predictions and
updates, probability update). The reference builds a filterpy ``IMMEstimator`` of three
``UnscentedKalmanFilter`` per (trial, channel) from the fused prior and fuses them as eq22.
filterpy is timed on ``--reference-trials`` trials (its cost is linear in trials);
the figure reported is channel-cycles per second for each, and their ratio.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from filterpy.kalman import IMMEstimator, MerweScaledSigmaPoints, UnscentedKalmanFilter

from mimo_radar_env import RadarModel, load_scenario
from mimo_radar_env.core.motion import transition_matrix
from mimo_radar_env.core.simulation import RadarSimulation
from mimo_radar_env.core.streams import keys_from_generator
from mimo_radar_env.tracking import IMMUKFTracker, markov_matrix
from mimo_radar_env.tracking.imm_ukf import DEFAULT_TURN_RATES_DEG

from ..settings import integer


def _record_inputs(trials: int, steps: int, seed: int = 0):
    """Measurements of a fixed 2x3 selection on paper-1, for ``steps`` steps."""
    model = RadarModel.from_scenario(load_scenario("paper-1"))
    sim = RadarSimulation(model, trials)
    rng = np.random.default_rng(seed)
    sim.reset(np.stack([keys_from_generator(rng) for _ in range(trials)]))
    tx_index, rx_index = np.tile([0, 1], (trials, 1)), np.tile([0, 1, 2], (trials, 1))
    valid = np.ones(trials, dtype=bool)
    inputs = []
    for _ in range(steps):
        sim.advance()
        obs = sim.observe(tx_index, rx_index, valid)
        inputs.append(
            (model.tx[obs.tx_stations], model.rx[obs.rx_stations], obs.measurement, obs.noise_variance)
        )
    return model, inputs


def _filterpy_channel_imm(model, means, covs, probs, tx, rx, variance):
    def hx(x):
        p = np.array([x[0], x[2]])
        return np.array(
            [np.linalg.norm(p - tx) + np.linalg.norm(p - rx), np.arctan2(p[1] - rx[1], p[0] - rx[0])]
        )

    def z_mean(sigmas, wm):
        return np.array([wm @ sigmas[:, 0], np.arctan2(wm @ np.sin(sigmas[:, 1]), wm @ np.cos(sigmas[:, 1]))])

    def residual_z(a, b):
        d = np.asarray(a - b, dtype=float)
        d[1] = (d[1] + np.pi) % (2 * np.pi) - np.pi
        return d

    filters = []
    for r, rate in enumerate(DEFAULT_TURN_RATES_DEG):
        F = transition_matrix(np.radians(rate), 1.0)
        ukf = UnscentedKalmanFilter(
            4,
            2,
            1.0,
            hx,
            lambda x, dt, F=F: F @ x,
            MerweScaledSigmaPoints(4, 1.0, 2.0, 0.0),
            z_mean_fn=z_mean,
            residual_z=residual_z,
        )
        ukf.Q = model.process_cov
        ukf.R = np.diag(variance)
        ukf.x, ukf.P = means[r].copy(), covs[r].copy()
        filters.append(ukf)
    return IMMEstimator(filters, probs.copy(), markov_matrix(3, 0.8))


def run_filterpy(model, inputs, trials: int) -> float:
    """Seconds for ``trials`` trials of the filterpy loop (average fusion over channels)."""
    initial = model.initial_states[0]
    cov0 = model.scenario.targets[0].initial_covariance
    states = [
        (np.tile(initial, (3, 1)), np.tile(cov0, (3, 1, 1)), np.array([0.8, 0.1, 0.1])) for _ in range(trials)
    ]
    start = time.perf_counter()
    for tx, rx, z, variance in inputs:
        for b in range(trials):
            means, covs, probs = states[b]
            results = []
            for c in range(z.shape[2]):
                i, j = divmod(c, rx.shape[1])  # channels are the TX-major pairs of the stations
                imm = _filterpy_channel_imm(model, means, covs, probs, tx[b, i], rx[b, j], variance[b, 0, c])
                imm.predict()
                imm.update(z[b, 0, c])
                results.append(imm)
            states[b] = (
                np.mean([[f.x for f in r.filters] for r in results], axis=0),
                np.mean([[f.P for f in r.filters] for r in results], axis=0),
                np.mean([r.mu for r in results], axis=0),
            )
    return time.perf_counter() - start


def run_batched(model, inputs, trials: int) -> float:
    tracker = IMMUKFTracker(model, trials, fusion="average")
    valid = np.ones(trials, dtype=bool)
    tracker.step(*inputs[0], valid)  # warm-up
    tracker.reset()
    start = time.perf_counter()
    for tx, rx, z, variance in inputs:
        tracker.step(tx, rx, z, variance, valid)
    return time.perf_counter() - start


def measure(trials: int = 500, steps: int = 20, reference_trials: int = 10) -> dict[str, float]:
    model, inputs = _record_inputs(trials, steps)
    channels = inputs[0][2].shape[2]
    batched_s = run_batched(model, inputs, trials)
    reference_inputs = [
        (tx[:reference_trials], rx[:reference_trials], z[:reference_trials], v[:reference_trials])
        for tx, rx, z, v in inputs
    ]
    filterpy_s = run_filterpy(model, reference_inputs, reference_trials)
    batched_rate = trials * channels * steps / batched_s
    filterpy_rate = reference_trials * channels * steps / filterpy_s
    return {
        "batched_channel_cycles_per_s": batched_rate,
        "filterpy_channel_cycles_per_s": filterpy_rate,
        "tracker_speedup_vs_filterpy": batched_rate / filterpy_rate,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description="Batched IMM-UKF vs a filterpy loop")
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--steps", type=integer(1), default=20)
    parser.add_argument("--reference-trials", type=integer(1), default=10)
    args = parser.parse_args()
    result = measure(args.trials, args.steps, args.reference_trials)
    print(f"IMM-UKF (3 models), paper-1, 6 channels, average fusion, {args.steps} steps")
    rows = (
        (f"batched, {args.trials} trials", f"{result['batched_channel_cycles_per_s']:,.0f} channel-cycles/s"),
        (
            f"filterpy loop, {args.reference_trials} trials",
            f"{result['filterpy_channel_cycles_per_s']:,.0f} channel-cycles/s",
        ),
        ("speed-up", f"{result['tracker_speedup_vs_filterpy']:,.0f}x"),
    )
    for label, value in rows:
        print(f"  {label:<28}{value:>28}")


if __name__ == "__main__":
    main()
