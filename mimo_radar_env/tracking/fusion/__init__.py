"""Fusions of the selected channels' measurements, by name: ``"average"`` (the paper's eq22)
and ``"centralized"``. :data:`FUSIONS` is the one registry; the env options take their
choices from it."""

from __future__ import annotations

from typing import Any

from .average import AverageFusion
from .base import Fusion, Posterior, Prior
from .centralized import CentralizedFusion

FUSIONS: dict[str, type[Fusion]] = {cls.name: cls for cls in (AverageFusion, CentralizedFusion)}


def make_fusion(name: str, **params: Any) -> Fusion:
    """A fusion by registry name."""
    if name not in FUSIONS:
        raise ValueError(f"fusion must be one of {sorted(FUSIONS)}, got {name!r}")
    return FUSIONS[name](**params)


def compiled_kernels(name: str) -> list[Any]:
    """The numba kernels a tracked env step with fusion ``name`` runs (the fusion's update and
    the bound's step); none without numba."""
    from ...core.compiled import HAVE_NUMBA

    if not HAVE_NUMBA:
        return []
    from .. import bound
    from . import average, centralized

    module = {"average": average, "centralized": centralized}[name]
    return [module._update_numba, bound._compiled_step]


__all__ = [
    "FUSIONS",
    "compiled_kernels",
    "AverageFusion",
    "CentralizedFusion",
    "Fusion",
    "Posterior",
    "Prior",
    "make_fusion",
]
