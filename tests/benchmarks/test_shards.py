"""Shard files: written whole, read only when they are this run's, this block's and unaltered."""

import numpy as np
import pytest

from benchmarks import shards
from benchmarks.harness import make_config, run_task
from benchmarks.shards import TRUTH_FIELD, ShardRecorder


@pytest.fixture(scope="module")
def one_shard():
    config = make_config("paper-3-v1", ["ucb1"], trials=3, steps=6, shard_size=3).to_json()
    return config, run_task(config, "ucb1", 0)


def test_a_shard_holds_every_documented_field_once_and_in_float64(one_shard):
    _, data = one_shard
    assert set(data) == set(shards.DATA_FIELDS)
    for name in shards.DATA_FIELDS:
        assert name in shards.__doc__, name  # the module docstring lists every field
    for name in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_bound_squared"):
        assert data[name].dtype == np.float64
    assert data["trial_expected"].shape == (3, 6) and data["trial_squared_error"].shape == (3, 6, 2)
    assert data["selections"].shape == (6, 4 + 6) and data["selections"].sum() == 3 * 6 * (2 + 3)


def test_write_then_read_round_trips_and_checks_identity_and_range(one_shard, tmp_path):
    config, data = one_shard
    path = shards.shard_path(tmp_path, "ucb1", 0)
    identity = shards.config_hash(config, "ucb1")
    shards.write_shard(path, data, range(0, 3), identity)
    back = shards.read_shard(path, range(0, 3), identity)
    for name in shards.DATA_FIELDS:
        np.testing.assert_array_equal(back[name], data[name])
    with pytest.raises(ValueError, match="another run or policy"):
        shards.read_shard(path, range(0, 3), shards.config_hash(config, "best"))
    with pytest.raises(ValueError, match=r"holds trials \[0, 3\]"):
        shards.read_shard(path, range(3, 6), identity)
    assert list(path.parent.glob("*.tmp.npz")) == []  # written atomically


def test_the_format_is_part_of_the_identity(one_shard, monkeypatch):
    config, _ = one_shard
    before = shards.config_hash(config, "ucb1")
    monkeypatch.setattr(shards, "SHARD_FORMAT", shards.SHARD_FORMAT + 1)
    assert shards.config_hash(config, "ucb1") != before


def test_policy_folders_are_readable_and_distinct():
    assert shards.policy_folder("mg-crb-cl") == "mg-crb-cl"
    assert shards.policy_folder("ppo:a/b_c.zip") != shards.policy_folder("ppo:a_b/c.zip")


@pytest.mark.parametrize("where", ["numpy", "torch"])
def test_the_recorder_gives_the_fields_computed_step_by_step_across_its_flushes(where):
    """130 steps (two flushes of 64 and a remainder) of random actions and infos: every field
    equals the field filled one step at a time on the host, bit for bit."""
    from mimo_radar_env.core.arrays import device_namespace

    rng = np.random.default_rng(4)
    n, T, K, S = 5, 130, 2, 7
    steps = []
    for _ in range(T):
        action = rng.integers(0, 2, (n, S)).astype(np.int8)
        optimal = action.copy()
        optimal[rng.random(n) < 0.5, 0] ^= 1
        info = {
            "expected_reward": rng.random(n),
            "optimal_reward": rng.random(n),
            "optimal_action": optimal,
            "true_state": rng.normal(size=(n, K, 4)),
            "position_error": rng.random((n, K)),
            "position_bound": rng.random((n, K)),
        }
        steps.append((action, info))
    first = rng.normal(size=(K, 4))
    if where == "torch":
        torch = pytest.importorskip("torch")
        xp = device_namespace("cpu")
        convert = torch.as_tensor
    else:
        xp, convert = device_namespace(None), np.asarray
    recorder = ShardRecorder(xp, xp.to_numpy, n, T, K, S, convert(first))
    for action, info in steps:
        recorder.add(convert(action), {key: convert(value) for key, value in info.items()})
    out = recorder.result()
    for t, (action, info) in enumerate(steps):
        np.testing.assert_array_equal(out["trial_expected"][:, t], info["expected_reward"])
        np.testing.assert_array_equal(out["trial_optimal"][:, t], info["optimal_reward"])
        matches = np.all(action == info["optimal_action"], axis=1)
        np.testing.assert_array_equal(out["trial_matches"][:, t], matches)
        np.testing.assert_array_equal(out["trial_squared_error"][:, t], info["position_error"] ** 2)
        np.testing.assert_array_equal(out["trial_bound_squared"][:, t], info["position_bound"] ** 2)
        np.testing.assert_array_equal(out["selections"][t], action.sum(axis=0))
        np.testing.assert_array_equal(out[TRUTH_FIELD][t + 1], info["true_state"][0][:, [0, 2]])
    np.testing.assert_array_equal(out[TRUTH_FIELD][0], first[:, [0, 2]])
    assert out["trial_matches"].dtype == np.uint8 and set(np.unique(out["trial_matches"])) == {0, 1}
