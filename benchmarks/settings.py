"""The settings of a study, and the command-line arguments they are read from.

:class:`Settings` is the one object a study passes down: how many trials and steps, the seed,
the shards, where and how the tasks run, the env options and the agent parameters. The
arguments every study shares are declared here once (:func:`add_run_arguments`).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mimo_radar_env import DEFAULT_VERSION, VERSIONS, EnvOptions, env_version
from mimo_radar_env.envs.device_forms import DEVICE_MODES
from mimo_radar_env.envs.options import option_choices, option_help, option_names
from mimo_radar_env.envs.versions import version_conflict

from .errors import BenchError
from .outputs import folder
from .resources import DEFAULT_MAX_HOURS, MAX_AUTO_SHARD_SIZE

DEFAULT_TRIALS = 500
#: The most Monte-Carlo trials a study takes (a million trials of the paper study take days).
MAX_TRIALS = 1_000_000


def default_workers() -> int:
    """The cores local workers use when none are given: all of them."""
    return os.cpu_count() or 1


def local_workers(requested: int | None) -> int:
    """The cores local workers use: ``requested``, capped at the machine's cores with a message
    (more compute threads than the cores only share them)."""
    cores = default_workers()
    if requested is None:
        return cores
    if requested > cores:
        print(
            f"mimo-radar-bench: --workers {requested} is more than this machine's {cores} cores; "
            f"using {cores}",
            file=sys.stderr,
        )
        return cores
    return requested


@dataclass(frozen=True)
class Settings:
    """Everything a study's runs share besides their scenarios, policies and folders.

    Attributes
    ----------
    out : Path
        The study's output folder.
    trials, steps, seed : int
        Monte-Carlo trials, steps per episode (None: the scenario's horizon) and the base seed
        (trial ``i`` uses ``seed + i``).
    shard_size : int or None
        Trials per shard (None: :func:`benchmarks.resources.auto_shard_size` for the workers and
        policies).
    workers, threads, backend, address
        The cores the local workers use, the compute threads of each worker process (None: chosen
        from the policies' declared costs, :func:`benchmarks.resources.choose_threads`),
        ``"local"`` or ``"ray"``, and the Ray cluster's address.
    progress, figures : bool
        A progress bar; the PNG figures.
    max_hours : float or None
        Runs estimated to take longer are refused before they start (None: no limit).
    env_version : str
        The env version whose defaults ``options`` start from.
    options : EnvOptions
        The runs' env options (a study may vary some, e.g. the fusion).
    agent_params : dict
        ``{policy: {parameter: value}}``.
    """

    out: Path
    trials: int = DEFAULT_TRIALS
    steps: int | None = None
    seed: int = 0
    shard_size: int | None = None
    workers: int = field(default_factory=default_workers)
    threads: int | None = None
    backend: str = "local"
    address: str | None = None
    progress: bool = True
    figures: bool = True
    max_hours: float | None = DEFAULT_MAX_HOURS
    env_version: str = DEFAULT_VERSION
    options: EnvOptions = field(default_factory=lambda: VERSIONS[DEFAULT_VERSION].options())
    agent_params: dict[str, dict[str, Any]] = field(default_factory=dict)
    device: str | None = None
    device_mode: str = "eager"
    pairs: str = "reference"

    @classmethod
    def from_args(cls, args: argparse.Namespace, paper_study: bool = False) -> Settings:
        """The settings of parsed arguments; ``paper_study`` starts the agent parameters from
        the version's paper study (:func:`study_agent_params`)."""
        items = getattr(args, "agent_param", [])
        params = study_agent_params(args.env_version, items) if paper_study else parse_agent_params(items)
        return cls(
            out=Path(args.out),
            trials=args.trials,
            steps=args.steps,
            seed=args.seed,
            shard_size=args.shard_size,
            workers=1
            if args.device is not None and args.workers is None
            else local_workers(args.workers)
            if args.backend == "local"
            else (args.workers if args.workers is not None else default_workers()),
            threads=args.threads,
            backend=args.backend,
            address=args.address,
            progress=not args.quiet,
            figures=not args.no_figures,
            max_hours=args.max_hours,
            env_version=args.env_version,
            options=env_options_from(args),
            agent_params=params,
            device=args.device,
            device_mode=args.device_mode,
            pairs=args.pairs,
        )

    def execution(self) -> dict[str, Any]:
        """The keywords of :func:`benchmarks.harness.run` besides the configuration and folder."""
        return {
            "workers": self.workers,
            "threads": self.threads,
            "backend": self.backend,
            "address": self.address,
            "device": self.device,
            "device_mode": self.device_mode,
        }


def scenario_for_version(scenario: Any, version: str) -> None:
    """Refuses ``--scenario NAME`` of another version's paper scenarios (or scenario sets) under
    ``--env-version`` (:func:`mimo_radar_env.envs.versions.version_conflict`), in the command
    line's words."""
    conflict = version_conflict(scenario, version)
    if conflict is None:
        return
    other = conflict.version
    hint = f"use --env-version {other.name}"
    if conflict.own is not None:
        hint = f"use {conflict.own!r} or --env-version {other.name}"
    raise BenchError(
        f"--scenario {scenario!r} is a scenario of {other.env_id}, not of --env-version {version}: "
        f"{hint} (a scenario file runs as given under any version)"
    )


# ------------------------------------------------------------------ argument types
#: The largest integer an argument takes (seeds, counts): beyond, a run would never end.
MAX_ARGUMENT = 2**31 - 1


def integer(low: int, why: str = "", high: int = MAX_ARGUMENT) -> Callable[[str], int]:
    """An argparse type: an integer in ``[low, high]`` (``why``: the reason for the lower bound,
    said on refusal)."""
    reason = f" ({why})" if why else ""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}{reason}, got {value}")
        if value > high:
            raise argparse.ArgumentTypeError(f"must be an integer <= {high:,}, got {value:,}")
        return value

    parse.__name__ = f"integer >= {low}"
    return parse


def hours(text: str) -> float | None:
    """An argparse type: a positive number of hours, or ``none`` (no limit)."""
    if text.lower() == "none":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number of hours > 0 or 'none', got {text!r}") from None
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"must be a number of hours > 0 or 'none', got {text!r}")
    return value


def _quality(text: str) -> float | None:
    if text.lower() == "none":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'none' or a number > 0, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected 'none' or a finite number > 0, got {text!r}")
    return value


def add_scenarios_argument(parser: argparse.ArgumentParser) -> None:
    """``--scenarios``, read by :func:`paper_numbers`."""
    parser.add_argument("--scenarios", default="1,2,3", help="paper scenarios to run (default 1,2,3)")


def comma_list(flag: str, text: str) -> list[str]:
    """A comma-separated argument's entries, stripped; an empty entry (``a,,b``, a trailing
    comma) is refused, not dropped."""
    entries = [entry.strip() for entry in text.split(",")]
    if not all(entries):
        raise BenchError(f"{flag} has an empty entry in {text!r}: separate the names by single commas")
    return entries


def paper_numbers(text: str) -> list[int]:
    """``"1,3"`` -> ``[1, 3]``: paper scenarios."""
    try:
        numbers = [int(s) for s in text.split(",")]
    except ValueError:
        raise BenchError(f"--scenarios must list paper scenarios 1, 2, 3, got {text!r}") from None
    if not numbers or not set(numbers) <= {1, 2, 3}:
        raise BenchError(f"--scenarios must list paper scenarios 1, 2, 3, got {text!r}")
    if len(set(numbers)) != len(numbers):
        raise BenchError(f"--scenarios lists a scenario twice: {text!r}")
    return numbers


# ------------------------------------------------------------------ env options
def add_env_options(parser: argparse.ArgumentParser) -> None:
    """``--env-version`` and one flag per env option, with the choices, default and help of
    :class:`EnvOptions` (absent unless given: the version's default applies)."""
    defaults, choices = EnvOptions().to_dict(), option_choices()
    group = parser.add_argument_group("env options (MimoRadarSelect keywords)")
    group.add_argument(
        "--env-version",
        choices=sorted(VERSIONS),
        default=DEFAULT_VERSION,
        help="MimoRadarSelect version whose defaults the options start from: "
        + "; ".join(f"{v.name}: {v.summary}" for v in VERSIONS.values())
        + " (default %(default)s)",
    )
    for name, text in option_help().items():
        flag = "--" + name.replace("_", "-")
        versions = ", ".join(
            f"{v.name}: {v.option_defaults.get(name, defaults[name])}" for v in VERSIONS.values()
        )
        help_text = f"{text} (default {versions})"
        given = argparse.SUPPRESS
        if name in choices:
            group.add_argument(flag, choices=choices[name], default=given, help=help_text)
        elif isinstance(defaults[name], bool):
            group.add_argument(flag, action=argparse.BooleanOptionalAction, default=given, help=help_text)
        else:  # measurement_quality, the one numeric option
            group.add_argument(flag, type=_quality, default=given, metavar="NONE|LAMBDA", help=help_text)


def env_options_from(args: argparse.Namespace) -> EnvOptions:
    """The :class:`EnvOptions` of parsed arguments; a combination the options refuse
    (``--reward information --no-tracking``) is a :class:`BenchError` in the flags' words."""
    given = {name: getattr(args, name) for name in option_names() if hasattr(args, name)}
    try:
        return env_version(args.env_version).options(**given)
    except ValueError as exc:
        names = "|".join(option_names())
        flagged = re.sub(rf"\b({names})=", lambda m: "--" + m.group(1).replace("_", "-") + "=", str(exc))
        raise BenchError(f"env options: {flagged}") from None


# ------------------------------------------------------------------ agent parameters
def parse_agent_params(items: Iterable[str]) -> dict[str, dict[str, Any]]:
    """``["mg-crb-cl.beta=1.5", "ucb1.solver=bpso"]`` -> ``{"mg-crb-cl": {"beta": 1.5}, ...}``.

    Values are read as YAML scalars (numbers, booleans, lists, strings).
    """
    import yaml

    params: dict[str, dict[str, Any]] = {}
    for item in items:
        if "=" not in item or "." not in item.split("=", 1)[0]:
            raise BenchError(f"--agent-param must look like agent.key=value, got {item!r}")
        target, raw = item.split("=", 1)
        policy, key = target.rsplit(".", 1)
        try:
            params.setdefault(policy, {})[key] = yaml.safe_load(raw)
        except yaml.YAMLError as exc:
            problem = getattr(exc, "problem", None) or "not valid YAML"
            raise BenchError(f"--agent-param {item!r}: the value is {problem}") from None
    return params


#: The agent parameters of each env version's paper study (``mimo-radar-bench paper`` and the
#: studies built on it): v1 reads eq21 as the standard BPSO position rule (docs/model.md,
#: section 13). The env versions themselves hold no agent parameters.
PAPER_AGENT_PARAMS: dict[str, dict[str, dict[str, Any]]] = {
    "v0": {},
    "v1": {"mg-crb-cl": {"solver_params": {"rule": "set"}}},
}


def paper_study_params(version: str) -> dict[str, dict[str, Any]]:
    """A copy of :data:`PAPER_AGENT_PARAMS` of env version ``version``."""
    env_version(version)  # a version that does not exist is named
    return {agent: dict(values) for agent, values in PAPER_AGENT_PARAMS[version].items()}


def study_agent_params(version: str, items: Sequence[str]) -> dict[str, dict[str, Any]]:
    """The paper study's agent parameters: the version's, then ``--agent-param`` over them
    (key by key, so ``mg-crb-cl.solver_params={rule: xor}`` replaces v1's solver_params)."""
    params = paper_study_params(version)
    for policy, values in parse_agent_params(items).items():
        params.setdefault(policy, {}).update(values)
    return params


def _over_paper_study() -> str:
    readings = "; ".join(
        f"{v.name}: "
        + (
            ", ".join(f"{a}.{k}={val}" for a, p in PAPER_AGENT_PARAMS[v.name].items() for k, val in p.items())
            or "none"
        )
        for v in VERSIONS.values()
    )
    return f"; over the version's paper-study parameters ({readings})"


def add_agent_param(parser: argparse.ArgumentParser, paper_study: bool = False) -> None:
    parser.add_argument(
        "--agent-param",
        action="append",
        default=[],
        metavar="AGENT.KEY=VALUE",
        help="agent parameter, repeatable, e.g. mg-crb-cl.solver=exact (values read as YAML)"
        + (_over_paper_study() if paper_study else ""),
    )


# ------------------------------------------------------------------ a study's shared arguments
def add_max_hours(parser: argparse.ArgumentParser) -> None:
    """``--max-hours``: the longest a command may be estimated to take before it starts."""
    parser.add_argument(
        "--max-hours",
        type=hours,
        default=DEFAULT_MAX_HOURS,
        metavar="H",
        help="refuse to start what is estimated (from declared costs, on a machine like the "
        "developers') to take longer; 'none': no limit (default %(default)s)",
    )


def trial_count(low: int) -> Callable[[str], int]:
    """An argparse type: a number of trials from ``low`` (above 1: the trials a paired 95 %
    interval needs) to ``MAX_TRIALS``."""
    return integer(low, f"a paired 95 % interval needs {low} trials or more" if low > 1 else "", MAX_TRIALS)


def add_run_arguments(
    parser: argparse.ArgumentParser, trials: int = DEFAULT_TRIALS, min_trials: int = 1
) -> None:
    """The arguments every study shares: trials, steps, seed, --out, shards, workers, backend,
    figures, progress and the env options (a study that judges paired intervals needs
    ``min_trials`` = ``uncertainty.MIN_INTERVAL_TRIALS``)."""
    parser.add_argument(
        "--trials",
        type=trial_count(min_trials),
        default=trials,
        help=f"Monte-Carlo trials, at least {min_trials} (default %(default)s)",
    )
    parser.add_argument(
        "--steps",
        type=integer(1),
        default=None,
        help="steps per episode (default: the scenario horizon, 1000 for the paper)",
    )
    parser.add_argument(
        "--seed", type=integer(0), default=0, help="base seed: trial i uses seed + i (default 0)"
    )
    parser.add_argument(
        "--out", required=True, type=folder, help="output directory (created; reused to resume)"
    )
    parser.add_argument(
        "--shard-size",
        type=integer(1),
        default=None,
        help="trials per shard; each finished shard is saved at once (default: each policy's trials "
        f"in the fewest shards that keep every worker busy, at most {MAX_AUTO_SHARD_SIZE})",
    )
    parser.add_argument(
        "--workers",
        type=integer(1),
        default=None,
        help="cores the local workers use (default: all of them; with --device, 1: this process), as "
        "worker processes of --threads compute threads each",
    )
    parser.add_argument(
        "--threads",
        type=integer(1),
        default=None,
        help="compute threads of each worker process, at most --workers (default: chosen from the "
        "policies' declared costs, said when more than one; the numbers are the same)",
    )
    parser.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="'local' processes (default) or a Ray cluster ('ray')",
    )
    parser.add_argument(
        "--address", default=None, help="Ray cluster address (default: start a local Ray instance)"
    )
    parser.add_argument(
        "--device",
        default=None,
        help="run the tasks on torch on this device ('cuda', 'cuda:1', 'cpu'), in this process or in "
        "--workers processes sharing it: numpy's numbers to rounding; a policy's trials are one "
        "batch unless --shard-size; no --max-hours (a CPU estimate) (default: numpy, no torch)",
    )
    parser.add_argument(
        "--device-mode",
        choices=DEVICE_MODES,
        default="eager",
        help="the form of each step on --device: 'eager' (default), 'graph' (one CUDA graph per "
        "step) or 'compiled' (torch.compile); the same numbers",
    )
    add_max_hours(parser)
    parser.add_argument(
        "--pairs",
        choices=("reference", "all"),
        default="reference",
        help="the paired differences table.md and the terminal show: the first policy's against each "
        "other one (default), or every pair (summary.json holds every pair)",
    )
    parser.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    add_env_options(parser)
