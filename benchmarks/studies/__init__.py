"""The studies of ``mimo-radar-bench``, on one engine (:mod:`benchmarks.studies.base`).

The built-in studies are ``paper`` and ``run`` (:mod:`~benchmarks.studies.paper`), ``claims``
(:mod:`~benchmarks.studies.claims`), ``mechanisms`` (:mod:`~benchmarks.studies.mechanisms`),
``ablations`` (:mod:`~benchmarks.studies.ablations`), ``search-layouts``
(:mod:`~benchmarks.studies.layout_search`), ``tracking`` (:mod:`~benchmarks.studies.tracking`),
``planning`` (:mod:`~benchmarks.studies.planning`), ``rl`` (:mod:`~benchmarks.studies.rl`) and
``calibrate-layout`` (:mod:`~benchmarks.studies.calibration`), each listed in the command
line's registry (:data:`benchmarks.cli.COMMANDS`). A new study is one module defining a
:class:`~benchmarks.studies.base.Study` subclass and calling
:func:`benchmarks.cli.register_command`.
"""

from .base import Finished, Run, Study, configure, execute
from .settings import Settings

__all__ = ["Finished", "Run", "Settings", "Study", "configure", "execute"]
