"""Shard files of a run: where they live, how they are written, checked and read.

A shard holds what the reports of one policy need about a block of trials, each piece once:

``trial_expected``, ``trial_optimal`` (n, T) float64
    the mean reward ``mu_t`` of the selected super arm and of the optimal one, per trial;
``trial_squared_error`` (n, T, K) float64
    the squared position error of each target's track (NaN without a tracker);
``trial_bound_squared`` (n, T, K) float64
    the squared posterior Cramer-Rao bound of the position for the selections made
    (``info["position_bound"]``; NaN without a tracker);
``trial_matches`` (n, T) uint8
    1 where the selected super arm is the optimal one;
``selections`` (T, M + N) float64
    how many of the shard's trials selected each station at each step (the selection maps);
``wall_s`` () float64
    the task's compute time in seconds;
``tracker_repairs`` () float64
    how many covariances the tracker repaired over the shard's trials (``info["tracker_repairs"]``
    at the last step; 0 without a tracker);
``first_trial_positions`` (T + 1, K, 2) float64
    the true positions of the shard's first trial (the geometry figure);

and three fields that make it self-describing: ``shard_trials`` (its trial range),
``config_hash`` (the hash of the run configuration, the policy and :data:`SHARD_FORMAT`) and
``checksum`` (of its data). Every reported number is computed from the per-trial arrays
(:class:`benchmarks.metrics.TrialMetrics`). A shard that fails any check (unreadable,
truncated, another run's or format's, another block's, altered) is named, set aside and
computed again; it never enters a result.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.metrics import TRIAL_FIELDS
from mimo_radar_env.core import motion

from .errors import HarnessError

#: The layout of the fields above; part of every shard's identity, so that shards of an older
#: layout are recomputed rather than read.
SHARD_FORMAT = 3
#: The true positions (steps + 1, K, 2) of the shard's first trial (for the geometry figure).
TRUTH_FIELD = "first_trial_positions"
DATA_FIELDS = (*TRIAL_FIELDS, "selections", "wall_s", "tracker_repairs", TRUTH_FIELD)
META_FIELDS = ("shard_trials", "config_hash", "checksum")


def policy_folder(policy: str) -> str:
    """A folder name for a policy: the name itself when it is plain, else a readable part and a hash
    (so that ``ppo:a/b_c.zip`` and ``ppo:a_b/c.zip`` never share a folder)."""
    if re.fullmatch(r"[A-Za-z0-9._-]+", policy):
        return policy
    readable = re.sub(r"[^A-Za-z0-9._-]+", "_", policy)[-40:]
    return f"{readable}-{hashlib.sha256(policy.encode()).hexdigest()[:12]}"


def shard_path(out: Path, policy: str, shard: int) -> Path:
    return Path(out) / "shards" / policy_folder(policy) / f"shard_{shard:05d}.npz"


def config_hash(config: dict[str, Any], policy: str) -> str:
    """The identity of a (run configuration, policy) pair, written into each of its shards."""
    text = json.dumps(config, sort_keys=True, allow_nan=False) + "\n" + policy + f"\nformat {SHARD_FORMAT}"
    return hashlib.sha256(text.encode()).hexdigest()


def checksum(data: dict[str, NDArray]) -> str:
    digest = hashlib.sha256()
    for key in DATA_FIELDS:
        array = np.ascontiguousarray(data[key])
        digest.update(f"{key}:{array.dtype.str}:{array.shape}".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def write_shard(path: Path, result: dict[str, NDArray], trials: range, identity: str) -> None:
    """Write atomically under a unique temporary name: a shard file is complete or absent."""
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = dict(result)
    payload["shard_trials"] = np.array([trials.start, trials.stop])
    payload["config_hash"] = np.array(identity)
    payload["checksum"] = np.array(checksum(result))
    try:
        handle, tmp = tempfile.mkstemp(prefix=path.stem + ".", suffix=".tmp.npz", dir=path.parent)
    except OSError as exc:
        raise _unwritable(path, exc) from None
    try:
        with os.fdopen(handle, "wb") as file:
            np.savez(file, **payload)
        os.replace(tmp, path)
    except OSError as exc:  # a full disk, a read-only folder: one line; what was written stays
        Path(tmp).unlink(missing_ok=True)
        raise _unwritable(path, exc) from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _unwritable(path: Path, exc: OSError) -> HarnessError:
    return HarnessError(
        f"cannot write the shard {path} ({exc.strerror or exc}): free space or give `out` a writable "
        "folder; the shards already written are kept, and the same run started again resumes"
    )


def read_shard(path: Path, trials: range, identity: str) -> dict[str, NDArray]:
    """The shard's data, or ``ValueError`` saying what is wrong with it."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            missing = sorted(set(DATA_FIELDS + META_FIELDS) - set(archive.files))
            if missing:
                raise ValueError(f"fields {missing} are missing")
            data = {key: archive[key] for key in DATA_FIELDS}
            meta = {key: archive[key] for key in META_FIELDS}
    except (OSError, EOFError, ValueError, zipfile.BadZipFile, KeyError) as exc:
        raise ValueError(f"unreadable ({type(exc).__name__}: {exc})") from exc
    if str(meta["config_hash"]) != identity:
        raise ValueError("it belongs to another run or policy")
    if meta["shard_trials"].tolist() != [trials.start, trials.stop]:
        raise ValueError(
            f"it holds trials {meta['shard_trials'].tolist()}, not [{trials.start}, {trials.stop}]"
        )
    if str(meta["checksum"]) != checksum(data):
        raise ValueError("its checksum does not match its data")
    return data


def set_aside(path: Path) -> Path:
    """Move a damaged shard out of the way (kept for inspection): ``shard_k.npz.damaged[-n]``."""
    target = path.with_name(path.name + ".damaged")
    count = 1
    while target.exists():
        count += 1
        target = path.with_name(f"{path.name}.damaged-{count}")
    os.replace(path, target)
    return target


class ShardRecorder:
    """A task's shard fields, filled step by step from the env's ``info`` and the actions where
    the env runs (numpy, or torch on a device) and brought to the host :attr:`FLUSH_STEPS` steps
    at a time: a run on a device reads from it once per field every ``FLUSH_STEPS`` steps, not
    every step. The values are those the host would compute: the same operations, in one place.

    ``trials`` x ``steps``, ``targets`` K and ``stations`` M + N; ``first_truth`` the reset's
    true state of the first trial (K, 4) and ``host`` the env's to-numpy function."""

    FLUSH_STEPS = 64

    def __init__(
        self, xp: Any, host: Any, trials: int, steps: int, targets: int, stations: int, first_truth: Any
    ) -> None:
        self.xp, self.host = xp, host
        self.out = {
            "trial_expected": np.zeros((trials, steps)),
            "trial_optimal": np.zeros((trials, steps)),
            "trial_squared_error": np.full((trials, steps, targets), np.nan),
            "trial_bound_squared": np.full((trials, steps, targets), np.nan),
            "trial_matches": np.zeros((trials, steps), np.uint8),
            "selections": np.zeros((steps, stations)),
            TRUTH_FIELD: np.empty((steps + 1, targets, 2)),
        }
        self.out[TRUTH_FIELD][0] = host(motion.positions(first_truth))
        self._pending: list[dict[str, Any]] = []
        self._done = 0

    def add(self, action: Any, info: dict[str, Any]) -> None:
        """One step's fields from the action played and the ``info`` it returned."""
        values = {
            "trial_expected": info["expected_reward"],
            "trial_optimal": info["optimal_reward"],
            "trial_matches": self.xp.all(action == info["optimal_action"], axis=1),
            "selections": action.sum(axis=0),
            TRUTH_FIELD: motion.positions(info["true_state"][0]),
        }
        if "position_error" in info:
            values["trial_squared_error"] = info["position_error"] ** 2
            values["trial_bound_squared"] = info["position_bound"] ** 2
        self._pending.append(values)
        if len(self._pending) == self.FLUSH_STEPS:
            self.flush()

    def flush(self) -> None:
        """The pending steps' fields to the host arrays."""
        if not self._pending:
            return
        start, end = self._done, self._done + len(self._pending)
        for name in self._pending[0]:
            per_trial = name not in ("selections", TRUTH_FIELD)
            stacked = self.host(self.xp.stack([v[name] for v in self._pending], axis=1 if per_trial else 0))
            if per_trial:
                self.out[name][:, start:end] = stacked
            else:
                offset = 1 if name == TRUTH_FIELD else 0
                self.out[name][start + offset : end + offset] = stacked
        self._pending, self._done = [], end

    def result(self) -> dict[str, NDArray]:
        self.flush()
        return self.out
