"""An env's declared cost: its memory bounds what it allocates, its operations follow the work, and an
env larger than the machine is refused before it allocates."""

import tracemalloc

import numpy as np
import pytest

from mimo_radar_env import random_scenario
from mimo_radar_env.core.superarm import random_super_arms
from mimo_radar_env.envs import cost
from tests.helpers import vector_env


def test_declared_operations_grow_with_the_fusions_work_and_the_layout():
    scenario = random_scenario(16, 16, 2, 4, 4, horizon=5, seed=0)
    assert (
        cost.operations_per_trial_step(scenario, True, "centralized")
        > cost.operations_per_trial_step(scenario, True, "average")
        > cost.operations_per_trial_step(scenario, False)
    )
    more_targets = random_scenario(16, 16, 4, 4, 4, horizon=5, seed=0)
    assert cost.operations_per_trial_step(more_targets) > cost.operations_per_trial_step(scenario)


@pytest.mark.parametrize("fusion", ["average", "centralized"])
def test_the_declared_memory_bounds_what_the_env_allocates(fusion):
    scenario = random_scenario(12, 12, 3, 3, 4, horizon=6, seed=0)
    trials = 16
    model, per_trial = cost.memory_parts(scenario)
    assert cost.memory_estimate(scenario, trials) == model + trials * per_trial
    rng = np.random.default_rng(0)
    actions = random_super_arms(rng, trials, 12, 12, 3, 4)
    warm = vector_env("MimoRadarSelect-v1", trials, scenario=scenario, fusion=fusion)
    warm.reset(seed=1)
    warm.step(actions)  # imports, first-call caches and compilation, outside the count
    tracemalloc.start()
    try:
        env = vector_env("MimoRadarSelect-v1", trials, scenario=scenario, fusion=fusion)
        env.reset(seed=0)
        env.step(actions)
        env.step(actions)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= cost.memory_estimate(scenario, trials)


def test_an_env_larger_than_the_machine_is_refused_in_one_line(monkeypatch):
    scenario = random_scenario(8, 8, 2, 2, 2, horizon=5, seed=0)
    need = cost.memory_estimate(scenario, 1000)
    monkeypatch.setattr(cost, "machine_memory", lambda: need)  # half of it is allowed
    cost.check_memory(scenario, 400)
    with pytest.raises(ValueError) as error:
        cost.check_memory(scenario, 1000)
    message = str(error.value)
    assert "\n" not in message and message.startswith("1000 trials of scenario")
    assert "use fewer trials, a shorter horizon or a smaller layout" in message


def test_an_envs_time_per_trial_step_is_each_part_at_its_rate():
    from mimo_radar_env.core.superarm import SEARCH_SECONDS_PER_OPERATION

    for size, method in ((8, "exact"), (64, "alternating")):
        scenario = random_scenario(size, size, 3, 4, 4, horizon=5, seed=0)
        parts = cost.operation_parts(scenario, True, "centralized")
        assert sum(parts.values()) == cost.operations_per_trial_step(scenario, True, "centralized")
        by_hand = (
            parts["channels"] * cost.SECONDS_PER_OPERATION["channels"]
            + parts["search"] * SEARCH_SECONDS_PER_OPERATION[method]
            + parts["tracker"] * cost.SECONDS_PER_OPERATION["tracker"]
        )
        assert cost.seconds_per_trial_step(scenario, True, "centralized") == pytest.approx(by_hand, rel=1e-12)
    assert cost.operation_parts(scenario, False)["tracker"] == 0


def test_the_threaded_part_of_a_step_is_the_compiled_updates_operations_at_their_rate():
    from mimo_radar_env.core.compiled import HAVE_NUMBA
    from mimo_radar_env.tracking.fusion.base import CHANNEL_OPERATIONS, MODELS

    scenario = random_scenario(8, 8, 3, 2, 3, horizon=5, seed=0)
    average = 3 * MODELS * 6 * (CHANNEL_OPERATIONS + 300)  # K models' updates of Ms Ns = 6 channels each
    expected = cost.COMPILED_UPDATE_SECONDS_PER_OPERATION * average if HAVE_NUMBA else 0.0
    assert cost.threaded_seconds_per_trial_step(scenario, True, "average") == pytest.approx(
        expected, rel=1e-12
    )
    for fusion in ("average", "centralized"):
        share = cost.threaded_seconds_per_trial_step(scenario, True, fusion)
        assert 0 < share < cost.seconds_per_trial_step(scenario, True, fusion) or not HAVE_NUMBA
        assert cost.threaded_seconds_per_trial_step(scenario, False, fusion) == 0.0
    # 4 x 8 channels stack a 64-dimensional measurement: the centralised update stays in numpy
    wide = random_scenario(8, 8, 3, 4, 8, horizon=5, seed=0)
    assert cost.threaded_seconds_per_trial_step(wide, True, "centralized") == 0.0
