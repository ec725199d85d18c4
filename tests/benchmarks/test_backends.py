"""Every backend, worker count and thread count gives the numbers of one process."""

import multiprocessing
import os
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from benchmarks import backends
from benchmarks.harness import HarnessError, load_per_trial, make_config, run, run_many
from mimo_radar_env.core import compiled
from mimo_radar_env.core.compiled import CHUNK


@pytest.mark.parametrize("context", ["forked", "spawned"])
def test_local_workers_give_the_numbers_of_one_process(tmp_path, monkeypatch, context):
    if context == "spawned":
        monkeypatch.setattr(backends, "_CONTEXT", backends._SpawnContext())
    config = make_config("paper-1", ["mg-crb-cl", "ucb1"], trials=4, steps=15, shard_size=1)
    one = run(config, tmp_path / "one", workers=1, progress=False)
    two = run(config, tmp_path / "two", workers=2, progress=False)
    for policy in config.policies:
        for key in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_matches", "selections"):
            np.testing.assert_array_equal(one[policy][key], two[policy][key])


def test_every_task_runs_on_one_blas_thread_in_this_process_and_on_ray(monkeypatch):
    """As in a worker process: where BLAS has two threads around the call, the task sees one
    (numpy 1.26's OpenBLAS inverts 8 x 8 matrices with bits that depend on its threads: a run on
    one worker then differed from a run on two under centralised fusion), and has two again
    after it."""
    threadpoolctl = pytest.importorskip("threadpoolctl")

    def blas_threads() -> set[int]:
        return {pool["num_threads"] for pool in threadpoolctl.threadpool_info() if pool["user_api"] == "blas"}

    seen = []
    for name in backends.ONE_BLAS_THREAD:  # threaded_task (a Ray task) pins them for later imports
        monkeypatch.setenv(name, "2")
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        if blas_threads() != {2}:
            pytest.skip(f"BLAS cannot be given two threads here: {blas_threads()}")
        backends.run_inline(
            lambda *task: seen.append(blas_threads()), [({}, "p", 0), ({}, "p", 1)], lambda *_: None
        )
        backends.threaded_task(lambda *task: seen.append(blas_threads()), 1, {}, "p", 0)
        assert blas_threads() == {2}
    assert seen == [{1}, {1}, {1}]


def test_threads_inside_a_task_give_the_numbers_of_one_thread(tmp_path, capsys):
    """Two-thread worker processes (their kernels' twins over threads, two chunks of trials a
    task) against this process on one thread; chosen, then said, for a run of one task."""
    config = make_config(
        "paper-1-v1", ["mg-crb-cl", "tracking-ucb"], trials=CHUNK + 6, steps=4, shard_size=CHUNK + 6
    )
    one = run(config, tmp_path / "one", workers=1, threads=1, progress=False)
    two = run(config, tmp_path / "two", workers=2, threads=2, progress=False)
    for policy in config.policies:
        for key in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_matches", "selections"):
            np.testing.assert_array_equal(one[policy][key], two[policy][key])
    capsys.readouterr()
    alone = make_config("paper-1-v1", ["mg-crb-cl"], trials=CHUNK + 6, steps=4, shard_size=CHUNK + 6)
    chosen = run(alone, tmp_path / "chosen", workers=2, progress=False)
    assert "1 worker of 2 threads:" in capsys.readouterr().err
    np.testing.assert_array_equal(chosen["mg-crb-cl"]["trial_expected"], one["mg-crb-cl"]["trial_expected"])


@pytest.mark.parametrize("threads", [0, 3, 1.5, True])
def test_threads_outside_one_to_the_workers_are_refused_naming_both(tmp_path, threads):
    config = make_config("paper-1", ["fix1"], trials=2, steps=2)
    with pytest.raises(HarnessError) as caught:
        run(config, tmp_path / "out", workers=2, threads=threads, progress=False)
    assert str(caught.value) == f"threads must be an integer from 1 to workers (2), got {threads!r}"
    assert caught.value.for_command_line().startswith("--threads must be an integer from 1 to --workers")
    assert not (tmp_path / "out").exists()


def test_ray_backend_gives_the_numbers_of_the_local_path(tmp_path):
    pytest.importorskip("ray", reason="the Ray backend needs the 'ray' extra: pip install -e '.[ray]'")
    config = make_config("paper-3", ["mg-crb-cl", "fix2"], trials=CHUNK + 2, steps=6, shard_size=CHUNK + 2)
    local = run(config, tmp_path / "local", workers=1, progress=False)
    remote = run(config, tmp_path / "ray", backend="ray", workers=2, threads=2, progress=False)
    for policy in config.policies:
        for key in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_matches", "selections"):
            np.testing.assert_array_equal(local[policy][key], remote[policy][key])


def test_a_ray_runs_arrays_are_its_own_not_views_of_the_object_store(tmp_path):
    """Results large enough for Ray's object store come back as read-only views of it, which its
    shutdown releases: the run's joined arrays are copies, the same numbers as read from disk."""
    pytest.importorskip("ray", reason="the Ray backend needs the 'ray' extra: pip install -e '.[ray]'")
    config = make_config("paper-1-v1", ["fix1"], trials=200, steps=100, shard_size=200, say=lambda m: None)
    remote = run(config, tmp_path / "ray", backend="ray", workers=2, progress=False)
    on_disk = load_per_trial(tmp_path / "ray", config)
    for key, value in remote["fix1"].items():
        assert value.flags.writeable, key
        np.testing.assert_array_equal(value, on_disk["fix1"][key], strict=True)


def test_a_run_on_ray_keeps_the_processs_sigterm_handler():
    """``ray.init`` puts its own SIGTERM handling in place (a command stopped by SIGTERM on Ray then
    exited 1 with a stack trace and no word of what it had saved); a run on Ray leaves the
    handler the process had, as the command line's stop on SIGTERM needs (checked as the tasks
    finish and after)."""
    pytest.importorskip("ray", reason="the Ray backend needs the 'ray' extra: pip install -e '.[ray]'")

    def handler(signum, frame):
        raise AssertionError("not called")

    seen = []
    previous = signal.signal(signal.SIGTERM, handler)
    try:
        backends.run_ray(
            lambda payload, policy, shard: {"shard": shard},
            [({"run": 0}, "fix1", shard) for shard in range(2)],
            lambda number, result: seen.append(signal.getsignal(signal.SIGTERM)),
            address=None,
        )
        assert seen == [handler, handler]
        assert signal.getsignal(signal.SIGTERM) is handler
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_ray_backend_runs_a_studys_runs_together_with_the_numbers_of_each_alone(tmp_path):
    pytest.importorskip("ray", reason="the Ray backend needs the 'ray' extra: pip install -e '.[ray]'")
    configs = [
        make_config(n, ["mg-crb-cl", "fix1"], trials=3, steps=8, shard_size=2) for n in ("paper-1", "paper-2")
    ]
    folders = [tmp_path / "one", tmp_path / "two"]
    assert run_many(list(zip(configs, folders, strict=True)), backend="ray", progress=False) == [True, True]
    for config, folder in zip(configs, folders, strict=True):
        alone = run(config, folder.with_name(folder.name + "-alone"), workers=1, progress=False)
        together = load_per_trial(folder, config)
        for policy in config.policies:
            for key in ("trial_expected", "trial_squared_error", "trial_matches", "selections"):
                np.testing.assert_array_equal(alone[policy][key], together[policy][key])


def test_idle_cores_are_shared_by_the_tasks_left_at_the_tail_and_never_taken_back():
    budget = [0] * 6
    backends.share_idle_cores(budget, [2, 3, 4, 5], workers=4, threads=2)  # as many left as workers
    assert budget == [0] * 6
    backends.share_idle_cores(budget, [3, 4, 5], workers=4, threads=2)  # 8 cores over 3 tasks
    assert budget == [0, 0, 0, 3, 3, 2]
    backends.share_idle_cores(budget, [5, 3], workers=4, threads=2)
    assert budget == [0, 0, 0, 4, 3, 4]  # task 4 ended; 3 and 5 get 4 each
    backends.share_idle_cores(budget, [3], workers=4, threads=2)
    assert budget[3] == 8


def _threads_seen(seconds):
    """A task of ``seconds`` that follows the thread budget every 50 ms: the most threads it had."""
    seen = compiled.threads()
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        backends.follow_thread_budget()
        seen = max(seen, compiled.threads())
        time.sleep(0.05)
    return {"threads": seen}


def test_the_last_task_running_takes_up_the_cores_the_others_left():
    pytest.importorskip("numba")
    results = {}
    tasks = [(0.2,), (6.0,), (0.2,)]
    backends.run_processes(_threads_seen, tasks, results.__setitem__, workers=2, threads=1)
    assert results == {0: {"threads": 1}, 1: {"threads": 2}, 2: {"threads": 1}}
    results.clear()
    asked = []

    def share_tail():  # asked once, the tasks submitted and the workers started
        asked.append(len(multiprocessing.active_children()))
        return False

    backends.run_processes(
        _threads_seen, tasks, results.__setitem__, workers=2, threads=1, share_tail=share_tail
    )
    assert results == {0: {"threads": 1}, 1: {"threads": 1}, 2: {"threads": 1}}
    assert asked == [2]


def _pid(_):
    return {"pid": os.getpid()}


def test_the_workers_exit_while_this_process_handles_the_last_result():
    """Once every task is submitted the pool is closed: each worker exits when the queue is done,
    without waiting for this process to finish with the results (the last run's outputs)."""
    alive_at_last, seen = [], []

    def finished(number, result):
        seen.append(number)
        if len(seen) == 4:
            end = time.monotonic() + 20
            while multiprocessing.active_children() and time.monotonic() < end:
                time.sleep(0.05)
            alive_at_last.extend(multiprocessing.active_children())

    backends.run_processes(_pid, [(k,) for k in range(4)], finished, workers=2, share_tail=False)
    assert alive_at_last == [] and multiprocessing.active_children() == []


def _print_unflushed(text):
    sys.stdout.write(text)  # no newline, no flush: the worker's exit must flush it
    return {"pid": os.getpid()}


@pytest.mark.parametrize("context", ["forked", "spawned"])
def test_a_worker_skips_the_interpreters_teardown_but_not_its_output(capfd, monkeypatch, context):
    from multiprocessing import forkserver

    if context == "spawned":
        monkeypatch.setattr(backends, "_CONTEXT", backends._SpawnContext())
    forkserver._forkserver._stop()  # its workers write where it was started: into this capture
    results = {}
    backends.run_processes(_print_unflushed, [("one-",), ("two-",)], results.__setitem__, workers=2)
    assert sorted(capfd.readouterr().out.split("-")[:2]) == ["one", "two"]
    assert len(results) == 2 and multiprocessing.active_children() == []
    assert backends._CONTEXT.Process.run is backends._ExitsAtOnce.run


def _semaphores(_):
    """This worker's named semaphores (numba's, made as the pool started its threads)."""
    import multiprocessing.util
    from multiprocessing.synchronize import SemLock

    names = [
        f._args[0]
        for f in multiprocessing.util._finalizer_registry.values()
        if f._callback == SemLock._cleanup
    ]
    return {"pid": os.getpid(), "names": names}


@pytest.mark.skipif(not Path("/dev/shm").is_dir(), reason="named semaphores as files of /dev/shm (Linux)")
def test_a_terminated_worker_removes_its_named_semaphores():
    """An interrupted run terminates its workers (SIGTERM): each runs multiprocessing's clean-up
    before it exits, so no semaphore is left for the resource tracker to report leaked (a second
    line after the run's one-line message)."""
    with backends.worker_pool(1, threads=2) as pool:
        seen = pool.submit(_semaphores, None).result()
        assert seen["names"], "the worker made no named semaphore: nothing to check"
        assert all(Path(f"/dev/shm/sem.{name.lstrip('/')}").exists() for name in seen["names"])
        pool.terminate()
        end = time.monotonic() + 20
        while time.monotonic() < end and _running(seen["pid"]):
            time.sleep(0.05)
        assert not _running(seen["pid"])
        assert not any(Path(f"/dev/shm/sem.{name.lstrip('/')}").exists() for name in seen["names"])


def _half_a_result(marker):
    """This worker's result begun in the result pipe and left there: a message's length and a
    part of it, as a worker killed while it writes a large result leaves it."""
    frame = sys._getframe()
    while frame.f_code.co_name != "_process_worker":
        frame = frame.f_back
    results = frame.f_locals["result_queue"]
    results._wlock.acquire()
    os.write(results._writer.fileno(), struct.pack("!i", 1 << 20) + b"part of a result")
    Path(marker).touch()
    time.sleep(120)


def test_a_worker_killed_while_writing_its_result_leaves_no_thread_waiting_for_the_rest(tmp_path):
    """Ctrl-C while a worker writes a result: the pool's manager thread, which the interpreter
    joins as it exits, had read the message's length and waited for the rest forever (an
    interrupted CI run never exited)."""
    marker = tmp_path / "writing"
    with pytest.raises(KeyboardInterrupt), backends.worker_pool(1) as pool:
        pool.submit(_half_a_result, str(marker))
        pool.close()
        end = time.monotonic() + 60
        while not marker.exists() and time.monotonic() < end:
            time.sleep(0.05)
        assert marker.exists(), "the worker wrote nothing"
        raise KeyboardInterrupt
    pool.manager.join(20)
    waiting = pool.manager.is_alive()
    if waiting:
        pool.manager.result_queue._writer.close()  # so that this test's process can exit
    assert not waiting


def test_ctrl_c_during_a_run_on_workers_is_raised_between_waits_never_inside_them():
    """A KeyboardInterrupt raised inside concurrent.futures.wait, while it holds the futures'
    locks, can leave one held: the pool's manager thread then waits on it, and the interpreter,
    which joins that thread as it exits, waits forever. A Ctrl-C during a run is held and raised
    where the run asks: after the results in hand are saved."""
    import signal

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    saved = []

    def finished(number, result):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)  # Python has run the handler by now: held, not raised
        saved.append(number)

    try:
        with pytest.raises(KeyboardInterrupt):
            backends.run_processes(_pid, [(k,) for k in range(4)], finished, workers=1, share_tail=False)
        assert saved and saved == list(range(len(saved)))  # every result being saved was saved whole
        with backends.signals_between_waits() as handle:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.2)
            with pytest.raises(KeyboardInterrupt):
                handle()
            handle()  # handled once
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.mark.skipif(not Path("/dev/shm").is_dir(), reason="named semaphores as files of /dev/shm (Linux)")
def test_a_second_sigterm_during_a_workers_clean_up_leaves_no_semaphore_reported_leaked(tmp_path):
    """An interrupted run's workers get a second SIGTERM: the pool's manager thread terminates
    the others once one has ended. Arriving after a worker's clean-up had unlinked a semaphore
    and before it told the resource tracker, it left the tracker's warnings after the run's
    one-line message (a CI run). Here the second SIGTERM is sent at exactly that point."""
    script = tmp_path / "second_sigterm.py"
    script.write_text(
        "import os, signal, time\n"
        "from multiprocessing import resource_tracker\n"
        "from benchmarks import backends\n"
        "lock = backends._CONTEXT.Lock()  # a named semaphore, registered with the tracker\n"
        "told = resource_tracker.unregister\n"
        "def unregister(name, rtype):  # called by the clean-up right after the unlinking\n"
        "    os.kill(os.getpid(), signal.SIGTERM)\n"
        "    time.sleep(0.2)\n"
        "    told(name, rtype)\n"
        "resource_tracker.unregister = unregister\n"
        "signal.signal(signal.SIGTERM, backends._stop)\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(10)\n"
    )
    # the tracker writes to this process's stderr; communicate() waits for it to end too
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 128 + signal.SIGTERM
    assert done.stderr == ""


@pytest.mark.parametrize("context", ["_ForkServerContext", "_SpawnContext"])
def test_a_worker_exits_when_the_process_that_started_it_is_killed(tmp_path, context):
    """A worker whose pool's process dies (killed: no clean-up) exits by itself, whether it was
    spawned by that process or forked by its fork server."""
    script = tmp_path / "orphan.py"
    script.write_text(
        "import time\n"
        "from benchmarks import backends\n"
        "if __name__ == '__main__':\n"
        f"    backends._CONTEXT = backends.{context}()\n"
        "    with backends.worker_pool(1) as pool:\n"
        "        pool.submit(time.sleep, 120)\n"
        "        while not pool._processes:\n"
        "            time.sleep(0.01)\n"
        "        print(*pool._processes, flush=True)\n"
        "        time.sleep(120)\n"
    )
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    worker = int(parent.stdout.readline())
    os.kill(worker, 0)  # running
    parent.kill()
    parent.wait()
    end = time.monotonic() + 20
    while time.monotonic() < end and _running(worker):
        time.sleep(0.05)
    assert not _running(worker)


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (exited, not reaped yet) is not running
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().split(") ")[-1][0] != "Z"
    except OSError:
        return True


def test_ray_calls_started_once_every_task_is_submitted(monkeypatch):
    """On Ray, as on local workers, what the command does as the tasks start (the progress
    bar's compile check, which imports numba) comes after they are all submitted, not before:
    a stand-in of Ray's API records the order."""
    import types

    events, outputs = [], {}

    class Remote:
        def __init__(self, function):
            self.function = function

        def remote(self, *arguments):
            events.append("submit")
            outputs[len(outputs)] = self.function(*arguments)
            return len(outputs) - 1

    fake = types.SimpleNamespace(
        is_initialized=lambda: True,
        remote=lambda num_cpus: Remote,
        put=lambda value: value,
        wait=lambda refs, num_returns: (refs[:num_returns], refs[num_returns:]),
        get=outputs.__getitem__,
        cancel=lambda ref, force: None,
        shutdown=lambda: events.append("shutdown"),
    )
    monkeypatch.setitem(sys.modules, "ray", fake)
    monkeypatch.setattr(backends, "pin_threads", lambda threads: None)
    results = {}
    todo = [({"run": 0}, "fix1", shard) for shard in range(3)]
    backends.run_ray(
        lambda payload, policy, shard: {"shard": shard},
        todo,
        lambda number, result: results.__setitem__(number, result),
        address=None,
        started=lambda: events.append("started"),
    )
    assert events == ["submit", "submit", "submit", "started"]  # Ray was running: not shut down here
    assert results == {number: {"shard": number} for number in range(3)}


def test_the_harness_leaves_rays_start_callback_to_run_ray(monkeypatch):
    from benchmarks import harness

    seen, calls = {}, []
    monkeypatch.setattr(
        backends, "run_ray", lambda *arguments, started, **_: seen.setdefault("started", started)
    )
    harness._dispatch([], lambda number, result: None, 2, "ray", None, 1, starting=lambda: calls.append(1))
    assert calls == []  # not before the tasks are submitted: run_ray calls it then
    seen["started"]()
    assert calls == [1]


class _Server:
    """A loopback TCP server on a thread that answers each connection with ``reply`` (None: it
    reads and says nothing until the test ends)."""

    def __init__(self, reply):
        import socket
        import threading

        self.listener = socket.create_server(("127.0.0.1", 0))
        self.address = f"127.0.0.1:{self.listener.getsockname()[1]}"
        self.held = []
        self.reply = reply
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                connection, _ = self.listener.accept()
            except OSError:
                return
            self.held.append(connection)
            connection.recv(1024)
            if self.reply is not None:
                connection.sendall(self.reply)
                connection.close()

    def close(self):
        self.listener.close()
        for connection in self.held:
            connection.close()


@pytest.fixture
def server():
    made = []
    yield lambda reply: made.append(_Server(reply)) or made[-1]
    for one in made:
        one.close()


def test_a_ray_address_is_accepted_where_a_grpc_server_answers(server):
    """What a Ray cluster's GCS (a gRPC server) sends first on a connection is an HTTP/2
    SETTINGS frame: a 9-byte header of length, type 4, flags and stream 0 (RFC 9113)."""
    settings = (0).to_bytes(3, "big") + bytes([4, 0]) + (0).to_bytes(4, "big")
    grpc = server(settings)
    backends.check_ray_address(grpc.address)
    backends.check_ray_address(f"ray://{grpc.address}")


def test_a_ray_address_where_a_web_server_or_nothing_answers_is_refused_within_the_timeout(server):
    """A dashboard (8265) or any server that is not gRPC, and one that never answers, are named
    at once or within the timeout: ``ray.init`` would wait on them for minutes."""
    web = server(b"HTTP/1.0 400 Bad Request\r\n\r\n")
    with pytest.raises(
        ValueError, match=r"not a Ray cluster \(not a gRPC server\).*not the dashboard's 8265"
    ):
        backends.check_ray_address(web.address)
    closes = server(b"")
    with pytest.raises(ValueError, match="not a Ray cluster"):
        backends.check_ray_address(closes.address)
    silent = server(None)
    start = time.perf_counter()
    with pytest.raises(
        ValueError, match=f"nothing at '{silent.address}' answered as a Ray cluster within 0.5 s"
    ):
        backends.check_ray_address(silent.address, timeout=0.5)
    assert time.perf_counter() - start < 2
    with pytest.raises(ValueError, match="is a web address"):
        backends.check_ray_address("http://127.0.0.1:8265")


def test_a_ray_that_refuses_the_connection_is_one_line(monkeypatch):
    """A gRPC server that passes the address check and is not Ray's, or a cluster that refuses
    the driver: ``ray.init``'s error becomes the command's one line."""
    import types

    def init(**_):
        raise ConnectionError("Failed to connect to Ray cluster at 10.0.0.1:6379\nmore")

    fake = types.SimpleNamespace(is_initialized=lambda: False, init=init)
    monkeypatch.setitem(sys.modules, "ray", fake)
    monkeypatch.setattr(backends, "check_ray_address", lambda address: None)
    monkeypatch.delenv("RAY_AUTH_MODE", raising=False)
    with pytest.raises(backends.BenchError) as error:
        backends.run_ray(lambda *task: {}, [], lambda number, result: None, address="10.0.0.1:6379")
    assert str(error.value) == (
        "cannot connect to the Ray cluster at '10.0.0.1:6379': "
        "Failed to connect to Ray cluster at 10.0.0.1:6379; "
        "a cluster with token authentication also needs RAY_AUTH_MODE=token here"
    )
    monkeypatch.setenv("RAY_AUTH_MODE", "token")  # set: the hint would not help
    with pytest.raises(backends.BenchError, match="6379$"):
        backends.run_ray(lambda *task: {}, [], lambda number, result: None, address="10.0.0.1:6379")


def test_a_ray_address_in_the_environment_that_is_not_a_clusters_is_named(monkeypatch):
    """``--address auto`` reads RAY_ADDRESS; the job-submission address Ray's docs have users
    export there (the dashboard's) is named as such, not Ray's own parse error."""
    pytest.importorskip("ray", reason="the ray extra")
    monkeypatch.setenv("RAY_ADDRESS", "http://127.0.0.1:8265")
    with pytest.raises(ValueError) as error:
        backends.check_ray_address("auto")
    assert str(error.value).startswith(
        "--address auto: RAY_ADDRESS='http://127.0.0.1:8265' is not a Ray cluster's address: set it to"
    )
