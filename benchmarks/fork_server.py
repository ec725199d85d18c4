"""What the local workers' fork server imports before it forks any worker
(:func:`benchmarks.backends.start_fork_server`): every module a task imports, and the numba
kernels a worker of one thread calls, loaded from numba's on-disk cache where ``compile`` (or an
earlier run) put them (where one is missing, nothing is compiled here: the server would hold
back every worker meanwhile). Each worker forked from the server starts with both; spawned, a
worker paid for them in its first task. Nothing here may start a thread: processes are forked
from this one.

The server ignores SIGTERM: a scheduler or ``kill`` that signals the command's whole process group
stops the command as Ctrl-C does (``benchmarks.cli``), and the server, ended by the signal in the
middle of forking, would leave a semaphore the resource tracker reports leaked. It ends when the
command does (multiprocessing closes its pipe)."""

from __future__ import annotations

import contextlib
import signal
import warnings

from mimo_radar_env.core.compiled import HAVE_NUMBA, load_cached

from . import harness  # noqa: F401 - what every task imports
from .precompile import all_kernels

if HAVE_NUMBA:
    with warnings.catch_warnings(), contextlib.suppress(Exception):
        warnings.simplefilter("ignore")
        load_cached(all_kernels(threaded=False))

signal.signal(signal.SIGTERM, signal.SIG_IGN)
