"""Mechanisms of the learners' contradicted claims, measured by changing one thing at a time.

``mimo-radar-bench ablations`` runs v1's paper study on the three paper scenarios (the claims
study's options, seed and trials, so the same trials and numbers) and, on those trials, the
learners with one parameter changed (:data:`VARIANTS`). Every comparison is paired on trials.

- **MG-CRB-CL's ASR** (S1.10, S2.5, S3.4): the paper's MG-CRB-CL (BPSO), then the exact solver
  (BPSO's share), then without the optimism of eq18 (``beta = 0``), with a longer memory in
  eq14 (``alpha_bar = 0.05``: about 20 samples instead of 5), and both. What each change does
  to the ASR says what keeps it low.
- **S1.7** (UCB1's regret below epsilon-greedy's early, above it late): both learners against
  their greedy core, UCB1 without its bonus (``beta = 0``: the best super arm for UCB1's eq29
  estimates, which epsilon-greedy also plays 90 % of the time). The difference to the greedy
  core is what each way of exploring costs, at 300 s and at the end.
- **S1.8** (fix1's RMSE lowest over 268-360 s; fix2's highest over 0-500 and 590-1000 s): every
  policy's ARMSE and position bound (the PCRB of its own selections) in the claim's windows.
- **S2.2** (every policy's SINR degrades after the maneuver at 400 s, MG-CRB-CL's does not):
  every policy's SINR change (400-500 s against 300-400 s), its SINR below Best's before and
  after, and how many super arms gain mean reward along the true track (v1's truth is shared).

Results go to ``OUT/ablations.json``; ``python -m benchmarks docs`` writes results-claims.md's tables
from the committed copy.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Hashable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.metrics import TrialMetrics
from mimo_radar_env import env_version
from mimo_radar_env.core import motion
from mimo_radar_env.envs.mimo_radar_select import MimoRadarSelectVectorEnv

from .. import harness, uncertainty
from ..report import trial_metrics
from ..settings import add_scenarios_argument, paper_numbers
from ..study import Finished, Run, Study
from .claims import paper_runs
from .mechanisms import super_arm_channels

#: The changed learners: label -> (policy, its parameters in place of the paper study's).
VARIANTS: dict[str, tuple[str, dict[str, Any]]] = {
    "mg-crb-cl, exact solver": ("mg-crb-cl", {"solver": "exact"}),
    "mg-crb-cl, exact, beta = 0": ("mg-crb-cl", {"solver": "exact", "beta": 0.0}),
    "mg-crb-cl, exact, alpha_bar = 0.05": ("mg-crb-cl", {"solver": "exact", "alpha_bar": 0.05}),
    "mg-crb-cl, exact, beta = 0, alpha_bar = 0.05": (
        "mg-crb-cl",
        {"solver": "exact", "beta": 0.0, "alpha_bar": 0.05},
    ),
    "ucb1, beta = 0": ("ucb1", {"beta": 0.0}),
}
#: S1.7: the step (1-based) of the early comparison; the late one is the run's last step.
EARLY = 300
#: S1.8: the claim's windows and the extreme fix1 or fix2 should take there.
S18_WINDOWS = (
    ((268, 360), "fix1", "lowest"),
    ((0, 500), "fix2", "highest"),
    ((590, 1000), "fix2", "highest"),
)
#: S2.2: 100 s before and after the maneuver's start.
BEFORE, AFTER = (300, 400), (400, 500)


def slug(label: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-")


def judged(metric: Callable[[NDArray], NDArray], trials: int, seed: int) -> dict[str, Any]:
    return uncertainty.estimate(metric, trials, seed)


def asr_ablation(paper: dict[str, TrialMetrics], variants: dict[str, TrialMetrics], seed: int) -> dict:
    """MG-CRB-CL's ASR and final regret, the paper's and each variant's, with each variant's
    paired difference to the paper's."""
    base = paper["mg-crb-cl"]
    n = base.num_trials
    out = {"paper": {"asr": judged(base.asr, n, seed), "final_regret": judged(base.final_regret, n, seed)}}
    for label, m in variants.items():
        out[label] = {
            "asr": judged(m.asr, n, seed),
            "final_regret": judged(m.final_regret, n, seed),
            "asr_minus_paper": judged(lambda w, m=m: m.asr(w) - base.asr(w), n, seed),
        }
    return out


def regret_crossing(a: TrialMetrics, b: TrialMetrics) -> int | None:
    """The first step (1-based) from which ``a``'s mean regret stays above ``b``'s (None: never)."""
    w = a.equal()
    above = a.regret_curve(w) > b.regret_curve(w)
    if not above[-1]:
        return None
    below = np.flatnonzero(~above)
    return int(below[-1]) + 2 if below.size else 1


def exploration_costs(paper: dict[str, TrialMetrics], greedy: TrialMetrics, seed: int) -> dict:
    """S1.7: UCB1's and epsilon-greedy's regret at :data:`EARLY` (where the run reaches it) and at
    the end, and each one's regret above the greedy core's (UCB1 with ``beta = 0``), paired."""
    ucb, eps = paper["ucb1"], paper["epsilon-greedy"]
    n = ucb.num_trials
    out: dict[str, Any] = {"crossing": regret_crossing(ucb, eps), "at": {}}
    for at in sorted({min(EARLY, ucb.steps), ucb.steps}):
        out["at"][str(at)] = {
            "ucb1": judged(lambda w, at=at: ucb.regret(w, at), n, seed),
            "epsilon-greedy": judged(lambda w, at=at: eps.regret(w, at), n, seed),
            "greedy": judged(lambda w, at=at: greedy.regret(w, at), n, seed),
            "ucb1_minus_greedy": judged(lambda w, at=at: ucb.regret(w, at) - greedy.regret(w, at), n, seed),
            "epsilon_greedy_minus_greedy": judged(
                lambda w, at=at: eps.regret(w, at) - greedy.regret(w, at), n, seed
            ),
            "ucb1_minus_epsilon_greedy": judged(
                lambda w, at=at: ucb.regret(w, at) - eps.regret(w, at), n, seed
            ),
        }
    return out


def rmse_windows(paper: dict[str, TrialMetrics], seed: int) -> list[dict]:
    """S1.8: every policy's ARMSE, bound and their ratio in each window, each with its interval
    over trials, and which policy has the lowest or highest ARMSE and bound (by the estimates)."""
    rows = []
    for window, policy, extreme in S18_WINDOWS:
        pick = min if extreme == "lowest" else max
        armse = {
            p: judged(lambda w, m=m, window=window: m.armse(w, window), m.num_trials, seed)
            for p, m in paper.items()
        }
        bound = {
            p: judged(lambda w, m=m, window=window: m.bound(w, window), m.num_trials, seed)
            for p, m in paper.items()
        }
        ratio = {
            p: judged(
                lambda w, m=m, window=window: m.armse(w, window) / m.bound(w, window), m.num_trials, seed
            )
            for p, m in paper.items()
        }
        rows.append(
            {
                "window": list(window),
                "policy": policy,
                "extreme": extreme,
                "armse": armse,
                "bound": bound,
                "armse_over_bound": ratio,
                "armse_extreme": pick(armse, key=lambda p: armse[p]["estimate"]),
                "bound_extreme": pick(bound, key=lambda p: bound[p]["estimate"]),
            }
        )
    return rows


def true_super_arm_values(scenario: Any, seed: int, steps: int, options: dict[str, Any]) -> NDArray:
    """Every super arm's mean reward (weighted mean SINR, linear) along trial ``seed``'s true
    track, (steps, A); under v1's shared truth it is every trial's."""
    env = MimoRadarSelectVectorEnv(num_envs=1, scenario=scenario, **{**options, "tracking": False})
    env.reset(seed=seed)
    engine = env.engine
    pairs = super_arm_channels(scenario)
    weights = np.asarray(engine.model.weights, dtype=np.float64)
    values = np.empty((steps, pairs.shape[0]))
    for t in range(steps):
        mean = engine.model.mean_sinr(motion.positions(engine.simulation.upcoming_state()))  # (1, K, M, N)
        values[t] = np.einsum("k,kmn,amn->a", weights, mean[0], pairs)
        env.step(engine.oracle_action())
    return values


def maneuver(paper: dict[str, TrialMetrics], values: NDArray, seed: int) -> dict:
    """S2.2: each policy's SINR change across the maneuver and its SINR below Best's before and
    after (paired), and the share of super arms whose mean reward rises."""
    best = paper["best"]
    n = best.num_trials
    policies = {}
    for p, m in paper.items():
        policies[p] = {
            "change_db": judged(lambda w, m=m: m.mean_sinr_db(w, AFTER) - m.mean_sinr_db(w, BEFORE), n, seed),
            **{
                f"below_best_{name}_db": judged(
                    lambda w, m=m, win=win: best.mean_sinr_db(w, win) - m.mean_sinr_db(w, win), n, seed
                )
                for name, win in (("before", BEFORE), ("after", AFTER))
            },
        }
    before, after = values[slice(*BEFORE)].mean(axis=0), values[slice(*AFTER)].mean(axis=0)
    return {
        "policies": policies,
        "super_arms": int(values.shape[1]),
        "super_arms_rising": int(np.sum(after > before)),
        "best_arm_changes": int(np.sum(np.diff(np.argmax(values[BEFORE[0] : AFTER[1]], axis=1)) != 0)),
    }


class AblationsStudy(Study):
    name = "ablations"
    paper_study = True
    description = __doc__

    @classmethod
    def add_study_arguments(cls, parser: Any) -> None:
        add_scenarios_argument(parser)

    def scenario_names(self) -> list[str]:
        version = env_version(self.settings.env_version)
        return [version.paper_scenario(n) for n in paper_numbers(self.args.scenarios)]

    def runs(self) -> list[Run]:
        out = self.settings.out
        runs = []
        for name in self.scenario_names():
            (paper,) = paper_runs([name], out / name)
            runs.append(Run((name, "paper"), paper.scenario, paper.policies, out / name / "paper"))
            for label, (policy, params) in VARIANTS.items():
                runs.append(
                    Run(
                        (name, label),
                        name,
                        (policy,),
                        out / name / slug(label),
                        agent_params={policy: params},
                    )
                )
        return runs

    def judge(self, finished: dict[Hashable, Finished]) -> dict[str, Any]:
        seed = self.settings.seed
        results: dict[str, Any] = {
            "variants": {k: {"policy": p, "params": v} for k, (p, v) in VARIANTS.items()}
        }
        for name in self.scenario_names():
            metrics = {
                key[1]: trial_metrics(f.config, harness.load_per_trial(f.folder, f.config))
                for key, f in finished.items()
                if key[0] == name
            }
            paper = metrics.pop("paper")
            variants = {label: m[VARIANTS[label][0]] for label, m in metrics.items()}
            entry: dict[str, Any] = {
                "trials": paper["best"].num_trials,
                "steps": paper["best"].steps,
                "asr": asr_ablation(
                    paper, {k: v for k, v in variants.items() if k.startswith("mg-crb-cl")}, seed
                ),
                "exploration": exploration_costs(paper, variants["ucb1, beta = 0"], seed),
            }
            if paper["best"].steps >= S18_WINDOWS[-1][0][1] and paper["best"].tracked:
                entry["rmse_windows"] = rmse_windows(paper, seed)
            if paper["best"].steps >= AFTER[1]:
                config = finished[(name, "paper")].config
                values = true_super_arm_values(
                    config.scenario_object, config.seed, AFTER[1], config.env_options
                )
                entry["maneuver"] = maneuver(paper, values, seed)
            results[name] = entry
        return results

    def report(self, finished: dict[Hashable, Finished], judged_results: Any) -> str:
        out = self.settings.out
        (out / "ablations.json").write_text(json.dumps(judged_results, indent=1, allow_nan=False))
        lines = []
        for name in self.scenario_names():
            asr = judged_results[name]["asr"]
            lines.append(
                f"{name}: MG-CRB-CL's ASR {100 * asr['paper']['asr']['estimate']:.1f} %; "
                + "; ".join(
                    f"{k}: {100 * v['asr']['estimate']:.1f} %" for k, v in asr.items() if k != "paper"
                )
            )
        return "\n".join(lines) + f"\n(written: {out / 'ablations.json'})"
