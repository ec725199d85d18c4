"""``mimo-radar-bench``: the command-line entry point."""

from __future__ import annotations

import argparse
from collections.abc import Sequence


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mimo-radar-bench",
        description="Benchmarks for transmitter/receiver selection in distributed MIMO radar.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="run one episode of a scenario with a random policy and the oracle")
    demo.add_argument(
        "--scenario", default="paper-1", help="scenario name or YAML/TOML file (default paper-1)"
    )
    demo.add_argument("--seed", type=int, default=0, help="episode seed (default 0)")
    demo.add_argument(
        "--steps", type=int, default=None, help="stop after this many steps (default: the horizon)"
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.command == "demo":
        from .demo import print_demo, run_demo

        print_demo(run_demo(args.scenario, args.seed, args.steps), args.scenario)
    return 0
