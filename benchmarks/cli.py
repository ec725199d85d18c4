"""``mimo-radar-bench``: the command-line entry point (also ``python -m benchmarks``).

Its subcommands are the registered commands and studies (:mod:`benchmarks.studies.base`): the
parser is built from their declarations and each runs itself; a failure it can name is one
line on standard error and exit code 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

EPILOG = """examples:
  mimo-radar-bench paper --scenario 1 --trials 20 --out runs/paper1
  mimo-radar-bench run --scenario paper-3 --policies mg-crb-cl,discounted-thompson \\
      --agent-param mg-crb-cl.solver=exact --fusion centralized --trials 100 --out runs/mine
  mimo-radar-bench run --scenario my_layout.yaml --policies ucb1,best --steps 200 --out runs/custom

Outputs (docs/benchmark.md): summary.json, curves.csv, table.md and PNG figures in --out.
An interrupted run started again with the same arguments and --out continues where it stopped."""


class OneLineParser(argparse.ArgumentParser):
    """argparse with its refusals on one line (the usage is one ``--help`` away)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """The parser of every registered command, in their order."""
    from . import commands, doctables, model_figures, studies  # noqa: F401  (importing them registers the commands)
    from .studies.base import COMMANDS

    parser = OneLineParser(
        prog="mimo-radar-bench",
        description="Monte-Carlo benchmarks of transmitter/receiver selection for distributed MIMO radar.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for command in sorted(COMMANDS.values(), key=lambda c: c.order):
        child = sub.add_parser(
            command.name, help=command.help, description=command.description or command.help
        )
        command.add_arguments(child)
        child.set_defaults(command_class=command)
    return parser


def foreign_packages() -> list[str]:
    """The top-level packages of mimo-radar-env that resolve to another distribution's package.

    ``agents`` and ``benchmarks`` are common names (openai-agents installs an ``agents``
    package; torchrl a top-level ``benchmarks`` folder); in one environment they collide.
    """
    import importlib

    foreign = []
    for name in ("agents", "benchmarks"):
        try:
            module = importlib.import_module(name)
        except ImportError:
            foreign.append(f"{name} (cannot be imported)")
            continue
        if getattr(module, "DISTRIBUTION", None) != "mimo-radar-env":
            where = getattr(module, "__file__", None) or list(getattr(module, "__path__", []))
            foreign.append(f"{name} (resolves to {where})")
    return foreign


def main(argv: Sequence[str] | None = None) -> int:
    foreign = foreign_packages()
    if foreign:
        print(
            f"mimo-radar-bench: error: another installed distribution provides {', '.join(foreign)}; "
            "mimo-radar-env needs its own 'agents' and 'benchmarks' packages: install it in a "
            "dedicated virtual environment",
            file=sys.stderr,
        )
        raise SystemExit(2)
    parser = build_parser()
    args = parser.parse_args(argv)
    from mimo_radar_env import ScenarioError

    from .errors import BenchError
    from .harness import RunInterrupted

    try:
        return args.command_class(args).main()
    except RunInterrupted as exc:
        parser.exit(130, f"mimo-radar-bench: {exc}\n")
    except KeyboardInterrupt:
        parser.exit(130, "mimo-radar-bench: interrupted\n")
    except (BenchError, ScenarioError) as exc:
        parser.exit(2, f"mimo-radar-bench: error: {exc}\n")
    return 0
