"""The operation counts: every torch operation of a block counted, those inside a GraphReplay
apart, and a policy's counts against the same calls counted on their own."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from benchmarks.speed import launches  # noqa: E402
from mimo_radar_env.core.arrays import device_namespace  # noqa: E402
from mimo_radar_env.core.streams import TrialRandom  # noqa: E402
from mimo_radar_env.envs.device_forms import GraphReplay  # noqa: E402


def test_counting_sees_every_operation_and_those_of_a_replayed_function_apart():
    a, b = torch.ones(3), torch.arange(3.0)
    twice = GraphReplay(lambda x: x * 2.0, "doubling")
    with launches.counting() as counts:
        c = a + b  # one operation
        d = twice(c)  # one, inside the replay
        (d - a).sum()  # two
        c.view(1, 3).expand(2, 3)  # views: counted, moving no bytes
    # float32: a + b reads 12 + 12 bytes and writes 12, d = 2c 12 + 12, d - a 36, its sum 12 + 4
    assert counts == {"total": 6, "replayed": 1, "compiled": 0, "bytes": 36 + 24 + 36 + 16}
    with launches.counting() as counts:
        pass
    assert counts == {"total": 0, "replayed": 0, "compiled": 0, "bytes": 0}


def test_mg_crb_cls_row_counts_bpsos_iterations_as_they_count_alone(monkeypatch):
    """The operations a row puts in the replayed graph are those of BPSO's iterations called on
    their own with the same shapes, as where they are captured (every iteration: on the CPU the
    trials would stop at their optimum); on CUDA they become one dispatch."""
    from mimo_radar_env.envs.device_forms import GraphReplay

    row = launches.policy_row("mg-crb-cl", 6, 1)
    assert GraphReplay.capture_on == "cuda"  # as it was
    monkeypatch.setattr(GraphReplay, "capture_on", "cpu")
    from agents.solvers import BPSOSolver

    solver = BPSOSolver(2, 3)
    index = torch.as_tensor(np.random.default_rng(0).exponential(size=(6, 4, 6)))
    positions, keys = solver.initial_swarm(TrialRandom.for_batch(0, 6, device_namespace("cpu")), 4, 6)
    with launches.counting() as counts:
        solver._iterations(index, positions, keys)
    assert row["act_replayed"] == counts["total"] > 1000
    assert row["act_dispatches_on_cuda"] == row["act"] - row["act_replayed"] + 1
    plain = launches.policy_row("ucb1", 6, 1)
    assert plain["act_replayed"] == 0 and plain["act_dispatches_on_cuda"] == plain["act"] > 0
    assert plain["env_step"] == row["env_step"] > 1000  # the same env, whatever acts on it
    assert plain["env_step_bytes_per_trial"] == row["env_step_bytes_per_trial"] > 0
    assert plain["env_step_bandwidth_bound"] == launches.H200_BYTES_PER_S / plain["env_step_bytes_per_trial"]


def test_an_agent_that_names_the_fusion_is_counted_on_each_fusions_env():
    """tracking-ucb's estimator takes the env's fusion: under centralised fusion its row was
    refused (an agent made for average fusion on a centralised env)."""
    rows = {
        fusion: launches.policy_row("tracking-ucb", 4, 1, fusion) for fusion in ("average", "centralized")
    }
    assert rows["average"]["env_step"] != rows["centralized"]["env_step"]
    assert all(row["act"] > 0 for row in rows.values())


@pytest.mark.filterwarnings("ignore:`torch.jit.script_method` is deprecated:DeprecationWarning")
def test_the_compiled_code_calls_are_its_generated_loops_and_its_library_kernels():
    """A pointwise chain before a matrix product fuses into one generated loop, the product calls
    a library kernel, and the pointwise chain and reduction after it are a second loop."""
    from torch._inductor.utils import run_and_get_code

    a, b = torch.randn(8, 8), torch.randn(8, 8)
    compiled = torch.compile(lambda x, y: ((x.sin() * 2.0) @ y).exp().sum(), dynamic=False)
    _, codes = run_and_get_code(compiled, a, b)
    assert [launches.code_calls(code) for code in codes] == [{"fused": 2, "library": 1}]


def test_the_compiled_act_counts_bpsos_iterations_apart_from_the_rest():
    """MG-CRB-CL's act in the compiled form: the operations in its replayed graph are the graph
    form's less an eager iteration's for each of the 100 iterations, which are calls of inductor's
    code instead (one fused loop each on the CPU)."""
    from agents.solvers import _bpso_kernels

    row = launches.compiled_act_row(6)
    graph = launches.policy_row("mg-crb-cl", 6, 1)
    iteration = []
    run = _bpso_kernels.swarm_iteration

    def counted(*args, **kwargs):
        with launches.counting() as counts:
            out = run(*args, **kwargs)
        iteration.append(counts["total"])
        return out

    import unittest.mock

    with unittest.mock.patch.object(_bpso_kernels, "swarm_iteration", counted):
        launches.policy_row("mg-crb-cl", 6, 1)
    per_iteration = iteration[-1]
    assert row["compiled_calls"] == 100 and row["fused"] >= 1
    assert row["act_replayed"] == graph["act_replayed"] - 100 * per_iteration
    assert row["act"] - row["act_replayed"] == graph["act"] - graph["act_replayed"]
