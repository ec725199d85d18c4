"""The Monte-Carlo harness, its command line, the study engine, reports, plots and PPO training.

A source checkout also holds the studies (:mod:`benchmarks.studies`, the paper's reproduction
among them), the speed suite (:mod:`benchmarks.speed`) and the docs' tooling
(:mod:`benchmarks.docs_tooling`); the wheel leaves those three out."""

#: Marks this package as mimo-radar-env's (another distribution may install a ``benchmarks``).
DISTRIBUTION = "mimo-radar-env"


def __getattr__(name: str):
    """``benchmarks.run``: :func:`benchmarks.paper.run_policies` (the ``run`` command as a
    Python call), imported when first asked for (the command line's help imports none of it)."""
    if name == "run":
        from .paper import run_policies

        return run_policies
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
