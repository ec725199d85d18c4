"""Counter-based random streams, vectorised over Monte-Carlo trials: the simulation's
(:class:`TrialStreams`) and the agents' (:class:`TrialRandom`), on one hash.

Every random number of the simulation is a pure function of
``(trial key, stream, step, element index)`` through :mod:`.counter_hash`. This gives
three properties at once, with no Python loop over trials:

* trial ``i`` of a vector env draws exactly what a single env with the same key
  draws (the keys of a vector env are derived per trial from ``seed + i``);
* the truth stream never depends on what the radar does, so two policies run
  with the same seed see the same target trajectories (common random numbers);
* the SINR sample and the measurement noise of channel ``(k, m, n)`` at step
  ``t`` are the same number whichever other channels are probed with it, which
  lowers the variance of policy comparisons further.

SplitMix64 passes BigCrush on sequential inputs; the tests check the laws the
simulation relies on (uniform, normal, exponential) with fixed seeds.

An agent's draws (:class:`TrialRandom`) follow the same rule: trial ``i`` of an agent seeded
``s`` draws from the key of ``s + i``, as trial ``i`` of the vector env does, so a trial's draws
depend only on its key, the stream, how many times the agent drew from that stream, and the
element, never on the other trials of the batch. A benchmark's numbers therefore do not depend
on how its trials are cut into shards, on the worker count or on the backend.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .arrays import NUMPY, NumpyNamespace, TorchNamespace
from .counter_hash import GOLDEN, OBSERVATION_STREAMS, Stream, element_bits, mix, stream_base, to_unit


def shared_truth_key(truth_seed: int) -> np.uint64:
    """The truth key of every trial when the truth is shared (a scenario's ``truth_seed``)."""
    return mix(np.array([truth_seed], dtype=np.uint64) * GOLDEN ^ np.uint64(Stream.SHARED_TRUTH_KEY))[0]


def keys_from_generator(generator: np.random.Generator) -> NDArray[np.uint64]:
    """Draw the two 64-bit keys (truth, observations) of one trial."""
    return generator.integers(0, 2**64, size=2, dtype=np.uint64, endpoint=False)


class TrialStreams:
    """Random draws for a batch of trials, one key pair per trial.

    Parameters
    ----------
    keys : array of shape (B, 2), uint64
        Per-trial keys: column 0 drives the truth (initial state and process
        noise), column 1 the observations (SINR samples, measurement noise).
    xp : array namespace
        Where the draws are computed (:mod:`.arrays`): numpy (default) or torch on a device,
        bit for bit the same.
    """

    def __init__(self, keys: ArrayLike, xp: NumpyNamespace | TorchNamespace = NUMPY) -> None:
        keys = np.asarray(keys, dtype=np.uint64)
        if keys.ndim != 2 or keys.shape[1] != 2:
            raise ValueError(f"keys must have shape (B, 2), got {keys.shape}")
        self.xp = xp
        self.keys = xp.words(keys)

    @property
    def batch_size(self) -> int:
        return self.keys.shape[0]

    def _bits(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.uint64]:
        """Hash of (key, stream, step, index); ``index`` has shape (B, ...)."""
        key = self.keys[:, 1 if stream in OBSERVATION_STREAMS else 0]
        base = stream_base(key, stream, step).reshape((-1,) + (1,) * (index.ndim - 1))
        return element_bits(base, index)

    def _rounded(self, draws: NDArray[np.float64]) -> NDArray[np.float64]:
        """Draws computed in float64, rounded to the engine's precision where it is float32
        (:func:`~.arrays.float_precision`): the same draws to that rounding, tails included."""
        return draws if self.xp.precision == "float64" else self.xp.astype(draws, np.float32)

    def uniform(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.float64]:
        """U[0, 1) draws, one per element of ``index`` (shape (B, ...))."""
        return self._rounded(to_unit(self._bits(stream, step, index)))

    def exponential(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.float64]:
        """Exponential(1) draws."""
        return self._rounded(-self.xp.log1p(-to_unit(self._bits(stream, step, index))))

    def normal(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.float64]:
        """Standard normal draws (Box-Muller on two hashed uniforms per element)."""
        xp = self.xp
        doubled = 2 * xp.astype(index, np.int64)
        # elements 2i and 2i + 1 of the stream hashed at once (the same bits as one by one)
        units = to_unit(self._bits(stream, step, xp.stack([doubled, doubled + 1], axis=-1)))
        u1, u2 = units[..., 0], units[..., 1]
        return self._rounded(xp.sqrt(-2.0 * xp.log1p(-u1)) * xp.cos(2.0 * np.pi * u2))


def full_index(
    batch_size: int, shape: tuple[int, ...], xp: NumpyNamespace | TorchNamespace = NUMPY
) -> NDArray[np.int64]:
    """Element indices ``0..prod(shape)-1`` broadcast to (B, *shape)."""
    index = xp.arange(int(np.prod(shape)), dtype=np.int64).reshape(shape)
    return xp.broadcast_to(index, (batch_size, *shape))


#: The largest seed an agent takes: trial ``i`` draws from the key of ``seed + i`` in 64 bits,
#: so below 2**63 no batch wraps onto the keys of small seeds.
MAX_AGENT_SEED = 2**63 - 1

#: Marsaglia-Tsang proposals drawn per Gamma variate in one batch (acceptance >= 95 % each);
#: the rare variate with no accepted proposal is drawn by inverse CDF from its own uniform.
GAMMA_PROPOSALS = 4


class TrialRandom:
    """Batch-first random draws with one key per trial.

    Parameters
    ----------
    seed : int, optional
        Trial ``i`` uses the key of ``seed + i``; ``None`` draws a fresh seed from the OS.
        At most :data:`MAX_AGENT_SEED`.
    """

    def __init__(self, seed: int | None) -> None:
        if seed is not None and (
            isinstance(seed, bool | np.bool_)
            or not isinstance(seed, int | np.integer)
            or not 0 <= seed <= MAX_AGENT_SEED
        ):
            raise ValueError(f"seed must be None or an integer from 0 to 2**63 - 1, got {seed!r}")
        if seed is None:
            seed = int(np.random.SeedSequence().entropy % 2**62)
        self.seed = int(seed)
        self.xp: NumpyNamespace | TorchNamespace = NUMPY
        self.keys = np.zeros(0, dtype=np.uint64)
        self.calls: dict[Stream, int] = {}

    @classmethod
    def for_batch(
        cls, seed: int | None, batch_size: int, xp: NumpyNamespace | TorchNamespace = NUMPY
    ) -> TrialRandom:
        """Streams for ``batch_size`` trials, ready to draw (for solvers used on their own)."""
        random = cls(seed)
        random.reset(batch_size, xp)
        return random

    def reset(self, batch_size: int, xp: NumpyNamespace | TorchNamespace = NUMPY) -> None:
        """Keys for trials ``0..B-1`` (seeds ``seed..seed+B-1``); every stream starts again. The
        draws are computed in namespace ``xp`` (numpy, or torch on a device: the same bits)."""
        seeds = (self.seed + np.arange(batch_size, dtype=np.uint64)).astype(np.uint64)
        self.xp = xp
        self.keys = xp.words(mix(mix(seeds * GOLDEN) ^ np.uint64(Stream.AGENT_KEY)))
        self.calls = {}

    @property
    def batch_size(self) -> int:
        return len(self.keys)

    def bases(self, stream: Stream) -> NDArray[np.uint64]:
        """One draw from ``stream`` left to a compiled kernel: the per-trial bases (B,) that
        :meth:`uniform` hashes its elements with, so that ``to_unit(element_bits(bases[:, None],
        i))`` is ``uniform(stream, shape)`` at flat index ``i``."""
        call = self.calls.get(stream, 0)
        self.calls[stream] = call + 1
        return stream_base(self.keys, stream, call)

    def _bits(self, stream: Stream, shape: tuple[int, ...]) -> NDArray[np.uint64]:
        base = self.bases(stream).reshape((-1,) + (1,) * len(shape))
        element = self.xp.arange(int(np.prod(shape)), dtype=np.int64).reshape(shape)
        return element_bits(base, element[None])

    def uniform(self, stream: Stream, shape: tuple[int, ...] = ()) -> NDArray[np.float64]:
        """U[0, 1) draws of shape (B, *shape)."""
        return to_unit(self._bits(stream, shape))

    def normal(self, stream: Stream, shape: tuple[int, ...] = ()) -> NDArray[np.float64]:
        """Standard normal draws of shape (B, *shape) (Box-Muller)."""
        xp = self.xp
        u = self.uniform(stream, (2, *shape))
        return xp.sqrt(-2.0 * xp.log1p(-u[:, 0])) * xp.cos(2.0 * np.pi * u[:, 1])

    def keys_for(self, stream: Stream) -> NDArray[np.uint64]:
        """One fresh 64-bit key per trial (for kernels with streams of their own)."""
        return self._bits(stream, ())

    def gamma(self, shape: NDArray[np.float64]) -> NDArray[np.float64]:
        """``Gamma(shape, 1)`` draws for a shape array (B, ...) (Marsaglia & Tsang, 2000)."""
        shape = np.asarray(shape, dtype=np.float64)
        dims = shape.shape[1:]
        boost = shape < 1.0
        a = np.where(boost, shape + 1.0, shape)
        d = a - 1.0 / 3.0
        c = 1.0 / np.sqrt(9.0 * d)
        x = self.normal(Stream.GAMMA_NORMAL, (GAMMA_PROPOSALS, *dims))  # (B, P, ...)
        u = self.uniform(Stream.GAMMA_UNIFORM, (GAMMA_PROPOSALS + 2, *dims))
        v = (1.0 + c[:, None] * x) ** 3
        with np.errstate(invalid="ignore", divide="ignore"):
            accept = (v > 0) & (
                np.log(u[:, :GAMMA_PROPOSALS]) < 0.5 * x * x + d[:, None] * (1 - v + np.log(v))
            )
        first = np.argmax(accept, axis=1)[:, None]
        value = d * np.take_along_axis(v, first, axis=1)[:, 0]
        missing = ~accept.any(axis=1)
        if missing.any():  # rare: inverse CDF from the variate's own spare uniform
            import scipy.special

            value[missing] = scipy.special.gammaincinv(a[missing], u[:, GAMMA_PROPOSALS][missing])
        return np.where(boost, value * u[:, GAMMA_PROPOSALS + 1] ** (1.0 / shape), value)
