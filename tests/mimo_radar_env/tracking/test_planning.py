"""The receding-horizon planner: the searches against the exhaustive optimum, the exhaustive search
against every plan scored on its own, the forecast, and the later steps' fast criterion."""

import numpy as np
import pytest

import agents
from benchmarks.docs_tooling.model_figures import plan_instances
from mimo_radar_env import MimoRadarSelectVectorEnv, random_scenario
from mimo_radar_env.tracking.planning import Planner, plan_cost, posterior_covariance, sequences, smallest


@pytest.mark.parametrize("fusion", ["centralized", "average"])
def test_the_exhaustive_search_is_the_best_of_every_plan_scored_alone(fusion):
    scenario = random_scenario(3, 3, 2, 1, 2, horizon=10, seed=4)
    env = MimoRadarSelectVectorEnv(num_envs=5, scenario=scenario, fusion=fusion)
    env.reset(seed=1)
    for _ in range(3):
        env.step(env.tracking_oracle_action())
    forecast = env.tracking_forecast(3)
    planner = Planner(3, 3, 1, 2, search="exhaustive", fusion=fusion)
    plans, cost = planner.plan(forecast)
    every = np.ascontiguousarray(np.broadcast_to(sequences(planner.arms, 3), (5, planner.arms**3, 3)))
    scored = plan_cost(planner, forecast, every)  # each of the 729 plans on its own
    np.testing.assert_allclose(cost, scored.min(axis=1), rtol=1e-12)
    np.testing.assert_allclose(plan_cost(planner, forecast, plans[:, None])[:, 0], cost, rtol=1e-12)


@pytest.mark.parametrize("fusion", ["centralized", "average"])
def test_beam_and_rollout_find_the_exhaustive_optimum_of_small_instances(fusion):
    """At about the rates docs/agents.md quotes (model-figures measures them on more instances);
    never below the optimum, and within a few per mille of it when they miss."""
    costs = plan_instances(fusion, layouts=3, steps=8, trials=8)
    best = costs["exhaustive"]
    for search, least in (("beam", 0.75), ("rollout", 0.65), ("mcts", 0.3)):
        assert (costs[search] >= best * (1 - 1e-12)).all()
        found = np.mean(costs[search] <= best * (1 + 1e-9))
        assert found >= least, (search, found)


def test_the_posterior_of_a_plan_step_is_the_fusions():
    """Centralised: the channels' information adds to the prior's; average (eq22): the
    channels' posteriors are averaged; checked against the formulas written out."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(2, 1, 4, 4))
    prior = a @ np.swapaxes(a, -1, -2) + 4 * np.eye(4)
    h = rng.normal(size=(2, 1, 2, 2, 2, 2))
    info = h @ np.swapaxes(h, -1, -2)  # (S, K, M=2, N=2, 2, 2)
    tx, rx = np.array([[True, False], [True, True]]), np.array([[True, True], [False, True]])
    E = np.zeros((2, 4))
    E[0, 0] = E[1, 2] = 1.0
    for s in range(2):
        channels = [(m, n) for m in range(2) for n in range(2) if tx[s, m] and rx[s, n]]
        J = np.linalg.inv(prior[s, 0])
        central = np.linalg.inv(J + sum(E.T @ info[s, 0, m, n] @ E for m, n in channels))
        average = np.mean([np.linalg.inv(J + E.T @ info[s, 0, m, n] @ E) for m, n in channels], axis=0)
        np.testing.assert_allclose(posterior_covariance(prior, info, tx, rx, "centralized")[s, 0], central)
        np.testing.assert_allclose(posterior_covariance(prior, info, tx, rx, "average")[s, 0], average)


def test_the_forecast_reads_the_truth_the_env_will_reach():
    env = MimoRadarSelectVectorEnv(num_envs=3, scenario="paper-2-v1")
    env.reset(seed=5)
    env.step(env.oracle_action())
    future = env.engine.simulation.future_states(4)
    reached = []
    for _ in range(4):
        env.step(env.oracle_action())
        reached.append(env.engine.simulation.state.copy())
    np.testing.assert_array_equal(future, np.stack(reached, axis=1))


# ---------------------------------------------------------------- the offline bound on selection
def _bound_run(env, policy, trials):
    """Run ``policy`` on ``env`` for the episode: its super arms' indices (B, T) and the env's
    PCRB position MSE of each step and target (B, T, K)."""
    from mimo_radar_env.tracking.planning import Planner

    sc = env.scenario
    arms = Planner(sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step, fusion="centralized")
    episode = agents.Rollout(agents.make_agent(policy, sc, seed=0), env, seed=7)
    forecast = env.engine.bound_forecast()
    played, bound = [], []
    for step in episode.run(sc.horizon):
        tx, rx = step.action[:, : sc.num_tx].astype(bool), step.action[:, sc.num_tx :].astype(bool)
        match = (arms.tx_masks[None] == tx[:, None]).all(-1) & (arms.rx_masks[None] == rx[:, None]).all(-1)
        played.append(np.argmax(match, axis=1))
        bound.append(step.info["position_bound"] ** 2)
    return forecast, arms, np.stack(played, axis=1), np.stack(bound, axis=1)


@pytest.mark.parametrize("policy", ["random", "best-tracking", "ucb1"])
def test_the_best_achievable_bound_is_at_most_every_policys_own(policy):
    from mimo_radar_env.tracking.planning import best_achievable_bound, position_traces

    scenario = random_scenario(3, 3, 2, 1, 2, horizon=12, seed=3)
    env = MimoRadarSelectVectorEnv(num_envs=4, scenario=scenario)
    forecast, arms, played, bound = _bound_run(env, policy, trials=4)
    # the forecast's recursion is the env's PCRB: the policy's own sequence scored offline
    np.testing.assert_allclose(position_traces(arms, forecast, played), bound, rtol=1e-9)
    best, plan = best_achievable_bound(forecast, 3, 3, 1, 2, width=10)
    weights = np.asarray(scenario.weights)
    own = (bound.mean(axis=1) * weights).sum(axis=1)
    offline = (best**2 * weights).sum(axis=1)
    assert (offline <= own * (1 + 1e-9)).all(), (offline, own)
    assert plan.shape == (4, 12)


@pytest.mark.parametrize("fusion", ["centralized", "average"])
@pytest.mark.parametrize("criterion", ["trace", "logdet"])
def test_later_steps_score_as_the_myopic_criterion_to_rounding(fusion, criterion):
    env = MimoRadarSelectVectorEnv(num_envs=6, scenario="paper-3-v1", fusion=fusion)
    env.reset(seed=3)
    for _ in range(4):
        env.step(env.tracking_oracle_action())
    forecast = env.tracking_forecast(2)
    planner = Planner(4, 6, 2, 3, criterion=criterion, fusion=fusion)
    exact = planner._costs(forecast.covariance, forecast.information[:, 1], forecast.weights, first=True)
    fast = planner._costs(forecast.covariance, forecast.information[:, 1], forecast.weights, first=False)
    np.testing.assert_allclose(fast, exact, rtol=1e-10, atol=1e-12)


def test_the_beams_selection_is_a_stable_sort_found_by_partition():
    """``smallest`` keeps the plans a stable argsort would, ties included (many ties: integers)."""
    rng = np.random.default_rng(0)
    for t in range(500):
        rows, n = rng.integers(1, 5), rng.integers(1, 40)
        keep = int(rng.integers(1, n + 3))
        values = rng.integers(0, 5, size=(rows, n)).astype(float) if t % 2 else rng.normal(size=(rows, n))
        expected = np.argsort(values, axis=1, kind="stable")[:, :keep]
        np.testing.assert_array_equal(smallest(values, keep), expected)
