"""Which numba kernels a run would compile first: the cache check and the kernels of a run."""

import importlib.util
import os
import sys

import pytest

from benchmarks.settings import paper_study_params
from mimo_radar_env.core.compiled import HAVE_NUMBA, uncached

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed")

KERNEL = """
import numba

@numba.njit(cache=True)
def doubled(x):
    return 2 * x
"""


def _kernel_module(tmp_path, monkeypatch, name: str):
    """KERNEL as module ``name`` in ``tmp_path`` (its numba cache beside it), and its spec."""
    source = tmp_path / f"{name}.py"
    source.write_text(KERNEL)
    spec = importlib.util.spec_from_file_location(name, source)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, name, module)
    spec.loader.exec_module(module)
    return module, spec


def test_a_kernel_is_uncached_until_its_first_call_writes_the_cache(tmp_path, monkeypatch):
    module, _ = _kernel_module(tmp_path, monkeypatch, "kernel_for_cache_test")
    assert uncached([module.doubled]) == ["doubled"]
    assert module.doubled(3) == 6
    assert uncached([module.doubled]) == []
    assert uncached([object()]) == []  # not a numba kernel: nothing claimed


def test_a_damaged_cache_index_is_found_removed_and_compiled_anew(tmp_path, monkeypatch):
    """Random bytes over a kernel's cache index made every call fail inside numba's
    ``_load_index``; the check finds it, removes it, and the next call compiles and caches."""
    from mimo_radar_env.core.compiled import repair_cache

    module, spec = _kernel_module(tmp_path, monkeypatch, "kernel_for_damage_test")
    assert module.doubled(3) == 6 and uncached([module.doubled]) == []
    index = module.doubled._cache._cache_file._index_path
    with open(index, "wb") as file:
        file.write(bytes(range(200, 256)))  # not a pickle
    assert repair_cache(module.doubled) and not os.path.exists(index)
    with open(index, "wb") as file:
        file.write(bytes(range(200, 256)))
    assert uncached([module.doubled]) == ["doubled"]  # compile would now compile it
    fresh = importlib.util.module_from_spec(spec)  # a new process's view: loads from the cache
    spec.loader.exec_module(fresh)
    assert fresh.doubled(4) == 8 and uncached([fresh.doubled]) == []


def test_cached_machine_code_is_loaded_without_a_call_and_a_changed_source_is_left(tmp_path, monkeypatch):
    """``load_cached`` gives a fresh module's kernel the overload its cache holds (a cache hit, no
    compilation, no call, no numba threads); for a kernel whose source changed since, the cache
    holds nothing current, and nothing is compiled."""
    from numba.np.ufunc import parallel

    from mimo_radar_env.core.compiled import load_cached

    module, spec = _kernel_module(tmp_path, monkeypatch, "kernel_for_load_test")
    assert module.doubled(3) == 6  # writes the cache
    fresh = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fresh)
    assert fresh.doubled.overloads == {}
    load_cached([fresh.doubled, object()])  # not a numba kernel: left alone
    assert len(fresh.doubled.overloads) == 1
    assert sum(fresh.doubled.stats.cache_hits.values()) == 1
    assert sum(fresh.doubled.stats.cache_misses.values()) == 0
    threads_started = parallel._is_initialized
    source = tmp_path / "kernel_for_load_test.py"
    source.write_text(KERNEL.replace("2 * x", "3 * x"))
    changed = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(changed)
    load_cached([changed.doubled])
    assert changed.doubled.overloads == {} and not changed.doubled.stats.cache_misses
    assert changed.doubled(3) == 9
    assert parallel._is_initialized == threads_started  # loading started none


def test_a_run_lists_its_fusion_bound_and_solver_kernels():
    from agents.solvers import _bpso_kernels
    from benchmarks.harness import PAPER_POLICIES, make_config, run_kernels
    from mimo_radar_env import VERSIONS
    from mimo_radar_env.tracking import bound
    from mimo_radar_env.tracking.fusion import average, centralized

    v1 = VERSIONS["v1"]
    quiet = dict(say=lambda message: None)
    paper = make_config(
        "paper-1-v1",
        PAPER_POLICIES,
        2,
        3,
        options=v1.options(),
        agent_params=paper_study_params("v1"),
        **quiet,
    )
    assert run_kernels(paper, threads=1) == [
        average._update_numba,
        bound._compiled_step,
        _bpso_kernels.initial_positions,
        _bpso_kernels.run_numba_serial,
    ]
    assert run_kernels(paper, threads=2)[-1] is _bpso_kernels.run_numba
    exact = make_config(
        "paper-1-v1",
        PAPER_POLICIES,
        2,
        3,
        options=v1.options(fusion="centralized"),
        agent_params={"mg-crb-cl": {"solver": "exact"}},
        **quiet,
    )
    assert run_kernels(exact) == [centralized._update_numba, bound._compiled_step]
    untracked = make_config("paper-1-v1", ["ucb1"], 2, 3, options=v1.options(tracking=False), **quiet)
    assert run_kernels(untracked) == []


# ------------------------------------------------------------------ kernels over threads
@pytest.fixture
def two_threads():
    """numba's threads set to 2 for the test (the kernels' twins over threads are taken)."""
    from mimo_radar_env.core import compiled

    with compiled.with_threads(2):
        yield


def _episode(fusion: str, trials: int, steps: int = 4):
    """Every observation and info of a tracked v1 episode under random super arms, stepped by
    tracking-ucb (so the tracking search runs too)."""
    import numpy as np

    import agents
    from mimo_radar_env import VERSIONS

    agent = agents.make_agent("tracking-ucb", "paper-1-v1", seed=0, fusion=fusion)
    env = agents.make_env(agent, trials, VERSIONS["v1"].options(fusion=fusion).to_dict(), "paper-1-v1")
    out = []
    for step in agents.Rollout(agent, env, seed=3).run(steps):
        out.append({key: np.asarray(value).copy() for key, value in step.info.items()})
        out[-1]["action"] = np.asarray(step.action).copy()
    return out


@pytest.mark.parametrize("fusion", ["average", "centralized"])
def test_an_episode_over_two_threads_gives_the_numbers_of_one_thread_bit_for_bit(fusion):
    import numpy as np

    from mimo_radar_env.core import compiled

    trials = 2 * compiled.CHUNK + 5  # three chunks, the last one partial
    with compiled.with_threads(1):
        serial = _episode(fusion, trials)
    with compiled.with_threads(2):
        threaded = _episode(fusion, trials)
    for one, two in zip(serial, threaded, strict=True):
        assert one.keys() == two.keys()
        for key in one:
            assert np.array_equal(one[key], two[key], equal_nan=True), key


def test_a_batch_takes_the_threaded_twin_only_with_threads_and_more_than_one_chunk(two_threads):
    from mimo_radar_env.core import compiled
    from mimo_radar_env.tracking.fusion import average

    kernels = average._KERNELS
    assert kernels.for_batch("_update_numba", compiled.CHUNK + 1) is average._update_numba_threaded
    assert kernels.for_batch("_update_numba", compiled.CHUNK) is average._update_numba
    compiled.set_threads(1)
    assert kernels.for_batch("_update_numba", 10 * compiled.CHUNK) is average._update_numba
    assert average._update_numba.py_func.__qualname__ != average._update_numba_threaded.py_func.__qualname__


@pytest.mark.parametrize("bad_trial", [3, 100, 139])
def test_the_bound_over_threads_says_unhealthy_wherever_the_failing_trial_is(two_threads, bad_trial):
    import numpy as np

    from mimo_radar_env.tracking import bound

    rng = np.random.default_rng(0)
    trials = 140
    root = rng.normal(size=(trials, 2, 4, 4))
    covariance = root @ np.swapaxes(root, -1, -2) + 4 * np.eye(4)
    transition = np.stack([np.eye(4)] * 2)
    process = 0.1 * np.eye(4)
    measured = np.stack([np.eye(2)] * 2)[None].repeat(trials, axis=0)
    args = (covariance, transition, process, measured, bound.MAX_CONDITION)
    serial, healthy = bound._compiled_step(*args)
    threaded, healthy_threaded = bound._compiled_step_threaded(*args)
    assert healthy and healthy_threaded and np.array_equal(serial, threaded)
    covariance[bad_trial, 1] = -np.eye(4)  # not a covariance: its prediction fails the check
    assert not bound._compiled_step(*args)[1]
    assert not bound._compiled_step_threaded(*args)[1]
