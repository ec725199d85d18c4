"""Verdicts from paired 95 % intervals: the one rule every scorecard uses.

A statement claims that a paired difference has a sign. Its 95 % interval (paired on the
same trials, :mod:`benchmarks.uncertainty`) decides:

* **holds**: the whole interval lies on the claimed side of 0;
* **contradicted**: the whole interval lies on the other side;
* **consistent**: the interval reaches 0 (not significant either way).

A statement of several comparisons (a paper claim, a tracking target over several policies)
holds when every comparison holds, is contradicted when any is, and is consistent otherwise;
one whose comparisons could not be evaluated (a window the run did not reach) is "not
evaluated". The paper's claims, the tracking study's targets and the layout calibration's
scores all count verdicts with :func:`count`.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

HOLDS, CONSISTENT, CONTRADICTED, NOT_EVALUATED = "holds", "consistent", "contradicted", "not evaluated"
VERDICTS = (HOLDS, CONSISTENT, CONTRADICTED)


def verdict(ci: Sequence[float], sign: int) -> str:
    """The verdict on "the difference is ``> 0``" (``sign=+1``) or ``< 0`` (``sign=-1``) from its
    interval ``[low, high]``."""
    if sign not in (1, -1):
        raise ValueError(f"sign must be +1 or -1, got {sign!r}")
    low, high = sign * ci[0], sign * ci[1]
    if low > 0 and high > 0:
        return HOLDS
    if low < 0 and high < 0:
        return CONTRADICTED
    return CONSISTENT


def combine(verdicts: Sequence[str]) -> str:
    """The verdict of a statement made of several comparisons."""
    evaluated = [v for v in verdicts if v != NOT_EVALUATED]
    if not evaluated:
        return NOT_EVALUATED
    if CONTRADICTED in evaluated:
        return CONTRADICTED
    if len(evaluated) == len(verdicts) and all(v == HOLDS for v in evaluated):
        return HOLDS
    return CONSISTENT


def count(verdicts: Iterable[str]) -> dict[str, int]:
    """``{"holds": n, "consistent": n, "contradicted": n}``."""
    verdicts = list(verdicts)
    return {v: verdicts.count(v) for v in VERDICTS}


def rank_key(counts: dict[str, int]) -> tuple[int, int]:
    """Higher is better: more statements hold, then fewer are contradicted."""
    return counts[HOLDS], -counts[CONTRADICTED]
