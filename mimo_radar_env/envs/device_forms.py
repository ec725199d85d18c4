"""The torch engine's step in three forms: eager, graph and compiled (``device_mode=``).

* ``"eager"`` runs :meth:`RadarEngine.advance` op by op, as the numpy engine does: every check
  that reads a device value (a failed factorisation, a covariance to repair) asks the host.
* ``"graph"`` traces that same method once (``torch.fx``'s ``make_fx``, with the checks deferred:
  :func:`~mimo_radar_env.core.arrays.deferred_checks`) into a function of the step's arrays
  (:meth:`RadarEngine.state_slots`) and the actions. On CUDA it is captured as one CUDA graph and
  replayed at every step; on the CPU the traced function runs.
* ``"compiled"`` runs the traced function through ``torch.compile`` (on CUDA with
  ``mode="reduce-overhead"``'s CUDA graphs, and eager's numerics: :data:`COMPILE_OPTIONS`),
  once per process for every env whose step traces to the same function (the same code and
  constants: a study's policies on one scenario).

The step is the eager code itself, traced: no second copy of the model. The host reads one
boolean per step, whether every deferred check passed; where one failed, the step is undone and
run again eagerly with its checks, so every form gives the eager numbers (to round-off, which a
compiler may reorder).

:class:`GraphReplay` does the same for a pure function of tensors with nothing to check (BPSO's
iterations): on CUDA, one graph per shape of its arguments, replayed. :class:`CompiledFunction`
is the compiled form of such a function (BPSO's iteration, where an agent acts in the compiled
form), which a graph replays in turn.
"""

from __future__ import annotations

import warnings
from collections import OrderedDict
from typing import TYPE_CHECKING, Any

from ..core.arrays import all_passed, deferred_checks

if TYPE_CHECKING:
    from .engine import RadarEngine

#: The forms of the torch step (:mod:`.device_forms`); ``"eager"`` is the reference.
DEVICE_MODES = ("eager", "graph", "compiled")

#: inductor's options for what it compiles: eager's numerics where its Triton kernels would
#: depart from them on CUDA (no fused multiply-adds, PyTorch's libdevice, IEEE float32 division;
#: its C++ loops on the CPU contract nothing already). The compiled step adds
#: ``mode="reduce-overhead"``'s CUDA graphs on CUDA; a :class:`CompiledFunction` adds none.
COMPILE_OPTIONS = {"emulate_precision_casts": True, "eager_numerics.division_rounding": True}
#: The first torch whose inductor has every option of :data:`COMPILE_OPTIONS` (2.10 has no
#: ``eager_numerics``); the eager and graph forms run on the ``rl`` extra's oldest torch.
COMPILE_TORCH = "2.11"


def missing_compile_options() -> list[str]:
    """The options of :data:`COMPILE_OPTIONS` that this torch's inductor does not have (none
    where torch is not installed: what needs it says so)."""
    try:
        from torch._inductor import config
    except ImportError:
        return []
    known = config.get_config_copy()
    return [name for name in COMPILE_OPTIONS if name not in known]


def check_device_mode(device_mode: Any, device: Any = "torch") -> None:
    """Refuse a form that is not one of :data:`DEVICE_MODES`, a traced form on numpy (``device``
    None), and the compiled form on a torch whose inductor cannot keep eager's numerics."""
    if device_mode not in DEVICE_MODES:
        raise ValueError(f"device_mode must be one of {', '.join(DEVICE_MODES)}; got {device_mode!r}")
    if device_mode != "eager" and device is None:
        raise ValueError(f"device_mode={device_mode!r} runs on torch: give a device ('cpu', 'cuda')")
    if device_mode == "compiled" and (missing := missing_compile_options()):
        import torch

        raise ValueError(
            f"device_mode='compiled' needs torch {COMPILE_TORCH} or later, whose compiler keeps eager's "
            f"numbers (inductor's {', '.join(missing)}); this is torch {torch.__version__}, on which the "
            "'graph' and 'eager' forms run"
        )


#: This process's latest compiled steps by what they compute (:func:`_fingerprint`): an env whose
#: step traces to an earlier env's function (the same scenario, options, trials, device and
#: precision, whatever its seed or agent) runs that env's compiled step rather than compiling it
#: again. The last :data:`COMPILED_STEPS_KEPT` are kept (each holds its code, constants and, on
#: CUDA, its graphs' memory).
_COMPILED_STEPS: OrderedDict[tuple[Any, ...], Any] = OrderedDict()
COMPILED_STEPS_KEPT = 8


class TracedStep:
    """The engine's :meth:`~RadarEngine.advance` as one traced function, run in ``mode``."""

    def __init__(self, engine: RadarEngine, mode: str) -> None:
        self.engine = engine
        self.mode = mode
        self.cuda = engine.xp.device.type == "cuda"
        self._function: Any = None
        self._graph: Any = None
        #: steps redone eagerly because a deferred check failed (the rest ran traced)
        self.eager_steps = 0

    # ------------------------------------------------------------------ the trace
    def _functional(self) -> Any:
        """``f(actions, *state) -> (new state, passed, (obs, reward, info))`` over the engine."""
        engine = self.engine
        xp = engine.xp

        def step(actions: Any, *state: Any) -> Any:
            slots = engine.state_slots()
            for (owner, name), value in zip(slots, state, strict=True):
                setattr(owner, name, value)
            engine.simulation.forget()  # nothing kept from before may enter the trace as a constant
            with deferred_checks() as flags:
                outputs = engine.advance(actions)
            passed = all_passed(flags, xp)
            return [getattr(owner, name) for owner, name in slots], passed, outputs

        return step

    def _trace(self, actions: Any, state: list[Any]) -> Any:
        from torch.fx.experimental.proxy_tensor import make_fx

        saved = [getattr(owner, name) for owner, name in self.engine.state_slots()]
        try:
            traced = make_fx(self._functional(), tracing_mode="fake", _allow_non_fake_inputs=True)(
                actions, *state
            )
        finally:
            self._put(saved)
        if self.cuda:
            constants_to(traced, self.engine.xp.device)
        if self.mode == "compiled":
            import torch

            key = (_fingerprint(traced), self.cuda)
            if key not in _COMPILED_STEPS:
                options = {**COMPILE_OPTIONS, "triton.cudagraphs": self.cuda}
                _COMPILED_STEPS[key] = torch.compile(traced, options=options, dynamic=False)
                while len(_COMPILED_STEPS) > COMPILED_STEPS_KEPT:
                    _COMPILED_STEPS.popitem(last=False)
            _COMPILED_STEPS.move_to_end(key)
            return _COMPILED_STEPS[key]
        return traced

    # ------------------------------------------------------------------ a step
    def step(self, actions: Any) -> tuple[dict[str, Any], Any, dict[str, Any]]:
        engine = self.engine
        # one layout whatever made the arrays (a reset leaves broadcast views): the trace's
        state = [getattr(owner, name).contiguous() for owner, name in engine.state_slots()]
        first = self._function is None
        if first:
            try:
                self._function = self._trace(actions, state)
            except Exception as error:  # a path of the step with no traced form (a numpy-only solver)
                self._give_up("traced", error)
        if self._function is False:
            return engine.advance(actions)
        try:
            new_state, passed, outputs = self._run(actions, state)
        except Exception as error:  # the first call compiles: a compiler's failure is its own
            if not first:
                raise
            self._give_up("compiled" if self.mode == "compiled" else "run traced", error)
            return engine.advance(actions)
        if not bool(passed):  # the one read of the step: redo it with the checks
            self._put([b.clone() for b in self._backup] if self._graph else state)
            self.eager_steps += 1
            return engine.advance(actions)
        self._put(new_state)
        return outputs

    def _run(self, actions: Any, state: list[Any]) -> tuple[list[Any], Any, Any]:
        if self.cuda and self.mode == "graph" and self._graph is not False:
            return self._replay(actions, state)
        if self.cuda and self.mode == "compiled":  # CUDA graphs: the next call rewrites its outputs
            import torch

            torch.compiler.cudagraph_mark_step_begin()
            return _cloned(self._function(actions, *state))
        return self._function(actions, *state)

    def _give_up(self, what: str, error: Exception) -> None:
        """From now on the eager step, said once in a warning."""
        self._function = False
        warnings.warn(
            f"device_mode={self.mode!r}: the step could not be {what} ({_named(error)}); it runs "
            "eagerly, with the same numbers",
            RuntimeWarning,
            stacklevel=6,
        )

    def _put(self, state: list[Any]) -> None:
        for (owner, name), value in zip(self.engine.state_slots(), state, strict=True):
            setattr(owner, name, value)
        self.engine.simulation.forget()

    # ------------------------------------------------------------------ CUDA graphs
    def _replay(self, actions: Any, state: list[Any]) -> tuple[list[Any], Any, Any]:
        """The traced step as one CUDA graph over static buffers. The graph copies the state it
        reads into a backup (for a step redone eagerly) and writes the new state back over it,
        so the engine's arrays are the static buffers between steps; its other outputs are
        copied out before the next replay overwrites them."""
        if self._graph is None:
            self._actions = actions.clone()
            self._state = [value.clone() for value in state]
            self._backup = [value.clone() for value in state]
            try:
                self._graph = cuda_graph(
                    self._graph_body, lambda: self._function(self._actions, *self._state)
                )
            except RuntimeError as error:  # a kernel this GPU's torch cannot capture: run traced
                self._graph = False
                warnings.warn(
                    f"the step could not be captured as a CUDA graph ({error}); it runs as the traced "
                    "function instead, with the same numbers",
                    RuntimeWarning,
                    stacklevel=7,
                )
                return self._function(actions, *state)
        self._actions.copy_(actions)
        for static, value in zip(self._state, state, strict=True):
            if value is not static:  # after a reset or a step redone eagerly
                static.copy_(value)
        passed, outputs = self._graph.replay()
        return self._state, passed, _cloned(outputs)

    def _graph_body(self) -> tuple[Any, Any]:
        for backup, static in zip(self._backup, self._state, strict=True):
            backup.copy_(static)
        new_state, passed, outputs = self._function(self._actions, *self._state)
        for static, new in zip(self._state, new_state, strict=True):
            static.copy_(new)
        return passed, outputs


class _CUDAGraph:
    """``body`` captured once as a CUDA graph; :meth:`replay` runs it and returns its outputs
    (the same tensors every time, rewritten). ``warm_up`` runs the same kernels with no effect
    on the buffers, as torch asks before a capture."""

    def __init__(self, body: Any, warm_up: Any) -> None:
        import torch

        side = torch.cuda.Stream()
        side.wait_stream(torch.cuda.current_stream())
        with torch.cuda.stream(side):
            warm_up()
        torch.cuda.current_stream().wait_stream(side)
        self._graph = torch.cuda.CUDAGraph()
        with torch.cuda.graph(self._graph):
            self._outputs = body()

    def replay(self) -> Any:
        self._graph.replay()
        return self._outputs


def cuda_graph(body: Any, warm_up: Any) -> Any:
    """``body`` (a function of no arguments that reads and writes static buffers) as a replayable
    graph: a CUDA graph (the tests put a stand-in with the same contract here)."""
    return _CUDAGraph(body, warm_up)


class GraphReplay:
    """``function``, a pure function of tensors that asks the host nothing, run on CUDA as one
    CUDA graph per signature of its arguments (shapes, dtypes, device): the first call captures
    it (after a warm-up run, as torch asks); each call copies the arguments into the graph's input
    buffers, replays it and clones its outputs out. The same kernels in the same order, so the
    same numbers as calling it. Elsewhere it is called as it is, as it is where a capture fails
    (said once, in a warning naming ``what``)."""

    #: The device type whose calls are captured (the tests play a CPU as if it were one).
    capture_on = "cuda"

    def __init__(self, function: Any, what: str) -> None:
        self.function, self.what = function, what
        self._graphs: dict[tuple[Any, ...], Any] = {}

    def __call__(self, *args: Any) -> Any:
        if args[0].device.type != self.capture_on:
            return self.function(*args)
        key = _signature(args)
        if key not in self._graphs:
            self._graphs[key] = self._capture(args)
        entry = self._graphs[key]
        if entry is False:
            return self.function(*args)
        inputs, graph = entry
        for static, value in zip(inputs, args, strict=True):
            static.copy_(value)
        return _cloned(graph.replay())

    def _capture(self, args: tuple[Any, ...]) -> Any:
        inputs = [a.clone() for a in args]
        try:
            return inputs, cuda_graph(lambda: self.function(*inputs), lambda: self.function(*inputs))
        except RuntimeError as error:
            warnings.warn(
                f"{self.what} could not be captured as a CUDA graph ({error}); it runs eagerly, with "
                "the same numbers",
                RuntimeWarning,
                stacklevel=6,
            )
            return False


class CompiledFunction:
    """``function``, a pure function of tensors (and of constants given as keywords) that asks the
    host nothing, traced (``torch.fx``'s ``make_fx``) and compiled by ``torch.compile`` with
    eager's numerics (:data:`COMPILE_OPTIONS`, no CUDA graphs of its own: a :class:`GraphReplay`
    may capture its calls), once per signature of its arguments and value of its constants: the
    first call of each compiles it. Where tracing or compiling fails, it is called as it is, with
    the same numbers (said once, in a warning naming ``what``)."""

    def __init__(self, function: Any, what: str) -> None:
        self.function, self.what = function, what
        self._compiled: dict[tuple[Any, ...], Any] = {}

    def __call__(self, *args: Any, **constants: Any) -> Any:
        key = (_signature(args), tuple(sorted(constants.items())))
        compiled = self._compiled.get(key)
        if compiled is False:
            return self.function(*args, **constants)
        if compiled is not None:
            return compiled(*args)
        try:  # traced and compiled, then its first call (where inductor compiles)
            compiled = self._compile(args, constants)
            outputs = compiled(*args)
        except Exception as error:
            self._compiled[key] = False
            warnings.warn(
                f"{self.what} could not be compiled ({_named(error)}); it runs eagerly, with the same "
                "numbers",
                RuntimeWarning,
                stacklevel=2,
            )
            return self.function(*args, **constants)
        self._compiled[key] = compiled
        return outputs

    def _compile(self, args: tuple[Any, ...], constants: dict[str, Any]) -> Any:
        import torch
        from torch.fx.experimental.proxy_tensor import make_fx

        traced = make_fx(lambda *a: self.function(*a, **constants), tracing_mode="fake")(*args)
        return torch.compile(traced, options=COMPILE_OPTIONS, dynamic=False)


def _signature(args: tuple[Any, ...]) -> tuple[Any, ...]:
    """The shapes, dtypes and devices of tensors: what a graph or a compiled function is made for."""
    return tuple((tuple(a.shape), a.dtype, a.device) for a in args)


def _named(error: Exception) -> str:
    """An error's type and first line."""
    text = str(error)
    return f"{type(error).__name__}: {text.splitlines()[0] if text else ''}"


def _cloned(outputs: Any) -> Any:
    """Every tensor of ``outputs`` (nested) copied out of a graph's buffers, which its next replay
    rewrites."""
    import torch

    return torch.utils._pytree.tree_map(lambda a: a.clone(), outputs)


def _fingerprint(traced: Any) -> tuple[Any, ...]:
    """What a traced function computes: its code and every tensor constant it reads (name,
    dtype, shape, device and values). Two functions with the same fingerprint are the same
    function of their arguments."""
    import hashlib

    constants = []
    for node in traced.graph.nodes:
        if node.op == "get_attr":
            value = getattr(traced, node.target)
            try:  # a traced sub-function, or a dtype numpy lacks: this trace's own
                values = value.detach().cpu().contiguous().numpy().tobytes()
            except (AttributeError, TypeError):
                return (traced,)
            digest = hashlib.sha256(values).hexdigest()
            constants.append((node.target, str(value.dtype), tuple(value.shape), str(value.device), digest))
    return traced.code, tuple(constants)


def constants_to(traced: Any, device: Any) -> None:
    """Move the tensor constants of a traced function (``torch.fx`` ``get_attr`` nodes) to
    ``device``. A step's constants that came from the host (an index written as a Python list, a
    numpy mask) are CPU tensors copied to the device each time they are used, which a CUDA graph
    cannot capture; on the device, each use is a copy there."""
    for node in traced.graph.nodes:
        if node.op == "get_attr":
            value = getattr(traced, node.target)
            if hasattr(value, "device") and value.device != device:
                setattr(traced, node.target, value.to(device))


def make_forms(engine: RadarEngine, device_mode: str) -> TracedStep | None:
    """The engine's step runner for ``device_mode`` (None: eager, the engine's own method)."""
    return None if device_mode == "eager" else TracedStep(engine, device_mode)
