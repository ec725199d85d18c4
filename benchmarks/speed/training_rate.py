"""PPO training throughput: env steps per second of SB3 PPO on the native vector env (CPU) against
the project's own torch-ppo on CPU torch and on a device, at several numbers of parallel trials.

Every row trains on ``paper-1-v1`` with the shipped ``hyperparams/ppo.yml`` entry, ``n_envs`` set
to B, rollouts of ``n_steps`` (default 64) steps per trial and ``batch_size = n_steps B / 8`` (the
entry's eight minibatches per epoch at any B), 10 epochs. A row times its rollouts after the first
(the first pays for warm-up: compilation, CUDA context), each rollout with its update: what a
training spends per env step end to end. CPU rows run on one thread, as ``train-ppo``'s workers
do, at the B values of ``--cpu-sizes`` (thousands of trials take minutes there). ``--processes``
adds rows of several trainings at once sharing the device, one process each: their timed
steps over the span of all their timed windows.

    python -m benchmarks.speed.training_rate --device cuda --json docs/results/perf/training.json
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from mimo_radar_env import EnvOptions, load_scenario
from mimo_radar_env.envs.device_forms import DEVICE_MODES, check_device_mode

from ..outputs import output_file, write_json
from ..settings import integer
from ..training import algorithm_kwargs, load_hyperparams, normalize_kwargs
from ..training_log import LearningCurve

SCENARIO = "paper-1-v1"
SIZES = (8, 512, 4096)
MINIBATCHES = 8


class _Clock(LearningCurve):
    """A learning curve that also notes when each rollout (with its update) ended."""

    def __init__(self) -> None:
        super().__init__()
        self.ends: list[tuple[int, float]] = []

    def close_rollout(self, timesteps: int) -> None:
        super().close_rollout(timesteps)
        self.ends.append((timesteps, time.perf_counter()))

    def rate(self) -> float:
        (first_steps, first), (last_steps, last) = self.ends[0], self.ends[-1]
        return (last_steps - first_steps) / (last - first)


def _params(trials: int, n_steps: int) -> dict[str, Any]:
    params = dict(load_hyperparams())
    params.update(n_envs=trials, n_steps=n_steps, batch_size=max(n_steps * trials // MINIBATCHES, 1))
    return params


def training_rate(
    learner: str,
    trials: int,
    device: str | None,
    rollouts: int = 3,
    n_steps: int = 64,
    device_mode: str = "eager",
) -> dict[str, Any]:
    """One row: ``learner`` ``"sb3"`` (``device`` None) or ``"torch-ppo"`` on ``device``, the
    env's step in form ``device_mode`` (:mod:`mimo_radar_env.envs.device_forms`)."""
    import torch

    if rollouts < 2:
        raise ValueError(f"rollouts must be >= 2 (the first is warm-up), got {rollouts}")
    params = _params(trials, n_steps)
    clock = _Clock()
    total = rollouts * n_steps * trials
    cuda = device is not None and str(device).startswith("cuda")
    threads = torch.get_num_threads()
    if not cuda:
        torch.set_num_threads(1)
    if cuda:
        torch.cuda.reset_peak_memory_stats()
    try:
        if learner == "sb3":
            from stable_baselines3 import PPO

            from mimo_radar_env.sb3 import NativeVecEnv

            policy, kwargs = algorithm_kwargs(params)
            venv = NativeVecEnv(SCENARIO, trials, seed=0, action="discrete")
            model = PPO(policy, venv, seed=0, verbose=0, device="cpu", **kwargs)
            model.learn(total_timesteps=total, callback=clock.callback())
        else:
            from .. import torch_ppo

            config = torch_ppo.PPOConfig.from_hyperparams(params, normalize=normalize_kwargs(params))
            with tempfile.TemporaryDirectory() as out:
                scenario = load_scenario(SCENARIO)
                torch_ppo.train(
                    scenario, total, Path(out), 0, config, EnvOptions(), device=device,
                    device_mode=device_mode, log=clock,
                )  # fmt: skip
    finally:
        torch.set_num_threads(threads)
    return {
        "learner": learner,
        "device": "numpy" if device is None else str(device),
        "device_mode": device_mode,
        "trials": trials,
        "n_steps": n_steps,
        "batch_size": params["batch_size"],
        "timed_steps": clock.ends[-1][0] - clock.ends[0][0],
        "env_steps_per_s": clock.rate(),
        # the timed window on the machine's monotonic clock (the same in every process)
        "timed_from_s": clock.ends[0][1],
        "timed_to_s": clock.ends[-1][1],
        "peak_device_memory_gib": torch.cuda.max_memory_allocated() / 2**30 if cuda else None,
    }


def shared_rate(
    trials: int, device: str, processes: int, rollouts: int = 3, n_steps: int = 64, device_mode: str = "eager"
) -> dict[str, Any]:
    """One row of ``processes`` torch-ppo trainings at once on ``device``, each in a worker
    process of its own (as ``train-ppo --workers`` with ``--device`` runs seeds): the env steps
    they all timed over the span from the first one's timed start to the last one's end (a
    process that starts late is not counted as running beside the others), with each one's own
    rate."""
    from ..backends import worker_pool

    with worker_pool(processes) as pool:
        futures = [
            pool.submit(training_rate, "torch-ppo", trials, device, rollouts, n_steps, device_mode)
            for _ in range(processes)
        ]
        each = [future.result() for future in futures]
    first = {k: v for k, v in each[0].items() if k not in ("timed_from_s", "timed_to_s")}
    return {
        **first,
        "processes": processes,
        "env_steps_per_s": sum(row["timed_steps"] for row in each)
        / (max(row["timed_to_s"] for row in each) - min(row["timed_from_s"] for row in each)),
        "per_process_steps_per_s": [row["env_steps_per_s"] for row in each],
        "per_process_windows_s": [[row["timed_from_s"], row["timed_to_s"]] for row in each],
        "peak_device_memory_gib": None,
    }


def rows(
    device: str | None,
    sizes: tuple[int, ...],
    cpu_sizes: tuple[int, ...],
    rollouts: int,
    n_steps: int,
    device_modes: tuple[str, ...] = ("eager",),
    processes: tuple[int, ...] = (1,),
) -> list[dict[str, Any]]:
    """Every backend's rows: SB3 on CPU and torch-ppo on CPU torch at ``cpu_sizes``, and with
    ``device``, torch-ppo there at ``sizes`` in each form of the step of ``device_modes``, for
    each count of trainings at once of ``processes`` (:func:`shared_rate` beyond one)."""
    backends = [("sb3", None, cpu_sizes, "eager", 1), ("torch-ppo", "cpu", cpu_sizes, "eager", 1)]
    if device:
        backends += [("torch-ppo", device, sizes, mode, k) for mode in device_modes for k in processes]
    out = []
    for learner, where, trial_counts, mode, k in backends:
        for trials in trial_counts:
            try:
                if k == 1:
                    row = training_rate(learner, trials, where, rollouts, n_steps, mode)
                else:
                    row = shared_rate(trials, where, k, rollouts, n_steps, mode)
            except ImportError as exc:  # a machine without stable-baselines3: that backend's rows say so
                out.append({"learner": learner, "device": where or "numpy", "trials": trials,
                            "skipped": f"not installed ({exc.name})"})  # fmt: skip
                break
            out.append(row)
            rate = row["env_steps_per_s"]
            at_once = f" x{k}" if k > 1 else ""
            print(
                f"  {learner:9s} {where or 'numpy':6s} {mode:8s} B={trials:>6,d}{at_once}: "
                f"{rate:>10,.0f} env steps/s",
                flush=True,
            )
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default=None, help="a torch device for torch-ppo's last rows ('cuda')")
    parser.add_argument("--sizes", default=",".join(map(str, SIZES)), help="B values on the device")
    parser.add_argument(
        "--cpu-sizes", default="8,512", help="B values on the CPU (SB3, CPU torch); '' for none"
    )
    parser.add_argument(
        "--device-modes",
        default="eager",
        help="the forms of the env's step for torch-ppo's rows on --device, comma-separated "
        f"({', '.join(DEVICE_MODES)}; default %(default)s)",
    )
    parser.add_argument(
        "--processes",
        default="1",
        help="trainings at once on --device, each in a process of its own, comma-separated "
        "(default 1); each count beyond one is a row of their steps over the span of their timed windows",
    )
    parser.add_argument("--rollouts", type=integer(2), default=3, help="rollouts per row, the first untimed")
    parser.add_argument("--n-steps", type=integer(1), default=64)
    parser.add_argument("--json", type=output_file, default=None)
    args = parser.parse_args(argv)
    sizes = tuple(int(s) for s in args.sizes.split(","))
    cpu_sizes = tuple(int(s) for s in args.cpu_sizes.split(",") if s)
    modes = tuple(args.device_modes.split(","))
    try:
        processes = tuple(int(k) for k in args.processes.split(","))
    except ValueError:
        processes = ()
    if not processes or min(processes) < 1:
        parser.error(f"--processes must list whole numbers >= 1, got {args.processes!r}")
    for mode in modes:
        try:
            check_device_mode(mode, args.device or "cpu")
        except ValueError as exc:
            parser.error(f"--device-modes: {exc}")
    print(f"PPO training, {SCENARIO}, env steps per second (rollouts of {args.n_steps} steps per trial)")
    result = {
        "scenario": SCENARIO,
        "machine": platform.processor() or platform.machine(),
        "rows": rows(args.device, sizes, cpu_sizes, args.rollouts, args.n_steps, modes, processes),
    }
    if args.device and args.device.startswith("cuda"):
        import torch

        result["device_name"] = torch.cuda.get_device_name(args.device)
    write_json(args.json, result)


if __name__ == "__main__":
    main()
