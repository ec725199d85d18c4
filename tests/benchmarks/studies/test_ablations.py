"""The ablations study: its windows and crossings against hand-made per-trial arrays, the true
super arms' values against itertools and the env's own optimum, the command end to end."""

import itertools
import json

import numpy as np
import pytest

from benchmarks.cli import main as cli_main
from benchmarks.metrics import TrialMetrics
from benchmarks.studies import ablations
from mimo_radar_env import VERSIONS, load_scenario
from mimo_radar_env.envs.mimo_radar_select import MimoRadarSelectVectorEnv


def metrics(expected, optimal=None, squared=None, bound=None) -> TrialMetrics:
    expected = np.asarray(expected, float)
    arrays = {
        "trial_expected": expected,
        "trial_optimal": expected.max() * np.ones_like(expected) if optimal is None else optimal,
        "trial_matches": np.zeros_like(expected),
    }
    if squared is not None:
        arrays["trial_squared_error"] = squared
        arrays["trial_bound_squared"] = bound
    return TrialMetrics(arrays, channels=6)


def test_regret_crossing_is_the_step_from_which_one_stays_above():
    optimal = np.full((2, 10), 5.0)
    # a: per-step regret 0 for 4 steps, then 3; b: 1 every step -> cumulative a > b from step 7 on
    a = metrics(np.tile(np.r_[np.full(4, 5.0), np.full(6, 2.0)], (2, 1)), optimal)
    b = metrics(np.full((2, 10), 4.0), optimal)
    regret_a, regret_b = np.cumsum(np.r_[np.zeros(4), np.full(6, 3.0)]), np.cumsum(np.ones(10))
    first = 1 + next(t for t in range(10) if all(regret_a[s] > regret_b[s] for s in range(t, 10)))
    assert ablations.regret_crossing(a, b) == first == 7
    assert ablations.regret_crossing(b, a) is None  # b ends below a
    assert ablations.regret_crossing(a, metrics(np.full((2, 10), 5.0), optimal)) == 5


def test_exploration_costs_are_paired_differences_of_the_regrets():
    rng = np.random.default_rng(0)
    optimal = np.full((30, 400), 5.0)
    runs = {
        name: metrics(5.0 - rng.exponential(scale, (30, 400)), optimal)
        for name, scale in (("ucb1", 1.0), ("epsilon-greedy", 0.5), ("greedy", 0.2))
    }
    out = ablations.exploration_costs(
        {"ucb1": runs["ucb1"], "epsilon-greedy": runs["epsilon-greedy"]}, runs["greedy"], seed=0
    )
    assert set(out["at"]) == {"300", "400"}
    for at in (300, 400):
        regret = {k: (optimal - m.expected)[:, :at].sum(axis=1).mean() for k, m in runs.items()}
        entry = out["at"][str(at)]
        assert entry["ucb1_minus_greedy"]["estimate"] == pytest.approx(regret["ucb1"] - regret["greedy"])
        assert entry["epsilon_greedy_minus_greedy"]["estimate"] == pytest.approx(
            regret["epsilon-greedy"] - regret["greedy"]
        )
        assert entry["ucb1_minus_greedy"]["ci"][0] > 0  # scale 1 against 0.2: UCB1 costs more
    assert out["crossing"] == 1  # ucb1's regret is above epsilon-greedy's from the first step


def test_rmse_windows_pick_the_extremes_of_armse_and_bound():
    trials, steps = 8, 1000
    levels = {"best": 1.0, "mg-crb-cl": 2.0, "fix1": 3.0, "fix2": 4.0}
    paper = {}
    for p, level in levels.items():
        squared = np.full((trials, steps, 1), level**2)
        bound = np.full((trials, steps, 1), (5.0 - level) ** 2)  # bounds ordered the other way
        if p == "fix1":
            squared[:, 268:360] = 0.25  # fix1 lowest in the claim's window
        paper[p] = metrics(np.ones((trials, steps)), squared=squared, bound=bound)
    rows = {tuple(r["window"]): r for r in ablations.rmse_windows(paper, seed=0)}
    assert rows[(268, 360)]["armse_extreme"] == "fix1" and rows[(268, 360)]["bound_extreme"] == "fix2"
    assert rows[(0, 500)]["armse_extreme"] == "fix2" and rows[(0, 500)]["bound_extreme"] == "best"
    assert rows[(268, 360)]["armse"]["fix1"]["estimate"] == pytest.approx(0.5)
    assert rows[(590, 1000)]["bound"]["best"]["estimate"] == pytest.approx(4.0)
    # fix1 in its window: ARMSE 0.5 over a bound of 2, the ratio of the two per resampled trials
    assert rows[(268, 360)]["armse_over_bound"]["fix1"]["estimate"] == pytest.approx(0.25)
    for row in rows.values():  # the bound and the ratio carry their intervals, as the ARMSE does
        for judged in (*row["bound"].values(), *row["armse_over_bound"].values()):
            assert judged["ci"][0] <= judged["estimate"] <= judged["ci"][1]


def test_true_super_arm_values_match_itertools_and_the_envs_optimum():
    sc = load_scenario("paper-3-v1")
    options = VERSIONS["v1"].options().to_dict()
    steps = 5
    values = ablations.true_super_arm_values(sc, seed=2, steps=steps, options=options)
    env = MimoRadarSelectVectorEnv(num_envs=1, scenario=sc, **{**options, "tracking": False})
    env.reset(seed=2)
    weights = np.asarray(sc.weights)
    for t in range(steps):
        mean = env.engine.model.mean_sinr(env.engine.simulation.upcoming_state()[..., [0, 2]])[0]
        weighted = np.tensordot(weights, mean, axes=1)
        brute = [
            sum(weighted[m, n] for m in tx for n in rx)
            for tx in itertools.combinations(range(sc.num_tx), sc.tx_per_step)
            for rx in itertools.combinations(range(sc.num_rx), sc.rx_per_step)
        ]
        assert sorted(values[t]) == pytest.approx(sorted(brute))
        _, _, _, _, info = env.step(env.engine.oracle_action())
        assert values[t].max() == pytest.approx(info["optimal_reward"][0])


def test_maneuver_counts_rising_super_arms_and_pairs_the_loss_against_best():
    steps, trials = 500, 6
    values = np.ones((steps, 3))
    values[400:, 0], values[400:, 1] = 2.0, 0.5  # arm 0 rises, arm 1 falls, arm 2 stays
    best = metrics(np.tile(np.r_[np.full(400, 6.0), np.full(100, 12.0)], (trials, 1)))
    learner = metrics(np.tile(np.r_[np.full(400, 6.0), np.full(100, 6.0)], (trials, 1)))
    out = ablations.maneuver({"best": best, "mg-crb-cl": learner}, values, seed=0)
    assert out["super_arms_rising"] == 1 and out["super_arms"] == 3
    mg = out["policies"]["mg-crb-cl"]
    assert mg["change_db"]["estimate"] == pytest.approx(0.0)
    assert mg["below_best_before_db"]["estimate"] == pytest.approx(0.0)
    assert mg["below_best_after_db"]["estimate"] == pytest.approx(10 * np.log10(2.0))
    assert out["policies"]["best"]["change_db"]["estimate"] == pytest.approx(10 * np.log10(2.0))


def test_the_command_pairs_every_variant_with_the_paper_study(tmp_path):
    out = tmp_path / "ablations"
    argv = "ablations --scenarios 2 --trials 6 --steps 30 --workers 1 --no-figures --quiet".split()
    code = cli_main([*argv, "--out", str(out)])
    assert code == 0
    result = json.loads((out / "ablations.json").read_text())
    entry = result["paper-2-v1"]
    assert set(entry["asr"]) == {"paper", *(k for k in ablations.VARIANTS if k.startswith("mg-crb-cl"))}
    # each variant ran on the paper study's trials: its paired difference is the difference of
    # the two runs' per-trial match rates
    paper = np.load(next((out / "paper-2-v1" / "paper").glob("shards/mg-crb-cl/*.npz")))["trial_matches"]
    for label in entry["asr"]:
        if label == "paper":
            continue
        folder = out / "paper-2-v1" / ablations.slug(label)
        variant = np.load(next(folder.glob("shards/mg-crb-cl/*.npz")))["trial_matches"]
        assert entry["asr"][label]["asr_minus_paper"]["estimate"] == pytest.approx(
            variant.mean() - paper.mean()
        )
    assert "maneuver" not in entry and "rmse_windows" not in entry  # 30 steps reach neither window
