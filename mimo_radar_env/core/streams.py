"""Counter-based random streams of the simulation, vectorised over Monte-Carlo trials.

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
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

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
    """

    def __init__(self, keys: ArrayLike) -> None:
        keys = np.asarray(keys, dtype=np.uint64)
        if keys.ndim != 2 or keys.shape[1] != 2:
            raise ValueError(f"keys must have shape (B, 2), got {keys.shape}")
        self.keys = keys

    @property
    def batch_size(self) -> int:
        return self.keys.shape[0]

    def _bits(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.uint64]:
        """Hash of (key, stream, step, index); ``index`` has shape (B, ...)."""
        key = self.keys[:, 1 if stream in OBSERVATION_STREAMS else 0]
        base = stream_base(key, stream, step).reshape((-1,) + (1,) * (index.ndim - 1))
        return element_bits(base, index)

    def uniform(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.float64]:
        """U[0, 1) draws, one per element of ``index`` (shape (B, ...))."""
        return to_unit(self._bits(stream, step, index))

    def exponential(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.float64]:
        """Exponential(1) draws."""
        return -np.log1p(-self.uniform(stream, step, index))

    def normal(self, stream: Stream, step: int, index: NDArray[np.integer]) -> NDArray[np.float64]:
        """Standard normal draws (Box-Muller on two hashed uniforms per element)."""
        doubled = 2 * np.asarray(index, dtype=np.int64)
        u1 = self.uniform(stream, step, doubled)
        u2 = self.uniform(stream, step, doubled + 1)
        return np.sqrt(-2.0 * np.log1p(-u1)) * np.cos(2.0 * np.pi * u2)


def full_index(batch_size: int, shape: tuple[int, ...]) -> NDArray[np.int64]:
    """Element indices ``0..prod(shape)-1`` broadcast to (B, *shape)."""
    index = np.arange(int(np.prod(shape)), dtype=np.int64).reshape(shape)
    return np.broadcast_to(index, (batch_size, *shape))
