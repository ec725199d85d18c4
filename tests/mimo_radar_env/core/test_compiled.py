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
