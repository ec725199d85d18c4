"""The fork server the local workers come from: what it imports and loads before it forks one."""

import os
import subprocess
import sys

import pytest

from benchmarks import backends
from mimo_radar_env.core import compiled


@pytest.mark.skipif(not isinstance(backends._CONTEXT, backends._ForkServerContext), reason="spawned workers")
def test_workers_are_forked_from_a_server_that_imported_and_loaded_what_a_task_needs():
    """The local workers come from the fork server, not from this process, and start with the
    project imported and, with numba, the one-thread kernels its cache holds loaded (here BPSO's,
    cached first): their first task imports and loads none of it again."""
    from multiprocessing import forkserver

    from tests.benchmarks import worker_probe

    if compiled.HAVE_NUMBA:
        from benchmarks import precompile

        precompile._bpso(1)  # cached (compiled at most once), before the server starts
    forkserver._forkserver._stop()
    backends.start_fork_server()
    results = {}
    modules = ("benchmarks.harness", "agents.solvers._bpso_kernels", "mimo_radar_env.tracking.imm_ukf")
    backends.run_processes(
        worker_probe.imported, [modules] * 2, results.__setitem__, workers=2, share_tail=False
    )
    assert [r["imported"] for r in results.values()] == [[True] * len(modules)] * 2
    parents = {r["parent"] for r in results.values()}
    assert len(parents) == 1 and os.getpid() not in parents
    if compiled.HAVE_NUMBA:
        loaded = {}
        task = ("agents.solvers._bpso_kernels", "run_numba_serial")
        backends.run_processes(worker_probe.overloads, [task], loaded.__setitem__, workers=2)
        assert loaded == {0: 1}


@pytest.mark.skipif(not isinstance(backends._CONTEXT, backends._ForkServerContext), reason="spawned workers")
def test_a_server_started_for_a_device_run_imported_torch_and_no_other_did():
    """Workers whose tasks run on a device start with torch imported (seconds, paid once in the
    server); a server started for numpy runs leaves torch out."""
    pytest.importorskip("torch")
    from multiprocessing import forkserver

    from tests.benchmarks import worker_probe

    try:
        for device in (False, True):
            forkserver._forkserver._stop()
            backends.start_fork_server(device=device)
            results = {}
            backends.run_processes(worker_probe.imported, [("torch",)], results.__setitem__, workers=2)
            assert results[0]["imported"] == [device]
    finally:
        forkserver._forkserver._stop()


@pytest.mark.skipif(not isinstance(backends._CONTEXT, backends._ForkServerContext), reason="spawned workers")
def test_a_forked_worker_has_one_blas_thread_as_a_spawned_one_has():
    """numpy loads its BLAS in the fork server, before a worker could set its own thread count:
    the server starts with one BLAS thread in its environment, and this process's environment is
    left as it was."""
    pytest.importorskip("threadpoolctl", reason="reads the BLAS libraries' thread counts")
    from multiprocessing import forkserver

    from tests.benchmarks import worker_probe

    before = {name: os.environ.get(name) for name in backends.ONE_BLAS_THREAD}
    forkserver._forkserver._stop()
    backends.start_fork_server()
    assert {name: os.environ.get(name) for name in backends.ONE_BLAS_THREAD} == before
    counts = {}
    backends.run_processes(worker_probe.blas_threads, [()] * 2, counts.__setitem__, workers=2)
    assert [set(c) for c in counts.values()] == [{1}, {1}]


def test_what_the_fork_server_imports_starts_no_thread():
    """Processes are forked from the server: importing its preload (loading the cached kernels
    included) leaves it with one thread and numba's thread pool not started."""
    probe = (
        "import threading, benchmarks.fork_server\n"
        "from mimo_radar_env.core.compiled import HAVE_NUMBA\n"
        "started = False\n"
        "if HAVE_NUMBA:\n"
        "    from numba.np.ufunc import parallel\n"
        "    started = parallel._is_initialized\n"
        "print(threading.active_count(), started)\n"
    )
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert result.stdout.split() == ["1", "False"]
