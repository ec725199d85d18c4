"""Monte-Carlo harness, the paper's reproduction, reports, plots and PPO training."""

#: Marks this package as mimo-radar-env's (another distribution may install a ``benchmarks``).
DISTRIBUTION = "mimo-radar-env"
