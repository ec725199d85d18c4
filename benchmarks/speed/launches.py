"""Torch operations per step: each policy's act and the env's step, counted on CPU torch.

Run: ``python -m benchmarks.speed.launches [--trials 500] [--json FILE]``.

On a GPU most operations launch a kernel (views and other operations on a tensor's shape launch
none), and at the paper's 500 trials a launch costs more than its arithmetic, so these counts say
where eager torch code is launch-bound there. They are counts of the code's calls, the same on any
device, so they are counted on the CPU, with a ``TorchDispatchMode`` that sees every operation,
and with small matrix products computed as on a GPU (``elementwise_products``: broadcast
products summed, where the CPU calls torch's).
Operations inside a :class:`~mimo_radar_env.envs.device_forms.GraphReplay` (BPSO's iterations)
are counted apart, run as they are captured: on CUDA they replay as one graph. ``--compiled``
also counts the calls of the env's step as ``torch.compile`` (inductor) writes it on this
machine's torch, and times its compile: the first compiled step from empty caches (a temporary
cache folder) and a second env's; and those of MG-CRB-CL's act in the compiled form, BPSO's
iteration compiled. docs/performance.md's table is generated from the JSON.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

from mimo_radar_env.core.arrays import elementwise_products

from ..outputs import output_file, write_json
from ..settings import integer

POLICIES = ("mg-crb-cl", "ucb1", "epsilon-greedy", "fix1", "random", "best", "best-tracking", "tracking-ucb")
SCENARIO = "paper-1-v1"
#: An NVIDIA H200's memory bandwidth, bytes per second (NVIDIA's figure: 4.8 TB/s): the step's
#: bytes per trial bound how many trial-steps a second its eager or graph form can run there.
H200_BYTES_PER_S = 4.8e12


def _tensor_bytes(tree: Any) -> int:
    import torch

    leaves = torch.utils._pytree.tree_leaves(tree)
    return sum(leaf.numel() * leaf.element_size() for leaf in leaves if isinstance(leaf, torch.Tensor))


@contextlib.contextmanager
def counting() -> Iterator[dict[str, int]]:
    """Counts the torch operations run in the block: ``"total"``, and ``"replayed"`` those inside
    a :class:`GraphReplay` call; ``"compiled"``, the calls of a compiled function
    (:class:`~mimo_radar_env.envs.device_forms.CompiledFunction`), whose own operations are
    inductor's code (:func:`code_calls` counts them), not counted here; and ``"bytes"``, what
    the operations that are not views read and write: their tensor arguments and results, each
    at its size (what an unfused kernel moves through memory once its arrays outgrow the caches)."""
    from torch.utils._python_dispatch import TorchDispatchMode

    from mimo_radar_env.envs.device_forms import CompiledFunction, GraphReplay

    counts = {"total": 0, "replayed": 0, "compiled": 0, "bytes": 0}
    inside = [False]
    compiled = [False]

    class Count(TorchDispatchMode):
        def __torch_dispatch__(self, func: Any, types: Any, args: Any = (), kwargs: Any = None) -> Any:
            out = func(*args, **(kwargs or {}))
            if not compiled[0]:
                counts["total"] += 1
                counts["replayed"] += inside[0]
                if not func.is_view:
                    counts["bytes"] += _tensor_bytes((args, kwargs)) + _tensor_bytes(out)
            return out

    compiled_call = CompiledFunction.__call__

    def compiled_function(self: CompiledFunction, *args: Any, **constants: Any) -> Any:
        counts["compiled"] += 1
        compiled[0] = True
        try:
            return compiled_call(self, *args, **constants)
        finally:
            compiled[0] = False

    call = GraphReplay.__call__
    where = GraphReplay.capture_on

    def replayed(self: GraphReplay, *args: Any) -> Any:
        # run as where it is captured: every operation a CUDA graph would hold (BPSO runs every
        # iteration there; on the CPU its trials stop at their optimum)
        inside[0] = True
        GraphReplay.capture_on = args[0].device.type
        try:
            return self.function(*args)
        finally:
            GraphReplay.capture_on = where
            inside[0] = False

    GraphReplay.__call__ = replayed  # type: ignore[method-assign]
    CompiledFunction.__call__ = compiled_function  # type: ignore[method-assign]
    try:
        with Count():
            yield counts
    finally:
        GraphReplay.__call__ = call  # type: ignore[method-assign]
        CompiledFunction.__call__ = compiled_call  # type: ignore[method-assign]


@elementwise_products(True)  # the products as a GPU computes them
def policy_row(policy: str, trials: int, steps: int, fusion: str = "average") -> dict[str, Any]:
    """The operations of ``policy``'s act, its update and the env's step, per step, averaged over
    ``steps`` steps after two (the first acts from the reset's observation)."""
    import agents

    # an agent that names the env's fusion (tracking-ucb's estimator) is made with the env's
    own = {"fusion": fusion} if "fusion" in agents.agent_class(policy).needs.env_option_params else {}
    agent = agents.make_agent(policy, SCENARIO, seed=0, **own)
    env = agents.make_env(agent, trials, {"fusion": fusion}, device="cpu")
    episode = agents.Rollout(agent, env, seed=0)
    for _ in range(2):
        episode.step()
    totals = {"act": 0, "act_replayed": 0, "update": 0, "env_step": 0, "env_step_bytes": 0}
    for _ in range(steps):
        with counting() as act:
            action = agent.act(episode.obs)
        with counting() as step:
            obs, reward, *_ = env.step(action)
        with counting() as update:
            agent.update(obs, reward)
        episode.obs = obs
        totals["act"] += act["total"]
        totals["act_replayed"] += act["replayed"]
        totals["update"] += update["total"]
        totals["env_step"] += step["total"]
        totals["env_step_bytes"] += step["bytes"]
    row: dict[str, Any] = {"policy": policy, "fusion": fusion, "trials": trials, "steps": steps}
    row |= {key: value / steps for key, value in totals.items() if key != "env_step_bytes"}
    # the eager step's memory traffic per trial, and the rate an H200's bandwidth allows it
    row["env_step_bytes_per_trial"] = totals["env_step_bytes"] / steps / trials
    row["env_step_bandwidth_bound"] = H200_BYTES_PER_S / row["env_step_bytes_per_trial"]
    # on CUDA a replayed graph is one dispatch (its replay) in place of its operations
    row["act_dispatches_on_cuda"] = row["act"] - row["act_replayed"] + (row["act_replayed"] > 0)
    return row


def code_calls(code: str) -> dict[str, int]:
    """The calls of the ``call`` function of an inductor module's code: ``fused``, the loops it
    generated (``cpp_fused_*`` on the CPU, ``triton_*`` on CUDA), and ``library``, the kernels of a
    library it calls (``extern_kernels.bmm``, ``torch.ops.aten.linalg_cholesky_ex``...)."""
    body = code[code.index("def call(") :].split("\n\n\n")[0]
    fused = re.findall(r"^\s+(?:cpp_fused_\w+|triton_\w+\.run)\(", body, re.M)
    library = re.findall(r"^\s+(?:\w+ = )?(?:extern_kernels\.\w+|torch\.ops\.\w+\.\w+\.\w+)\(", body, re.M)
    return {"fused": len(fused), "library": len(library)}


def total_calls(codes: list[str]) -> dict[str, int]:
    """:func:`code_calls` summed over the modules inductor wrote."""
    calls = [code_calls(code) for code in codes]
    return {kind: sum(c[kind] for c in calls) for kind in ("fused", "library")}


#: A new process's first compiled step (seconds, printed last), inductor's caches as this one's.
FIRST_STEP = """
import time, gymnasium as gym, mimo_radar_env
from mimo_radar_env.core.arrays import elementwise_products
env = gym.make_vec("MimoRadarSelect-v1", num_envs={trials}, vectorization_mode="vector_entry_point",
                   scenario="{scenario}", fusion="{fusion}", device="{device}", device_mode="compiled")
with elementwise_products(True):
    env.reset(seed=0)
    action = env.oracle_action()
    start = time.perf_counter()
    env.step(action)
    print(time.perf_counter() - start)
"""


@elementwise_products(True)  # the products as a GPU computes them
def compiled_row(trials: int, fusion: str, device: str = "cpu") -> dict[str, Any]:
    """The calls of the v1 env's step compiled (``device_mode="compiled"``) on ``device``, as
    inductor writes it there (C++ loops on the CPU, Triton kernels on CUDA), and the operations
    of the same env's eager step (its third, counted as :func:`policy_row` counts); with the
    seconds of the compiled env's first step (``compile_s``: it traces and compiles) and of a
    second compiled env's of the same options in this process (``again_s``: what a study's next
    policy pays: it traces its step, finds the first env's function and runs its compiled step)
    and in a new process (``new_process_s``: what each worker of a study pays, inductor's caches
    on disk warm; it traces the step again)."""
    import gymnasium as gym
    from torch._inductor.utils import run_and_get_code

    import mimo_radar_env  # noqa: F401 - registers the env

    def env(mode: str) -> Any:
        made = gym.make_vec("MimoRadarSelect-v1", num_envs=trials, vectorization_mode="vector_entry_point",
                            scenario=SCENARIO, fusion=fusion, device=device, device_mode=mode)  # fmt: skip
        made.reset(seed=0)
        return made

    eager = env("eager")
    for _ in range(3):
        action = eager.oracle_action()
        with counting() as operations:
            eager.step(action)
    compiled = env("compiled")
    start = time.perf_counter()
    _, codes = run_and_get_code(compiled.step, compiled.oracle_action())
    compile_s = time.perf_counter() - start
    again = env("compiled")
    start = time.perf_counter()
    again.step(again.oracle_action())
    again_s = time.perf_counter() - start
    first_step = FIRST_STEP.format(trials=trials, scenario=SCENARIO, fusion=fusion, device=device)
    run = subprocess.run([sys.executable, "-c", first_step], capture_output=True, text=True, check=True)
    new_process_s = float(run.stdout.split()[-1])
    return {"fusion": fusion, "trials": trials, "device": device, **total_calls(codes),
            "eager": operations["total"], "compile_s": compile_s, "again_s": again_s,
            "new_process_s": new_process_s}  # fmt: skip


@elementwise_products(True)  # the products as a GPU computes them
def compiled_act_row(trials: int, device: str = "cpu") -> dict[str, Any]:
    """MG-CRB-CL's act in the compiled form (``use_device_mode("compiled")``: each of BPSO's
    iterations compiled) on ``device``: the calls of an iteration's code as inductor writes it
    there (``fused``, ``library``), the seconds of the first act (``compile_s``: it traces and
    compiles), and a later act's operations outside the compiled code (``act``, of which
    ``act_replayed`` inside the replayed graph) and its calls of the compiled iteration
    (``compiled_calls``). On CUDA the graph replays ``act_replayed + compiled_calls x (fused +
    library)`` kernels."""
    from torch._inductor.utils import run_and_get_code

    import agents

    agent = agents.make_agent("mg-crb-cl", SCENARIO, seed=0)
    episode = agents.Rollout(agent, agents.make_env(agent, trials, device=device), seed=0)
    agent.use_device_mode("compiled")
    start = time.perf_counter()
    _, codes = run_and_get_code(agent.act, episode.obs)
    compile_s = time.perf_counter() - start
    episode.step()
    with counting() as act:
        agent.act(episode.obs)
    return {"policy": "mg-crb-cl", "trials": trials, "device": device, **total_calls(codes),
            "compile_s": compile_s, "act": act["total"], "act_replayed": act["replayed"],
            "compiled_calls": act["compiled"]}  # fmt: skip


def _compiled_line(row: dict[str, Any]) -> str:
    return (
        f"{row['fusion']:12s} compiled env step: {row['fused']} fused loops, {row['library']} library "
        f"calls; first step {row['compile_s']:.1f} s, a second env's {row['again_s']:.1f} s, a new "
        f"process's {row['new_process_s']:.1f} s"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=integer(1), default=500)
    parser.add_argument("--steps", type=integer(1), default=3, help="steps counted per policy")
    parser.add_argument("--policies", default=",".join(POLICIES))
    parser.add_argument(
        "--compiled",
        action="store_true",
        help="also count the calls of the env's step compiled by torch.compile (minutes: it compiles)",
    )
    parser.add_argument("--compiled-device", default="cpu", help="where --compiled compiles (default cpu)")
    parser.add_argument("--json", type=output_file, default=None)
    args = parser.parse_args(argv)
    if not args.compiled:
        return count(args)
    # a cold compile: inductor's caches on disk start empty for this run
    with tempfile.TemporaryDirectory(prefix="launches-inductor-") as cache:
        os.environ["TORCHINDUCTOR_CACHE_DIR"] = cache
        count(args)


def count(args: argparse.Namespace) -> None:
    """The counts :func:`main`'s arguments ask for, printed and written."""
    import torch

    rows = []
    for fusion in ("average", "centralized"):
        for policy in args.policies.split(","):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)  # a random policy's invalid-action notes
                row = policy_row(policy, args.trials, args.steps, fusion)
            rows.append(row)
            print(
                f"{fusion:12s} {policy:16s} act {row['act']:9,.0f} ops ({row['act_replayed']:,.0f} in a "
                f"replayed graph), update {row['update']:5,.0f}, env step {row['env_step']:6,.0f} "
                f"({row['env_step_bytes_per_trial']:,.0f} bytes a trial: an H200's bandwidth allows "
                f"{row['env_step_bandwidth_bound'] / 1e6:.1f} M trial-steps/s)",
                flush=True,
            )
    result = {"scenario": SCENARIO, "torch": torch.__version__, "numpy": np.__version__, "rows": rows}
    if args.compiled:
        fusions = ("average", "centralized")
        result["compiled"] = [compiled_row(args.trials, f, args.compiled_device) for f in fusions]
        print("\n".join(map(_compiled_line, result["compiled"])))
        act = result["compiled_act"] = compiled_act_row(args.trials, args.compiled_device)
        print(
            f"mg-crb-cl compiled act: {act['act']:,} ops ({act['act_replayed']:,} in a replayed graph) "
            f"and {act['compiled_calls']} calls of BPSO's iteration compiled, each {act['fused']} fused "
            f"loops and {act['library']} library calls; first act {act['compile_s']:.1f} s"
        )
    write_json(args.json, result)
    if args.json:
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
