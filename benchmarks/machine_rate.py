"""How fast this machine runs the project's step, against the developers' machine: the factor the
time estimates (:func:`benchmarks.resources.estimate_seconds`) are scaled by.

``mimo-radar-bench compile`` times :func:`workload_seconds` (the v1 env step with its tracker and
bound, :data:`TRIALS` trials of a random policy, :data:`STEPS` steps after a warm-up, in this
process) and keeps its ratio to :data:`REFERENCE_SECONDS`, the same workload on the developers'
machine, in :func:`rate_file`. Every estimate after that is this machine's; without the file the
estimates are the developers' machine's, and say so.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

#: The workload: trials of the v1 paper scenario 1 and steps timed after a warm-up step.
TRIALS, STEPS = 64, 100
#: The workload's seconds on the developers' machine (2 cores, x86_64, Python 3.11.7, numba),
#: measured in the session that fitted the cost model's rates (``agents.costs``,
#: ``mimo_radar_env.envs.cost``): the median of seven ``python -c "from benchmarks.machine_rate
#: import workload_seconds; print(workload_seconds())"``.
REFERENCE_SECONDS = 0.26
#: The environment variable that names the file the factor is kept in; empty: no factor.
RATE_ENV = "MIMO_RADAR_RATE_FILE"
#: A factor outside this range is refused as a mismeasurement (a machine busy with other work).
PLAUSIBLE = (0.05, 20.0)


def rate_file() -> Path | None:
    """Where the factor is kept: ``$MIMO_RADAR_RATE_FILE`` (empty: nowhere), else the user's cache
    folder (``$XDG_CACHE_HOME`` or ``~/.cache``)/mimo-radar-env/machine-rate.json."""
    configured = os.environ.get(RATE_ENV)
    if configured is not None:
        return Path(configured) if configured else None
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "mimo-radar-env" / "machine-rate.json"


def workload_seconds(repeats: int = 3) -> float:
    """The median seconds of :data:`STEPS` steps of the workload, over ``repeats`` episodes."""
    import agents
    from mimo_radar_env import VERSIONS, load_scenario

    scenario = load_scenario("paper-1-v1")
    options = VERSIONS["v1"].options().to_dict()
    times = []
    for _ in range(repeats):
        agent = agents.make_agent("random", scenario, seed=0)
        rollout = agents.Rollout(agent, agents.make_env(agent, TRIALS, options, scenario), seed=0)
        rollout.step()  # warm-up: kernels loaded, arrays allocated
        start = time.perf_counter()
        for _ in rollout.run(STEPS):
            pass
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def calibrate(repeats: int = 3) -> tuple[dict[str, Any], Path | None]:
    """Time the workload here and keep its ratio to the developers' machine in :func:`rate_file`
    (when there is one); the record, and the file it was kept in (None: not kept, as a ratio
    outside :data:`PLAUSIBLE` is not)."""
    seconds = workload_seconds(repeats)
    record = {
        "factor": seconds / REFERENCE_SECONDS,
        "seconds": seconds,
        "reference_seconds": REFERENCE_SECONDS,
        "machine": platform.machine(),
        "cores": os.cpu_count(),
        "python": platform.python_version(),
    }
    path = rate_file()
    if path is None or not PLAUSIBLE[0] <= record["factor"] <= PLAUSIBLE[1]:
        return record, None
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2))
    return record, path


_READ: dict[tuple[Path, float], float | None] = {}


def factor() -> float | None:
    """This machine's factor (its workload's seconds over the developers'), or None where none
    is kept or the file is not a record :func:`calibrate` wrote (read once per version of it).
    It is the kept seconds over today's :data:`REFERENCE_SECONDS`, so a record kept before the
    reference was measured again stays right."""
    path = rate_file()
    try:
        key = (path, path.stat().st_mtime) if path is not None else None
    except OSError:
        return None
    if key is None:
        return None
    if key not in _READ:
        try:
            seconds = json.loads(path.read_text())["seconds"]
            value = seconds / REFERENCE_SECONDS if isinstance(seconds, int | float) else None
            ok = value is not None and PLAUSIBLE[0] <= value <= PLAUSIBLE[1]
            _READ[key] = float(value) if ok else None
        except (OSError, ValueError, KeyError, TypeError):
            _READ[key] = None
    return _READ[key]
