"""Binary particle swarm optimisation for super arms (Section III-B, eq19-eq21)."""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env.core.compiled import HAVE_NUMBA
from mimo_radar_env.core.counter_hash import Stream
from mimo_radar_env.core.streams import TrialRandom
from mimo_radar_env.core.superarm import masks_to_actions, top_mask
from mimo_radar_env.envs.device_forms import CompiledFunction, GraphReplay

from ..parameters import check_integer, check_parameter
from .base import SuperArmSolver

#: BPSO position-update rules (docs/agents.md).
BPSO_RULES = ("xor", "set")
#: Bounds of the swarm: 200 times the paper's (Npop = 50, q_max = 100), beyond which one
#: selection of a 500-trial batch would take minutes.
MAX_POPULATION = 10_000
MAX_ITERATIONS = 20_000


def _bpso_kernels() -> ModuleType:
    """The swarm's kernels (:mod:`._bpso_kernels`), imported when a selection first runs: they
    define numba functions at import."""
    from . import _bpso_kernels

    return _bpso_kernels


def _swarm_iteration(*arrays: Any, **constants: Any) -> tuple[Any, ...]:
    """:func:`._bpso_kernels.swarm_iteration`, its module imported when first called."""
    return _bpso_kernels().swarm_iteration(*arrays, **constants)


#: eq19 by table lookup when the particle has at most this many bits (``2^bits`` doubles per
#: trial; the kernels' last argument); longer particles sum their selected channels directly.
TABLE_BITS = 14
#: Iterations the ``"set"`` rule takes to reach a tabulated optimum, roughly (its cost model).
SET_RULE_ITERATIONS = 20


class BPSOSolver(SuperArmSolver):
    """BPSO as written in the paper, vectorised over trials and particles.

    A particle is the bit vector ``D = [delta_t, delta_r]`` (M + N bits). Fitness
    is eq19: the index sum of the selected channels, 0 for a particle that breaks
    the ``Ms``/``Ns`` cardinality. Velocities follow eq20 with inertia decreasing
    linearly from ``inertia_start`` to ``inertia_end`` over the iterations and are
    clamped to ``+-velocity_clamp``; positions follow eq21: a bit flips when a
    uniform draw falls below ``sigmoid(V)``.

    Choices the paper leaves open (docs/model.md): particles start at uniformly
    random *valid* super arms with zero velocity; ``r1``, ``r2`` are drawn per
    particle and iteration; the personal and global bests are only ever
    replaced by valid particles with a strictly larger fitness, so the result is
    always a valid super arm (also on ties and all-zero indices).

    Note on eq21 as written: a bit whose velocity has decayed to 0 flips with
    probability 1/2, so the swarm keeps exploring rather than converging; the
    best valid particle seen is what is returned.

    Parameters
    ----------
    population : int
        ``Npop`` (default 50).
    iterations : int
        ``q_max`` (default 100).
    c1, c2 : float
        Acceleration constants (default 2, 2).
    inertia_start, inertia_end : float
        Inertia weight ``omega`` at the first and last iteration (0.9, 0.4).
    velocity_clamp : float
        ``|V| <= velocity_clamp`` (default 6).
    rule : {"xor", "set"}
        The position update: ``"xor"``, eq21 as written, flips a bit with probability
        ``sigmoid(V)`` (reading 0, default); ``"set"`` sets it to 1 with that probability
        (Kennedy & Eberhart's binary PSO, the one the paper cites; reading 1).
    use_numba : bool
        Run the compiled kernel when numba is installed (default). The pure-numpy
        kernel gives the same numbers, more slowly (docs/performance.md times both).

    Random numbers come from the agent's per-trial streams (initial particles, and one key per
    trial and call for the iteration streams), ``r1``, ``r2`` once per particle and iteration,
    one 16-bit flip draw per bit; the sigmoid uses an exp built from + and *
    (relative error < 1e-7). Both kernels share these, so they agree number for number.
    Both kernels stop a trial's swarm as soon as its global best holds the best value any valid
    super arm has (its eq19 table's maximum; the numpy kernel then drops the trial from its
    arrays): only a strictly larger fitness replaces a best, so the remaining iterations could
    not change the result. How much that saves depends on the rule: on i.i.d. exponential
    indices ``"set"`` reaches the optimum in about 99 % of trials and ``"xor"`` in about half
    (docs/performance.md).

    On torch the numpy kernel runs on the index's device; on CUDA its iterations (thousands of
    small kernels a selection) are captured once per batch shape as one CUDA graph and replayed
    (:class:`~mimo_radar_env.envs.device_forms.GraphReplay`): the same kernels, the same numbers,
    every trial running every iteration (a graph's shapes cannot depend on the data). In the
    compiled form (:attr:`device_mode` ``"compiled"``, which an agent takes from its env's
    ``device_mode``) each iteration (:func:`~._bpso_kernels.swarm_iteration`, about fifty
    operations) runs as the code ``torch.compile`` writes for it, compiled once per batch shape
    (:class:`~mimo_radar_env.envs.device_forms.CompiledFunction`; one fused loop on the CPU), every
    trial running every iteration; on CUDA the graph replays its kernels.
    """

    name = "bpso"
    seconds_per_operation = 1.7e-9

    def __init__(
        self,
        tx_count: int,
        rx_count: int,
        population: int = 50,
        iterations: int = 100,
        c1: float = 2.0,
        c2: float = 2.0,
        inertia_start: float = 0.9,
        inertia_end: float = 0.4,
        velocity_clamp: float = 6.0,
        rule: str = "xor",
        use_numba: bool = True,
    ) -> None:
        super().__init__(tx_count, rx_count)
        check_integer("population", population, 1, MAX_POPULATION)
        check_integer("iterations", iterations, 1, MAX_ITERATIONS)
        for name, value in (
            ("c1", c1),
            ("c2", c2),
            ("inertia_start", inertia_start),
            ("inertia_end", inertia_end),
        ):
            check_parameter(name, value, 0.0, 10.0)
        check_parameter("velocity_clamp", velocity_clamp, 0.0, 100.0, low_open=True)
        if not isinstance(use_numba, bool):
            raise ValueError(f"use_numba must be true or false, got {use_numba!r}")
        self.population = population
        self.iterations = iterations
        self.c1, self.c2 = c1, c2
        self.inertia_start, self.inertia_end = inertia_start, inertia_end
        self.velocity_clamp = velocity_clamp
        if rule not in BPSO_RULES:
            raise ValueError(f"rule must be one of {list(BPSO_RULES)}, got {rule!r}")
        self.rule = rule
        self.use_numba = use_numba
        self._replayed = GraphReplay(self._iterations, "BPSO's iterations")
        self._compiled_iteration = CompiledFunction(_swarm_iteration, "BPSO's iteration")

    @property
    def threaded(self) -> bool:  # type: ignore[override]
        """The compiled kernel (numba installed and ``use_numba``) spreads the trials over threads."""
        return self.use_numba and HAVE_NUMBA

    def memory_per_trial(self, num_tx: int, num_rx: int) -> int:
        """The swarm: positions, velocities, personal bests and draws of every particle."""
        return 8 * 8 * self.population * (num_tx + num_rx) + super().memory_per_trial(num_tx, num_rx)

    def operations_per_trial(self, num_tx: int, num_rx: int) -> float:
        """Every particle's velocity, position and value at every iteration (a compiled,
        vectorised kernel: about one operation per station and per selected channel). Where the
        kernel knows the optimum (a particle of at most ``TABLE_BITS`` stations: every super
        arm's value is tabulated) it stops on reaching it, which rule ``"set"`` does within
        about :data:`SET_RULE_ITERATIONS` iterations (measured: 14 us a trial at 4 x 6 against
        85 us for ``"xor"``, which runs them all about half the time)."""
        per_particle = num_tx + num_rx + self.tx_count * self.rx_count
        iterations = self.iterations
        if self.rule == "set" and num_tx + num_rx <= TABLE_BITS:
            iterations = min(iterations, SET_RULE_ITERATIONS)
        return float(self.population * iterations * per_particle)

    def initial_swarm(
        self, random: TrialRandom, num_tx: int, num_rx: int
    ) -> tuple[NDArray[np.int8], NDArray[np.uint64]]:
        """A call's starting swarm from the agent's per-trial streams: every particle a uniformly
        random valid super arm, (B, population, M + N) int8, and one key per trial for the
        iteration streams (the kernels' ``positions`` and ``keys``). With numba, a compiled
        twin (``_bpso_bpso_kernels().initial_positions``) hashes the same draws."""
        xp = random.xp
        if self.use_numba and HAVE_NUMBA and not xp.is_torch:
            tx_bases, rx_bases = random.bases(Stream.BPSO_INIT_TX), random.bases(Stream.BPSO_INIT_RX)
            positions = _bpso_kernels().initial_positions(
                tx_bases, rx_bases, self.population, num_tx, num_rx, self.tx_count, self.rx_count
            )
        else:
            tx = top_mask(random.uniform(Stream.BPSO_INIT_TX, (self.population, num_tx)), self.tx_count)
            rx = top_mask(random.uniform(Stream.BPSO_INIT_RX, (self.population, num_rx)), self.rx_count)
            positions = masks_to_actions(tx, rx)
        return positions, random.keys_for(Stream.BPSO_KEYS)

    def swarm_arguments(self) -> tuple[int, float, float, float, float, float, bool, int]:
        """The kernels' arguments after ``keys``: ``q_max``, ``c1``, ``c2``, the inertia at the first
        and last iteration, the velocity clamp, whether the rule is ``"set"`` and
        :data:`TABLE_BITS`."""
        return (
            self.iterations,
            float(self.c1),
            float(self.c2),
            float(self.inertia_start),
            float(self.inertia_end),
            float(self.velocity_clamp),
            self.rule == "set",
            TABLE_BITS,
        )

    def solve(
        self, index: NDArray[np.float64], random: TrialRandom
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        index = self.check(index)
        batch, num_tx, num_rx = index.shape
        if random.batch_size != batch:
            raise ValueError(f"random streams for {random.batch_size} trials, index for {batch}")
        positions, keys = self.initial_swarm(random, num_tx, num_rx)
        xp = random.xp
        if xp.is_torch:
            best = self._replayed(index, positions, keys)
        else:
            kernel = (
                _bpso_kernels().numba_kernel() if self.use_numba and HAVE_NUMBA else _bpso_kernels().run_numpy
            )
            best = kernel(index, self.tx_count, self.rx_count, positions, keys, *self.swarm_arguments())
        return xp.astype(best[:, :num_tx], bool), xp.astype(best[:, num_tx:], bool)

    def _iterations(self, index: Any, positions: Any, keys: Any) -> Any:
        """The swarm's iterations on torch tensors: the numpy kernel, a function of them, each
        iteration compiled in the compiled form. Where they are captured as a CUDA graph or
        compiled, every trial runs every iteration (no shape that depends on the data); elsewhere
        a trial stops at its optimum, as on numpy."""
        compiled = self.device_mode == "compiled"
        return _bpso_kernels().run_numpy(
            index,
            self.tx_count,
            self.rx_count,
            positions,
            keys,
            *self.swarm_arguments(),
            stop_at_optimum=index.device.type != GraphReplay.capture_on and not compiled,
            iterate=self._compiled_iteration if compiled else None,
        )
