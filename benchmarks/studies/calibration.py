"""Layout calibration: station positions under which the most of the paper's claims hold.

The paper's layout figure is missing. This search looks for a layout, inside the paper's
100 km x 100 km region, that satisfies the hard constraints of the paper's text and under which
the most claims of :mod:`benchmarks.studies.claims` hold. It is a calibration against the paper's
text, not the paper's layout. Three stages, each cheaper per candidate than the next:

1. **Constraints and noise-free screen** (every candidate, milliseconds each): inside the
   region; no station within :data:`MIN_TRACK_DISTANCE` of a nominal track of any paper
   scenario; on the noise-free Scenario 1 track Best selects the paper's super arms over
   0-380 s and 590-1000 s (claim S1.1, at least 95 % of the steps of each window). Passing
   candidates are scored by :func:`noise_free_checks`, comparisons of the paper's claims that
   need no Monte-Carlo: the fixed policies' SINR (S1.2) and the ARMSE orderings of Best, fix1
   and fix2 with the measurement-only Cramer-Rao bound of the position standing in for the
   RMSE.
2. **Short scorecards**: the best ``screen`` candidates (and the reference layout) run the
   three paper studies with ``screen_trials`` trials and are judged by the full scorecard.
3. **Full scorecards**: the best ``final`` of stage 2 and the reference run ``final_trials``
   trials. A candidate is adopted only if its scorecard beats the reference's: more claims
   hold, or as many and fewer are contradicted.

Candidates are the reference layout jittered station by station with a Gaussian of a scale
cycling through :data:`JITTER_KM`, from one seeded generator: the same arguments give the same
candidates, and every study folder resumes, so a stopped calibration continues.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import VERSIONS, RadarModel, Scenario, load_scenario
from mimo_radar_env.core import motion
from mimo_radar_env.scenarios.scenario import closest_approach
from mimo_radar_env.tracking.information import channel_information

from .. import verdicts
from ..harness import output_folder
from ..settings import integer, trial_count
from ..study import Study, machine, write_timing
from . import claims

REGION_M = 100_000.0
#: The text's hard constraint: no station this close (m) to a nominal track.
MIN_TRACK_DISTANCE = 2_000.0
#: Station-wise jitter scales (km) the candidates cycle through.
JITTER_KM = (2.0, 5.0, 10.0, 20.0)
#: The version whose paper scenarios hold the reference layout (section 1's reconstruction).
REFERENCE_VERSION = "v0"
PAPER_SCENARIOS = VERSIONS[REFERENCE_VERSION].paper_scenarios
#: The search's sizes (the command's defaults): candidates, layouts with short scorecards,
#: their trials, layouts with full scorecards.
CANDIDATES, SCREEN, SCREEN_TRIALS, FINAL = 400, 10, 40, 2


@dataclass
class Candidate:
    index: int
    tx_km: list[list[float]]
    rx_km: list[list[float]]
    jitter_km: float | None = None  # None: the reference layout
    rejected: str | None = None
    noise_free: dict[str, bool] = field(default_factory=dict)
    scorecards: dict[str, dict[str, int]] = field(default_factory=dict)  # trials -> counts

    @property
    def noise_free_score(self) -> int:
        return sum(self.noise_free.values())

    def scenarios(self) -> list[Scenario]:
        if self.jitter_km is None:
            return [load_scenario(name) for name in PAPER_SCENARIOS]
        tx, rx = np.array(self.tx_km) * 1e3, np.array(self.rx_km) * 1e3
        return [load_scenario(name, tx_positions=tx, rx_positions=rx) for name in PAPER_SCENARIOS]


def candidates(count: int, seed: int) -> list[Candidate]:
    """The reference layout (index 0) and ``count`` jittered layouts, reproducibly."""
    reference = load_scenario(PAPER_SCENARIOS[0])
    tx0, rx0 = reference.tx_positions / 1e3, reference.rx_positions / 1e3
    rng = np.random.default_rng(seed)
    out = [Candidate(0, tx0.tolist(), rx0.tolist())]
    for i in range(1, count + 1):
        scale = JITTER_KM[(i - 1) % len(JITTER_KM)]
        tx = _reflect(tx0 + scale * rng.standard_normal(tx0.shape))
        rx = _reflect(rx0 + scale * rng.standard_normal(rx0.shape))
        out.append(Candidate(i, np.round(tx, 3).tolist(), np.round(rx, 3).tolist(), scale))
    return out


def _reflect(km: NDArray[np.float64]) -> NDArray[np.float64]:
    """Fold jittered coordinates back into [0, 100] km at the edges (stations on the edge stay
    near it)."""
    size = REGION_M / 1e3
    return size - np.abs(size - np.abs(km))


def constraint_check(candidate: Candidate) -> tuple[float, str | None]:
    """How far the candidate is from the text's hard constraints, and the first one it breaks.

    The amount is 0 when it meets them all, else the sum of how far stations lie outside the
    region (km), the track-distance shortfalls (in units of :data:`MIN_TRACK_DISTANCE`), the S1.1
    windows' shortfalls below ``BEST_WINDOW_FRACTION``, and 1 for a layout that is not a valid
    scenario (then nothing else is checked). The reason is None exactly when the amount is 0.
    """
    tx, rx = np.array(candidate.tx_km) * 1e3, np.array(candidate.rx_km) * 1e3
    stations = np.concatenate([tx, rx])
    outside = float(np.sum(np.maximum(-stations, 0) + np.maximum(stations - REGION_M, 0))) / 1e3
    reasons = ["a station outside the 100 km x 100 km region"] if outside > 0 else []
    try:
        scenarios = candidate.scenarios()
    except ValueError as exc:  # ScenarioError: e.g. two stations at one place
        return 1.0 + outside, (reasons or [f"not a valid scenario: {exc}"])[0]
    total = outside
    for sc in scenarios:
        model = RadarModel.from_scenario(sc)
        for k in range(sc.num_targets):
            distance, _, _ = closest_approach(motion.positions(model.nominal[k]), stations)
            if distance < MIN_TRACK_DISTANCE:
                total += (MIN_TRACK_DISTANCE - distance) / MIN_TRACK_DISTANCE
                reasons.append(f"a station {distance / 1e3:.2f} km from a nominal track of {sc.name}")
    fractions = claims.best_selection_windows(scenarios[0])
    if min(fractions.values()) < claims.BEST_WINDOW_FRACTION:
        total += sum(max(claims.BEST_WINDOW_FRACTION - f, 0.0) for f in fractions.values())
        reasons.append(
            "noise-free Scenario 1: Best selects the paper's super arm in "
            + ", ".join(f"{f:.0%} of {window}" for window, f in fractions.items())
        )
    return total, (reasons[0] if reasons else None)


def constraint_failure(candidate: Candidate) -> str | None:
    """Why the candidate breaks a hard constraint of the text, or None."""
    return constraint_check(candidate)[1]


def scan_bound(model: RadarModel, tx: NDArray[np.bool_], rx: NDArray[np.bool_], scale: str) -> NDArray:
    """Per target and step, ``sqrt(trace J^-1)`` of the position from one scan of the selected
    channels on the noise-free track, ``J = sum H_mn' (Sigma0 / lambda_mn)^-1 H_mn`` (eq6,
    eq32): the measurement-only Cramer-Rao bound (m), shape (T+1, K). ``tx``/``rx`` masks
    (T+1, M/N)."""
    positions = model.nominal_positions  # (T+1, K, 2)
    variance = model.measurement_variance(model.quality(model.mean_sinr(positions), scale=scale))
    info = channel_information(positions, model.tx, model.rx, variance)  # (T+1, K, M, N, 2, 2)
    selected = (tx[:, :, None] & rx[:, None, :]).astype(float)  # (T+1, M, N)
    total = np.einsum("tmn,tkmnij->tkij", selected, info)
    return np.sqrt(np.trace(np.linalg.inv(total), axis1=-2, axis2=-1))


def noise_free_checks(candidate: Candidate, scale: str) -> dict[str, bool]:
    """Comparisons of the paper's claims that need no Monte-Carlo, on the noise-free tracks."""
    from agents.fixed import PAPER_FIXED

    checks: dict[str, bool] = {}
    for number, sc in enumerate(candidate.scenarios(), start=1):  # the paper's Scenarios 1, 2, 3
        model = RadarModel.from_scenario(sc)
        steps = model.nominal.shape[1]
        masks = {"best": claims.noise_free_best(model)}
        for name, (tx_idx, rx_idx) in PAPER_FIXED.items():
            tx, rx = np.zeros((steps, model.num_tx), bool), np.zeros((steps, model.num_rx), bool)
            tx[:, list(tx_idx)], rx[:, list(rx_idx)] = True, True
            masks[name] = (tx, rx)
        bound = {p: scan_bound(model, *m, scale) for p, m in masks.items()}
        weights = model.nominal_channel_weights()  # (T+1, M, N)

        def armse(policy: str, a: int = 0, b: int = steps, bound: dict = bound) -> float:
            return float(bound[policy][a:b].mean(axis=0).mean())

        def sinr(policy: str, a: int, b: int, masks: dict = masks, weights: NDArray = weights) -> float:
            tx, rx = masks[policy]
            return float(np.einsum("tm,tn,tmn->", tx[a:b], rx[a:b], weights[a:b]))

        n = number
        if number == 1:
            checks["S1.2 fix1 > fix2 SINR 0-500 s"] = sinr("fix1", 0, 500) > sinr("fix2", 0, 500)
            checks["S1.2 fix2 > fix1 SINR 500-1000 s"] = sinr("fix2", 500, 1000) > sinr("fix1", 500, 1000)
            checks["S1.8 fix1 lowest bound 268-360 s"] = armse("fix1", 268, 360) < min(
                armse("best", 268, 360), armse("fix2", 268, 360)
            )
            checks["S1.8 fix2 highest bound 0-500 s"] = armse("fix2", 0, 500) > max(
                armse("best", 0, 500), armse("fix1", 0, 500)
            )
        checks[f"S{n} bound best < fix1"] = armse("best") < armse("fix1")
        checks[f"S{n} bound fix1 < fix2"] = armse("fix1") < armse("fix2")
    return checks


def scorecard_counts(results: list[dict[str, Any]]) -> dict[str, int]:
    return verdicts.count(r["verdict"] for r in results)


StudyRunner = Callable[[list[Scenario], Path, int], list[dict[str, Any]]]


def calibrate(
    out: Path,
    run_scorecard: StudyRunner,
    count: int = CANDIDATES,
    seed: int = 0,
    screen: int = SCREEN,
    screen_trials: int = SCREEN_TRIALS,
    final: int = FINAL,
    final_trials: int = 500,
    scale: str = "db",
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Run the three stages into ``out``; write and return ``calibration.json``.

    ``run_scorecard(scenarios, folder, trials)`` runs the three paper studies of a layout into
    ``folder`` (resumably) and returns the judged claims.
    """
    output_folder(out)
    pool = candidates(count, seed)
    for c in pool:
        c.rejected = constraint_failure(c)
        if c.rejected is None:
            c.noise_free = noise_free_checks(c, scale)
    passing = [c for c in pool if c.rejected is None]
    log(f"stage 1: {len(passing)} of {len(pool)} layouts meet the constraints")
    reference = pool[0]
    ranked = sorted((c for c in passing if c.index != 0), key=lambda c: -c.noise_free_score)
    shortlist = [reference, *ranked[:screen]]
    for c in shortlist:
        results = run_scorecard(c.scenarios(), out / "screen" / f"layout-{c.index:04d}", screen_trials)
        c.scorecards[str(screen_trials)] = scorecard_counts(results)
        log(f"stage 2: layout {c.index}: {c.scorecards[str(screen_trials)]}")
    finalists = sorted(
        shortlist[1:], key=lambda c: verdicts.rank_key(c.scorecards[str(screen_trials)]), reverse=True
    )
    for c in [reference, *finalists[:final]]:
        results = run_scorecard(c.scenarios(), out / "final" / f"layout-{c.index:04d}", final_trials)
        c.scorecards[str(final_trials)] = scorecard_counts(results)
        log(f"stage 3: layout {c.index}: {c.scorecards[str(final_trials)]}")
    judged = [c for c in pool if str(final_trials) in c.scorecards]
    best = max(judged, key=lambda c: (verdicts.rank_key(c.scorecards[str(final_trials)]), c.index == 0))
    adopted = best.index != 0 and verdicts.rank_key(best.scorecards[str(final_trials)]) > verdicts.rank_key(
        reference.scorecards[str(final_trials)]
    )
    report = {
        "seed": seed,
        "count": count,
        "scale": scale,
        "stages": {
            "screen": screen,
            "screen_trials": screen_trials,
            "final": final,
            "final_trials": final_trials,
        },
        "best": best.index,
        "adopted": adopted,
        "candidates": [{**asdict(c), "noise_free_score": c.noise_free_score} for c in pool],
    }
    (out / "calibration.json").write_text(json.dumps(report, indent=1, allow_nan=False))
    (out / "calibration.md").write_text(calibration_markdown(report))
    return report


def calibration_markdown(report: dict[str, Any]) -> str:
    stages = report["stages"]
    screen, final = str(stages["screen_trials"]), str(stages["final_trials"])
    lines = [
        "# Layout calibration",
        "",
        "A calibration against the paper's text, not the paper's layout (its figure is missing).",
        "",
        f"{report['count']} jittered layouts (seed {report['seed']}) and the reference (layout 0). "
        f"Stage 1: hard constraints and {len(report['candidates'][0]['noise_free'])} noise-free checks; "
        f"stage 2: scorecards at {screen} trials; stage 3: at {final} trials. Best layout: {report['best']}; "
        + (
            "adopted (its scorecard beats the reference's)."
            if report["adopted"]
            else "not adopted: no layout beats the reference's scorecard."
        ),
        "",
        f"| layout | jitter (km) | constraints | noise-free checks | holds / consistent / contradicted at "
        f"{screen} trials | at {final} trials |",
        "|---|---|---|---|---|---|",
    ]

    def counts(c: dict[str, Any], trials: str) -> str:
        s = c["scorecards"].get(trials)
        return f"{s['holds']} / {s['consistent']} / {s['contradicted']}" if s else "—"

    best = next(c for c in report["candidates"] if c["index"] == report["best"])
    reference = report["candidates"][0]
    lines[-3:-3] = [
        "",
        f"Station positions (km) of the best layout ({best['index']}) and of the reference:",
        "",
        "| station | best layout | reference |",
        "|---|---|---|",
        *(
            f"| {kind}{i + 1} | ({p[0]:.3f}, {p[1]:.3f}) | ({q[0]:g}, {q[1]:g}) |"
            for kind, key in (("TX", "tx_km"), ("RX", "rx_km"))
            for i, (p, q) in enumerate(zip(best[key], reference[key], strict=True))
        ),
    ]
    order = sorted(
        report["candidates"], key=lambda c: (c["rejected"] is not None, -c["noise_free_score"], c["index"])
    )
    for c in order:
        jitter = "reference" if c["jitter_km"] is None else f"{c['jitter_km']:g}"
        constraint = "met" if c["rejected"] is None else c["rejected"]
        checks = f"{c['noise_free_score']} / {len(c['noise_free'])}" if c["rejected"] is None else "—"
        cells = [str(c["index"]), jitter, constraint, checks, counts(c, screen), counts(c, final)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


class CalibrationStudy(Study):
    name = "calibrate-layout"
    description = (
        "Jitter the reference layout into candidates (seeded), reject those that break the paper's "
        "text (region, 2 km from every nominal track, Best's selections in Scenario 1), rank the rest "
        "by noise-free checks, judge the best by short scorecards, then the best of those and the "
        "reference by full scorecards (--trials). Writes OUT/calibration.md and OUT/calibration.json "
        "with every candidate's score; resumable (docs/benchmark.md)."
    )
    paper_study = True

    @classmethod
    def add_study_arguments(cls, parser: argparse.ArgumentParser) -> None:
        for flag, default, text, kind in (
            ("--candidates", CANDIDATES, "jittered layouts to draw", integer(1)),
            ("--screen", SCREEN, "layouts judged by short scorecards", integer(1)),
            ("--screen-trials", SCREEN_TRIALS, "trials of the short scorecards", trial_count(cls.min_trials)),
            ("--final", FINAL, "layouts judged by full scorecards", integer(1)),
        ):
            parser.add_argument(flag, type=kind, default=default, help=f"{text} (default {default})")

    def main(self) -> int:
        start = time.perf_counter()
        load_before = machine()
        settings = self.settings

        def scorecard(scenarios: list[Scenario], out: Path, trials: int) -> list[dict[str, Any]]:
            return claims.scorecard(scenarios, out, dataclasses.replace(settings, trials=trials))

        out = settings.out
        report = calibrate(
            out,
            scorecard,
            count=self.args.candidates,
            seed=settings.seed,
            screen=self.args.screen,
            screen_trials=self.args.screen_trials,
            final=self.args.final,
            final_trials=settings.trials,
            scale=settings.options.lambda_scale,
        )
        write_timing(out, self.name, time.perf_counter() - start, load_before)
        print((out / "calibration.md").read_text().split("\n\n| layout")[0])
        print(
            f"best layout {report['best']}: {'adopted' if report['adopted'] else 'not adopted'}; "
            f"every candidate in {out / 'calibration.md'}"
        )
        return 0
