"""The first steps of ``mimo-radar-bench`` that are not studies: ``train-ppo``, ``agents``,
``demo`` and ``compile``."""

from __future__ import annotations

import argparse
import sys

from agents.ppo import LEARNER_NAMES, LEARNERS, TORCH_PPO
from mimo_radar_env import DEFAULT_VERSION, VERSIONS
from mimo_radar_env.envs.device_forms import DEVICE_MODES

from .cli import Command
from .errors import BenchError
from .outputs import folder
from .settings import add_env_options, add_max_hours, env_options_from, integer


class TrainPPO(Command):
    name = "train-ppo"
    description = (
        "Train a learner (--algo) on the native vector env; saves DIR/model.zip (torch-ppo: "
        "DIR/model.pt), the observation normalisation (DIR/vecnormalize.npz, and SB3's "
        "DIR/vecnormalize.pkl), the learning curve DIR/curve.csv and DIR/ppo.json; with --seeds N, "
        "each seed in DIR/seed-S, resumably. Evaluate it with 'mimo-radar-bench run --policies "
        "ALGO:DIR,...'. --device trains the project's own PPO (torch-ppo) with the env on that device."
    )

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "--scenario",
            default=None,
            help="shipped name or YAML/TOML file (default: paper scenario 1 of --env-version, paper-1-v1)",
        )
        parser.add_argument(
            "--timesteps",
            type=integer(1),
            default=None,
            help="environment steps to train for (default: n_timesteps of the hyperparameters)",
        )
        parser.add_argument("--out", required=True, type=folder, help="output directory for the model")
        cls.add_learner_arguments(parser)
        parser.add_argument("--seed", type=integer(0), default=0, help="training seed (default 0)")
        parser.add_argument(
            "--seeds",
            type=integer(1, high=100),
            default=1,
            help="train seeds --seed, --seed + 1, ... each into DIR/seed-S (default 1: DIR itself)",
        )
        parser.add_argument(
            "--workers",
            type=integer(1),
            default=1,
            help="seeds trained at once, one process each, sharing --device where one is given "
            "(capped at the cores; default 1)",
        )
        parser.add_argument(
            "--tensorboard", action="store_true", help="write TensorBoard logs in DIR/tensorboard"
        )
        parser.add_argument(
            "--overwrite",
            action="store_true",
            help="replace a model already in --out (its files are removed first)",
        )
        parser.add_argument("--quiet", action="store_true", help="no progress bar")
        add_max_hours(parser)
        add_env_options(parser)

    @staticmethod
    def add_learner_arguments(parser: argparse.ArgumentParser) -> None:
        """The learner, where it trains, and its hyperparameters."""
        parser.add_argument(
            "--algo",
            choices=list(LEARNER_NAMES),
            default=None,
            help="the learner: PPO (SB3), MaskablePPO or RecurrentPPO (sb3-contrib), or the project's "
            f"own PPO in plain torch, {TORCH_PPO} (default ppo; {TORCH_PPO} with --device)",
        )
        parser.add_argument(
            "--device",
            default=None,
            help=f"train {TORCH_PPO} with the env, the network and the updates on this torch device "
            "('cuda', 'cuda:1', 'cpu'); the SB3 learners run on the numpy env (default: none)",
        )
        parser.add_argument(
            "--device-mode",
            choices=DEVICE_MODES,
            default="eager",
            help=f"the form of the env's step on --device ({TORCH_PPO}): 'eager' (default), 'graph' (one "
            "CUDA graph per step) or 'compiled' (torch.compile); the same numbers",
        )
        parser.add_argument(
            "--n-envs",
            type=integer(1),
            default=None,
            help="parallel trials of the training env (default: n_envs of the hyperparameters, 8; "
            "thousands on a device)",
        )
        parser.add_argument(
            "--hyperparams",
            default=None,
            help="rl-zoo3-style YAML file (default: the shipped benchmarks/hyperparams/ALGO.yml, "
            "rl-zoo3's name: ppo.yml, ppo_mask.yml, ppo_lstm.yml)",
        )
        parser.add_argument(
            "--hyperparams-key",
            default=None,
            help="entry of the YAML file to use (default: the flat env id of --env-version, "
            "MimoRadarSelectFlat-v1)",
        )
        parser.add_argument(
            "--action",
            choices=("auto", "discrete", "scores"),
            default="auto",
            help="one Discrete action per super arm, or per-station scores (default: auto)",
        )

    def main(self) -> int:
        from .harness import HarnessError, RunInterrupted
        from .settings import local_workers, scenario_for_version
        from .training import seed_folder, train_ppo

        args = self.args
        algo = args.algo or (TORCH_PPO if args.device is not None else "ppo")
        version = VERSIONS[args.env_version]
        if args.scenario is not None:
            scenario_for_version(args.scenario, args.env_version)
        try:
            meta = train_ppo(
                args.scenario or version.default_scenario,
                args.timesteps,
                args.out,
                seed=args.seed,
                hyperparams=args.hyperparams,
                hyperparams_key=args.hyperparams_key or version.flat_env_id,
                action=args.action,
                tensorboard=args.tensorboard,
                progress=not args.quiet,
                options=env_options_from(args),
                overwrite=args.overwrite,
                algo=algo,
                seeds=args.seeds,
                workers=local_workers(args.workers),
                device=args.device,
                n_envs=args.n_envs,
                device_mode=args.device_mode,
                max_hours=args.max_hours,
                say=lambda message: print(f"mimo-radar-bench: {message}", file=sys.stderr),
            )
        except (RunInterrupted, HarnessError):
            raise
        except (ValueError, OSError) as exc:
            raise BenchError(str(exc)) from exc
        # PPO, MaskablePPO, RecurrentPPO or torch-ppo
        algorithm = LEARNERS[algo].algorithm.partition(":")[2] if algo in LEARNERS else algo
        if args.seeds == 1:
            where = f" on {meta['device']}" if "device" in meta else ""
            print(
                f"trained {algorithm} for {meta.get('trained_timesteps', meta['timesteps'])} steps "
                f"({meta['timesteps']} asked, in whole rollouts){where} in {meta['train_wall_s']:.0f} s "
                f"({meta['trained_timesteps'] / meta['train_wall_s']:,.0f} steps/s); saved {args.out}"
            )
        else:
            folder = seed_folder(args.out, args.seed).parent
            print(
                f"trained {algorithm}, {args.seeds} seeds of {meta['timesteps']} steps; saved {folder}/seed-*"
            )
        return 0


class Agents(Command):
    name = "agents"

    def main(self) -> int:
        import inspect
        import textwrap

        import agents

        for name in agents.available_agents():
            print(
                textwrap.fill(
                    agents.agent_summary(name), 100, initial_indent=f"{name:<22}", subsequent_indent=" " * 22
                )
            )
            defaults = agents.registry.agent_parameter_defaults(name)
            listed = ", ".join(
                f"{p} (required)" if d is inspect.Parameter.empty else f"{p}={d!r}"
                for p, d in defaults.items()
            )
            print(
                textwrap.fill(
                    f"parameters: {listed or '-'}", 100, initial_indent=" " * 22, subsequent_indent=" " * 24
                )
            )
        return 0


class Demo(Command):
    name = "demo"

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        default = VERSIONS[DEFAULT_VERSION].default_scenario
        parser.add_argument(
            "--scenario", default=default, help=f"scenario name or YAML/TOML file (default {default})"
        )
        parser.add_argument("--seed", type=integer(0), default=0, help="episode seed (default 0)")
        parser.add_argument(
            "--steps", type=integer(1), default=None, help="stop after this many steps (default: the horizon)"
        )

    def main(self) -> int:
        from .demo import print_demo, run_demo

        print_demo(run_demo(self.args.scenario, self.args.seed, self.args.steps), self.args.scenario)
        return 0


class Compile(Command):
    name = "compile"
    description = (
        "A fresh install has no numba cache: a run compiles the kernels it calls on their first call. "
        "This compiles all of them up front (the env's fusions and bound, the tracking search, BPSO), "
        "spread over worker processes; later runs load them. Nothing else changes: a run gives the "
        "same numbers with or without it. A cached kernel whose index numba cannot read back (a damaged "
        "cache) counts as not cached: its index is removed and it is compiled anew, here and before a run."
    )

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(
            "--workers", type=integer(1), default=None, help="worker processes (default: cores)"
        )

    def main(self) -> int:
        import os
        import time

        from mimo_radar_env.core.compiled import HAVE_NUMBA, uncached

        from .precompile import all_kernels, precompile

        if HAVE_NUMBA and not uncached(all_kernels()):
            print(f"all {len(all_kernels())} numba kernels are cached already: nothing to compile")
        else:
            start = time.perf_counter()
            workers = self.args.workers or os.cpu_count() or 1
            print(
                f"compiling numba kernels in {workers} worker processes (once: later runs load them)",
                flush=True,
            )
            for name, seconds in precompile(workers):
                print(f"  {name}: {seconds:.1f} s", flush=True)
            print(
                f"all {len(all_kernels())} kernels compiled and cached in {time.perf_counter() - start:.1f} s"
            )
        self.time_this_machine()
        return 0

    @staticmethod
    def time_this_machine() -> None:
        """Time the reference step here, for the time estimates (:mod:`benchmarks.machine_rate`)."""
        from .machine_rate import calibrate

        record, kept = calibrate()
        print(
            f"this machine runs the reference step in {record['seconds']:.3f} s, "
            f"{record['factor']:.2f} times the developers' machine: "
            + (
                f"time estimates use that (kept in {kept})"
                if kept
                else "not kept, estimates stay the developers'"
            )
        )
