"""``mimo-radar-bench model-figures``: the measured facts the model and agent pages quote.

docs/model.md and docs/agents.md state how well some parts work: how often a search finds the
optimum, how consistent the tracker is, how close it comes to the bound, what the bound costs.
Each such number is a *figure* here: a registered function that measures it from a fixed seed
and returns its value with a 95 % interval (Wilson for a rate, the bootstrap over trials of
:mod:`benchmarks.uncertainty` for a mean or ratio over trials) or, for a timing, the machine it
ran on. The command writes them all to ``docs/results/model/figures.json``; the docs quote
them through ``<!-- value: model NAME -->`` spans that ``mimo-radar-bench docs`` fills
(:mod:`benchmarks.docs_tooling.pages`).
"""

from __future__ import annotations

import argparse
import json
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from scipy import stats

import agents
from mimo_radar_env import VERSIONS, RadarModel, load_scenario, random_scenario
from mimo_radar_env.core.simulation import RadarSimulation
from mimo_radar_env.core.streams import keys_from_generator
from mimo_radar_env.core.superarm import random_super_arms, subset_masks

from ..cli import Command
from ..errors import BenchError
from ..harness import output_folder
from ..outputs import folder
from ..study import machine
from ..uncertainty import estimate

FIGURES_FILE = "model/figures.json"
Figure = dict[str, Any]
FIGURES: dict[str, Callable[[], Figure]] = {}


def figure(*names: str) -> Callable[[Callable[[], dict[str, Figure]]], Callable[[], dict[str, Figure]]]:
    """Register a measurement that returns the figures ``names`` (one run may give several)."""

    def register(function: Callable[[], dict[str, Figure]]) -> Callable[[], dict[str, Figure]]:
        for name in names:
            FIGURES[name] = function
        return function

    return register


def rate(successes: NDArray[np.bool_], what: str) -> Figure:
    """A proportion with its Wilson 95 % interval."""
    k, n = int(np.sum(successes)), int(np.size(successes))
    ci = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
    return {"value": k / n, "ci": [ci.low, ci.high], "method": "Wilson", "n": n, "kind": "rate", "what": what}


def mean_over_trials(per_trial: NDArray[np.float64], what: str, seed: int = 0) -> Figure:
    """The mean over trials with its bootstrap interval over trials."""
    x = np.asarray(per_trial, np.float64)
    result = estimate(lambda w: w @ x, x.size, seed)
    return {**_estimate(result), "n": int(x.size), "kind": "mean", "what": what}


def ratio_over_trials(numerator: NDArray, denominator: NDArray, what: str, seed: int = 0) -> Figure:
    """``sqrt(mean numerator / mean denominator)`` over the same trials (a ratio of RMS values),
    its interval resampling the trials of both together."""
    a, b = np.asarray(numerator, np.float64), np.asarray(denominator, np.float64)
    result = estimate(lambda w: np.sqrt((w @ a) / (w @ b)), a.size, seed)
    return {**_estimate(result), "n": int(a.size), "kind": "ratio", "what": what}


def _estimate(result: dict[str, Any]) -> dict[str, Any]:
    return {"value": result["estimate"], "ci": result["ci"], "method": result["method"]}


def timing(seconds: float, what: str) -> Figure:
    return {"value": seconds, "ci": None, "method": "wall time", "kind": "seconds", "what": what}


#: How each kind of figure is quoted: the value, then its 95 % interval where it has one.
FORMATS = {
    "rate": ("{:.1f} %", 100.0),
    "fraction": ("{:.2f} %", 100.0),
    "share": ("{:.0f} %", 100.0),
    "mean": ("{:.2f}", 1.0),
    "ratio": ("{:.2f}x", 1.0),
    "metres": ("{:.3f} m", 1.0),
    "seconds": ("{:.2f} s", 1.0),
}


def format_figure(figure: Figure) -> str:
    """``96.0 % [92.3, 98.0]``, ``1.19x [1.18, 1.20]``, ``0.27 s``: the figure as the docs quote it."""
    text, scale = FORMATS[figure["kind"]]
    quoted = text.format(scale * figure["value"])
    if figure.get("ci") is not None:
        number = re.sub(r"[^{]*(\{[^}]*\}).*", r"\1", text)
        low, high = (number.format(scale * end) for end in figure["ci"])
        quoted += f" [{low}, {high}]"
    return quoted


# ---------------------------------------------------------------- solvers
def _exact_on_random_indices(seed: int, shape: tuple[int, int, int], tx_count: int, rx_count: int):
    """i.i.d. Exponential(1) index matrices of ``shape`` (B, M, N), the exact solver's selections
    on them, and the trials' streams a solver under test is given."""
    from agents.solvers import ExactSolver
    from mimo_radar_env.core.streams import TrialRandom

    index = np.random.default_rng(seed).exponential(size=shape)
    etx, erx = ExactSolver(tx_count, rx_count).solve(index, TrialRandom.for_batch(0, shape[0]))
    return index, etx, erx, TrialRandom.for_batch(0, shape[0])


@figure("bpso-set-optimal", "bpso-xor-optimal")
def bpso_rules() -> dict[str, Figure]:
    from agents.solvers import BPSOSolver

    out = {}
    for rule in ("set", "xor"):
        index, etx, erx, streams = _exact_on_random_indices(1, (500, 4, 6), 2, 3)
        tx, rx = BPSOSolver(2, 3, rule=rule).solve(index, streams)
        optimal = (tx == etx).all(axis=1) & (rx == erx).all(axis=1)
        out[f"bpso-{rule}-optimal"] = rate(
            optimal,
            f"BPSO rule {rule!r} (population 50, 100 iterations) finds the exact optimum; 500 "
            "i.i.d. Exponential(1) index matrices of 4 x 6, 2 TX and 3 RX",
        )
    return out


@figure("alternating-optimal", "alternating-gap")
def alternating() -> dict[str, Figure]:
    from agents.solvers import AlternatingSolver

    index, etx, erx, streams = _exact_on_random_indices(3, (400, 10, 12), 3, 4)
    tx, rx = AlternatingSolver(3, 4).solve(index, streams)
    value = np.einsum("bm,bmn,bn->b", tx.astype(float), index, rx.astype(float))
    best = np.einsum("bm,bmn,bn->b", etx.astype(float), index, erx.astype(float))
    where = "400 i.i.d. Exponential(1) index matrices of 10 x 12, 3 TX and 4 RX"
    return {
        "alternating-optimal": rate(
            np.isclose(value, best, rtol=1e-12), f"alternating finds the optimum; {where}"
        ),
        "alternating-gap": {
            **mean_over_trials(1 - value / best, f"alternating's mean relative gap to the optimum; {where}"),
            "kind": "fraction",
        },
    }


@figure("greedy-optimal-centralized", "greedy-optimal-average")
def greedy_tracking_search() -> dict[str, Figure]:
    from mimo_radar_env.tracking.information import channel_information
    from mimo_radar_env.tracking.selection import greedy_super_arm, super_arm_criterion

    rng = np.random.default_rng(2)
    batch, num_tx, num_rx = 200, 6, 8
    tx, rx = rng.uniform(0, 5e4, (num_tx, 2)), rng.uniform(0, 5e4, (num_rx, 2))
    position = rng.uniform(0, 5e4, (batch, 1, 2))
    root = rng.normal(0, 3, (batch, 1, 2, 2))
    position_cov = root @ np.swapaxes(root, -1, -2) + np.eye(2)
    variance = np.stack(
        [rng.uniform(1, 25, (batch, 1, num_tx, num_rx)), rng.uniform(1e-4, 1e-2, (batch, 1, num_tx, num_rx))],
        -1,
    )
    weights = np.ones(1)
    info = channel_information(position, tx, rx, variance)
    tx_sets, rx_sets = subset_masks(num_tx, 2), subset_masks(num_rx, 3)
    all_tx = np.repeat(tx_sets, len(rx_sets), axis=0)
    all_rx = np.tile(rx_sets, (len(tx_sets), 1))
    out = {}
    for fusion in ("centralized", "average"):
        exact = super_arm_criterion(position_cov, info, all_tx, all_rx, weights, fusion=fusion).min(axis=1)
        g_tx, g_rx = greedy_super_arm(position_cov, info, weights, 2, 3, fusion=fusion)
        greedy = super_arm_criterion(position_cov, info, g_tx[:, None], g_rx[:, None], weights, fusion=fusion)
        out[f"greedy-optimal-{fusion}"] = rate(
            np.isclose(greedy[:, 0], exact, rtol=1e-9),
            f"the greedy and swap search finds the exact minimum of the {fusion} criterion; 200 "
            "random 6 x 8 instances (random stations, target, covariance and channel variances), "
            "2 TX and 3 RX",
        )
    return out


def plan_instances(
    fusion: str, layouts: int = 6, steps: int = 12, trials: int = 10, width: int = 3, horizon: int = 3
) -> dict[str, NDArray[np.float64]]:
    """Small planning instances (3 x 3 stations, 1 TX and 2 RX: 9 super arms; ``horizon``-step
    plans, 729 sequences at H = 3): the closed loop of best-tracking on ``layouts`` random layouts
    (seeds 0, 1, ...), its forecasts at ``steps`` steps of ``trials`` trials each, and the cost of
    the best plan found by every search, the exhaustive one's the reference."""
    from mimo_radar_env import MimoRadarSelectVectorEnv, random_scenario
    from mimo_radar_env.tracking.planning import PLAN_SEARCHES, Planner

    costs: dict[str, list] = {search: [] for search in PLAN_SEARCHES}
    for seed in range(layouts):
        scenario = random_scenario(3, 3, 2, 1, 2, horizon=steps + 2, seed=seed)
        env = MimoRadarSelectVectorEnv(num_envs=trials, scenario=scenario, fusion=fusion)
        env.reset(seed=seed)
        planners = {s: Planner(3, 3, 1, 2, search=s, width=width, fusion=fusion) for s in PLAN_SEARCHES}
        for _ in range(steps):
            forecast = env.tracking_forecast(horizon)
            for search, planner in planners.items():
                costs[search].append(planner.plan(forecast)[1])
            env.step(env.tracking_oracle_action())
    return {search: np.concatenate(values) for search, values in costs.items()}


@figure(*(f"plan-{s}-optimal-{f}" for s in ("beam", "rollout", "mcts") for f in ("centralized", "average")))
def plan_optimality() -> dict[str, Figure]:
    out = {}
    for fusion in ("centralized", "average"):
        costs = plan_instances(fusion)
        for search in ("beam", "rollout", "mcts"):
            found = costs[search] <= costs["exhaustive"] * (1 + 1e-9)
            what = {
                "beam": "a beam of width 3",
                "rollout": "the rollout of every first super arm",
                "mcts": "MCTS with 64 simulations over 8 candidates per node",
            }[search]
            out[f"plan-{search}-optimal-{fusion}"] = rate(
                found,
                f"{what} finds the exhaustive optimum of 3-step plans (9 super arms: 3 x 3 stations, 1 TX "
                f"and 2 RX, 2 targets), {fusion} fusion; 720 forecasts: 6 random layouts x 12 steps x 10 "
                "trials of best-tracking's closed loop",
            )
    return out


@figure("oracle-exact-32x32-step-s")
def oracle_exact_cost() -> dict[str, Figure]:
    scenario = random_scenario(32, 32, 1, 4, 4, horizon=5, seed=0)
    venv = gym.make_vec(
        "MimoRadarSelect-v1",
        num_envs=20,
        vectorization_mode="vector_entry_point",
        scenario=scenario,
        oracle_solver="exact",
        tracking=False,
    )
    venv.reset(seed=0)
    actions = random_super_arms(np.random.default_rng(0), 20, 32, 32, 4, 4)
    start = time.perf_counter()
    for _ in range(3):
        venv.step(actions)
    seconds = (time.perf_counter() - start) / 3
    venv.close()
    return {
        "oracle-exact-32x32-step-s": timing(
            seconds,
            "one env step with oracle_solver='exact' on a random 32 x 32 layout, Ms = Ns = 4, 20 trials",
        )
    }


# ---------------------------------------------------------------- the tracker
def nees_per_step(batch: int, steps: int, turn_rates: tuple, probabilities: tuple) -> NDArray[np.float64]:
    """The NEES of every step after 20 steps of transient and every trial (steps - 20, batch), on
    paper-1 (v0's per-trial NCV truth), centralised fusion, the fixed selection {TX1,TX2;
    RX1,RX2,RX3} (tests/mimo_radar_env/tracking/test_closed_loop.py asserts its consistency from it too)."""
    from mimo_radar_env.tracking import IMMUKFTracker

    model = RadarModel.from_scenario(load_scenario("paper-1"))
    sim = RadarSimulation(model, batch)
    rng = np.random.default_rng(0)
    sim.reset(np.stack([keys_from_generator(rng) for _ in range(batch)]))
    tracker = IMMUKFTracker(
        model, batch, fusion="centralized", turn_rates_deg=turn_rates, initial_probabilities=probabilities
    )
    tx, rx, valid = np.tile([0, 1], (batch, 1)), np.tile([0, 1, 2], (batch, 1)), np.ones(batch, bool)
    out = []
    for _ in range(steps):
        sim.advance()
        obs = sim.observe(tx, rx, valid)
        tracker.step(
            model.tx[obs.tx_stations], model.rx[obs.rx_stations], obs.measurement, obs.noise_variance, valid
        )
        error = tracker.estimate - sim.state
        out.append(np.einsum("bki,bkij,bkj->b", error, np.linalg.inv(tracker.covariance), error))
    return np.array(out)[20:]


@figure("nees-ncv", "nees-imm")
def consistency() -> dict[str, Figure]:
    where = (
        "time-averaged NEES (dimension 4) over steps 21-200 of 200 paper-1 trials, centralised fusion, "
        "the fixed selection {TX1,TX2; RX1,RX2,RX3}"
    )
    return {
        "nees-ncv": mean_over_trials(
            nees_per_step(200, 200, (0.0,), (1.0,)).mean(axis=0), f"single-model NCV UKF: {where}"
        ),
        "nees-imm": mean_over_trials(
            nees_per_step(200, 200, (0.0, 3.0, -3.0), (0.8, 0.1, 0.1)).mean(axis=0),
            f"the paper's three-model IMM: {where}",
        ),
    }


def vector_run(scenario: str, batch: int, steps: int, fusion: str, fixed=None, **options) -> tuple:
    """Target 0's position errors (steps, batch) and model probabilities (steps, batch, R) of a
    v0 vector env, with ``fixed`` selections (an action (M + N,)) or the oracle's
    (tests/mimo_radar_env/tracking/test_closed_loop.py asserts on them too)."""
    if fixed is None:
        agent = agents.make_agent("best", scenario)
    else:
        num_tx = load_scenario(scenario).num_tx
        tx, rx = np.flatnonzero(fixed[:num_tx]).tolist(), np.flatnonzero(fixed[num_tx:]).tolist()
        agent = agents.make_agent("fixed", scenario, tx=tx, rx=rx)
    env = agents.make_env(agent, batch, VERSIONS["v0"].options(fusion=fusion, **options))
    errors, modes = [], []
    for step in agents.Rollout(agent, env, seed=0).run(steps):
        errors.append(step.info["position_error"][:, 0])
        modes.append(step.obs["mode_prob"][:, 0])
    env.close()
    return np.array(errors), np.array(modes)


@figure("rmse-ratio-average", "rmse-ratio-centralized")
def closed_loop() -> dict[str, Figure]:
    fixed = np.array([1, 1, 0, 0, 1, 1, 1, 0, 0, 0], dtype=np.int8)
    out = {}
    for fusion in ("average", "centralized"):
        squared = {}
        for quality in (0.2, 1.2):
            errors, _ = vector_run("paper-1", 100, 300, fusion, fixed, measurement_quality=quality)
            squared[quality] = (errors[100:] ** 2).mean(axis=0)  # per trial, steps 101-300
        out[f"rmse-ratio-{fusion}"] = ratio_over_trials(
            squared[0.2],
            squared[1.2],
            f"RMSE with lambda = 0.2 on every channel over RMSE with lambda = 1.2 (v0, paper-1, {fusion} "
            "fusion, the fixed selection {TX1,TX2; RX1,RX2,RX3}, steps 101-300, 100 trials, the same "
            "trials at both)",
        )
    return out


@figure(*(f"mode-{turn}-{fusion}" for turn in ("first", "second") for fusion in ("average", "centralized")))
def maneuver_modes() -> dict[str, Figure]:
    out = {}
    for fusion in ("average", "centralized"):
        _, modes = vector_run("paper-2", 30, 660, fusion)
        for turn, (start, stop, model) in {"first": (405, 440, 1), "second": (605, 640, 2)}.items():
            out[f"mode-{turn}-{fusion}"] = mean_over_trials(
                modes[start:stop, :, model].mean(axis=0),
                f"mean probability of NCT({'+' if model == 1 else '-'}3 deg/s) during the {turn} turn "
                f"(steps {start + 1}-{stop}), v0, paper-2, {fusion} fusion, the oracle's selections, "
                "30 trials",
            )
    return out


# ---------------------------------------------------------------- the bound
def error_and_bound(trials: int, steps: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Squared position errors and squared bounds (steps, trials) of paper-1-v1, centralised
    fusion, uniformly random selections, seed 0 (tests/mimo_radar_env/tracking/test_bound.py reads
    them too)."""
    venv = gym.make_vec(
        "MimoRadarSelect-v1", num_envs=trials, vectorization_mode="vector_entry_point", fusion="centralized"
    )
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    squared, bounds = [], []
    for _ in range(steps):
        _, _, _, _, info = venv.step(random_super_arms(rng, trials, 4, 6, 2, 3))
        squared.append(info["position_error"][:, 0] ** 2)
        bounds.append(info["position_bound"][:, 0] ** 2)
    venv.close()
    return np.array(squared), np.array(bounds)


@figure("bound-ratio", "bound-rmse", "bound-value")
def bound_tightness() -> dict[str, Figure]:
    trials = 200
    squared, bounds = error_and_bound(trials, 300)
    squared_error = squared[50:].mean(axis=0)  # per trial, steps 51-300
    bound = bounds[50:].mean(axis=0)
    where = "paper-1-v1, centralised fusion, uniformly random selections, 200 trials, steps 51-300"
    return {
        "bound-ratio": ratio_over_trials(squared_error, bound, f"the IMM-UKF's RMSE over the bound; {where}"),
        "bound-rmse": {
            **_estimate(estimate(lambda w: np.sqrt(w @ squared_error), trials)),
            "n": trials,
            "kind": "metres",
            "what": f"the IMM-UKF's position RMSE (m); {where}",
        },
        "bound-value": {
            **_estimate(estimate(lambda w: np.sqrt(w @ bound), trials)),
            "n": trials,
            "kind": "metres",
            "what": f"the posterior Cramer-Rao bound (m); {where}",
        },
    }


@figure("bound-share-paper-1-v1", "bound-share-paper-3-v1")
def bound_cost() -> dict[str, Figure]:
    from ..speed.stages import env_stages

    out = {}
    for name in ("paper-1-v1", "paper-3-v1"):
        trials, steps = 500, 60
        stages = env_stages("average", trials, steps, scenario=name)
        out[f"bound-share-{name}"] = {
            "value": stages["bound"] / sum(stages.values()),
            "ci": None,
            "method": "wall time",
            "kind": "share",
            "what": f"share of a tracking env step spent on the bound; {name}, average fusion, "
            f"{trials} trials, {steps} steps",
        }
    return out


# ---------------------------------------------------------------- the command
def check_names(names: list[str]) -> None:
    """Raise :class:`BenchError` unless ``names`` are registered figures (at least one)."""
    unknown = sorted(set(names) - set(FIGURES))
    if unknown or not names:
        raise BenchError(f"unknown figure(s) {unknown}; known: {', '.join(FIGURES)}")


def measure(names: list[str] | None = None, progress: Callable[[str], None] = print) -> dict[str, Figure]:
    """Run the measurements behind ``names`` (default: all), each once."""
    names = list(FIGURES) if names is None else names
    check_names(names)
    out: dict[str, Figure] = {}
    done: set[Callable] = set()
    for name in names:
        function = FIGURES[name]
        if function in done:
            continue
        start = time.perf_counter()
        figures = function()
        wall = time.perf_counter() - start
        for key, value in figures.items():
            out[key] = {**value, "wall_s": round(wall, 3)}
        done.add(function)
        progress(f"  {function.__name__}: {', '.join(figures)} ({wall:.1f} s)")
    return out


class ModelFigures(Command):
    name = "model-figures"
    description = (
        "Measure every figure the model and agent pages quote (search optimality rates, tracker "
        "consistency, the bound's tightness and cost) with its 95 % interval, and write them with "
        "the machine to OUT/figures.json (default docs/results/model), which 'mimo-radar-bench docs' reads."
    )

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "--out", type=folder, default="docs/results/model", help="output folder (default %(default)s)"
        )
        parser.add_argument(
            "--only",
            default=None,
            help="comma-separated figures to re-measure, merged into an existing file "
            f"(known: {', '.join(FIGURES)})",
        )

    def main(self) -> int:
        out = Path(self.args.out)
        path = out / "figures.json"
        names = (
            None if self.args.only is None else [n.strip() for n in self.args.only.split(",") if n.strip()]
        )
        if names is not None:
            check_names(names)
        output_folder(out)
        existing: dict[str, Any] = {}
        if names is not None and path.exists():
            try:
                old = json.loads(path.read_text())
                # each kept figure keeps the command and the load it was measured with
                existing = {
                    name: {
                        "command": old["command"],
                        "load_average_1min": old["machine"]["load_average_1min"],
                        **figure,
                    }
                    for name, figure in old["figures"].items()
                }
            except (OSError, ValueError, KeyError, TypeError) as exc:
                raise BenchError(f"{path} is not a figures file ({exc}); rerun without --only") from None
        before = machine()
        start = time.perf_counter()
        print(f"measuring {len(names or FIGURES)} figure(s) into {path}")
        command = "mimo-radar-bench model-figures" + (f" --only {self.args.only}" if names else "")
        measured = {
            name: {"command": command, "load_average_1min": before["load_average_1min"], **figure}
            for name, figure in measure(names).items()
        }
        figures = {**existing, **measured}
        record = {
            "command": command,
            "wall_s": round(time.perf_counter() - start, 3),
            "machine": before,
            "figures": {name: figures[name] for name in FIGURES if name in figures},
        }
        path.write_text(json.dumps(record, indent=2) + "\n")
        print(f"wrote {path}")
        return 0
