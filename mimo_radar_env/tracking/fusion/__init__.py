"""Fusions of the selected channels' measurements, by name: ``"average"`` (the paper's eq22)
and ``"centralized"``. :data:`FUSIONS` is the one registry: the env option ``fusion``, the
tracker, the tracking search, the planner and the cost model all take a fusion from it, so a
new fusion is one module with one :class:`Fusion` subclass passed to :func:`register_fusion`."""

from __future__ import annotations

from typing import Any

from .average import AverageFusion
from .base import Fusion, Posterior, Prior
from .centralized import CentralizedFusion

FUSIONS: dict[str, type[Fusion]] = {}
#: The fusion the env, the tracker and the tracking policies take unless told otherwise: the
#: paper's eq22.
DEFAULT_FUSION = AverageFusion.name


def register_fusion(cls: type[Fusion]) -> type[Fusion]:
    """Add a fusion class to :data:`FUSIONS` under its ``name`` (usable as a decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, Fusion)) or not getattr(cls, "name", ""):
        raise TypeError(f"a fusion is a Fusion subclass with a name, got {cls!r}")
    if cls.compiled_posterior not in (None, "information", "mean"):
        raise ValueError(
            f"{cls.__name__}.compiled_posterior must be None, 'information' or 'mean', "
            f"got {cls.compiled_posterior!r}"
        )
    FUSIONS[cls.name] = cls
    return cls


for _cls in (AverageFusion, CentralizedFusion):
    register_fusion(_cls)


def fusion_class(name: str) -> type[Fusion]:
    """The fusion class registered as ``name``; ``ValueError`` naming the choices otherwise."""
    if not isinstance(name, str) or name not in FUSIONS:
        raise ValueError(f"fusion must be one of {list(FUSIONS)}, got {name!r}")
    return FUSIONS[name]


def make_fusion(name: str, **params: Any) -> Fusion:
    """A fusion by registry name."""
    return fusion_class(name)(**params)


def compiled_kernels(name: str, threaded: bool = False) -> list[Any]:
    """The numba kernels a tracked env step with fusion ``name`` runs (the fusion's update and
    the bound's step; their twins over threads with ``threaded``); none without numba."""
    from ...core.compiled import HAVE_NUMBA

    if not HAVE_NUMBA:
        return []
    from .. import bound

    step = bound._compiled_step_threaded if threaded else bound._compiled_step
    return [*fusion_class(name).compiled_kernels(threaded), step]


__all__ = [
    "DEFAULT_FUSION",
    "FUSIONS",
    "compiled_kernels",
    "AverageFusion",
    "CentralizedFusion",
    "Fusion",
    "Posterior",
    "Prior",
    "fusion_class",
    "make_fusion",
    "register_fusion",
]
