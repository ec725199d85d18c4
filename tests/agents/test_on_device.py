"""Agents on the torch engine (checked on CPU torch): the same selections as on numpy, every
step, for the policies of the paper and the tracking-aware ones, with their draws computed on
the device."""

import os
import warnings

import numpy as np
import pytest

torch = pytest.importorskip("torch")

#: The device the torch side runs on: CPU torch in CI; .ci/device-check sets "cuda" on a GPU.
DEVICE = os.environ.get("MIMO_RADAR_TEST_DEVICE", "cpu")

import agents  # noqa: E402
from mimo_radar_env.core.arrays import device_namespace  # noqa: E402
from mimo_radar_env.core.counter_hash import Stream  # noqa: E402
from mimo_radar_env.core.streams import TrialRandom  # noqa: E402
from mimo_radar_env.envs import device_forms  # noqa: E402
from tests.helpers import StandInGraph, needs_torch_compiler  # noqa: E402

#: policy, its parameters, steps: the paper's policies (MG-CRB-CL with BPSO, as in the paper, and
#: with the exact solver), the baselines, the oracles and tracking-ucb.
POLICIES = [
    ("mg-crb-cl", {}, 12),
    ("mg-crb-cl", {"solver": "bpso", "solver_params": {"rule": "set"}}, 12),
    ("mg-crb-cl", {"solver": "exact"}, 40),
    ("ucb1", {}, 40),
    ("epsilon-greedy", {}, 40),
    ("fix1", {}, 10),
    ("best", {}, 20),
    ("best-tracking", {}, 20),
    ("tracking-ucb", {}, 20),
    ("random", {}, 20),
    ("sliding-window-ucb", {"window": 5}, 20),
]


def _actions(policy, params, steps, device, fusion="average"):
    agent = agents.make_agent(policy, "paper-1-v1", seed=3, **params)
    env = agents.make_env(agent, 5, {"fusion": fusion}, device=device)
    actions = []
    for step in agents.Rollout(agent, env, seed=11).run(steps):
        action = step.action
        assert isinstance(action, torch.Tensor) == (device is not None)
        actions.append(action.cpu().numpy() if device is not None else action)
        assert isinstance(step.reward, torch.Tensor) == (device is not None)
    return np.array(actions)


@pytest.mark.parametrize(
    ("policy", "params", "steps"), POLICIES, ids=[f"{p}-{i}" for i, (p, _, _) in enumerate(POLICIES)]
)
def test_an_agent_selects_the_same_super_arms_on_torch(policy, params, steps):
    np.testing.assert_array_equal(
        _actions(policy, params, steps, DEVICE), _actions(policy, params, steps, None)
    )


@pytest.mark.parametrize("policy", ["mg-crb-cl", "best", "best-tracking", "tracking-ucb"])
def test_an_agent_selects_the_same_super_arms_with_the_products_a_gpu_computes(policy):
    """The small matrix products and einsums as broadcast products summed (CUDA's way), on
    the policies whose criteria or tracks go through them."""
    from mimo_radar_env.core.arrays import elementwise_products

    with elementwise_products(True):
        on_torch = _actions(policy, {}, 15, DEVICE)
    np.testing.assert_array_equal(on_torch, _actions(policy, {}, 15, None))


def test_the_tracking_oracle_on_torch_under_centralized_fusion():
    np.testing.assert_array_equal(
        _actions("best-tracking", {}, 10, DEVICE, "centralized"),
        _actions("best-tracking", {}, 10, None, "centralized"),
    )


def test_an_agents_draws_on_torch_are_numpys_bit_for_bit():
    ours, theirs = TrialRandom.for_batch(7, 6), TrialRandom.for_batch(7, 6, device_namespace(DEVICE))
    for _ in range(2):  # a stream's second call draws anew, on both
        np.testing.assert_array_equal(
            theirs.uniform(Stream.AGENT_EXPLORE, (3,)).cpu().numpy(), ours.uniform(Stream.AGENT_EXPLORE, (3,))
        )
        np.testing.assert_allclose(
            theirs.normal(Stream.GAMMA_NORMAL, (4,)).cpu().numpy(),
            ours.normal(Stream.GAMMA_NORMAL, (4,)),
            rtol=1e-15,
        )
    np.testing.assert_array_equal(
        theirs.keys_for(Stream.BPSO_KEYS).cpu().numpy().view(np.uint64), ours.keys_for(Stream.BPSO_KEYS)
    )


def test_an_agent_that_acts_on_numpy_only_refuses_a_device_env_by_name():
    agent = agents.make_agent("cts", "paper-1-v1", seed=0)
    assert not agent.needs.device and agents.make_agent("ucb1", "paper-1-v1").needs.device
    env = agents.make_env(agent, 2, device="cpu")
    with pytest.raises(ValueError, match=r"cts acts on numpy arrays only, .* make its env with device=None"):
        agents.Rollout(agent, env, seed=0)


def test_an_agent_on_a_device_names_what_is_not_finite_after_one_read_of_all():
    agent = agents.make_agent("ucb1", "paper-1-v1", seed=0)
    episode = agents.Rollout(agent, agents.make_env(agent, 4, device=DEVICE), seed=0)
    obs = episode.obs
    reward = torch.zeros(4, dtype=torch.float64, device=DEVICE)
    agent.update(obs, reward)  # all finite: accepted
    with pytest.raises(ValueError, match="ucb1: the 'reward' it was given is not finite"):
        agent.update(obs, torch.full_like(reward, float("nan")))
    bad = {**obs, "track": obs["track"].clone()}
    bad["track"][1, 0, 2] = float("inf")
    with pytest.raises(ValueError, match="ucb1: the 'track' it was given is not finite"):
        agent.update(bad, reward)


def _bpso_selections(solver, batch_sizes, seed=0):
    """BPSO's selections on torch for indices of each batch size in turn (one TrialRandom each)."""
    rng = np.random.default_rng(seed)
    selections = []
    for batch in batch_sizes:
        index = torch.as_tensor(rng.exponential(size=(batch, 4, 6)), device=DEVICE)
        random = TrialRandom.for_batch(seed, batch, device_namespace(DEVICE))
        tx, rx = solver.solve(index, random)
        selections.append(torch.cat([tx, rx], dim=1).cpu().numpy())
    return selections


def test_bpso_replayed_as_a_graph_selects_what_it_selects_eagerly(monkeypatch):
    """On CUDA, BPSO's iterations are captured once per batch shape and replayed: played on the
    CPU with a stand-in graph of a CUDA graph's contract (inputs copied into fixed buffers, the
    outputs rewritten in place), the selections are the eager ones, call after call."""
    from agents.solvers import BPSOSolver

    sizes = [7, 7, 3, 7]
    eager = _bpso_selections(BPSOSolver(2, 3, iterations=30), sizes)
    captured = []
    monkeypatch.setattr(
        device_forms, "cuda_graph", lambda body, warm_up: captured.append(body) or StandInGraph(body, warm_up)
    )
    monkeypatch.setattr(device_forms.GraphReplay, "capture_on", torch.device(DEVICE).type)
    replayed = _bpso_selections(BPSOSolver(2, 3, iterations=30), sizes)
    assert len(captured) == 2  # one graph per batch shape
    for ours, theirs in zip(replayed, eager, strict=True):
        np.testing.assert_array_equal(ours, theirs)


@needs_torch_compiler()
def test_bpso_compiled_selects_what_it_selects_eagerly_with_one_compile_a_shape(monkeypatch):
    """In the compiled form each iteration runs as inductor's code (one fused loop on the CPU),
    compiled once per batch shape, every trial running every iteration: the eager selections,
    called on their own and replayed as a graph (a stand-in of a CUDA graph's contract)."""
    from agents.solvers import BPSOSolver

    sizes = [7, 3, 7]
    eager = _bpso_selections(BPSOSolver(2, 3, iterations=30), sizes)
    solver = BPSOSolver(2, 3, iterations=30)
    solver.device_mode = "compiled"
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no fall-back to the eager iteration
        compiled = _bpso_selections(solver, sizes)
        assert len(solver._compiled_iteration._compiled) == 2  # one a batch shape, each compiled
        monkeypatch.setattr(device_forms, "cuda_graph", StandInGraph)
        monkeypatch.setattr(device_forms.GraphReplay, "capture_on", torch.device(DEVICE).type)
        replayed = _bpso_selections(solver, sizes[:2])
    for ours, theirs in zip(compiled + replayed, eager + eager[:2], strict=True):
        np.testing.assert_array_equal(ours, theirs)


def test_a_rollout_gives_the_agent_and_its_solver_the_envs_form():
    agent = agents.make_agent("mg-crb-cl", "paper-1-v1", seed=0)
    assert agent.device_mode == agent.solver.device_mode == "eager"
    agents.Rollout(agent, agents.make_env(agent, 2, device=DEVICE, device_mode="graph"), seed=0)
    assert agent.device_mode == agent.solver.device_mode == "graph"
    with pytest.raises(ValueError, match="device_mode must be one of eager, graph, compiled; got 'jit'"):
        agent.use_device_mode("jit")


def test_bpso_on_torch_selects_the_same_in_blocks_of_iterations_and_without_its_table(monkeypatch):
    """On torch, BPSO hashes a block of iterations' draws at once (one block at the study's size)
    and looks eq19 up in a table: blocks of 7 iterations, and the direct sums, select the same."""
    from agents.solvers import BPSOSolver, _bpso_kernels

    whole = _bpso_selections(BPSOSolver(2, 3, iterations=30), [7])
    monkeypatch.setitem(_bpso_kernels.DRAW_BLOCK_BYTES, "torch", 8 * 7 * 50 * 12 * 7)  # 7 iterations
    monkeypatch.setattr(_bpso_kernels, "FITNESS_TABLE_BYTES", 0)
    np.testing.assert_array_equal(_bpso_selections(BPSOSolver(2, 3, iterations=30), [7])[0], whole[0])


def test_bpsos_iterations_ask_the_host_nothing_and_copy_nothing_from_it(monkeypatch):
    """What a CUDA graph's capture needs: inside the iterations, no bool(), item() or the like of
    a tensor, and no tensor made from host data (a scalar goes to its kernel as an argument),
    once a first call has made the hash's constant words."""
    from agents.solvers import BPSOSolver

    solver = BPSOSolver(2, 3, iterations=5)
    monkeypatch.setattr(device_forms.GraphReplay, "capture_on", torch.device(DEVICE).type)  # as captured
    index = torch.as_tensor(np.random.default_rng(1).exponential(size=(4, 4, 6)), device=DEVICE)
    positions, keys = solver.initial_swarm(TrialRandom.for_batch(0, 4, device_namespace(DEVICE)), 4, 6)
    solver._iterations(index, positions, keys)  # the warm-up a capture runs first
    reads = []
    for name in ("as_tensor", "tensor"):
        original = getattr(torch, name)

        def made(data, *args, _name=name, _original=original, **kwargs):
            if not isinstance(data, torch.Tensor):
                reads.append(f"torch.{_name}({data!r})")
            return _original(data, *args, **kwargs)

        monkeypatch.setattr(torch, name, made)
    for name in ("__bool__", "item", "__int__", "__float__", "tolist", "numpy"):
        original = getattr(torch.Tensor, name)

        def spy(self, *args, _name=name, _original=original, **kwargs):
            reads.append(_name)
            return _original(self, *args, **kwargs)

        monkeypatch.setattr(torch.Tensor, name, spy)
    solver._iterations(index, positions, keys)
    monkeypatch.undo()
    assert reads == []


def test_bpso_that_cannot_be_captured_runs_eagerly_with_a_warning(monkeypatch):
    from agents.solvers import BPSOSolver

    def refuse(body, warm_up):
        raise RuntimeError("operation not permitted when stream is capturing")

    eager = _bpso_selections(BPSOSolver(2, 3, iterations=10), [5])
    monkeypatch.setattr(device_forms, "cuda_graph", refuse)
    monkeypatch.setattr(device_forms.GraphReplay, "capture_on", torch.device(DEVICE).type)
    with pytest.warns(RuntimeWarning, match="BPSO's iterations could not be captured as a CUDA graph"):
        replayed = _bpso_selections(BPSOSolver(2, 3, iterations=10), [5, 5])
    np.testing.assert_array_equal(replayed[0], eager[0])
    agent = agents.make_agent("mg-crb-cl", "paper-1-v1", seed=0)
    episode = agents.Rollout(agent, agents.make_env(agent, 3, device=DEVICE), seed=0)
    with pytest.warns(RuntimeWarning, match="could not be captured") as said:
        agent.act(episode.obs)
    assert said[0].filename == __file__  # said where the agent acted
