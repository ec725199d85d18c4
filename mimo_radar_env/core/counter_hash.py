"""The counter-based hash behind every random draw of the project (numpy and numba twins).

A draw is a pure function of ``(key, stream, step, element)``: the SplitMix64 finaliser
(Steele, Lea & Flood, OOPSLA 2014) applied twice,

* ``base = mix(key ^ mix(counter(stream, step) * GOLDEN))`` with
  ``counter(stream, step) = stream * 2^32 + step + 1`` (the one counter layout), then
* ``bits = mix(base + (element + 1) * GOLDEN)``.

Every stream has one identifier in :class:`Stream`; the env's truth and observation
streams and the BPSO solver's streams share the layout, so no two of them can collide.
Identifiers never change once published: they are part of every recorded number.

numba is optional: its twins (:mod:`._counter_hash_kernels`, which the compiled kernels import)
compute the same integers as the numpy functions.
"""

from __future__ import annotations

from enum import IntEnum
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .arrays import namespace

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
MUL1 = np.uint64(0xBF58476D1CE4E5B9)
MUL2 = np.uint64(0x94D049BB133111EB)
#: Steps (or iterations) of one stream: ``step < 2^32``.
STEP_BITS = 32
TWO_POW_M53 = 2.0**-53


class Stream(IntEnum):
    """Identifiers of the random streams (never renumbered)."""

    BPSO_R1 = 1  #: BPSO's ``r1`` of eq20, per particle and iteration
    BPSO_R2 = 2  #: BPSO's ``r2`` of eq20
    BPSO_FLIP = 3  #: BPSO's position draws of eq21 (four 16-bit lanes per hash)
    BPSO_INIT = 4  #: reserved: the initial particles of a candidate BPSO kernel (in the tree to 0b8e389)
    INITIAL_STATE = 0x100  #: the truth: initial states
    PROCESS_NOISE = 0x200  #: the truth: process noise
    SINR = 0x300  #: observations: Swerling-I SINR samples
    MEASUREMENT = 0x400  #: observations: measurement noise
    INITIAL_ESTIMATE = 0x500  #: a trial's initial estimate error (shared truth, reading 1)
    SHARED_TRUTH_KEY = 0x600  #: the truth key of a scenario's ``truth_seed`` (shared truth)
    AGENT_KEY = 0x1000  #: an agent's per-trial keys, from its seed + trial index
    AGENT_EXPLORE = 0x1001  #: epsilon-greedy's exploration coin
    AGENT_RANDOM_TX = 0x1002  #: uniformly random super arms: transmitters
    AGENT_RANDOM_RX = 0x1003  #: uniformly random super arms: receivers
    BPSO_INIT_TX = 0x1004  #: BPSO's initial particles: transmitters
    BPSO_INIT_RX = 0x1005  #: BPSO's initial particles: receivers
    BPSO_KEYS = 0x1006  #: the per-trial keys of BPSO's iteration streams (1, 2, 3)
    ALTERNATING_STARTS = 0x1007  #: random starts of alternating maximisation
    GAMMA_NORMAL = 0x1008  #: Thompson sampling's Gamma draws: normals
    GAMMA_UNIFORM = 0x1009  #: Thompson sampling's Gamma draws: uniforms
    PPO_ACTION = 0x100A  #: torch-ppo's training: the action sampled per trial and step
    PPO_MINIBATCH = 0x100B  #: torch-ppo's training: the order of a rollout's samples per epoch


#: Streams drawn from a trial's observation key; the others use its truth key.
OBSERVATION_STREAMS = frozenset({Stream.SINR, Stream.MEASUREMENT, Stream.INITIAL_ESTIMATE})


def mix(z: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """SplitMix64 finaliser: a bijection of 64-bit words with good avalanche (numpy ``uint64`` or
    torch ``int64`` words, :mod:`.arrays`)."""
    xp = namespace(z)
    z = (z ^ xp.shift_right(z, 30)) * xp.word(int(MUL1))
    z = (z ^ xp.shift_right(z, 27)) * xp.word(int(MUL2))
    return z ^ xp.shift_right(z, 31)


def counter(stream: int, step: int) -> np.uint64:
    """The one counter layout: ``stream * 2^32 + step + 1``."""
    if not 0 <= step < 2**STEP_BITS:
        raise ValueError(f"step must be in [0, 2^{STEP_BITS}), got {step}")
    return np.uint64((int(stream) << STEP_BITS) + step + 1)


def stream_base(keys: NDArray[np.uint64], stream: int, step: Any) -> NDArray[np.uint64]:
    """``mix(key ^ mix(counter * GOLDEN))`` for every key. ``step`` is an integer, or on torch a
    0-d ``int64`` tensor on the keys' device (a step read on the device, never by the host: a
    CUDA graph replays it at every step); both give the same bits."""
    xp = namespace(keys)
    if not xp.is_torch or not isinstance(step, xp.torch.Tensor):
        salt = int(mix(np.array([counter(stream, step)]) * GOLDEN)[0])
        return mix(xp.words(keys) ^ xp.word(salt))
    count = step + xp.word((int(stream) << STEP_BITS) + 1)  # counter(stream, step), wrapped alike
    return mix(xp.words(keys) ^ mix(count * xp.word(int(GOLDEN))))


def stream_bases(keys: NDArray[np.uint64], stream: int, steps: int) -> NDArray[np.uint64]:
    """:func:`stream_base` of steps ``0 .. steps - 1`` at once, (B, steps), the same bits: a loop
    that draws once per step reads its column instead of hashing the keys again (on torch, with
    nothing copied from the host)."""
    if not 0 < steps <= 2**STEP_BITS:
        raise ValueError(f"steps must be in [1, 2^{STEP_BITS}], got {steps}")
    xp = namespace(keys)
    first = (int(stream) << STEP_BITS) + 1  # counter(stream, 0)
    if xp.is_torch:
        salts = mix((xp.arange(steps, dtype=np.int64) + xp.word(first)) * xp.word(int(GOLDEN)))
    else:
        salts = mix((np.arange(steps, dtype=np.uint64) + np.uint64(first)) * GOLDEN)
    return mix(xp.words(keys)[:, None] ^ salts[None, :])


def element_bits(base: NDArray[np.uint64], element: NDArray[np.integer]) -> NDArray[np.uint64]:
    """64 hashed bits per element: ``mix(base + (element + 1) * GOLDEN)``."""
    xp = namespace(base)
    # the constant as an array: a compiler that folds an arange's arithmetic into its index
    # expressions would overflow on a 64-bit product (torch inductor does); an array it loads
    golden = xp.word_array(int(GOLDEN)) if xp.is_torch else xp.word(int(GOLDEN))
    return mix(base + (xp.word_index(element) + xp.word(1)) * golden)


def to_unit(bits: NDArray[np.uint64]) -> NDArray[np.float64]:
    """The top 53 bits as a uniform double in [0, 1) (a double in any precision, :mod:`.arrays`:
    ``xp.float64`` is the dtype itself)."""
    xp = namespace(bits)
    return xp.astype(xp.shift_right(bits, 11), xp.float64) * TWO_POW_M53
