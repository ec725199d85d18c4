"""Monte-Carlo harness, the paper's reproduction, reports, plots and PPO training."""

#: Marks this package as mimo-radar-env's (another distribution may install a ``benchmarks``).
DISTRIBUTION = "mimo-radar-env"


def __getattr__(name: str):
    """``benchmarks.run``: :func:`benchmarks.studies.paper.run_policies` (the ``run`` command as a
    Python call), imported when first asked for (the command line's help imports none of it)."""
    if name == "run":
        from .studies.paper import run_policies

        return run_policies
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
