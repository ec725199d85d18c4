"""Where a run's tasks execute: in the calling process, in local worker processes, or on Ray.

A task is ``(payload, policy, shard)``: the run's configuration travels with each task, so one
call can mix the tasks of several runs (a study's). They are started in the order given. Every
backend hands each finished task to ``finished`` (with its position in the list) as soon as
it is done, so the harness saves it at once. Ctrl-C (``KeyboardInterrupt``) stops a run
within seconds: queued tasks are cancelled, worker processes are terminated, and the
interruption propagates to the caller after every finished task has been saved. Workers
ignore SIGINT (the parent decides) and exit by themselves when their parent dies.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any

#: ``(payload, policy, shard)``: the run's configuration (``RunConfig.to_json()``) and one task.
Task = tuple[dict[str, Any], str, int]
#: Called with a task's position in the list and its result.
Finished = Callable[[int, dict], None]
Runner = Callable[[dict[str, Any], str, int], dict]


def worker_init(parent: int, threads: int = 1) -> None:
    """Worker set-up: ``threads`` compute threads for the compiled kernels, SIGINT left to the
    parent, exit when the parent dies."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    pin_threads(threads)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)  # the parent is gone: nobody will read our results

    threading.Thread(target=watch, daemon=True, name="parent-watch").start()


def pin_threads(threads: int) -> None:
    """This process's compute threads: ``threads`` for numba's kernels, one for BLAS and the
    libraries imported later (torch, for a trained PPO policy, starts one per core by default:
    two workers on two cores ran PPO 3x slower)."""
    for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ[name] = "1"
    from mimo_radar_env.core import compiled

    if compiled.HAVE_NUMBA:
        compiled.set_threads(threads)


def run_inline(runner: Runner, todo: list[Task], finished: Finished) -> None:
    for number, task in enumerate(todo):
        finished(number, runner(*task))


@contextlib.contextmanager
def worker_pool(workers: int, threads: int = 1) -> Iterator[ProcessPoolExecutor]:
    """Spawned worker processes (:func:`worker_init`: ``threads`` compute threads each, exiting
    when this process dies); on an error or an interrupt the running ones are terminated at once,
    their results not wanted."""
    import multiprocessing

    context = multiprocessing.get_context("spawn")  # no inherited threads or state
    pool = ProcessPoolExecutor(
        max_workers=workers, mp_context=context, initializer=worker_init, initargs=(os.getpid(), threads)
    )
    try:
        yield pool
    except BaseException:
        for process in list(getattr(pool, "_processes", {}).values()):
            process.terminate()  # do not wait for running tasks: their results are not wanted
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def run_processes(
    runner: Runner, todo: list[Task], finished: Finished, workers: int, threads: int = 1
) -> None:
    with worker_pool(workers, threads) as pool:
        pending = {pool.submit(runner, *task): number for number, task in enumerate(todo)}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=pending.__getitem__):
                finished(pending.pop(future), future.result())


def check_ray_address(address: str | None, timeout: float = 3.0) -> None:
    """Fail within ``timeout`` seconds, naming the address, when a Ray head cannot be reached.
    ``auto`` is resolved as Ray resolves it (``RAY_ADDRESS``, then the cluster started on this
    machine), so a missing cluster is named before anything is written."""
    if address in (None, "local"):
        return
    if address == "auto":
        address = _resolve_auto_address()
        if address == "auto":
            return
    target = address.split("://", 1)[-1]
    host, _, port = target.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"--address must look like HOST:PORT (or ray://HOST:PORT), got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except OSError as exc:
        raise ValueError(f"cannot reach the Ray cluster at {address!r}: {exc.strerror or exc}") from None


def _resolve_auto_address() -> str:
    """The address ``--address auto`` stands for, or a ``ValueError`` saying no cluster runs."""
    from mimo_radar_env.extras import require

    require("ray", "ray", "--backend ray")
    try:
        from ray._private import services
    except ImportError:  # pragma: no cover - a Ray without the helper: let ray.init resolve it
        return "auto"
    try:
        return str(services.canonicalize_bootstrap_address("auto"))
    except ConnectionError:
        raise ValueError(
            "--address auto: no Ray cluster is running on this machine and RAY_ADDRESS is not set; start "
            "one with 'ray start --head', give its HOST:PORT, or leave --address out to start a local Ray"
        ) from None


def threaded_task(runner: Runner, threads: int, *task: Any) -> dict:
    """``runner(*task)`` on ``threads`` compute threads (a Ray task: its worker process serves
    tasks of any thread count)."""
    pin_threads(threads)
    return runner(*task)


def run_ray(
    runner: Runner, todo: list[Task], finished: Finished, address: str | None, threads: int = 1
) -> None:
    """The tasks on Ray, each reserving ``threads`` CPUs and running on as many threads."""
    from mimo_radar_env.extras import require

    ray = require("ray", "ray", "--backend ray")
    check_ray_address(address)
    started_here = not ray.is_initialized()
    if started_here:
        ray.init(address=address, include_dashboard=False, log_to_driver=False, ignore_reinit_error=True)
    pending: dict[Any, int] = {}
    try:
        remote_task = ray.remote(num_cpus=threads)(threaded_task)
        payloads: dict[int, Any] = {}  # each run's configuration is put in the object store once
        for number, (payload, policy, shard) in enumerate(todo):
            if id(payload) not in payloads:
                payloads[id(payload)] = ray.put(payload)
            pending[remote_task.remote(runner, threads, payloads[id(payload)], policy, shard)] = number
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                finished(pending.pop(ref), ray.get(ref))
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started_here:
            ray.shutdown()
