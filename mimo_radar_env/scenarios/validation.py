"""Checks of scenario fields: each raises :class:`ScenarioError` naming the field and what is allowed."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
from numpy.typing import NDArray


class ScenarioError(ValueError):
    """A scenario field is missing, unknown or out of its allowed range."""


#: A scenario's name: the studies name a folder after it (``OUT/<name>``), so no separator, no dot first.
SCENARIO_NAME = re.compile(r"[\w+-][\w.+-]{0,99}")
#: What a name is not made of (SCENARIO_NAME's other characters).
_NOT_IN_NAME = re.compile(r"[^\w.+-]+")


def scenario_name(value: Any) -> str:
    """``value`` if it is a name a folder can carry."""
    if not isinstance(value, str) or not SCENARIO_NAME.fullmatch(value):
        raise ScenarioError(
            "name must be a string of 1 to 100 letters, digits, '_', '-', '+' or '.' (not first), as a "
            f"study names a folder after it; got {value!r}"
        )
    return value


def name_from(text: str) -> str:
    """``text`` (a file's stem) made a scenario name: other characters as ``-``, no dot first, at most
    100 characters; ``"custom"`` where nothing is left."""
    return _NOT_IN_NAME.sub("-", text).lstrip(".")[:100] or "custom"


def numeric_array(name: str, value: Any) -> NDArray[np.float64]:
    """``value`` as a float array of finite numbers (booleans and strings are not numbers)."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nesting
        raise ScenarioError(f"{name} must be numeric, got {value!r}") from exc
    if raw.dtype.kind not in "iuf":
        kind = {"b": "booleans", "U": "strings", "S": "strings"}.get(raw.dtype.kind, "non-numbers")
        raise ScenarioError(f"{name} must be numbers, got {kind}: {value!r}")
    arr = raw.astype(np.float64)
    if not np.all(np.isfinite(arr)):
        raise ScenarioError(f"{name} must be finite numbers, got {arr.tolist()}")
    return arr


def number(name: str, value: Any) -> float:
    """A single finite number (not a boolean)."""
    if isinstance(value, bool):
        raise ScenarioError(f"{name} must be a number, got {value!r}")
    arr = numeric_array(name, value)
    if arr.shape != ():
        raise ScenarioError(f"{name} must be a single number, got shape {arr.shape}")
    return float(arr)


def positive_number(name: str, value: Any) -> float:
    out = number(name, value)
    if out <= 0:
        raise ScenarioError(f"{name} must be > 0, got {out}")
    return out


def integer_in(name: str, value: Any, low: int, high: int | None, allowed: str) -> int:
    """An integer in ``[low, high]`` (``high=None``: no upper bound); ``allowed`` explains the range.
    A float is refused even when integral (``2.0``), as Gymnasium refuses one for ``Discrete``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ScenarioError(f"{name} must be an integer, got {value!r}")
    value = int(value)
    if value < low or (high is not None and value > high):
        bound = f"between {low} and {high}" if high is not None else f">= {low}"
        raise ScenarioError(f"{name} must be {bound} ({allowed}), got {value}")
    return value


def positions(name: str, value: Any) -> NDArray[np.float64]:
    """A non-empty list of ``[x, y]`` pairs."""
    arr = numeric_array(name, value)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
        raise ScenarioError(f"{name} must be a list of [x, y] pairs in metres, got shape {arr.shape}")
    return arr


def broadcast_field(name: str, arr: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray[np.float64]:
    try:
        return np.broadcast_to(arr, shape).copy()
    except ValueError as exc:
        raise ScenarioError(
            f"{name} must be a single number or an array of shape {shape}, got shape {arr.shape}"
        ) from exc


def positive_array(name: str, value: Any, shape: tuple[int, ...]) -> NDArray[np.float64]:
    arr = broadcast_field(name, numeric_array(name, value), shape)
    if np.any(arr <= 0):
        raise ScenarioError(f"{name} must be > 0 everywhere, got {arr.min()}")
    return arr


def nonnegative_array(name: str, value: Any, shape: tuple[int, ...]) -> NDArray[np.float64]:
    arr = broadcast_field(name, numeric_array(name, value), shape)
    if np.any(arr < 0):
        raise ScenarioError(f"{name} must be >= 0 everywhere, got {arr.min()}")
    return arr


def distinct_positions(name: str, stations: NDArray[np.float64]) -> None:
    """Every station at its own position."""
    diff = np.linalg.norm(stations[:, None, :] - stations[None, :, :], axis=-1)
    i, j = np.nonzero(np.triu(diff < 1e-6, k=1))
    if len(i):
        raise ScenarioError(
            f"{name} has duplicate stations {int(i[0])} and {int(j[0])} at "
            f"{stations[i[0]].tolist()} m; every station needs its own position"
        )
