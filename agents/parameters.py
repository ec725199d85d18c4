"""Checks of agent and solver parameters: a clear ``ValueError`` naming the parameter and the
range allowed, before anything runs."""

from __future__ import annotations

import numpy as np


def check_parameter(
    name: str, value: float, low: float, high: float = np.inf, low_open: bool = False
) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is a number in [low, high] (or (low, high])."""
    bracket = "(" if low_open else "["
    upper = "inf)" if high == np.inf else f"{high:g}]"
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        hint = ""
        if isinstance(value, str):
            try:
                number = float(value)
            except ValueError:
                number = np.nan
            if np.isfinite(number):  # "1e3", not "nan" or "inf", which YAML reads as text too
                hint = f" (text: YAML reads an exponent without a dot as text; write {number:.1e})"
        raise ValueError(f"{name} must be a number in {bracket}{low:g}, {upper}, got {value!r}{hint}")
    if not np.isfinite(value):
        raise ValueError(f"{name} must be a finite number in {bracket}{low:g}, {upper}, got {value}")
    inside = (value > low if low_open else value >= low) and value <= high
    if not inside:
        raise ValueError(f"{name} must be in {bracket}{low:g}, {upper}, got {value}")


def check_integer(name: str, value: int, low: int, high: int) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is an integer in [low, high]
    (``2.0`` is not an integer parameter: a float is refused, not truncated)."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ValueError(f"{name} must be an integer in [{low:,}, {high:,}], got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"{name} must be in [{low:,}, {high:,}], got {value:,}")
