"""The studies of ``mimo-radar-bench``, on one engine (:mod:`benchmarks.studies.base`).

Importing this package registers the built-in studies: ``paper`` and ``run``
(:mod:`~benchmarks.studies.paper`), ``claims`` (:mod:`~benchmarks.studies.claims`), ``mechanisms``
(:mod:`~benchmarks.studies.mechanisms`), ``ablations`` (:mod:`~benchmarks.studies.ablations`),
``search-layouts``
(:mod:`~benchmarks.studies.layout_search`),
``tracking`` (:mod:`~benchmarks.studies.tracking`), ``planning``
(:mod:`~benchmarks.studies.planning`), ``rl`` (:mod:`~benchmarks.studies.rl`) and
``calibrate-layout``
(:mod:`~benchmarks.studies.calibration`). A new study is one module defining a
:class:`~benchmarks.studies.base.Study` subclass with a ``name``.
"""

from . import ablations, calibration, claims, layout_search, mechanisms, paper, planning, rl, tracking
from .base import COMMANDS, Command, Finished, Run, Study, configure, execute
from .settings import Settings

__all__ = [
    "COMMANDS",
    "Command",
    "Finished",
    "Run",
    "Settings",
    "Study",
    "ablations",
    "calibration",
    "claims",
    "configure",
    "execute",
    "layout_search",
    "mechanisms",
    "paper",
    "planning",
    "rl",
    "tracking",
]
