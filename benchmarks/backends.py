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
import multiprocessing
import multiprocessing.connection
import multiprocessing.util
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any

from .errors import BenchError


class _ExitsAtOnce:
    """A worker that exits at once when its pool tells it to stop: the interpreter's own
    teardown of numpy, numba and the project (about 0.2 s a process) would only delay the pool's
    end. multiprocessing's own clean-up still runs (numba's threads make a named semaphore in a
    forked worker, which would otherwise be reported leaked). A worker that fails exits as any
    process does."""

    def run(self) -> None:
        super().run()  # type: ignore[misc]
        _exit_at_once(0)


def _exit_at_once(code: int) -> None:
    """This worker's end without the interpreter's teardown: multiprocessing's clean-up first
    (the named semaphore numba makes as it starts its threads in a forked worker, which the
    resource tracker would otherwise report leaked), its output flushed. A SIGTERM from here on
    is ignored (an interrupted run's pool sends a second one, from its manager thread, once a
    first worker has ended): its handler, run in the middle of the clean-up, would end the
    process between a semaphore's unlinking and the tracker being told, which then reports it
    leaked."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    multiprocessing.util._run_finalizers(0)
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    os._exit(code)


def _stop(signum: int, frame: Any) -> None:
    """A worker's SIGTERM (:meth:`WorkerPool.terminate`: an interrupted run): out at once, cleanly."""
    _exit_at_once(128 + signum)


class _ForkedWorker(_ExitsAtOnce, multiprocessing.context.ForkServerProcess):
    pass


class _SpawnedWorker(_ExitsAtOnce, multiprocessing.context.SpawnProcess):
    pass


class _ForkServerContext(multiprocessing.context.ForkServerContext):
    Process = _ForkedWorker


class _SpawnContext(multiprocessing.context.SpawnContext):
    Process = _SpawnedWorker


#: What the fork server imports once, before it forks any worker: what every task imports (numpy,
#: the env, the agents, the harness) and the kernels a worker of one thread calls, loaded from
#: numba's cache (:mod:`benchmarks.fork_server`).
FORK_SERVER_PRELOAD = ("benchmarks.fork_server",)
#: What it imports besides for tasks on a device: torch, seconds to import, which starts no thread
#: and touches no device as it imports (each worker initialises its own CUDA, as a fork needs).
DEVICE_PRELOAD = ("torch",)
#: The environment that gives a process one BLAS (and OpenMP) thread: read as the libraries load.
ONE_BLAS_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
#: Workers are forked from a server process that has imported :data:`FORK_SERVER_PRELOAD`, so
#: each starts in milliseconds with nothing of this process inherited (no threads, no state), on
#: Linux, where Python 3.14 makes the fork server its default; elsewhere spawned, each importing
#: it all again (on macOS a fork after some system libraries have loaded is not safe).
_CONTEXT = _ForkServerContext() if sys.platform.startswith("linux") else _SpawnContext()


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS (numpy's matrix products and inverses) held to one thread in this block (or call,
    as a decorator), in the calling thread, as every worker process has it
    (:data:`ONE_BLAS_THREAD`). A product's or an inverse's last bits may depend on how many
    threads share it (numpy 1.26's OpenBLAS 0.3.23 inverts matrices of 8, 9 and 16 rows so), so
    every task and every interval runs on one: the same numbers in this process, in a worker, on
    Ray and on any count of cores; and the statistics a study's parent computes while its
    workers hold the cores start no BLAS thread per core among them. Calls from several threads
    at once may see each other's limit (the harness and the studies make them from one).
    threadpoolctl walks the loaded libraries under the dynamic loader's lock: no other thread
    may be importing an extension module meanwhile (:func:`benchmarks.study.execute` keeps to
    that)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield


def start_fork_server(device: bool = False) -> None:
    """Start the fork server now, where the workers come from one: it imports (and loads) what a
    task needs while this process goes on (parsing, checking and planning a run), so the workers
    a run starts later are forked ready to run. It starts with :data:`ONE_BLAS_THREAD` in its
    environment, read as it imports numpy: each worker then has one BLAS thread, as a spawned one
    has. With ``device``, it imports :data:`DEVICE_PRELOAD` too. Where it runs already, nothing."""
    if not isinstance(_CONTEXT, _ForkServerContext):
        return
    from multiprocessing import forkserver

    _CONTEXT.set_forkserver_preload([*FORK_SERVER_PRELOAD, *(DEVICE_PRELOAD if device else ())])
    saved = {name: os.environ.get(name) for name in ONE_BLAS_THREAD}
    os.environ.update(ONE_BLAS_THREAD)
    try:
        forkserver.ensure_running()
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


#: ``(payload, policy, shard)``: the run's configuration (``RunConfig.to_json()``) and one task.
Task = tuple[dict[str, Any], str, int]
#: Called with a task's position in the list and its result.
Finished = Callable[[int, dict], None]
Runner = Callable[[dict[str, Any], str, int], dict]


#: In a worker of :func:`run_processes`: the threads it starts each task on, the run's shared
#: thread budget (one entry per task, 0 until the parent raises it) and the entry of the task it
#: is running (:func:`follow_thread_budget`).
_BASE_THREADS = 1
_BUDGET: Any = None
_ENTRY: int | None = None


def worker_init(threads: int = 1, budget: Any = None) -> None:
    """Worker set-up: ``threads`` compute threads for the compiled kernels, the run's shared
    thread ``budget``, SIGINT left to the parent, a clean exit on SIGTERM, exit when the parent
    dies."""
    global _BASE_THREADS, _BUDGET
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop)
    pin_threads(threads)
    _BASE_THREADS, _BUDGET = threads, budget

    # the pool's process, not os.getppid(): the parent of a worker forked by the fork server
    sentinel = multiprocessing.parent_process().sentinel

    def watch() -> None:
        multiprocessing.connection.wait([sentinel])  # ready when the pool's process has ended
        os._exit(1)  # nobody will read our results

    threading.Thread(target=watch, daemon=True, name="parent-watch").start()


def pin_threads(threads: int) -> None:
    """This process's compute threads: ``threads`` for numba's kernels, one for BLAS and the
    libraries imported later (torch, for a trained PPO policy, starts one per core by default:
    two workers on two cores ran PPO 3x slower)."""
    os.environ.update(ONE_BLAS_THREAD)
    from mimo_radar_env.core import compiled

    if compiled.HAVE_NUMBA:
        compiled.set_threads(threads)


def budgeted_task(runner: Runner, entry: int, *task: Any) -> dict:
    """``runner(*task)`` in a worker, as task ``entry`` of the run's thread budget: it starts on
    the worker's threads and takes up more where :func:`follow_thread_budget` finds them."""
    global _ENTRY
    from mimo_radar_env.core import compiled

    if compiled.HAVE_NUMBA:
        compiled.set_threads(_BASE_THREADS)
    _ENTRY = entry
    try:
        return runner(*task)
    finally:
        _ENTRY = None


def follow_thread_budget() -> None:
    """Between two steps of a task: take up the threads the parent has given it since (the
    tasks still running at a run's tail share the cores of those that ended). Outside a worker
    of :func:`run_processes`, nothing. The numbers do not depend on the threads."""
    if _BUDGET is None or _ENTRY is None:
        return
    wanted = _BUDGET[_ENTRY]
    from mimo_radar_env.core import compiled

    if wanted > 0 and compiled.HAVE_NUMBA and wanted != compiled.threads():
        compiled.set_threads(wanted)


def share_idle_cores(budget: Any, unfinished: list[int], workers: int, threads: int) -> None:
    """Once fewer tasks are left than workers (every one running: a pool starts them in order),
    their entries of ``budget`` get the ``workers * threads`` cores shared among them, the
    first ones one more where they do not divide; an entry is never lowered."""
    if not unfinished or len(unfinished) >= workers:
        return
    each, extra = divmod(workers * threads, len(unfinished))
    for rank, entry in enumerate(sorted(unfinished)):
        budget[entry] = max(budget[entry], each + (rank < extra))


def run_inline(runner: Runner, todo: list[Task], finished: Finished) -> None:
    """The tasks in this process, one after the other, on one BLAS thread as in a worker."""
    with one_blas_thread():
        for number, task in enumerate(todo):
            finished(number, runner(*task))


class WorkerPool(ProcessPoolExecutor):
    """A process pool whose caller says when it has submitted its last task (:meth:`close`): the
    workers then exit as soon as that task is done, while this process goes on (writing the
    outputs of the last results) rather than after it."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # the workers and the thread that stops them, kept past shutdown(wait=False), which drops
        # the pool's own references
        self.workers: list[Any] = []
        self.manager: Any = None

    def close(self) -> None:
        """No more tasks: those submitted run to their end, then the workers exit."""
        self.workers = list((self._processes or {}).values())
        self.manager = self._executor_manager_thread
        self.shutdown(wait=False)

    def terminate(self) -> None:
        """Every worker killed at once, the queued tasks cancelled.

        A worker killed while it writes a result leaves part of it in the result pipe, and the
        pool's manager thread (which the interpreter joins as it exits) would wait for the rest
        forever: this process's end of the pipe is closed too, so once the workers have exited
        the manager reads an end of file instead and stops."""
        manager = self.manager or self._executor_manager_thread
        for process in [*self.workers, *(self._processes or {}).values()]:
            process.terminate()
        self.shutdown(wait=False, cancel_futures=True)
        if manager is not None:
            manager.result_queue._writer.close()

    def join(self) -> None:
        """Wait for every worker to exit."""
        self.shutdown()
        if self.manager is not None:
            self.manager.join()  # it joins the workers (a second join of one would race it)


@contextlib.contextmanager
def worker_pool(workers: int, threads: int = 1, budget: Any = None) -> Iterator[WorkerPool]:
    """Worker processes (:func:`worker_init`: ``threads`` compute threads each, the shared
    thread ``budget``, exiting when this process dies), all exited when the block ends; on an
    error or an interrupt the running ones are terminated at once, their results not wanted."""
    start_fork_server()
    pool = WorkerPool(
        max_workers=workers,
        mp_context=_CONTEXT,
        initializer=worker_init,
        initargs=(threads, budget),
    )
    try:
        yield pool
    except BaseException:
        pool.terminate()  # do not wait for running tasks: their results are not wanted
        raise
    pool.join()


#: Seconds between two looks at a held Ctrl-C or SIGTERM while a run waits on its pool.
SIGNAL_LOOK_S = 0.1


@contextlib.contextmanager
def signals_between_waits() -> Iterator[Callable[[], None]]:
    """Ctrl-C and SIGTERM held while the block runs, and handled, by the handlers they had, where
    it calls the function it is given: between two waits on a pool, never inside
    ``concurrent.futures.wait``. A ``KeyboardInterrupt`` raised there, while it holds the
    futures' locks, leaves one held; the pool's manager thread then waits on it, and the
    interpreter, which joins that thread as it exits, waits forever. Off the main thread (where
    no handler can be set), nothing is held."""
    if threading.current_thread() is not threading.main_thread():
        yield lambda: None
        return
    held: list[int] = []
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}

    def hold(signum: int, frame: Any) -> None:
        held.append(signum)

    def handle() -> None:
        while held:
            signum = held.pop(0)
            handler = handlers[signum]
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                signal.signal(signum, signal.SIG_DFL)
                signal.raise_signal(signum)

    for signum in handlers:
        signal.signal(signum, hold)
    try:
        yield handle
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)
        handle()


def each_finished(
    futures: dict[Future, Any],
    on_finished: Callable[[Future], None],
    before_wait: Callable[[], None] = lambda: None,
) -> None:
    """``on_finished(future)`` for each of ``futures`` as it finishes (those that finish together in
    the dict's order), ``before_wait()`` before each wait on them; Ctrl-C and SIGTERM are taken
    between waits (:func:`signals_between_waits`)."""
    pending = dict(futures)
    with signals_between_waits() as handle_signals:
        while pending:
            handle_signals()
            before_wait()
            done, _ = wait(pending, timeout=SIGNAL_LOOK_S, return_when=FIRST_COMPLETED)
            for future in [future for future in pending if future in done]:
                del pending[future]
                on_finished(future)


def run_processes(
    runner: Runner,
    todo: list[Task],
    finished: Finished,
    workers: int,
    threads: int = 1,
    share_tail: bool | Callable[[], bool] = True,
) -> None:
    """The tasks on ``workers`` local processes of ``threads`` compute threads each; at the tail,
    with ``share_tail`` (or where it returns true, asked once the tasks are submitted), the tasks
    still running take up the cores of those that ended (:func:`share_idle_cores`)."""
    budget = _CONTEXT.Array("i", max(1, len(todo)), lock=False)
    with worker_pool(workers, threads, budget) as pool:
        pending = {
            pool.submit(budgeted_task, runner, number, *task): number for number, task in enumerate(todo)
        }
        pool.close()
        sharing = share_tail() if callable(share_tail) else share_tail

        def share() -> None:
            if sharing:
                share_idle_cores(budget, list(pending.values()), workers, threads)

        def save(future: Future) -> None:
            finished(pending.pop(future), future.result())

        each_finished(pending, save, share)


#: What a gRPC server (a Ray cluster's GCS, a Ray Client server) sends first: an HTTP/2 SETTINGS
#: frame (RFC 9113, 3.4), answering a client's connection preface and its own SETTINGS.
_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
_HTTP2_SETTINGS = 4
_CLUSTER_PORT = "the port 'ray start --head' printed, 6379 by default, not the dashboard's 8265"


def check_ray_address(address: str | None, timeout: float = 3.0) -> None:
    """Fail within ``timeout`` seconds, naming the address, when a Ray head cannot be reached
    there, or what answers is not a gRPC server as a Ray cluster is (a dashboard, a web server:
    ``ray.init`` would wait on it for minutes). ``auto`` is resolved as Ray resolves it
    (``RAY_ADDRESS``, then the cluster started on this machine), so a missing cluster is named
    before anything is written."""
    if address in (None, "local"):
        return
    if address == "auto":
        address = _resolve_auto_address()
        if address == "auto":
            return
    scheme, _, target = address.rpartition("://")
    if scheme not in ("", "ray"):
        raise ValueError(
            f"--address {address!r} is a web address (a dashboard's, for job submission): give the "
            f"cluster's HOST:PORT ({_CLUSTER_PORT}), or ray://HOST:PORT for Ray Client"
        )
    host, _, port = target.rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"--address must look like HOST:PORT (or ray://HOST:PORT), got {address!r}")
    deadline = time.monotonic() + timeout
    try:
        connection = socket.create_connection((host, int(port)), timeout=timeout)
    except OSError as exc:
        raise ValueError(f"cannot reach the Ray cluster at {address!r}: {exc.strerror or exc}") from None
    with connection:
        try:
            connection.settimeout(max(deadline - time.monotonic(), 0.1))
            connection.sendall(_HTTP2_PREFACE)
            first = _read(connection, 9)
        except TimeoutError:
            first = None
        except OSError:  # it reset the connection on the preface
            first = b""
    if first is None:
        raise ValueError(
            f"nothing at {address!r} answered as a Ray cluster within {timeout:g} s: give the cluster's "
            f"address ({_CLUSTER_PORT})"
        )
    if len(first) < 9 or first[3] != _HTTP2_SETTINGS:
        raise ValueError(
            f"what answers at {address!r} is not a Ray cluster (not a gRPC server): give the cluster's "
            f"address ({_CLUSTER_PORT})"
        )


def _read(connection: socket.socket, size: int) -> bytes:
    """Up to ``size`` bytes, fewer where the peer closes first (the socket's timeout applies)."""
    data = b""
    while len(data) < size and (chunk := connection.recv(size - len(data))):
        data += chunk
    return data


def _resolve_auto_address() -> str:
    """The address ``--address auto`` stands for, or a ``ValueError`` saying no cluster runs."""
    from mimo_radar_env.extras import require

    require("ray", "ray", "--backend ray")
    try:
        from ray._private import services
    except ImportError:  # pragma: no cover - a Ray without the helper: let ray.init resolve it
        return "auto"
    not_a_cluster = ValueError(
        f"--address auto: RAY_ADDRESS={os.environ.get('RAY_ADDRESS')!r} is not a Ray cluster's address: "
        f"set it to the cluster's HOST:PORT ({_CLUSTER_PORT}), or give --address"
    )
    try:
        address = str(services.canonicalize_bootstrap_address("auto"))
    except ConnectionError:
        raise ValueError(
            "--address auto: no Ray cluster is running on this machine and RAY_ADDRESS is not set; start "
            "one with 'ray start --head', give its HOST:PORT, or leave --address out to start a local Ray"
        ) from None
    except ValueError:  # RAY_ADDRESS that Ray cannot read as a cluster's address
        raise not_a_cluster from None
    scheme = address.rpartition("://")[0]
    if scheme not in ("", "ray"):  # a web address in RAY_ADDRESS, which older Ray passes on (2.40 did)
        raise not_a_cluster
    return address


def threaded_task(runner: Runner, threads: int, *task: Any) -> dict:
    """``runner(*task)`` on ``threads`` compute threads (a Ray task: its worker process serves
    tasks of any thread count) and one BLAS thread, as a local worker's."""
    pin_threads(threads)
    with one_blas_thread():
        return runner(*task)


@contextlib.contextmanager
def _keeping_sigterm() -> Iterator[None]:
    """SIGTERM's handler as it was before the block: ``ray.init`` replaces it with its own (one that
    exits, and its core worker's, which prints a stack trace), so a command stopped by SIGTERM on
    Ray exited 1, with no word of the tasks it had saved, where it should stop as on Ctrl-C
    (``benchmarks.cli``). Off the main thread, where no handler can be set, nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handler = signal.getsignal(signal.SIGTERM)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, handler if handler is not None else signal.SIG_DFL)


def run_ray(
    runner: Runner,
    todo: list[Task],
    finished: Finished,
    address: str | None,
    threads: int = 1,
    started: Callable[[], None] = lambda: None,
) -> None:
    """The tasks on Ray, each reserving ``threads`` CPUs and running on as many threads;
    ``started()`` is called once they are all submitted. Ray is shut down at the end where it
    was started here."""
    from mimo_radar_env.extras import require

    ray = require("ray", "ray", "--backend ray")
    check_ray_address(address)
    started_here = not ray.is_initialized()
    if started_here:
        try:
            with _keeping_sigterm():
                ray.init(
                    address=address, include_dashboard=False, log_to_driver=False, ignore_reinit_error=True
                )
        except (ConnectionError, RuntimeError) as exc:  # a gRPC server that is not Ray's, a cluster gone
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            if not address:
                raise BenchError(f"cannot start Ray on this machine: {reason}") from None
            hint = (  # Ray reads a cluster's auth mode for auto only (its log lines above say why)
                ""
                if os.environ.get("RAY_AUTH_MODE") == "token"
                else "; a cluster with token authentication also needs RAY_AUTH_MODE=token here"
            )
            raise BenchError(f"cannot connect to the Ray cluster at {address!r}: {reason}{hint}") from None
    pending: dict[Any, int] = {}
    try:
        remote_task = ray.remote(num_cpus=threads)(threaded_task)
        payloads: dict[int, Any] = {}  # each run's configuration is put in the object store once
        for number, (payload, policy, shard) in enumerate(todo):
            if id(payload) not in payloads:
                payloads[id(payload)] = ray.put(payload)
            pending[remote_task.remote(runner, threads, payloads[id(payload)], policy, shard)] = number
        started()
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
