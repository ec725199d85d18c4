"""``mimo-radar-bench``: the command-line entry point (also ``python -m benchmarks``)."""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

EPILOG = """examples:
  mimo-radar-bench paper --scenario 1 --trials 20 --out runs/paper1
  mimo-radar-bench run --scenario paper-3 --policies mg-crb-cl,discounted-thompson \\
      --agent-param mg-crb-cl.solver=exact --fusion centralized --trials 100 --out runs/mine
  mimo-radar-bench run --scenario my_layout.yaml --policies ucb1,best --steps 200 --out runs/custom

Outputs (docs/benchmark.md): summary.json, curves.csv, table.md and PNG figures in --out.
An interrupted run started again with the same arguments and --out continues where it stopped."""


def _integer(low: int) -> Callable[[str], int]:
    """An argparse type: an integer >= ``low``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}, got {value}")
        return value

    parse.__name__ = f"integer >= {low}"
    return parse


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


def add_env_options(parser: argparse.ArgumentParser) -> None:
    """One flag per env option, with the choices, default and help of :class:`EnvOptions`."""
    from mimo_radar_env import DEFAULT_VERSION, VERSIONS, EnvOptions
    from mimo_radar_env.envs.options import option_choices, option_help

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
        given = argparse.SUPPRESS  # absent unless given: the version's default applies
        if name in choices:
            group.add_argument(flag, choices=choices[name], default=given, help=help_text)
        elif isinstance(defaults[name], bool):
            group.add_argument(flag, action=argparse.BooleanOptionalAction, default=given, help=help_text)
        else:  # measurement_quality, the one numeric option
            group.add_argument(flag, type=_quality, default=given, metavar="NONE|LAMBDA", help=help_text)


def env_options_from(args: argparse.Namespace) -> Any:
    """The :class:`EnvOptions` of parsed arguments."""
    from mimo_radar_env import EnvOptions
    from mimo_radar_env.envs.options import option_names

    given = {name: getattr(args, name) for name in option_names() if hasattr(args, name)}
    return EnvOptions.for_version(args.env_version, **given)


def _over_reading() -> str:
    """How --agent-param combines with the paper study's per-version agent parameters."""
    from mimo_radar_env import VERSIONS

    readings = "; ".join(
        f"{v.name}: "
        + (
            ", ".join(f"{a}.{k}={val}" for a, p in v.paper_agent_params.items() for k, val in p.items())
            or "none"
        )
        for v in VERSIONS.values()
    )
    return f"; over the version's paper-study parameters ({readings})"


def _add_agent_param(parser: argparse.ArgumentParser, over: str = "") -> None:
    parser.add_argument(
        "--agent-param",
        action="append",
        default=[],
        metavar="AGENT.KEY=VALUE",
        help="agent parameter, repeatable, e.g. mg-crb-cl.solver=exact (values read as YAML)" + over,
    )


def study_agent_params(env_version: str, items: Sequence[str]) -> dict[str, dict[str, Any]]:
    """The paper study's agent parameters: the version's reading, then ``--agent-param`` over it
    (key by key, so ``mg-crb-cl.solver_params={rule: xor}`` replaces the reading's solver_params)."""
    from mimo_radar_env import env_version as version_of

    from .harness import parse_agent_params

    params = version_of(env_version).paper_study_params()
    for policy, values in parse_agent_params(items).items():
        params.setdefault(policy, {}).update(values)
    return params


def _add_run_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--trials", type=_integer(1), default=500, help="Monte-Carlo trials (default %(default)s)"
    )
    parser.add_argument(
        "--steps",
        type=_integer(1),
        default=None,
        help="steps per episode (default: the scenario horizon, 1000 for the paper)",
    )
    parser.add_argument(
        "--seed", type=_integer(0), default=0, help="base seed: trial i uses seed + i (default 0)"
    )
    parser.add_argument("--out", required=True, help="output directory (created; reused to resume)")
    parser.add_argument(
        "--shard-size",
        type=_integer(1),
        default=50,
        help="trials per shard; each finished shard is saved at once (default 50)",
    )
    parser.add_argument(
        "--workers",
        type=_integer(1),
        default=None,
        help="local worker processes (default: the number of cores)",
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
    parser.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    add_env_options(parser)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mimo-radar-bench",
        description="Monte-Carlo benchmarks of transmitter/receiver selection for distributed MIMO radar.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", required=True)

    paper = sub.add_parser(
        "paper",
        help="the paper's study: six policies on a paper scenario",
        description="Run best, mg-crb-cl, ucb1, epsilon-greedy, fix1 and fix2 on a paper "
        "scenario with common random numbers and print the table.",
    )
    paper.add_argument(
        "--scenario", type=int, choices=(1, 2, 3), required=True, help="paper scenario 1, 2 or 3"
    )
    _add_agent_param(paper, over=_over_reading())
    _add_run_options(paper)

    run = sub.add_parser(
        "run",
        help="any scenario, any registered policies",
        description="Run registered agents (ppo:PATH for a trained PPO model) on a scenario and "
        "print the table.",
    )
    run.add_argument("--scenario", required=True, help="shipped name (paper-1...) or a YAML/TOML file")
    run.add_argument(
        "--policies",
        required=True,
        help="comma-separated agents (see 'mimo-radar-bench agents') or ppo:PATH/model.zip",
    )
    _add_agent_param(run)
    _add_run_options(run)

    train = sub.add_parser(
        "train-ppo",
        help="train a Stable-Baselines3 PPO policy (needs the rl extra)",
        description="Train PPO on vectorised training envs; saves DIR/model.zip, the "
        "observation normalisation DIR/vecnormalize.npz and DIR/ppo.json. Evaluate it with "
        "'mimo-radar-bench run --policies ppo:DIR/model.zip,...'.",
    )
    train.add_argument(
        "--scenario",
        default=None,
        help="shipped name or YAML/TOML file (default: paper scenario 1 of --env-version, paper-1-v1)",
    )
    train.add_argument(
        "--timesteps",
        type=_integer(1),
        default=None,
        help="environment steps to train for (default: n_timesteps of the hyperparameters)",
    )
    train.add_argument("--out", required=True, help="output directory for the model")
    train.add_argument("--seed", type=_integer(0), default=0, help="training seed (default 0)")
    train.add_argument(
        "--hyperparams",
        default=None,
        help="rl-zoo3-style YAML file (default: the shipped benchmarks/hyperparams/ppo.yml)",
    )
    train.add_argument(
        "--hyperparams-key",
        default=None,
        help="entry of the YAML file to use (default: the flat env id of --env-version, "
        "MimoRadarSelectFlat-v1)",
    )
    train.add_argument(
        "--action",
        choices=("auto", "discrete", "scores"),
        default="auto",
        help="one Discrete action per super arm, or per-station scores (default: auto)",
    )
    train.add_argument("--tensorboard", action="store_true", help="write TensorBoard logs in DIR/tensorboard")
    train.add_argument("--quiet", action="store_true", help="no progress bar")
    add_env_options(train)

    perf = sub.add_parser(
        "perf",
        help="performance figures, each as a ratio to a reference measured in the same run",
        description="Measure the tracker against filterpy, exact vs BPSO, the vector env's "
        "throughput and the wall time of the paper's study; write DIR/perf.json and print a table.",
    )
    perf.add_argument("--out", required=True, help="output directory for perf.json")
    perf.add_argument("--quick", action="store_true", help="small sizes, under a minute (CI smoke test)")
    perf.add_argument(
        "--workers", type=_integer(1), default=None, help="worker processes for the study (default: cores)"
    )

    claims = sub.add_parser(
        "claims",
        help="judge the paper's claims on paper studies (holds / consistent / contradicted)",
        description="Evaluate the paper's claims (docs/results.md) on finished 'paper' runs, or run the "
        "paper studies first (into OUT/paper-N, resumable). Writes OUT/claims.md and OUT/claims.json.",
    )
    claims.add_argument("runs", nargs="*", help="finished paper-study folders (default: run them into --out)")
    claims.add_argument("--scenarios", default="1,2,3", help="paper scenarios to run (default 1,2,3)")
    _add_agent_param(claims, over=_over_reading())
    _add_run_options(claims)

    tracking = sub.add_parser(
        "tracking",
        help="the tracking study: tracking-aware policies beside the SINR-driven ones, and its targets "
        "(default 200 trials)",
        description="Run best, best-tracking, mg-crb-cl, tracking-ucb (and its SINR weights "
        "0.25, 0.5, 0.75), ucb1, epsilon-greedy, fix1, fix2 and random on the paper scenarios under "
        "both fusions (into OUT/<scenario>-<fusion>, resumable); judge the targets on paired "
        "differences; write OUT/targets.md, OUT/targets.json and OUT/tradeoff_paper-N.png.",
    )
    tracking.add_argument("--scenarios", default="1,2,3", help="paper scenarios (default 1,2,3)")
    tracking.add_argument(
        "--fusions", default="average,centralized", help="fusions to run (default average,centralized)"
    )
    tracking.add_argument(
        "--ppo",
        default=None,
        metavar="PATTERN",
        help="also run a trained PPO: its model path with {scenario} and {fusion} filled in, e.g. "
        "runs/ppo-info/paper-{scenario}-{fusion}/model.zip",
    )
    _add_agent_param(tracking, over=_over_reading())
    _add_run_options(tracking)
    from .tracking import DEFAULT_TRIALS

    tracking.set_defaults(trials=DEFAULT_TRIALS)

    calibrate = sub.add_parser(
        "calibrate-layout",
        help="search station layouts under which the most of the paper's claims hold",
        description="Jitter the reference layout into candidates (seeded), reject those that break "
        "the paper's text (region, 2 km from every nominal track, Best's selections in Scenario 1), "
        "rank the rest by noise-free checks, judge the best by short scorecards, then the best of "
        "those and the reference by full scorecards (--trials). Writes OUT/calibration.md and "
        "OUT/calibration.json with every candidate's score; resumable (docs/benchmark.md).",
    )
    from .calibration import CANDIDATES, FINAL, SCREEN, SCREEN_TRIALS

    for flag, default, text in (
        ("--candidates", CANDIDATES, "jittered layouts to draw"),
        ("--screen", SCREEN, "layouts judged by short scorecards"),
        ("--screen-trials", SCREEN_TRIALS, "trials of the short scorecards"),
        ("--final", FINAL, "layouts judged by full scorecards"),
    ):
        calibrate.add_argument(flag, type=_integer(1), default=default, help=f"{text} (default {default})")
    _add_agent_param(calibrate, over=_over_reading())
    _add_run_options(calibrate)

    compare = sub.add_parser(
        "compare-claims",
        help="the verdicts of several scorecards side by side",
        description="Print one row per claim and one verdict column per scorecard "
        "(LABEL=PATH, PATH a claims.json written by 'claims' or 'calibrate-layout', or its folder).",
    )
    compare.add_argument(
        "scorecards", nargs="+", metavar="LABEL=PATH", help="a label and a claims.json (or its folder)"
    )

    sub.add_parser("agents", help="list the registered agents and their parameters")

    demo = sub.add_parser("demo", help="one episode of a scenario with a random policy and the oracle")
    demo.add_argument(
        "--scenario", default="paper-1-v1", help="scenario name or YAML/TOML file (default paper-1-v1)"
    )
    demo.add_argument("--seed", type=_integer(0), default=0, help="episode seed (default 0)")
    demo.add_argument(
        "--steps", type=_integer(1), default=None, help="stop after this many steps (default: the horizon)"
    )
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
    parser = build_parser()
    foreign = foreign_packages()
    if foreign:
        parser.exit(
            2,
            f"mimo-radar-bench: error: another installed distribution provides {', '.join(foreign)}; "
            "mimo-radar-env needs its own 'agents' and 'benchmarks' packages: install it in a "
            "dedicated virtual environment\n",
        )
    args = parser.parse_args(argv)
    from mimo_radar_env import ScenarioError

    from .harness import HarnessError, RunInterrupted

    try:
        return _dispatch(args)
    except RunInterrupted as exc:
        parser.exit(130, f"mimo-radar-bench: {exc}\n")
    except KeyboardInterrupt:
        parser.exit(130, "mimo-radar-bench: interrupted\n")
    except (HarnessError, ScenarioError) as exc:
        parser.exit(2, f"mimo-radar-bench: error: {exc}\n")
    return 0


def _study_runner(args: argparse.Namespace) -> Callable[..., list[Path]]:
    """Run the paper studies of the given scenarios into a folder with the command's options."""
    from .claims import run_studies

    options = env_options_from(args)
    params = study_agent_params(args.env_version, args.agent_param)
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)

    def run(scenarios: Sequence[Any], out: Path, trials: int) -> list[Path]:
        return run_studies(
            scenarios,
            out,
            trials=trials,
            steps=args.steps,
            seed=args.seed,
            shard_size=args.shard_size,
            agent_params=params,
            options=options,
            workers=workers,
            backend=args.backend,
            address=args.address,
            progress=not args.quiet,
            figures=not args.no_figures,
        )

    return run


def _claims(args: argparse.Namespace) -> int:
    from mimo_radar_env import paper_scenario

    from . import claims

    out = Path(args.out)
    runs = [Path(r) for r in args.runs]
    if not runs:
        names = [paper_scenario(n, args.env_version) for n in _paper_numbers(args.scenarios)]
        runs = _study_runner(args)(names, out, args.trials)
    results = claims.judge_studies(runs, args.seed)
    claims.write_scorecard(results, out, claims.describe_studies(runs))
    print((out / "claims.md").read_text())
    return 0


def _paper_numbers(text: str) -> list[int]:
    from .harness import HarnessError

    try:
        numbers = [int(s) for s in text.split(",")]
    except ValueError:
        raise HarnessError(f"--scenarios must list paper scenarios 1, 2, 3, got {text!r}") from None
    if not numbers or not set(numbers) <= {1, 2, 3}:
        raise HarnessError(f"--scenarios must list paper scenarios 1, 2, 3, got {text!r}")
    return numbers


def _tracking(args: argparse.Namespace) -> int:
    from . import tracking
    from .harness import HarnessError

    if hasattr(args, "fusion"):
        raise HarnessError("the tracking study runs each of --fusions; --fusion does not apply")
    fusions = [f.strip() for f in args.fusions.split(",") if f.strip()]
    folders = tracking.run_tracking_studies(
        args.out,
        scenarios=_paper_numbers(args.scenarios),
        fusions=fusions,
        trials=args.trials,
        options=env_options_from(args),
        agent_params=study_agent_params(args.env_version, args.agent_param),
        ppo=args.ppo,
        env_version=args.env_version,
        steps=args.steps,
        seed=args.seed,
        shard_size=args.shard_size,
        workers=args.workers if args.workers is not None else (os.cpu_count() or 1),
        backend=args.backend,
        address=args.address,
        progress=not args.quiet,
        figures=not args.no_figures,
    )
    path = tracking.write_targets(tracking.judge_targets(folders), args.out, folders)
    if not args.no_figures:
        tracking.plot_tradeoff(folders, args.out)
    print(path.read_text())
    return 0


def _compare_claims(args: argparse.Namespace) -> int:
    from . import claims
    from .harness import HarnessError

    scorecards = {}
    for item in args.scorecards:
        label, sep, where = item.partition("=")
        path = Path(where) / "claims.json" if Path(where).is_dir() else Path(where)
        if not sep or not label:
            raise HarnessError(f"scorecards are given as LABEL=PATH, got {item!r}")
        if not path.is_file():
            raise HarnessError(f"{where} is neither a scorecard (.json) nor a folder holding claims.json")
        scorecards[label] = json.loads(path.read_text())
    print(claims.comparison_markdown(scorecards), end="")
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    from . import calibration, claims

    run = _study_runner(args)

    def scorecard(scenarios: Sequence[Any], out: Path, trials: int) -> list[dict[str, Any]]:
        folders = run(scenarios, out, trials)
        results = claims.judge_studies(folders, args.seed)
        claims.write_scorecard(results, out, claims.describe_studies(folders))
        return results

    report = calibration.calibrate(
        Path(args.out),
        scorecard,
        count=args.candidates,
        seed=args.seed,
        screen=args.screen,
        screen_trials=args.screen_trials,
        final=args.final,
        final_trials=args.trials,
        scale=env_options_from(args).lambda_scale,
    )
    print(Path(args.out, "calibration.md").read_text().split("\n\n| layout")[0])
    print(
        f"best layout {report['best']}: {'adopted' if report['adopted'] else 'not adopted'}; "
        f"every candidate in {Path(args.out, 'calibration.md')}"
    )
    return 0


def _dispatch(args: argparse.Namespace) -> int:
    if args.command == "demo":
        from .demo import print_demo, run_demo

        print_demo(run_demo(args.scenario, args.seed, args.steps), args.scenario)
        return 0
    if args.command == "train-ppo":
        from mimo_radar_env import FLAT_ENV_IDS, paper_scenario

        from .harness import HarnessError
        from .ppo import train_ppo

        try:
            meta = train_ppo(
                args.scenario or paper_scenario(1, args.env_version),
                args.timesteps,
                args.out,
                seed=args.seed,
                hyperparams=args.hyperparams,
                hyperparams_key=args.hyperparams_key or FLAT_ENV_IDS[args.env_version],
                action=args.action,
                tensorboard=args.tensorboard,
                progress=not args.quiet,
                options=env_options_from(args),
            )
        except (ValueError, OSError) as exc:
            raise HarnessError(str(exc)) from exc
        print(
            f"trained PPO for {meta['timesteps']} steps in {meta['train_wall_s']:.0f} s; "
            f"saved {Path(args.out, 'model.zip')}"
        )
        return 0
    if args.command == "perf":
        from .harness import HarnessError

        try:
            from .speed.perf import main as perf_main
        except ImportError as exc:
            raise HarnessError(
                "perf is a developer tool that needs a source checkout (benchmarks/speed is not "
                "installed with the package): clone the repository and pip install -e ."
            ) from exc

        perf_main(args.out, quick=args.quick, workers=args.workers)
        return 0
    if args.command == "claims":
        return _claims(args)
    if args.command == "tracking":
        return _tracking(args)
    if args.command == "calibrate-layout":
        return _calibrate(args)
    if args.command == "compare-claims":
        return _compare_claims(args)
    if args.command == "agents":
        import agents

        for name in agents.available_agents():
            print(f"{name:<22}{agents.agent_summary(name)}")
            print(f"{'':<22}parameters: {', '.join(agents.agent_parameters(name)) or '-'}")
        return 0

    from mimo_radar_env import paper_scenario

    from .harness import PAPER_POLICIES, make_config, parse_agent_params, run
    from .report import write_outputs

    if args.command == "paper":
        scenario = paper_scenario(args.scenario, args.env_version)
        policies = list(PAPER_POLICIES)
        params: dict = study_agent_params(args.env_version, args.agent_param)
    else:
        scenario = args.scenario
        policies = [p.strip() for p in args.policies.split(",") if p.strip()]
        params = parse_agent_params(args.agent_param)
    config = make_config(
        scenario,
        policies,
        args.trials,
        args.steps,
        args.seed,
        args.shard_size,
        params,
        options=env_options_from(args),
    )
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    totals = run(
        config,
        args.out,
        workers=workers,
        backend=args.backend,
        address=args.address,
        progress=not args.quiet,
    )
    write_outputs(config, totals, args.out, figures=not args.no_figures)
    print(Path(args.out, "table.md").read_text())
    return 0
