"""Every backend and worker count gives the numbers of one process."""

import numpy as np
import pytest

from benchmarks.harness import make_config, run


def test_local_workers_give_the_numbers_of_one_process(tmp_path):
    config = make_config("paper-1", ["mg-crb-cl", "ucb1"], trials=4, steps=15, shard_size=1)
    one = run(config, tmp_path / "one", workers=1, progress=False)
    two = run(config, tmp_path / "two", workers=2, progress=False)
    for policy in config.policies:
        for key in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_matches", "selections"):
            np.testing.assert_array_equal(one[policy][key], two[policy][key])


def test_ray_backend_gives_the_numbers_of_the_local_path(tmp_path):
    pytest.importorskip("ray", reason="the Ray backend needs the 'ray' extra: pip install -e '.[ray]'")
    config = make_config("paper-3", ["mg-crb-cl", "fix2"], trials=4, steps=15, shard_size=2)
    local = run(config, tmp_path / "local", workers=1, progress=False)
    remote = run(config, tmp_path / "ray", backend="ray", progress=False)
    for policy in config.policies:
        for key in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_matches", "selections"):
            np.testing.assert_array_equal(local[policy][key], remote[policy][key])
