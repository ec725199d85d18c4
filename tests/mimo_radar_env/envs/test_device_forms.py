"""The torch step's traced forms (``device_mode="graph"``, ``"compiled"``) against the eager step,
on CPU torch (on a GPU where .ci/device-check sets MIMO_RADAR_TEST_DEVICE): the same numbers over
episodes, a step redone eagerly where a deferred check fails, no read of a device value inside the
step, and the CUDA graph's buffers handled as a real graph would hold them (a stand-in graph with
the same contract)."""

import os
import re
import warnings

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from benchmarks.speed.device import _keys, relative_difference  # noqa: E402
from mimo_radar_env import VERSIONS, load_scenario  # noqa: E402
from mimo_radar_env.core.arrays import deferred_checks  # noqa: E402
from mimo_radar_env.core.superarm import random_super_arms  # noqa: E402
from mimo_radar_env.envs import device_forms  # noqa: E402
from mimo_radar_env.envs.engine import RadarEngine  # noqa: E402
from mimo_radar_env.tracking import unscented  # noqa: E402
from tests.helpers import StandInGraph, needs_torch_compiler  # noqa: E402

DEVICE = os.environ.get("MIMO_RADAR_TEST_DEVICE", "cpu")
needs_compiler = needs_torch_compiler()


def _engine(version, fusion, trials, mode, precision="float64"):
    env_version = VERSIONS[version]
    options = env_version.options(fusion=fusion)
    scenario = load_scenario(env_version.default_scenario)
    return RadarEngine(
        options, scenario, batch_size=trials, device=DEVICE, device_mode=mode, precision=precision
    )


def _play(version, fusion, mode, trials=3, steps=25, reset_at=None, precision="float64"):
    """The largest relative difference of every output between the eager engine and one in
    ``mode`` over ``steps`` steps (random valid actions, the first trial probing nothing every
    fifth step, the oracle's action read between steps), and the traced engine."""
    eager = _engine(version, fusion, trials, "eager", precision)
    other = _engine(version, fusion, trials, mode, precision)
    keys = _keys(trials)
    eager.reset_from_keys(keys)
    other.reset_from_keys(keys)
    sc = eager.scenario
    rng = np.random.default_rng(3)
    worst = 0.0
    for t in range(steps):
        if t == reset_at:  # a new episode mid-way: the graph's buffers take the fresh state
            keys = _keys(trials, seed=7)
            eager.reset_from_keys(keys)
            other.reset_from_keys(keys)
        action = random_super_arms(rng, trials, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step)
        if t % 5 == 0:
            action[0] = 0
        assert torch.equal(eager.oracle_action(), other.oracle_action())
        obs_a, reward_a, _, trunc_a, info_a = eager.step(torch.as_tensor(action, device=DEVICE))
        obs_b, reward_b, _, trunc_b, info_b = other.step(torch.as_tensor(action, device=DEVICE))
        assert torch.equal(trunc_a, trunc_b)
        for ours, theirs in ((obs_a, obs_b), (info_a, info_b)):
            assert set(ours) == set(theirs)
            worst = max([worst, *(relative_difference(ours[k], theirs[k]) for k in ours)])
        worst = max(worst, relative_difference(reward_a, reward_b))
    return worst, other


@pytest.mark.parametrize(("version", "fusion"), [("v1", "average"), ("v1", "centralized"), ("v0", "average")])
def test_the_graph_form_gives_the_eager_numbers_bit_for_bit(version, fusion):
    worst, engine = _play(version, fusion, "graph", reset_at=17)
    assert worst == 0.0
    assert engine._forms.eager_steps == 0  # every step ran traced


def test_a_second_traced_engine_in_the_process_gives_the_eager_numbers(monkeypatch):
    """The device's namespace is one per process: a constant its first trace made (a fake tensor
    under make_fx, had it been kept) must serve the next engine's steps as a real tensor, as a
    study's policies, one engine each, run one after another on the device."""
    from torch._subclasses.fake_tensor import FakeTensor

    from mimo_radar_env.core.arrays import device_namespace

    xp = device_namespace(DEVICE)
    monkeypatch.setattr(xp, "_constants", {})  # as in a fresh process: made first inside a trace
    monkeypatch.setattr(xp, "_words", {})
    keys, sc = _keys(3), load_scenario(VERSIONS["v1"].default_scenario)
    actions = random_super_arms(
        np.random.default_rng(5), 3, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step
    )
    rewards = []
    for mode in ("graph", "graph", "eager"):
        engine = _engine("v1", "average", 3, mode)
        engine.reset_from_keys(keys)
        rewards.append([engine.step(torch.as_tensor(actions, device=DEVICE))[1] for _ in range(3)])
        cached = [*xp._constants.values(), *xp._words.values()]
        assert cached and not any(isinstance(tensor, FakeTensor) for tensor in cached)
    for first, second, eager in zip(*rewards, strict=True):
        assert torch.equal(first, eager) and torch.equal(second, eager)


def test_the_graph_form_in_float32_gives_the_eager_float32_numbers_bit_for_bit():
    worst, engine = _play("v1", "centralized", "graph", steps=12, precision="float32")
    assert worst == 0.0 and engine._forms.eager_steps == 0
    assert engine.simulation.state.dtype == torch.float32


def test_a_failed_deferred_check_redoes_the_step_eagerly_with_the_same_numbers(monkeypatch):
    """The closed-form test of the covariance guard made to fail everywhere: each traced step's
    flag is False, so each step is undone and run again with its checks (which then factorise
    and find nothing to repair): the eager numbers, every step redone."""
    monkeypatch.setattr(
        unscented,
        "_certainly_conditioned",
        lambda m, c: torch.zeros(m.shape[:-2], dtype=bool, device=m.device),
    )
    worst, engine = _play("v1", "average", "graph", steps=6)
    assert worst == 0.0
    assert engine._forms.eager_steps == 6


def test_the_traced_step_reads_no_device_value(monkeypatch):
    """Inside the deferred checks, the step asks the host nothing: bool() or item() of a tensor
    there would stall a GPU and cannot be captured in a graph."""
    engine = _engine("v1", "centralized", 4, "eager")
    engine.reset_from_keys(_keys(4))
    sc = engine.scenario
    action = random_super_arms(np.random.default_rng(0), 4, sc.num_tx, sc.num_rx, 2, 3)
    action = torch.as_tensor(action, device=DEVICE)
    reads = []
    for name in ("__bool__", "item", "__int__", "__float__", "tolist"):
        original = getattr(torch.Tensor, name)

        def spy(self, *args, _name=name, _original=original, **kwargs):
            reads.append(_name)
            return _original(self, *args, **kwargs)

        monkeypatch.setattr(torch.Tensor, name, spy)
    with deferred_checks() as flags:
        engine.advance(action)
    monkeypatch.undo()
    assert reads == []
    assert len(flags) >= 4  # the prior's factors, the update's guard (both covariances at once), the bound's


@pytest.mark.parametrize(("version", "fusion"), [("v1", "average"), ("v1", "centralized"), ("v0", "average")])
def test_an_eager_step_makes_no_tensor_from_host_data(version, fusion):
    """No tensor of an eager step is made from host data (a list of indices, a numpy table, a
    scalar written into a tensor): on a GPU each would be copied there from the host, which waits
    for the device's queue, several times a step. The oracle's action, read between steps, too."""
    from torch.utils._python_dispatch import TorchDispatchMode

    made = []

    class Watch(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            if func is torch.ops.aten.lift_fresh.default:
                made.append(func)
            return func(*args, **(kwargs or {}))

    engine = _engine(version, fusion, 4, "eager")
    engine.reset_from_keys(_keys(4))
    sc = engine.scenario
    actions = random_super_arms(
        np.random.default_rng(0), 3, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step
    )
    actions = torch.as_tensor(actions, device=DEVICE)[:, None]
    engine.step(actions[0].expand(4, -1))  # the constants a step keeps are made once, here
    with Watch():
        for action in actions[1:]:
            engine.oracle_action()
            engine.step(action.expand(4, -1))
    assert made == []


def test_the_cuda_graph_path_keeps_the_engines_arrays_in_its_buffers(monkeypatch):
    monkeypatch.setattr(device_forms, "cuda_graph", StandInGraph)
    monkeypatch.setattr(device_forms.TracedStep, "__init__", _as_if_on_cuda)
    worst, engine = _play("v1", "average", "graph", steps=30, reset_at=12)
    assert worst == 0.0
    forms = engine._forms
    assert forms._graph is not None
    assert engine.tracker.means is forms._state[engine.state_slots().index((engine.tracker, "means"))]


_init = device_forms.TracedStep.__init__


def _as_if_on_cuda(self, engine, mode):
    _init(self, engine, mode)
    self.cuda = True
    self.mode = mode


def test_a_traced_form_needs_a_device_and_a_known_name():
    with pytest.raises(ValueError, match="device_mode must be one of eager, graph, compiled; got 'jit'"):
        device_forms.check_device_mode("jit", "cpu")
    with pytest.raises(ValueError, match="runs on torch"):
        device_forms.check_device_mode("graph", None)


def test_the_compiled_form_is_refused_on_a_torch_whose_compiler_cannot_keep_eagers_numbers(monkeypatch):
    """torch 2.11 brought the last of inductor's options for eager's numbers (``eager_numerics``):
    this torch has them all exactly where its version, read apart, is 2.11 or later; an option
    it lacks is named, with the torch, before an engine is made, and the other forms run."""
    installed = tuple(int(part) for part in re.findall(r"\d+", torch.__version__)[:2])
    assert (device_forms.missing_compile_options() == []) == (installed >= (2, 11))
    monkeypatch.setitem(device_forms.COMPILE_OPTIONS, "no_such_option", True)
    refused = (
        r"device_mode='compiled' needs torch 2\.11 or later, whose compiler keeps eager's numbers "
        rf"\(inductor's (\S+, )*no_such_option\); this is torch {re.escape(torch.__version__)}, on which "
        "the 'graph' and 'eager' forms run"
    )
    with pytest.raises(ValueError, match=refused):
        device_forms.check_device_mode("compiled", "cpu")
    with pytest.raises(ValueError, match=refused):
        _engine("v1", "average", 2, "compiled")
    device_forms.check_device_mode("graph", "cpu")


@needs_compiler
@pytest.mark.slow
@pytest.mark.parametrize("elementwise", [False, True], ids=["library-products", "elementwise-products"])
def test_the_compiled_form_gives_the_eager_numbers_to_round_off(elementwise):
    """torch.compile (inductor, C++ on the CPU; about two minutes to compile on two cores) may
    reorder floating-point sums: within the torch engine's tolerance of the numpy engine, with
    the small matrix products as torch's (the CPU's) and as broadcast products summed (CUDA's,
    which inductor fuses into its loops)."""
    from mimo_radar_env.core.arrays import elementwise_products

    with elementwise_products(elementwise), warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # a step that could not be compiled says so
        worst, engine = _play("v1", "average", "compiled", steps=12)
    assert worst <= 1e-9
    assert engine._forms.eager_steps == 0 and engine._forms._function is not False  # it ran compiled


@needs_compiler
def test_the_step_is_compiled_with_eagers_numerics_and_on_cuda_its_graphs(monkeypatch):
    """inductor is asked for no fused multiply-adds, PyTorch's libdevice and IEEE division (where
    its Triton kernels would depart from the eager step) and, on CUDA only, the CUDA graphs of
    ``mode="reduce-overhead"``; inductor knows every option."""
    import torch._inductor as inductor

    calls = []
    monkeypatch.setattr(torch, "compile", lambda fn, **kwargs: calls.append(kwargs) or fn)
    monkeypatch.setattr(device_forms, "_COMPILED_STEPS", device_forms.OrderedDict())
    engine = _engine("v1", "average", 2, "compiled")
    engine.reset_from_keys(_keys(2))
    state = [getattr(owner, name).contiguous() for owner, name in engine.state_slots()]
    for on_cuda in (False, True):
        engine._forms.cuda = on_cuda
        engine._forms._trace(engine.oracle_action(), state)
    assert [call["options"].pop("triton.cudagraphs") for call in calls] == [False, True]
    assert inductor.list_mode_options("reduce-overhead") == {"triton.cudagraphs": True}
    assert calls == [{"options": device_forms.COMPILE_OPTIONS, "dynamic": False}] * 2
    assert device_forms.COMPILE_OPTIONS["emulate_precision_casts"]
    with inductor.config.patch(device_forms.COMPILE_OPTIONS):  # an unknown option raises here
        assert inductor.config.emulate_precision_casts and inductor.config.eager_numerics.division_rounding


@needs_compiler
def test_engines_whose_steps_trace_alike_share_one_compiled_step(monkeypatch):
    """A study's policies, one engine each, on one scenario: the second engine's step traces to
    the first's function (another seed, the same code and constants) and runs its compiled step,
    with its own numbers; another fusion, or other station positions of the same sizes (other
    constants), compiles its own; the latest few are kept. A stand-in compile counts (the traced
    function runs as it is)."""
    compiled = []
    monkeypatch.setattr(torch, "compile", lambda fn, **kwargs: compiled.append(fn) or fn)
    monkeypatch.setattr(device_forms, "_COMPILED_STEPS", device_forms.OrderedDict())
    monkeypatch.setattr(device_forms, "COMPILED_STEPS_KEPT", 2)
    scenario = load_scenario(VERSIONS["v1"].default_scenario)
    moved = scenario.replace(tx_positions=scenario.tx_positions + 1.0)
    actions = torch.as_tensor(
        random_super_arms(
            np.random.default_rng(2),
            3,
            scenario.num_tx,
            scenario.num_rx,
            scenario.tx_per_step,
            scenario.rx_per_step,
        ),
        device=DEVICE,
    )

    def stepped(mode, fusion="average", seed=0, sc=scenario):
        options = VERSIONS["v1"].options(fusion=fusion)
        engine = RadarEngine(options, sc, batch_size=3, device=DEVICE, device_mode=mode)
        engine.reset_from_keys(_keys(3, seed=seed))
        return engine, [engine.step(actions)[1] for _ in range(2)]

    first, _ = stepped("compiled")
    second, rewards = stepped("compiled", seed=7)
    assert len(compiled) == 1 and second._forms._function is first._forms._function
    for ours, eager in zip(rewards, stepped("eager", seed=7)[1], strict=True):
        assert torch.equal(ours, eager)
    stepped("compiled", fusion="centralized")
    assert len(compiled) == 2
    elsewhere, _ = stepped("compiled", sc=moved)
    assert len(compiled) == 3
    assert elsewhere._forms._function.code == first._forms._function.code  # only the constants differ
    stepped("compiled", fusion="centralized")  # the latest two are kept: the first was let go
    assert len(compiled) == 3 and len(device_forms._COMPILED_STEPS) == 2
    stepped("compiled", seed=3)
    assert len(compiled) == 4


def test_a_step_that_cannot_be_captured_runs_traced_with_a_warning(monkeypatch):
    def refuse(body, warm_up):
        raise RuntimeError("operation not permitted when stream is capturing")

    monkeypatch.setattr(device_forms, "cuda_graph", refuse)
    monkeypatch.setattr(device_forms.TracedStep, "__init__", _as_if_on_cuda)
    with pytest.warns(RuntimeWarning, match="could not be captured as a CUDA graph"):
        worst, engine = _play("v1", "average", "graph", steps=8)
    assert worst == 0.0
    assert engine._forms._graph is False


def test_a_step_with_no_traced_form_runs_eagerly_with_a_warning():
    """The alternating oracle solver runs on numpy only: the trace fails, and the env says so once
    and steps eagerly, with the eager numbers."""
    import gymnasium as gym

    if DEVICE != "cpu":
        pytest.skip("the alternating solver reads numpy arrays: CPU torch only")

    def make(mode):
        return gym.make_vec(
            "MimoRadarSelect-v1",
            num_envs=3,
            vectorization_mode="vector_entry_point",
            device=DEVICE,
            device_mode=mode,
            oracle_solver="alternating",
        )

    eager, graph = make("eager"), make("graph")
    eager.reset(seed=2)
    graph.reset(seed=2)
    with pytest.warns(RuntimeWarning, match="device_mode='graph': the step could not be traced") as said:
        for _ in range(3):
            action = eager.sample_action()
            ours, theirs = eager.step(action), graph.step(action)
            assert all(relative_difference(ours[4][k], theirs[4][k]) == 0.0 for k in ours[4])
    assert graph.engine._forms._function is False
    assert [w.filename for w in said if "could not be traced" in str(w.message)] == [__file__]  # the caller


def test_a_traced_functions_host_constants_move_to_the_device():
    """An index written as a Python list or a numpy array enters a trace as a CPU constant, which a
    CUDA graph cannot copy to the GPU while capturing: constants_to moves every one (here to the
    meta device, which a CPU-only machine has), and the function runs there."""
    from torch.fx.experimental.proxy_tensor import make_fx

    index = np.array([1, 3])

    def function(x):
        return x[:, [0, 2]].sum(-1) + x[:, index].prod(-1) * torch.tensor(2.0)

    x = torch.arange(8.0).reshape(2, 4)
    traced = make_fx(function, tracing_mode="fake", _allow_non_fake_inputs=True)(x)
    constants = [getattr(traced, n.target) for n in traced.graph.nodes if n.op == "get_attr"]
    assert len(constants) >= 2 and all(c.device.type == "cpu" for c in constants)
    device_forms.constants_to(traced, torch.device("meta"))
    assert all(
        getattr(traced, n.target).device.type == "meta" for n in traced.graph.nodes if n.op == "get_attr"
    )
    assert traced(x.to("meta")).shape == (2,)
    again = make_fx(function, tracing_mode="fake", _allow_non_fake_inputs=True)(x)
    device_forms.constants_to(again, torch.device("cpu"))  # where they are already: the same function
    torch.testing.assert_close(again(x), function(x), rtol=0, atol=0)


@needs_compiler
def test_a_compiled_function_is_compiled_once_a_signature_and_gives_its_numbers():
    calls = []

    def scaled(x, *, k):
        calls.append(k)  # run when traced, not when the compiled code runs
        return (x * k + 1.0).sum(dim=1)

    compiled = device_forms.CompiledFunction(scaled, "scaling")
    a, b = torch.arange(6.0).reshape(2, 3), torch.ones(4, 3)
    for x, k in [(a, 2.0), (a * 3, 2.0), (b, 2.0), (a, 5.0)]:
        assert torch.equal(compiled(x, k=k), (x * k + 1.0).sum(dim=1))
    assert len(compiled._compiled) == 3 and calls == [2.0, 2.0, 5.0]  # shapes (2, 3), (4, 3); k=5


def test_a_function_that_cannot_be_compiled_runs_as_it_is_with_one_warning():
    def data_dependent(x):
        return x * 2.0 if bool(x.sum() > 0) else x  # a host read: no traced form

    compiled = device_forms.CompiledFunction(data_dependent, "doubling")
    x = torch.arange(3.0)
    with pytest.warns(RuntimeWarning, match="doubling could not be compiled .*; it runs eagerly"):
        assert torch.equal(compiled(x), x * 2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert torch.equal(compiled(-x - 1.0), -x - 1.0)
