"""Each policy's declared cost: its memory bounds what a step allocates, its operations follow the work."""

import tracemalloc

import numpy as np
import pytest

import agents
from mimo_radar_env import load_scenario, random_scenario
from mimo_radar_env.core.compiled import HAVE_NUMBA
from mimo_radar_env.envs.cost import memory_parts
from tests.helpers import vector_env


@pytest.mark.parametrize(
    "policy",
    # plan-tracking enumerates super arms: too many at 24 x 24 (its memory: the next test)
    [
        p
        for p in agents.available_agents()
        if p not in ("fixed", "fix1", "fix2", *agents.learned_agents()) and not p.startswith("plan-")
    ],
)
def test_declared_memory_bounds_what_a_step_allocates(policy):
    """The declared memory per trial is an upper estimate of what one step of the policy
    allocates (tracemalloc), on a layout where the tracking search is greedy."""

    scenario = random_scenario(24, 24, 2, 4, 4, horizon=5, seed=0)
    trials = 3
    params = {"solver": "alternating"} if issubclass(agents.agent_class(policy), agents.IndexPolicy) else {}
    agent = agents.make_agent(policy, scenario, seed=0, **params)
    env = vector_env(
        "MimoRadarSelect-v1",
        trials,
        scenario=scenario,
        oracle_solver="alternating",
        **agent.needs.observation_options,
    )
    episode = agents.Rollout(agent, env, seed=0)
    episode.step()  # warm-up: first-call caches, imports and compilation
    tracemalloc.start()
    try:
        step = episode.step()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    _, env_per_trial = memory_parts(scenario)
    declared = trials * (agents.costs.memory_per_trial(agent) + env_per_trial)
    assert peak <= declared, (
        f"{policy}: {peak / 2**20:.1f} MiB allocated, {declared / 2**20:.1f} MiB declared"
    )
    assert np.isfinite(step.reward).all()


def test_declared_operations_follow_the_work():
    scenario = random_scenario(16, 16, 2, 4, 4, horizon=5, seed=0)
    small = agents.make_agent("mg-crb-cl", scenario, solver="bpso", solver_params={"population": 10})
    large = agents.make_agent("mg-crb-cl", scenario, solver="bpso", solver_params={"population": 20})
    base = agents.costs.BOOKKEEPING.operations_per_trial_step(small)
    assert agents.costs.operations_per_trial_step(large) - base == pytest.approx(
        2 * (agents.costs.operations_per_trial_step(small) - base)
    )
    # the tracking search: enumerated at 4 x 6, greedy at 64 x 64, more work for more targets
    costs = {
        (m, k): agents.costs.operations_per_trial_step(
            agents.make_agent("best-tracking", random_scenario(m, m, k, 4, 4, horizon=5, seed=0))
        )
        for m in (8, 64)
        for k in (1, 5)
    }
    assert costs[8, 1] < costs[8, 5] and costs[64, 1] < costs[64, 5] and costs[8, 5] < costs[64, 5]


@pytest.mark.parametrize("search", ["beam", "rollout", "mcts"])
def test_the_planners_declared_memory_bounds_what_a_step_allocates(search):

    trials = 3
    agent = agents.make_agent("plan-tracking", "paper-1-v1", seed=0, horizon=3, search=search)
    env = vector_env("MimoRadarSelect-v1", trials)
    agent.attach(env)
    learner = agents.make_agent("plan-tracking-ucb", "paper-1-v1", horizon=3, search=search)
    assert agents.costs.memory_per_trial(learner) >= agents.costs.memory_per_trial(
        agent
    )  # the same plans, and its estimates
    obs, _ = env.reset(seed=0)
    agent.reset(obs)
    obs, *_ = env.step(agent.act(obs))  # warm-up: first-call caches and imports
    tracemalloc.start()
    try:
        action = agent.act(obs)
        obs, reward, *_ = env.step(action)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    _, env_per_trial = memory_parts(load_scenario("paper-1-v1"))
    assert peak <= trials * (agents.costs.memory_per_trial(agent) + env_per_trial)


def test_each_parts_time_is_its_operations_at_its_own_rate():
    from agents.costs import BOOKKEEPING, ORACLE_SEARCH, SOLVER, TRACKING_SEARCH
    from mimo_radar_env.core.superarm import SEARCH_SECONDS_PER_OPERATION, search_operations

    scenario = random_scenario(16, 16, 2, 4, 4, horizon=5, seed=0)
    ucb = agents.make_agent("ucb1", scenario)  # the exact solver
    by_hand = (
        BOOKKEEPING.operations_per_trial_step(ucb) * BOOKKEEPING.seconds_per_operation
        + ucb.solver.operations_per_trial(16, 16) * SEARCH_SECONDS_PER_OPERATION["exact"]
    )
    assert agents.costs.seconds_per_trial_step(ucb) == pytest.approx(by_hand, rel=1e-12)
    assert (
        SOLVER.seconds_per_trial_step(ucb) / SOLVER.operations_per_trial_step(ucb)
        == (SEARCH_SECONDS_PER_OPERATION["exact"])
    )
    alternating = agents.make_agent("ucb1", scenario, solver="alternating")
    assert SOLVER.seconds_per_trial_step(alternating) == pytest.approx(
        alternating.solver.operations_per_trial(16, 16) * SEARCH_SECONDS_PER_OPERATION["alternating"]
    )
    best = agents.make_agent("best", scenario)  # the oracle's search: exact at 16 x 16 with 4 of each
    assert ORACLE_SEARCH.seconds_per_trial_step(best) == pytest.approx(
        search_operations(16, 16, 4, 4) * SEARCH_SECONDS_PER_OPERATION["exact"]
    )
    tracking = agents.make_agent("best-tracking", scenario)
    assert TRACKING_SEARCH.seconds_per_trial_step(tracking) == pytest.approx(
        TRACKING_SEARCH.operations_per_trial_step(tracking) * TRACKING_SEARCH.seconds_per_operation
    )


def test_the_threaded_part_is_the_parts_whose_compiled_kernels_spread_trials_over_threads():
    from agents.costs import SOLVER, TRACKING_SEARCH, threaded_seconds_per_trial_step

    scenario = load_scenario("paper-1-v1")
    assert threaded_seconds_per_trial_step(agents.make_agent("ucb1", scenario)) == 0.0  # the exact solver
    bpso = agents.make_agent("mg-crb-cl", scenario)
    numpy_bpso = agents.make_agent("mg-crb-cl", scenario, solver_params={"use_numba": False})
    assert threaded_seconds_per_trial_step(numpy_bpso) == 0.0
    tracking = agents.make_agent("best-tracking", scenario)
    if not HAVE_NUMBA:  # no compiled kernels: nothing spreads a task's trials over threads
        assert threaded_seconds_per_trial_step(bpso) == threaded_seconds_per_trial_step(tracking) == 0.0
        return
    assert threaded_seconds_per_trial_step(bpso) == SOLVER.seconds_per_trial_step(bpso) > 0
    assert threaded_seconds_per_trial_step(tracking) == TRACKING_SEARCH.seconds_per_trial_step(tracking) > 0
    assert threaded_seconds_per_trial_step(tracking) < agents.costs.seconds_per_trial_step(tracking)
