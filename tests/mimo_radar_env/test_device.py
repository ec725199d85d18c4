"""The batch engine on torch (``device=``), checked on CPU torch: the hash bit for bit, the draws,
whole episodes against the numpy engine, the Gymnasium surface, and the errors."""

import os

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from benchmarks.speed import device as device_bench  # noqa: E402
from mimo_radar_env.core import counter_hash  # noqa: E402
from mimo_radar_env.core.arrays import device_namespace, elementwise_products, float_precision  # noqa: E402
from mimo_radar_env.core.counter_hash import Stream  # noqa: E402
from mimo_radar_env.core.streams import TrialStreams, full_index  # noqa: E402
from tests.helpers import random_valid_actions, vector_env  # noqa: E402

CPU = device_namespace("cpu")
#: The device of the equality checks: CPU torch in CI; .ci/device-check sets "cuda" on a GPU.
DEVICE = os.environ.get("MIMO_RADAR_TEST_DEVICE", "cpu")


def _words(rng, size):
    """uint64 words covering the whole range, the top bit set in about half of them."""
    return rng.integers(0, 2**64, size=size, dtype=np.uint64, endpoint=False)


def test_the_hash_on_int64_words_gives_numpys_bits_and_uniforms_bit_for_bit():
    rng = np.random.default_rng(1)
    words = _words(rng, 100_000)
    words[:4] = [0, 1, 2**63, 2**64 - 1]
    ours = counter_hash.mix(CPU.words(words)).numpy().view(np.uint64)
    np.testing.assert_array_equal(ours, counter_hash.mix(words))
    keys = _words(rng, 50)
    base = counter_hash.stream_base(keys, Stream.MEASUREMENT, 7)
    base_t = counter_hash.stream_base(CPU.words(keys), Stream.MEASUREMENT, 7)
    np.testing.assert_array_equal(base_t.numpy().view(np.uint64), base)
    element = np.arange(2000)
    bits = counter_hash.element_bits(base[:, None], element[None])
    bits_t = counter_hash.element_bits(base_t[:, None], torch.arange(2000)[None])
    np.testing.assert_array_equal(bits_t.numpy().view(np.uint64), bits)
    np.testing.assert_array_equal(counter_hash.to_unit(bits_t).numpy(), counter_hash.to_unit(bits))


def test_the_trial_streams_draw_the_same_numbers_on_torch():
    keys = _words(np.random.default_rng(2), (6, 2))
    ours, theirs = TrialStreams(keys), TrialStreams(keys, CPU)
    index, index_t = full_index(6, (3, 4)), full_index(6, (3, 4), CPU)
    for draw in ("uniform", "exponential", "normal"):
        a = getattr(ours, draw)(Stream.SINR, 3, index)
        b = getattr(theirs, draw)(Stream.SINR, 3, index_t)
        assert isinstance(b, torch.Tensor) and b.dtype == torch.float64
        np.testing.assert_allclose(b.numpy(), a, rtol=1e-15, atol=0)


@pytest.mark.parametrize(
    ("version", "fusion", "trials", "steps", "elementwise"),
    [
        ("v1", "average", 3, None, False),
        ("v1", "centralized", 3, 250, False),
        ("v0", "average", 3, 250, False),
        ("v0", "centralized", 3, 250, False),
        ("v1", "average", 3, 250, True),  # the products as on CUDA
        ("v1", "centralized", 3, 250, True),
    ],
)
def test_an_episode_on_torch_equals_the_numpy_engine(version, fusion, trials, steps, elementwise):
    """Truth, observations, rewards, tracks and bounds within 1e-9 (normwise per trial), the oracle's
    actions identical; oracle and random valid actions, and a trial that probes nothing every
    fifth step; with the small matrix products as torch's and as broadcast products summed."""
    with elementwise_products(elementwise):
        worst = device_bench.episode_differences(version, fusion, trials, DEVICE, steps)
    assert worst["oracle_action"] == 0
    assert {"obs.track", "obs.sinr", "info.true_state", "info.position_bound", "reward"} <= set(worst)
    too_far = {k: v for k, v in worst.items() if not v <= device_bench.TOLERANCE}
    assert not too_far, too_far


@pytest.mark.slow
@pytest.mark.parametrize("version", ["v1", "v0"])
@pytest.mark.parametrize("fusion", ["average", "centralized"])
def test_whole_episodes_of_many_trials_on_torch_equal_the_numpy_engine(version, fusion):
    worst = device_bench.episode_differences(version, fusion, 16, DEVICE)
    assert worst["oracle_action"] == 0
    assert max(worst.values()) <= device_bench.TOLERANCE, worst


def test_the_vector_env_on_a_device_returns_tensors_there_and_takes_either_kind_of_action():
    env = vector_env("MimoRadarSelect-v1", 4, device="cpu")
    reference = vector_env("MimoRadarSelect-v1", 4)
    assert env.device == torch.device("cpu") and reference.device is None
    obs, info = env.reset(seed=5)
    reference.reset(seed=5)
    assert all(
        isinstance(v, torch.Tensor) and v.device.type == "cpu" for v in [*obs.values(), *info.values()]
    )
    sc = env.scenario
    actions = random_valid_actions(
        np.random.default_rng(0), 4, sc.num_tx, sc.num_rx, sc.tx_per_step, sc.rx_per_step
    )
    twin = vector_env("MimoRadarSelect-v1", 4, device="cpu")
    twin.reset(seed=5)
    a = env.step(actions)  # numpy actions
    b = twin.step(torch.as_tensor(actions, dtype=torch.float32))  # a float tensor of 0/1
    c = reference.step(actions)
    for one, other in ((a, b), (a, c)):
        assert device_bench.relative_difference(c[1], one[1]) <= 1e-12
        for key in c[4]:
            assert device_bench.relative_difference(one[4][key], other[4][key]) <= 1e-9, key
    assert isinstance(a[1], torch.Tensor) and a[2].dtype == torch.bool and a[3].dtype == torch.bool


def test_the_device_vector_env_resets_itself_after_the_horizon_with_tensors():
    env = vector_env("MimoRadarSelect-v1", 2, device="cpu", scenario="paper-1-v1", horizon=3)
    env.reset(seed=0)
    for _ in range(3):
        _, _, _, truncated, _ = env.step(env.oracle_action())
    assert bool(truncated.all())
    obs, reward, terminated, truncated, _ = env.step(env.oracle_action())  # next-step autoreset
    assert isinstance(reward, torch.Tensor) and not bool(truncated.any()) and not bool(terminated.any())
    assert int(obs["probed"].sum()) == 2 * env.scenario.num_tx * env.scenario.num_rx


@pytest.mark.parametrize(
    ("action", "message"),
    [
        (torch.zeros((2, 3), dtype=torch.int8), r"action must have shape \(2, 10\)"),
        (torch.full((2, 10), 2, dtype=torch.int64), r"action values must be 0 or 1, got \[2\]"),
        (torch.full((2, 10), float("nan")), "NaN or infinite"),
        (torch.zeros((2, 10), dtype=torch.complex64), "dtype"),
    ],
)
def test_bad_tensor_actions_are_refused_by_name(action, message):
    env = vector_env("MimoRadarSelect-v1", 2, device="cpu")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_the_single_env_takes_no_device_and_the_numpy_only_oracles_say_so():
    import gymnasium as gym

    with pytest.raises(TypeError, match="device"):
        gym.make("MimoRadarSelect-v1", device="cpu")
    env = vector_env("MimoRadarSelect-v1", 2, device="cpu")
    env.reset(seed=0)
    with pytest.raises(NotImplementedError, match="numpy only: make the env with device=None"):
        env.tracking_forecast(3)
    with pytest.raises(NotImplementedError, match="numpy only"):
        env.engine.bound_forecast()


def test_float32_draws_are_the_float64_draws_rounded():
    keys = _words(np.random.default_rng(4), (5, 2))
    double, single = TrialStreams(keys, CPU), TrialStreams(keys, CPU)
    index = full_index(5, (2, 3), CPU)
    for draw in ("uniform", "exponential", "normal"):
        a = getattr(double, draw)(Stream.MEASUREMENT, 2, index)
        with float_precision("float32"):
            b = getattr(single, draw)(Stream.MEASUREMENT, 2, index)
        assert b.dtype == torch.float32
        assert torch.equal(b, a.to(torch.float32)), draw


@pytest.mark.parametrize("fusion", ["average", "centralized"])
def test_float32_on_torch_returns_float32_and_stays_near_the_float64_numbers(fusion):
    """Every float the env returns is float32, and its numbers differ from numpy's by more than
    float64 rounding (it really is float32) and by no more than the error docs/performance.md
    states for it (measured there over whole episodes of more trials)."""
    env = vector_env("MimoRadarSelect-v1", 3, device=DEVICE, precision="float32", fusion=fusion)
    obs, info = env.reset(seed=1)
    _, reward, _, _, info = env.step(env.oracle_action())
    floats = [v for v in [*obs.values(), *info.values(), reward] if v.is_floating_point()]
    assert floats and all(v.dtype == torch.float32 for v in floats)
    worst = device_bench.episode_differences("v1", fusion, 3, DEVICE, 60, precision="float32")
    assert worst["info.true_state"] <= 1e-5 and worst["obs.sinr"] <= 1e-4
    numbers = {k: v for k, v in worst.items() if k != "oracle_action"}
    assert 1e-7 < max(numbers.values()) <= 5e-2, numbers


def test_float32_is_refused_on_numpy_and_an_unknown_precision_is_refused():
    with pytest.raises(ValueError, match="precision='float32' runs on torch"):
        vector_env("MimoRadarSelect-v1", 2, precision="float32")
    with pytest.raises(ValueError, match="precision must be one of 'float64', 'float32', got 'half'"):
        vector_env("MimoRadarSelect-v1", 2, device="cpu", precision="half")
