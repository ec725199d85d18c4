"""``mimo-radar-bench compile``: every kernel a run can call is compiled up front, for the
argument types a run passes, so that a run after it compiles nothing."""

import importlib.util
import os
import subprocess
import sys

import pytest

from benchmarks import precompile
from benchmarks.cli import main
from benchmarks.errors import BenchError
from benchmarks.harness import PAPER_POLICIES, make_config, run_kernels
from mimo_radar_env import VERSIONS
from mimo_radar_env.core.compiled import CHUNK, HAVE_NUMBA

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed")

QUIET = dict(say=lambda message: None)


@pytest.mark.parametrize("fusion", ["average", "centralized"])
@pytest.mark.parametrize("threads", [1, 2])
def test_the_compiled_kernels_include_every_kernel_a_run_lists(fusion, threads):
    v1 = VERSIONS["v1"]
    policies = [*PAPER_POLICIES, "best-tracking", "tracking-ucb"]
    config = make_config("paper-2-v1", policies, 2, 3, options=v1.options(fusion=fusion), **QUIET)
    listed = run_kernels(config, threads)
    assert listed and set(listed) <= set(precompile.all_kernels())
    names = {kernel.__name__ for kernel in listed}
    assert {"initial_positions", "posterior_values"} <= names
    assert ("run_numba_serial" if threads == 1 else "run_numba") in names


def test_every_compiled_kernel_is_one_a_run_can_list():
    v1 = VERSIONS["v1"]
    listed = []
    for fusion in ("average", "centralized"):
        for trials in (2, CHUNK + 1):  # one chunk of trials, and more than one (the twins over threads)
            config = make_config(
                "paper-1-v1",
                ["mg-crb-cl", "best-tracking"],
                trials,
                3,
                options=v1.options(fusion=fusion),
                **QUIET,
            )
            listed += run_kernels(config, 1) + run_kernels(config, 2)
    assert set(precompile.all_kernels()) == set(listed)
    assert len(precompile.all_kernels()) == len(set(precompile.all_kernels()))


def test_compile_fails_naming_a_kernel_its_workloads_left_uncached(tmp_path, monkeypatch):
    source = tmp_path / "kernel_never_called.py"
    source.write_text("import numba\n\n@numba.njit(cache=True)\ndef never_called(x):\n    return x\n")
    spec = importlib.util.spec_from_file_location("kernel_never_called", source)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "kernel_never_called", module)
    spec.loader.exec_module(module)
    monkeypatch.setattr(precompile, "WORKLOADS", {})
    monkeypatch.setattr(precompile, "all_kernels", lambda: [module.never_called])
    with pytest.raises(BenchError, match="still not cached: never_called"):
        list(precompile.precompile(workers=1))


def test_compile_without_numba_is_one_line_naming_the_extra(monkeypatch, capsys):
    monkeypatch.setattr(precompile, "HAVE_NUMBA", False)
    monkeypatch.setattr("mimo_radar_env.core.compiled.HAVE_NUMBA", False)
    with pytest.raises(SystemExit) as exit_:
        main(["compile"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "numba is not installed" in err[0] and "[fast]" in err[0]


GYM_EPISODES = """
import gymnasium as gym
import mimo_radar_env
for version, fusion in [("v0", "average"), ("v1", "average"), ("v1", "centralized")]:
    env = gym.make(f"MimoRadarSelect-{version}", fusion=fusion)
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.action_space.sample())
"""


def _bench(args, cache):
    return subprocess.run(
        [sys.executable, "-m", "benchmarks", *args],
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
        capture_output=True,
        text=True,
        check=True,
    ).stdout


def _cache_files(cache):
    return {p.relative_to(cache): p.stat().st_mtime_ns for p in cache.rglob("*") if p.is_file()}


@pytest.mark.slow
def test_after_compile_no_run_compiles_anything(tmp_path):
    cache = tmp_path / "cache"
    out = _bench(["compile", "--workers", "2"], cache)
    assert "kernels compiled and cached" in out
    before = _cache_files(cache)
    assert before
    runs = [  # a harness worker's kernels, a one-process run's, both fusions, the tracking search,
        # one-trial tasks
        ["paper", "--scenario", "1", "--trials", "2", "--steps", "2", "--workers", "2"],
        ["run", "--scenario", "paper-3-v1", "--policies", "best-tracking,mg-crb-cl", "--trials", "2",
         "--steps", "2", "--workers", "1", "--fusion", "centralized"],
        ["run", "--scenario", "paper-2-v1", "--policies", "best-tracking,tracking-ucb,plan-tracking",
         "--trials", "1", "--steps", "2", "--workers", "2"],
    ]  # fmt: skip
    for number, args in enumerate(runs):
        _bench([*args, "--quiet", "--no-figures", "--out", str(tmp_path / f"run{number}")], cache)
    subprocess.run(  # one-trial envs through Gymnasium, both versions and fusions
        [sys.executable, "-W", "ignore", "-c", GYM_EPISODES],
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
        check=True,
    )
    assert _cache_files(cache) == before  # no kernel compiled, no cache index rewritten
    assert "cached already: nothing to compile" in _bench(["compile"], cache)
