"""``mimo-radar-bench``: the command-line entry point (also ``python -m benchmarks``).

Its subcommands are listed in one explicit registry, :data:`COMMANDS`: a name, the group its
help lists it under, a one-line help and where its :class:`Command` class lives
(``"module:Class"``). The registry imports nothing: ``--help`` and a mistyped command name
answer before numpy, numba, scipy, torch or matplotlib are imported, and a command's own module
is imported only when that command is named. A failure a command can name is one line on
standard error and exit code 2.

A study of one's own is one module defining a :class:`~benchmarks.study.Study` and
calling :func:`register_command`; ``mimo-radar-bench --import MODULE NAME ...`` imports it
first (as rl-zoo3's ``--gym-packages`` does).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import importlib.util
import os
import signal
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

PROG = "mimo-radar-bench"
#: The help's groups, in the order it lists them.
GROUPS = ("first steps", "studies", "maintenance")

EPILOG = """examples:
  mimo-radar-bench demo
  mimo-radar-bench paper --scenario 1 --trials 20 --out runs/paper1
  mimo-radar-bench run --scenario paper-3-v1 --policies mg-crb-cl,discounted-thompson \\
      --agent-param mg-crb-cl.solver=exact --fusion centralized --trials 100 --out runs/mine
  mimo-radar-bench run --scenario my_layout.yaml --policies ucb1,best --steps 200 --out runs/custom

Outputs (docs/benchmark.md): summary.json, curves.csv, table.md and PNG figures in --out.
An interrupted run started again with the same arguments and --out continues where it stopped.
'mimo-radar-bench COMMAND --help' lists a command's options."""


class Command:
    """A subcommand of ``mimo-radar-bench``.

    Subclasses set :attr:`name` (the registry's key), optionally :attr:`description` (the
    registry's help line stands in for it), declare their arguments in :meth:`add_arguments`
    and run in :meth:`main`.
    """

    name: ClassVar[str] = ""
    description: ClassVar[str | None] = None
    #: What the command keeps when it is stopped (Ctrl-C, SIGTERM) outside a run's tasks, whose
    #: own message says what they saved: said after ``interrupted``.
    when_stopped: ClassVar[str | None] = None

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Declare the command's arguments."""

    def main(self) -> int:
        """Run the command; its exit code."""
        raise NotImplementedError


@dataclass(frozen=True)
class CommandEntry:
    """A registered command: its group in the help, its one-line help, its class as
    ``"module:Class"`` (imported by :meth:`load` only when the command runs), and whether it runs
    tasks on worker processes (``runs_tasks``: a study's ``--workers``, ``--backend`` and
    ``--device``; their fork server then starts as the command is named, :func:`main`)."""

    name: str
    group: str
    help: str
    target: str
    runs_tasks: bool = False

    @property
    def installed(self) -> bool:
        """Whether the command's module is here: the wheel leaves the studies and the maintenance
        commands out (they run from a source checkout). Asked without importing the module."""
        try:
            return importlib.util.find_spec(self.target.partition(":")[0]) is not None
        except ModuleNotFoundError:
            return False

    def load(self) -> type[Command]:
        module, _, attribute = self.target.partition(":")
        try:
            cls = getattr(importlib.import_module(module), attribute)
        except ModuleNotFoundError as exc:
            if exc.name is None or not module.startswith(exc.name):
                raise
            raise SystemExit(
                f"{PROG}: error: '{self.name}' runs from a source checkout of mimo-radar-env (git clone, "
                f"then pip install -e .): its module {module} is not installed here"
            ) from None
        if not (isinstance(cls, type) and issubclass(cls, Command)):
            raise TypeError(f"command {self.name!r}: {self.target} is not a Command class")
        return cls


_BUILT_IN = (
    ("demo", "first steps", "one episode of a scenario with a random policy and the oracle", "commands:Demo"),
    ("agents", "first steps", "list the registered agents and their parameters", "commands:Agents"),
    (
        "paper",
        "first steps",
        "the paper's study: six policies on a paper scenario",
        "paper:PaperStudy",
    ),
    ("run", "first steps", "any scenario, any registered policies", "paper:RunStudy"),
    (
        "compile",
        "first steps",
        "compile every numba kernel once into numba's cache, so that no run compiles (fast extra)",
        "commands:Compile",
    ),
    (
        "train-ppo",
        "first steps",
        "train PPO, MaskablePPO or RecurrentPPO, one seed or several (needs the rl extra)",
        "commands:TrainPPO",
    ),
    (
        "claims",
        "studies",
        "judge the paper's claims on paper studies (holds / consistent / contradicted)",
        "studies.claims:ClaimsStudy",
    ),
    (
        "compare-claims",
        "studies",
        "the verdicts of several scorecards side by side",
        "studies.claims:CompareClaims",
    ),
    (
        "tracking",
        "studies",
        "the tracking study: tracking-aware policies beside the SINR-driven ones, and its targets",
        "studies.tracking:TrackingStudy",
    ),
    (
        "planning",
        "studies",
        "the planning study: looking ahead in tracking, against the one-step policies and the best bound",
        "studies.planning:PlanningStudy",
    ),
    (
        "rl",
        "studies",
        "the RL study: PPO, MaskablePPO and RecurrentPPO over several seeds beside the bandits",
        "studies.rl:RLStudy",
    ),
    (
        "mechanisms",
        "studies",
        "measure why the paper's ASR and ARMSE claims fail under v1 (gap, sampling oracles, bound vs SINR)",
        "studies.mechanisms:MechanismsStudy",
    ),
    (
        "ablations",
        "studies",
        "the learners with one parameter changed, paired with v1's paper study: mechanisms of "
        "S1.7, S1.8, S2.2 and MG-CRB-CL's ASR",
        "studies.ablations:AblationsStudy",
    ),
    (
        "calibrate-layout",
        "studies",
        "search station layouts under which the most of the paper's claims hold",
        "studies.calibration:CalibrationStudy",
    ),
    (
        "search-layouts",
        "studies",
        "differential evolution over every layout the paper's text allows, then full scorecards",
        "studies.layout_search:LayoutSearch",
    ),
    (
        "docs",
        "maintenance",
        "regenerate the docs' tables and numbers from the committed artefacts (--check: compare only)",
        "docs_tooling.pages:DocsCommand",
    ),
    (
        "model-figures",
        "maintenance",
        "measure the figures docs/model.md and docs/agents.md quote (solvers, tracker, bound)",
        "docs_tooling.model_figures:ModelFigures",
    ),
    (
        "perf",
        "maintenance",
        "performance figures, each as a ratio to a reference measured in the same run",
        "speed.perf:Perf",
    ),
)
#: The built-in commands that run tasks on worker processes (tested against their options).
_RUNS_TASKS = frozenset(
    ("paper", "run", "claims", "tracking", "planning", "rl", "ablations")
    + ("calibrate-layout", "search-layouts")
)
#: Every command, by name, in the help's order within its group.
COMMANDS: dict[str, CommandEntry] = {
    name: CommandEntry(name, group, help, f"benchmarks.{target}", name in _RUNS_TASKS)
    for name, group, help, target in _BUILT_IN
}


def register_command(
    name: str, target: str, help: str, group: str = "studies", runs_tasks: bool = False
) -> None:
    """Add a command of one's own (``target``: ``"module:Class"``) to :data:`COMMANDS`;
    ``runs_tasks`` for a study whose tasks run on worker processes (:class:`CommandEntry`)."""
    if group not in GROUPS:
        raise ValueError(f"group must be one of {list(GROUPS)}, got {group!r}")
    if name in COMMANDS and COMMANDS[name].target != target:
        raise ValueError(f"two commands are called {name!r}: {COMMANDS[name].target} and {target}")
    COMMANDS[name] = CommandEntry(name, group, help, target, runs_tasks)


class OneLineParser(argparse.ArgumentParser):
    """argparse with its refusals on one line (the usage is one ``--help`` away)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


#: How the help marks commands whose module is not installed (a wheel without the studies).
NOT_INSTALLED = "from a source checkout, not installed here"


def _listing() -> str:
    width = max(len(name) for name in COMMANDS) + 2
    lines = []
    for group in GROUPS:
        entries = [entry for entry in COMMANDS.values() if entry.group == group]
        if entries:
            installed = {entry.name: entry.installed for entry in entries}
            none_here = not any(installed.values())
            lines.append(f"{group} ({NOT_INSTALLED}):" if none_here else f"{group}:")
            lines += [
                f"  {entry.name:<{width}}{entry.help}"
                + ("" if installed[entry.name] or none_here else f" ({NOT_INSTALLED})")
                for entry in entries
            ]
            lines.append("")
    return "\n".join(lines)


def build_parser(commands: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The command line's parser, with the arguments of ``commands`` (default: every command;
    their modules are imported) and only the names of the others."""
    parser = OneLineParser(
        prog=PROG,
        description="Monte-Carlo benchmarks of transmitter/receiver selection for distributed MIMO radar.\n\n"
        + _listing(),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--import",
        dest="imports",
        action="append",
        default=[],
        metavar="MODULE",
        help="import MODULE first (a module of one's own that calls register_command)",
    )
    sub = parser.add_subparsers(
        dest="command",
        required=True,
        metavar="COMMAND",
        help="one of the commands above",
        parser_class=OneLineParser,
    )
    chosen = set(COMMANDS) if commands is None else set(commands)
    for entry in COMMANDS.values():
        if entry.name not in chosen:
            sub.add_parser(entry.name, add_help=False)
            continue
        command = entry.load()
        child = sub.add_parser(entry.name, description=command.description or entry.help)
        command.add_arguments(child)
        child.set_defaults(command_class=command)
    return parser


def _leading(argv: list[str]) -> tuple[list[str], str | None]:
    """The ``--import MODULE`` (or ``--import=MODULE``) modules named before the command, and the
    command: the first word that is neither an option nor an option's value."""
    imports, expect_module = [], False
    for word in argv:
        if expect_module:
            imports.append(word)
            expect_module = False
        elif word == "--import":
            expect_module = True
        elif word.startswith("--import="):
            imports.append(word.partition("=")[2])
        elif not word.startswith("-"):
            return imports, word
    return imports, None


def _import_modules(modules: list[str]) -> None:
    """Import the modules of one's own that register commands."""
    for module in modules:
        try:
            importlib.import_module(module)
        except ImportError as exc:
            raise SystemExit(f"{PROG}: error: --import {module}: {exc}") from None


def foreign_packages() -> list[str]:
    """The top-level packages of mimo-radar-env that resolve to another distribution's package.

    ``agents`` and ``benchmarks`` are common names (openai-agents installs an ``agents``
    package; torchrl a top-level ``benchmarks`` folder); in one environment they collide.
    Each package's ``__init__.py`` is read for mimo-radar-env's marker, not imported.
    """
    foreign = []
    for name in ("agents", "benchmarks"):
        spec = importlib.util.find_spec(name)
        if spec is None or spec.origin is None:
            foreign.append(f"{name} (cannot be imported)")
            continue
        try:
            marked = 'DISTRIBUTION = "mimo-radar-env"' in Path(spec.origin).read_text()
        except OSError:
            marked = False
        if not marked:
            where = spec.origin or list(spec.submodule_search_locations or [])
            foreign.append(f"{name} (resolves to {where})")
    return foreign


def program() -> None:
    """The ``mimo-radar-bench`` program (and ``python -m benchmarks``): :func:`main`, where the
    process's teardown after an interrupt (:data:`INTERRUPTED_CODES`) is bounded by
    :data:`INTERRUPTED_TEARDOWN_S`. :func:`main` called from Python (a test, a notebook) leaves
    the caller's process alone."""
    try:
        code = main()
    except SystemExit as exc:
        if exc.code in INTERRUPTED_CODES:
            _exit_within(INTERRUPTED_TEARDOWN_S, exc.code)
        raise
    raise SystemExit(code)


def main(argv: Sequence[str] | None = None) -> int:
    foreign = foreign_packages()
    if foreign:
        print(
            f"{PROG}: error: another installed distribution provides {', '.join(foreign)}; "
            "mimo-radar-env needs its own 'agents' and 'benchmarks' packages: install it in a "
            "dedicated virtual environment",
            file=sys.stderr,
        )
        raise SystemExit(2)
    argv = list(sys.argv[1:] if argv is None else argv)
    if os.getcwd() not in sys.path and "" not in sys.path:
        # a user's module in the current folder (--policies mymodule:MyAgent, --import), as under
        # `python -m benchmarks`, which puts it first; last here, so installed packages win
        sys.path.append(os.getcwd())
    imports, name = _leading(argv)
    _import_modules(imports)
    if name in COMMANDS and COMMANDS[name].runs_tasks:
        _start_workers_early(argv)
    parser = build_parser([name] if name in COMMANDS else [])
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # named with the command they were given to, whose --help lists its arguments
        where = f"{PROG} {args.command}"
        parser.exit(
            2, f"{where}: error: unrecognized arguments: {' '.join(unknown)} (see '{where} --help')\n"
        )
    return run(parser, args)


def run(parser: argparse.ArgumentParser, args: Any) -> int:
    """Run the parsed command; its failures as one line and an exit code."""
    from mimo_radar_env import ScenarioError

    from .errors import BenchError, HarnessError
    from .harness import RunInterrupted

    if _starts_local_workers(args):
        from .backends import start_fork_server

        # the workers' imports, while the command checks and plans its runs
        start_fork_server(device=getattr(args, "device", None) is not None)
    terminated: list[int] = []
    previous = _stop_on_sigterm(terminated)
    try:
        return args.command_class(args).main()
    except RunInterrupted as exc:
        parser.exit(
            INTERRUPTED_CODES[bool(terminated)],
            f"{PROG}: {'terminated (SIGTERM), ' if terminated else ''}{exc}\n",
        )
    except KeyboardInterrupt:
        note = args.command_class.when_stopped
        stopped = "terminated (SIGTERM)" if terminated else "interrupted"
        parser.exit(INTERRUPTED_CODES[bool(terminated)], f"{PROG}: {stopped}{f'; {note}' if note else ''}\n")
    except (BenchError, ScenarioError) as exc:
        message = exc.for_command_line() if isinstance(exc, HarnessError) else str(exc)
        parser.exit(2, f"{PROG}: error: {message}\n")
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    return 0


#: The exit codes of a command stopped by Ctrl-C (SIGINT) and by SIGTERM, in that order.
INTERRUPTED_CODES = (130, 143)
#: Seconds the interpreter's teardown may take after an interrupt (joining the pool's threads and
#: processes, the finalizers), the finished tasks saved and the message written before it starts.
INTERRUPTED_TEARDOWN_S = 5.0


def _exit_within(seconds: float, code: int) -> None:
    """Exit with ``code`` after ``seconds`` even where the teardown has not ended (a thread or
    process that does not stop must not hold a stopped command), with one line saying so."""

    def force() -> None:
        time.sleep(seconds)
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.write(
                f"{PROG}: exited {seconds:g} s after the interrupt, without waiting for "
                "what had not stopped\n"
            )
            sys.stderr.flush()
        os._exit(code)

    threading.Thread(target=force, daemon=True, name="teardown-limit").start()


def _stop_on_sigterm(terminated: list[int]) -> Any:
    """Stop the command on SIGTERM as on Ctrl-C (a batch scheduler's time limit, ``kill``, ``timeout``):
    the finished tasks are saved and the command says how to resume. Appends the signal to
    ``terminated``; the handler it replaced (None off the main thread, where none can be set)."""

    command = os.getpid()

    def stop(signum: int, frame: Any) -> None:
        if os.getpid() != command:  # a process forked with this handler (a scipy pool's): ends as by default
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        terminated.append(signum)
        raise KeyboardInterrupt

    try:
        return signal.signal(signal.SIGTERM, stop)
    except ValueError:  # not the main thread
        return None


class _EarlyParser(argparse.ArgumentParser):
    """A first reading of a few options, silent where the full parse will speak."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise ValueError(message)


def _start_workers_early(argv: list[str]) -> None:
    """Start the workers' fork server as a command that runs tasks is named, from a first reading
    of its ``--workers``, ``--backend`` and ``--device`` (:func:`_starts_local_workers`): it imports
    what a task needs while this process imports the command's module and parses, checks and
    plans its runs. ``--help``, or an option the first reading cannot read, starts nothing here
    (:func:`run` starts it after the full parse where it is wanted)."""
    if "-h" in argv or "--help" in argv:
        return
    early = _EarlyParser(add_help=False)
    early.add_argument("--workers", type=int, default=None)
    early.add_argument("--backend", default="local")
    early.add_argument("--device", default=None)
    try:
        args, _ = early.parse_known_args(argv)
    except ValueError:
        return
    if _starts_local_workers(args):
        from .backends import start_fork_server

        start_fork_server(device=args.device is not None)


def _starts_local_workers(args: Any) -> bool:
    """Whether the command may run its tasks on local worker processes: a run or study on the
    local backend with more than one worker (by default the machine's cores; one on a device)."""
    on_device = getattr(args, "device", None) is not None
    workers = getattr(args, "workers", None) or (1 if on_device else os.cpu_count() or 1)
    return getattr(args, "backend", None) == "local" and workers > 1
