"""A global search over the station layouts the paper's text allows.

``mimo-radar-bench search-layouts`` searches every position of the 4 transmitters and 6
receivers in the 100 km x 100 km region with ``scipy.optimize.differential_evolution``. The
text's hard constraints (:func:`benchmarks.studies.calibration.constraint_failure`: the region,
no station within 2 km of a nominal track, Best's Scenario 1 selections in their windows; fix1
and fix2 are the stated station indices) are enforced through a penalty that measures how far a
layout is from meeting them, so the search is led back into the allowed set.

Layouts are scored on v1's paper scenarios (``paper-k-v1`` with the layout's stations). The
objective is cheap and noise-free (about ten layouts a second here): the number of the claims'
noise-free predictors that hold (:func:`predictors`), with the smallest median lead of the best
super arm in Scenarios 2 and 3 as a tie-break (a dominant best super arm is what the paper's
ASR needs, docs/results-claims.md). The best ``--final`` layouts of the last population and v1's own
layout (layout 116 of the calibration) then get full scorecards (``claims.scorecard``, v1's
paper study, ``--trials``), and every predictor with a scorecard comparison of its own is
checked against it (:data:`PREDICTED`, :func:`agreement`).

The search is reproducible: the same ``--seed`` gives the same layouts. Its first population
holds v1's layout and section 1's reconstruction jittered (``calibration.candidates``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import differential_evolution

from mimo_radar_env import RadarModel, Scenario, load_scenario

from .. import harness, resources
from ..backends import worker_pool
from ..errors import BenchError
from ..settings import integer
from ..study import Study, configure, machine, write_timing
from . import calibration, claims, mechanisms

#: v1's paper scenarios: the layouts searched replace their stations.
V1_SCENARIOS = ("paper-1-v1", "paper-2-v1", "paper-3-v1")
#: Predictors with a comparison of their own in the scorecard: predictor -> (claim, comparison).
PREDICTED = {
    "S1.2 fix1 > fix2 SINR 0-500 s": ("S1.2", "sinr_db over 0-500 s: fix1 > fix2"),
    "S1.2 fix2 > fix1 SINR 500-1000 s": ("S1.2", "sinr_db over 500-1000 s: fix2 > fix1"),
    "S2.2 fix1 SINR 400-500 s < 300-400 s": ("S2.2", "sinr_db of fix1: 400-500 s < 300-400 s"),
    "S2.2 fix2 SINR 400-500 s < 300-400 s": ("S2.2", "sinr_db of fix2: 400-500 s < 300-400 s"),
}

#: Layout coordinates: 4 TX then 6 RX, (x, y) each, km.
NUM_TX, NUM_RX = 4, 6
DIMENSIONS = 2 * (NUM_TX + NUM_RX)
#: Penalty offset of a layout that breaks a hard constraint (above any feasible objective).
INFEASIBLE = 100.0


class Layout(calibration.Candidate):
    """A searched layout: v1's paper scenarios with its stations."""

    def scenarios(self) -> list[Scenario]:
        tx, rx = np.array(self.tx_km) * 1e3, np.array(self.rx_km) * 1e3
        return [load_scenario(name, tx_positions=tx, rx_positions=rx) for name in V1_SCENARIOS]


def v1_layout() -> Layout:
    """v1's own layout (layout 116 of the calibration)."""
    sc = load_scenario(V1_SCENARIOS[0])
    return Layout(0, (sc.tx_positions / 1e3).tolist(), (sc.rx_positions / 1e3).tolist(), jitter_km=0.0)


def layout_from_vector(x: NDArray[np.float64]) -> Layout:
    km = np.asarray(x, dtype=np.float64).reshape(NUM_TX + NUM_RX, 2)
    return Layout(-1, km[:NUM_TX].tolist(), km[NUM_TX:].tolist(), jitter_km=0.0)


def vector_from_layout(candidate: calibration.Candidate) -> NDArray[np.float64]:
    return np.concatenate([np.ravel(candidate.tx_km), np.ravel(candidate.rx_km)])


def violation(candidate: calibration.Candidate) -> float:
    """How far the layout is from the hard constraints (0 when it meets them all):
    :func:`benchmarks.studies.calibration.constraint_check`'s amount."""
    return calibration.constraint_check(candidate)[0]


def median_lead(model: RadarModel) -> float:
    """The median over the noise-free track's steps of the best super arm's lead over the second
    (best / second - 1)."""
    weights = model.nominal_channel_weights()  # (T+1, M, N)
    value = np.einsum("tmn,amn->ta", weights, mechanisms.super_arm_channels(model.scenario))
    return float(np.median(mechanisms.leads(value)))


def predictors(candidate: calibration.Candidate, scale: str = "db") -> dict[str, Any]:
    """The noise-free predictors of a feasible layout: ``calibration.noise_free_checks`` (S1.2,
    S1.8, the bound orderings of Best, fix1 and fix2), S2.2's fixed policies' SINR degrading
    after the maneuver, and the median lead in each scenario."""
    from agents.fixed import PAPER_FIXED

    checks = dict(calibration.noise_free_checks(candidate, scale))
    leads = {}
    for number, sc in enumerate(candidate.scenarios(), start=1):
        model = RadarModel.from_scenario(sc)
        leads[sc.name] = median_lead(model)
        if number == 2:
            weights = model.nominal_channel_weights()
            for name, (tx_idx, rx_idx) in PAPER_FIXED.items():
                value = weights[:, list(tx_idx)][:, :, list(rx_idx)].sum(axis=(1, 2))
                checks[f"S2.2 {name} SINR 400-500 s < 300-400 s"] = bool(
                    value[400:500].mean() < value[300:400].mean()
                )
    return {"checks": checks, "median_lead": leads}


def objective(x: NDArray[np.float64], scale: str = "db") -> float:
    """What differential evolution minimises: ``INFEASIBLE + violation`` for a layout breaking a
    hard constraint; else minus the number of predictors that hold, minus the smallest median lead
    of Scenarios 2 and 3 (a fraction, below 1: a tie-break)."""
    candidate = layout_from_vector(x)
    broken = violation(candidate)
    if broken > 0:
        return INFEASIBLE + broken
    p = predictors(candidate, scale)
    leads = list(p["median_lead"].values())[1:]  # Scenarios 2 and 3
    return -float(sum(p["checks"].values())) - min(min(leads), 0.999)


def search(
    seed: int = 0, generations: int = 20, population: int = 3, workers: int = 1, scale: str = "db"
) -> dict[str, Any]:
    """Run differential evolution. Returns the evaluations, wall time and layouts per second, the
    best objective of each generation, and the last population ranked (feasible layouts first)."""
    rng = np.random.default_rng(seed)
    size = population * DIMENSIONS
    start = np.array(
        [
            vector_from_layout(v1_layout()),
            *(vector_from_layout(c) for c in calibration.candidates(size - 2, seed)),
        ]
    )
    generation_best: list[float] = []
    t0 = time.perf_counter()
    # the project's worker processes, not scipy's own pool: that pool's workers are forked from
    # this process with the command's SIGTERM handler, and its terminate() at the search's end
    # waited for one of them for good (a hung test run in CI)
    with worker_pool(workers) if workers > 1 else contextlib.nullcontext() as pool:
        result = differential_evolution(
            objective,
            bounds=[(0.0, calibration.REGION_M / 1e3)] * DIMENSIONS,
            args=(scale,),
            maxiter=generations,
            init=np.clip(start, 0.0, calibration.REGION_M / 1e3),
            seed=int(rng.integers(2**31)),
            polish=False,
            tol=0.0,
            workers=1 if pool is None else pool.map,
            updating="deferred",
            callback=lambda intermediate_result: generation_best.append(float(intermediate_result.fun)),
        )
    wall = time.perf_counter() - t0
    order = np.argsort(result.population_energies, kind="stable")
    ranked = [
        {
            "vector": np.round(result.population[i], 3).tolist(),
            "objective": float(result.population_energies[i]),
        }
        for i in order
    ]
    return {
        "seed": seed,
        "generations": generations,
        "population": size,
        "evaluations": int(result.nfev),
        "wall_s": wall,
        "layouts_per_s": result.nfev / wall,
        "generation_best": generation_best,
        "v1_objective": objective(vector_from_layout(v1_layout()), scale),
        "ranked": ranked,
    }


def distinct_feasible(ranked: list[dict[str, Any]], count: int) -> list[dict[str, Any]]:
    """The ``count`` best feasible layouts of a ranked population, no two alike (to 1 m)."""
    out: list[dict[str, Any]] = []
    for entry in ranked:
        if entry["objective"] >= INFEASIBLE or any(
            np.allclose(entry["vector"], other["vector"], atol=1e-3) for other in out
        ):
            continue
        out.append(entry)
        if len(out) == count:
            break
    return out


def agreement(checks: dict[str, bool], results: list[dict[str, Any]]) -> dict[str, Any]:
    """Each predictor of :data:`PREDICTED` against its scorecard comparison (holds or not)."""
    verdicts_by = {
        (r["id"], c["comparison"]): c["verdict"] == "holds" for r in results for c in r["comparisons"]
    }
    pairs = {
        name: (checks[name], verdicts_by[key])
        for name, key in PREDICTED.items()
        if name in checks and key in verdicts_by
    }
    return {
        "pairs": {name: {"predicted": p, "scorecard": v} for name, (p, v) in pairs.items()},
        "agree": sum(p == v for p, v in pairs.values()),
        "compared": len(pairs),
    }


class LayoutSearch(Study):
    name = "search-layouts"
    paper_study = True
    description = __doc__
    when_stopped = (
        "the search runs again from its start (the same --seed finds the same layouts) and every "
        "scorecard task finished is kept: run the same command again to resume"
    )

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--generations", type=integer(1), default=20, help="(default 20)")
        parser.add_argument(
            "--population",
            type=integer(1),
            default=3,
            help="layouts per dimension (scipy's popsize, default 3)",
        )
        parser.add_argument(
            "--final", type=integer(0), default=3, help="best layouts given full scorecards (default 3)"
        )
        parser.add_argument(
            "--score",
            type=integer(1),
            nargs="+",
            metavar="RANK",
            help="score only these of the --final best layouts (1-based ranks; default all of them), "
            "e.g. to give the ranks a short scorecard singled out a longer one",
        )
        parser.add_argument(
            "--no-v1-scorecard",
            action="store_true",
            help="do not run v1's own layout (its scorecard under the same options is the claims study's)",
        )

    def estimate_seconds(self, cards: int) -> float:
        """The search's and the scorecards' wall time, roughly: the search's layouts at the time
        one takes here (timed on v1's layout), ``--workers`` at once, and ``cards`` scorecards
        each as long as v1's paper study under the same settings (configured, so checked too:
        nothing is written)."""
        settings = self.settings
        layout = vector_from_layout(v1_layout())
        objective(layout, settings.options.lambda_scale)  # the first call builds what the rest reuse
        timer = time.perf_counter()
        objective(layout, settings.options.lambda_scale)
        per_layout = time.perf_counter() - timer
        layouts = (self.args.generations + 1) * self.args.population * DIMENSIONS
        seconds = layouts * per_layout / settings.workers
        if cards:
            runs = claims.paper_runs(v1_layout().scenarios(), settings.out / "v1")
            per_card = sum(resources.run_seconds(c, settings.workers) for c in configure(runs, settings))
            seconds += cards * per_card
        return seconds

    def main(self) -> int:
        settings = self.settings
        ranks = self.args.score or range(1, self.args.final + 1)
        beyond = [r for r in ranks if r > self.args.final]
        if beyond:
            raise BenchError(
                f"--score {' '.join(map(str, beyond))}: ranks run from 1 to --final ({self.args.final})"
            )
        cards = len(set(ranks)) + (0 if self.args.no_v1_scorecard else 1)
        seconds = self.estimate_seconds(cards)
        resources.check_time(
            seconds,
            f"the search and its {cards} scorecard(s)",
            "mg-crb-cl" if cards else "the search",
            settings.max_hours,
            lambda message: print(f"mimo-radar-bench: {message}", file=sys.stderr),
        )
        start, before = time.perf_counter(), machine()
        out = settings.out
        harness.output_folder(out)
        found = search(
            settings.seed,
            self.args.generations,
            self.args.population,
            settings.workers,
            settings.options.lambda_scale,
        )
        print(
            f"mimo-radar-bench: {found['evaluations']} layouts in {found['wall_s']:.0f} s "
            f"({found['layouts_per_s']:.1f} /s)",
            flush=True,
        )
        finalists = (
            []
            if self.args.no_v1_scorecard
            else [{"name": "v1", "vector": vector_from_layout(v1_layout()).tolist()}]
        )
        best = distinct_feasible(found["ranked"], self.args.final)
        if ranks and len(best) < max(ranks):
            print(
                f"mimo-radar-bench: the last population holds {len(best)} distinct feasible layouts; "
                f"ranks above {len(best)} are not scored",
                flush=True,
            )
        finalists += [
            {"name": f"search-{r}", "rank": r, **best[r - 1]} for r in sorted(set(ranks)) if r <= len(best)
        ]
        for entry in finalists:
            layout = layout_from_vector(np.array(entry["vector"]))
            entry["predictors"] = predictors(layout, settings.options.lambda_scale)
            results = claims.scorecard(layout.scenarios(), out / entry["name"], settings)
            entry["counts"] = calibration.scorecard_counts(results)
            entry["verdicts"] = {r["id"]: r["verdict"] for r in results}
            entry["agreement"] = agreement(entry["predictors"]["checks"], results)
            print(f"mimo-radar-bench: {entry['name']}: {entry['counts']}", flush=True)
        record = {**found, "trials": settings.trials, "steps": settings.steps, "finalists": finalists}
        (out / "search.json").write_text(json.dumps(record, indent=1))
        write_timing(out, self.name, time.perf_counter() - start, before, {"search": found["wall_s"]})
        for entry in finalists:
            a = entry["agreement"]
            print(
                f"{entry['name']}: {entry['counts']}; predictors agree with the scorecard "
                f"{a['agree']}/{a['compared']}"
            )
        return 0
