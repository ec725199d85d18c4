"""Shard files: written whole, read only when they are this run's, this block's and unaltered."""

import numpy as np
import pytest

from benchmarks import shards
from benchmarks.harness import make_config, run_task


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
