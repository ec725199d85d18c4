"""Mechanisms behind the paper's contradicted claims, measured.

``mimo-radar-bench mechanisms`` measures two mechanisms on the v1 paper scenarios:

1. **Why no learner reaches the paper's ASR** (S1.10, S2.5, S3.4). Each step, every super arm's
   mean reward is the sum of its channels' weighted true mean SINR (what Best maximises). The
   *lead* of a step is ``best / second - 1``: how much the best super arm's mean reward exceeds
   the second best's. A small lead makes the best super arm hard to tell apart: a learner sees
   Swerling-I samples (exponential, coefficient of variation 1), so ``n`` samples of a channel
   estimate its mean with a relative error near ``1 / sqrt(n)``. The *sampling oracle* with
   ``n`` samples knows each channel's current mean SINR only through the mean of ``n`` fresh
   Swerling-I samples of it (``mean x Gamma(n, 1) / n`` per target and channel, every step)
   and selects the best super arm for those estimates. Its ASR is a cap on any learner that has
   no more than ``n`` samples of every channel's *current* mean: a learner's samples are fewer
   (it probes ``Ms Ns`` of the ``M N`` channels a step) and older (the channels change).
   The *window oracle* of width ``W`` sees one Swerling-I sample of every channel every step
   and estimates each channel's mean by the mean of its last ``W`` samples (of the means of
   those past steps): its ASR is a cap on sliding-window learners, which see fewer channels a
   step. Small windows are noisy, wide ones stale; the best width bounds what such a learner
   can reach on these channels. The *probing window oracle* sees only ``Ms Ns`` channels a step,
   as a learner does, in a fixed rotation (channel ``c`` at the steps ``t`` with
   ``(t + c) mod P = 0``, ``P = ceil(M N / (Ms Ns))``), and averages each channel's last ``W``
   samples (``P W`` steps): the cap of a sliding-window learner that probes evenly.
2. **Why the ARMSE orderings differ from the paper's** (S1.9, S2.4, S3.2, S3.3). For every
   ARMSE comparison of the claims, the measured difference is set beside the difference of the
   two policies' position bounds (the PCRB of their own selections: geometry and SINR through
   eq32's lambda) and of their mean SINR. A comparison *follows the bound* when the policy with
   the smaller bound has the smaller ARMSE, and *follows SINR* when the policy with the higher
   SINR has the smaller ARMSE.

Part 1 runs the env under v1's options (its truth and mean SINR only: no tracker, no policy); part 2 reads the
claims study's results (``--claims``, ``--summaries``: the committed v1 average-fusion ones by
default). Results go to ``OUT/mechanisms.json``; ``python -m benchmarks docs`` writes the tables
of docs/results-claims.md from the committed copy.
"""

from __future__ import annotations

import argparse
import json
import re
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import VERSIONS, load_scenario
from mimo_radar_env.core import motion
from mimo_radar_env.core.superarm import all_super_arms
from mimo_radar_env.envs.mimo_radar_select import MimoRadarSelectVectorEnv

from .. import uncertainty
from ..cli import Command
from ..errors import BenchError
from ..harness import output_folder
from ..outputs import folder
from ..report import paired_difference
from ..settings import integer, trial_count
from ..study import machine, write_timing

#: Swerling-I samples per channel of the sampling oracles.
SAMPLES = (1, 3, 10, 30, 100, 300, 1000)
#: Widths (steps) of the window oracles.
WINDOWS = (1, 3, 10, 30, 100, 300)
#: Leads below which a step counts as close (fractions).
CLOSE = (0.02, 0.05)
SCENARIOS = ("paper-1-v1", "paper-2-v1", "paper-3-v1")
#: The claims whose mechanism part 1 measures (ASR orderings), by scenario.
ASR_CLAIMS = {"paper-1-v1": "S1.10", "paper-2-v1": "S2.5", "paper-3-v1": "S3.4"}
DOCS_RESULTS = Path(__file__).resolve().parents[2] / "docs" / "results"
DEFAULT_CLAIMS = DOCS_RESULTS / "claims" / "v1.json"
DEFAULT_SUMMARIES = DOCS_RESULTS / "v1"
_ARMSE = re.compile(r"^armse(?: of target (\d+))?: (\S+) < (\S+)$")


def super_arm_channels(sc: Any) -> NDArray[np.float64]:
    """Every super arm's channels as 0/1 matrices, (A, M, N)."""
    tx, rx = all_super_arms(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
    return (tx[:, :, None] & rx[:, None, :]).astype(np.float64)


def leads(value: NDArray[np.float64]) -> NDArray[np.float64]:
    """The best super arm's lead over the second, ``best / second - 1``, for mean rewards
    (..., A)."""
    top2 = -np.partition(-value, 1, axis=-1)[..., :2]
    return top2[..., 0] / top2[..., 1] - 1.0


def lead_and_sampling_oracles(
    scenario: str, trials: int, seed: int, samples: tuple[int, ...] = SAMPLES, steps: int | None = None
) -> dict[str, Any]:
    """Part 1 on one scenario: per trial, the lead's median and the fraction of steps with a lead
    below each of :data:`CLOSE`, and the ASR of each sampling oracle (``samples``), window oracle
    and probing window oracle (:data:`WINDOWS`); means over trials with their 95 % intervals
    (``benchmarks.uncertainty``)."""
    sc = load_scenario(scenario)
    options = {**VERSIONS["v1"].option_defaults, "tracking": False}  # v1's truth and lambda, no tracker
    env = MimoRadarSelectVectorEnv(num_envs=trials, scenario=sc, **options)
    env.reset(seed=seed)
    engine = env.engine
    horizon = steps or sc.horizon
    pairs = super_arm_channels(sc)  # (A, M, N)
    weights = np.asarray(engine.model.weights, dtype=np.float64)  # (K,)

    def rewards(mean: NDArray[np.float64]) -> NDArray[np.float64]:
        """Every super arm's weighted mean SINR for channel means (B, K, M, N): (B, A)."""
        return np.einsum("k,bkmn,amn->ba", weights, mean, pairs)

    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x5A3B]))
    lead = np.empty((trials, horizon))
    matches = np.zeros((len(samples), trials))
    window_matches = np.zeros((len(WINDOWS), trials))
    probe_matches = np.zeros((len(WINDOWS), trials))
    sums = probed_sums = None  # cumulative sums of the channels' samples, (T + 1, B, K, M, N)
    period = -(-(sc.num_tx * sc.num_rx) // (sc.tx_per_step * sc.rx_per_step))
    channel = np.arange(sc.num_tx * sc.num_rx).reshape(sc.num_tx, sc.num_rx)
    probed_counts = np.zeros((horizon + 1, sc.num_tx, sc.num_rx))
    action = engine.oracle_action()
    for t in range(horizon):
        upcoming = motion.positions(engine.simulation.upcoming_state())
        mean = engine.model.mean_sinr(upcoming)  # (B, K, M, N)
        value = rewards(mean)
        lead[:, t] = leads(value)
        best = np.argmax(value, axis=1)
        for i, n in enumerate(samples):
            estimate = mean * rng.gamma(n, 1.0 / n, size=mean.shape)
            matches[i] += np.argmax(rewards(estimate), axis=1) == best
        sample = mean * rng.exponential(size=mean.shape)  # Swerling I: one sample per channel
        if sums is None:
            sums, probed_sums = np.zeros((horizon + 1, *mean.shape)), np.zeros((horizon + 1, *mean.shape))
        sums[t + 1] = sums[t] + sample
        probed = (channel + t) % period == 0
        probed_sums[t + 1] = probed_sums[t] + sample * probed
        probed_counts[t + 1] = probed_counts[t] + probed
        for i, width in enumerate(WINDOWS):
            low = max(t + 1 - width, 0)
            estimate = (sums[t + 1] - sums[low]) / (t + 1 - low)
            window_matches[i] += np.argmax(rewards(estimate), axis=1) == best
            low = max(t + 1 - period * width, 0)
            count = np.maximum(probed_counts[t + 1] - probed_counts[low], 1.0)
            estimate = (probed_sums[t + 1] - probed_sums[low]) / count
            probe_matches[i] += np.argmax(rewards(estimate), axis=1) == best
        env.step(action)
        action = engine.oracle_action()
    per_trial = {
        "median_lead": np.median(lead, axis=1),
        **{f"fraction_lead_below_{c:g}": (lead < c).mean(axis=1) for c in CLOSE},
    }
    out: dict[str, Any] = {"scenario": scenario, "trials": trials, "steps": horizon}
    for name, values in per_trial.items():
        out[name] = uncertainty.estimate(lambda w, v=values: w @ v, trials, seed)
    out["sampling_oracle_asr"] = {
        str(n): uncertainty.estimate(lambda w, v=matches[i] / horizon: w @ v, trials, seed)
        for i, n in enumerate(samples)
    }
    out["window_oracle_asr"] = {
        str(w): uncertainty.estimate(lambda x, v=window_matches[i] / horizon: x @ v, trials, seed)
        for i, w in enumerate(WINDOWS)
    }
    out["probing_window_oracle_asr"] = {
        str(w): uncertainty.estimate(lambda x, v=probe_matches[i] / horizon: x @ v, trials, seed)
        for i, w in enumerate(WINDOWS)
    }
    out["probing_period"] = period
    out["lead_quantiles"] = {str(q): float(np.quantile(lead, q)) for q in (0.1, 0.25, 0.5, 0.75, 0.9)}
    return out


def bound_versus_sinr(claims: list[dict[str, Any]], summaries: Path) -> list[dict[str, Any]]:
    """Part 2: every ARMSE comparison of the claims beside the two policies' bound and SINR
    (read from the run summaries ``{scenario}-v1-average.summary.json`` in ``summaries``)."""
    rows = []
    read: dict[str, dict[str, Any]] = {}
    for claim in claims:
        for comparison in claim["comparisons"]:
            match = _ARMSE.match(comparison["comparison"])
            if match is None:
                continue
            target, a, b = match.groups()
            scenario = claim["scenario"]
            if scenario not in read:
                read[scenario] = json.loads((summaries / f"{scenario}-v1-average.summary.json").read_text())
            summary = read[scenario]
            k = int(target) - 1 if target else None
            (bound_a, ci_a), (bound_b, ci_b) = (_bound(summary["policies"][p], k) for p in (a, b))
            sinr = paired_difference(summary, a, b, "mean_sinr_db")
            armse = comparison["estimate"]
            rows.append(
                {
                    "claim": claim["id"],
                    "scenario": claim["scenario"],
                    "comparison": comparison["comparison"],
                    "verdict": comparison["verdict"],
                    "armse_difference": {"estimate": armse, "ci": comparison["ci"]},
                    "bound_difference": bound_a - bound_b,
                    # the bounds' own intervals (not paired): the sign is settled when they are disjoint
                    "bound_settled": ci_a[1] < ci_b[0] or ci_b[1] < ci_a[0],
                    "sinr_db_difference": sinr,
                    "follows_bound": bool(np.sign(armse) == np.sign(bound_a - bound_b)),
                    "follows_sinr": bool(np.sign(armse) == -np.sign(sinr["estimate"])),
                }
            )
    return rows


def _bound(policy: dict[str, Any], target: int | None) -> tuple[float, list[float]]:
    """A summary's bound of one policy (of one target, or over targets) with its interval."""
    if target is None:
        return policy["bound"], policy["ci"]["bound"]
    return policy["bound_per_target"][target], policy["ci"]["bound_per_target"][target]


def summarise(rows: list[dict[str, Any]]) -> dict[str, int]:
    """How many ARMSE comparisons (and how many of the contradicted ones) follow each predictor."""
    contradicted = [r for r in rows if r["verdict"] == "contradicted"]
    return {
        "comparisons": len(rows),
        "follow_bound": sum(r["follows_bound"] for r in rows),
        "follow_sinr": sum(r["follows_sinr"] for r in rows),
        "contradicted": len(contradicted),
        "contradicted_follow_bound": sum(r["follows_bound"] for r in contradicted),
        "contradicted_follow_sinr": sum(r["follows_sinr"] for r in contradicted),
    }


def paper_asr(claims: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    """The paper's ASR (%) per ASR claim, by policy."""
    return {
        c["id"]: {p: float(np.ravel(v)[0]) for p, v in c["paper"]["asr"].items()}
        for c in claims
        if "asr" in (c.get("paper") or {})
    }


class MechanismsStudy(Command):
    name = "mechanisms"
    description = __doc__

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        fewest = uncertainty.MIN_INTERVAL_TRIALS
        parser.add_argument(
            "--trials",
            type=trial_count(fewest),
            default=500,
            help=f"trials per scenario, at least {fewest} (default 500)",
        )
        parser.add_argument("--seed", type=integer(0), default=0, help="master seed (default 0)")
        parser.add_argument("--steps", type=integer(1), default=None, help="steps (default: the horizon)")
        parser.add_argument("--scenarios", nargs="+", default=list(SCENARIOS), choices=SCENARIOS)
        parser.add_argument("--claims", type=Path, default=DEFAULT_CLAIMS, help="a claims study's v1.json")
        parser.add_argument(
            "--summaries", type=Path, default=DEFAULT_SUMMARIES, help="the folder of its runs' summary.json"
        )
        parser.add_argument("--out", type=folder, default="runs/mechanisms")

    def main(self) -> int:
        args = self.args
        args.out = Path(args.out)
        claims = _check_inputs(args)
        output_folder(args.out)
        start, before = time.perf_counter(), machine()
        lead = {}
        for scenario in args.scenarios:
            lead[scenario] = lead_and_sampling_oracles(scenario, args.trials, args.seed, steps=args.steps)
            lead[scenario]["claim"] = ASR_CLAIMS[scenario]
            print(f"mimo-radar-bench: {scenario} done", flush=True)
        rows = bound_versus_sinr(claims, args.summaries)
        result = {
            "samples": list(SAMPLES),
            "windows": list(WINDOWS),
            "close": list(CLOSE),
            "lead": lead,
            "paper_asr": paper_asr(claims),
            "armse_comparisons": rows,
            "armse_summary": summarise(rows),
            "claims_file": str(args.claims),
        }
        (args.out / "mechanisms.json").write_text(json.dumps(result, indent=2))
        write_timing(args.out, self.name, time.perf_counter() - start, before)
        for scenario, entry in lead.items():
            asr = entry["sampling_oracle_asr"]
            print(
                f"{scenario}: median lead {100 * entry['median_lead']['estimate']:.2f} %, "
                f"{100 * entry['fraction_lead_below_0.02']['estimate']:.0f} % of steps below 2 %; "
                "sampling-oracle ASR "
                + ", ".join(f"n={n}: {100 * asr[str(n)]['estimate']:.0f} %" for n in SAMPLES)
                + "; window-oracle ASR "
                + ", ".join(
                    f"W={w}: {100 * entry['window_oracle_asr'][str(w)]['estimate']:.0f} %" for w in WINDOWS
                )
                + "; probing ASR "
                + ", ".join(
                    f"W={w}: {100 * entry['probing_window_oracle_asr'][str(w)]['estimate']:.0f} %"
                    for w in WINDOWS
                )
            )
        s = summarise(rows)
        print(
            f"ARMSE comparisons: {s['follow_bound']} of {s['comparisons']} follow the bound, "
            f"{s['follow_sinr']} follow SINR; of the {s['contradicted']} contradicted, "
            f"{s['contradicted_follow_bound']} follow the bound, {s['contradicted_follow_sinr']} SINR"
        )
        return 0


def _check_inputs(args: Any) -> list[dict[str, Any]]:
    """The claims file read, after checking every input before anything is computed: the claims
    file (JSON of a claims study), the summaries' folder and the scenarios (once each); ``--out``
    is checked by its argparse type and made before the work (:func:`~benchmarks.harness.output_folder`)."""
    if len(set(args.scenarios)) != len(args.scenarios):
        raise BenchError(f"--scenarios lists a scenario twice: {args.scenarios}")
    try:
        claims = json.loads(Path(args.claims).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BenchError(f"--claims {str(args.claims)!r} is not a claims study's JSON file ({exc})") from None
    if not isinstance(claims, list):
        raise BenchError(
            f"--claims {str(args.claims)!r} is not a claims study's JSON file (not a list of claims)"
        )
    if not Path(args.summaries).is_dir():
        raise BenchError(f"--summaries {str(args.summaries)!r} is not a folder of a claims study's runs")
    return claims
