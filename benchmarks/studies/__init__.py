"""The studies group of ``mimo-radar-bench``: the paper's reproduction and this project's own
studies, each a :class:`~benchmarks.study.Study` on the one engine.

``claims`` and ``compare-claims`` (:mod:`~benchmarks.studies.claims`), ``mechanisms``
(:mod:`~benchmarks.studies.mechanisms`), ``ablations`` (:mod:`~benchmarks.studies.ablations`),
``search-layouts`` (:mod:`~benchmarks.studies.layout_search`), ``calibrate-layout``
(:mod:`~benchmarks.studies.calibration`), ``tracking`` (:mod:`~benchmarks.studies.tracking`),
``planning`` (:mod:`~benchmarks.studies.planning`) and ``rl`` (:mod:`~benchmarks.studies.rl`),
each listed in the command line's registry (:data:`benchmarks.cli.COMMANDS`). They run from a
source checkout: the wheel leaves this package out, as it does the speed suite and the docs'
tooling. The first steps' studies, ``paper`` and ``run``, are :mod:`benchmarks.paper`; a study of
one's own is one module defining a :class:`~benchmarks.study.Study` and calling
:func:`benchmarks.cli.register_command`.
"""
