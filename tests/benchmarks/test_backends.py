"""Every backend and worker count gives the numbers of one process."""

import numpy as np
import pytest

from benchmarks.harness import load_per_trial, make_config, run, run_many


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


def test_ray_backend_runs_a_studys_runs_together_with_the_numbers_of_each_alone(tmp_path):
    pytest.importorskip("ray", reason="the Ray backend needs the 'ray' extra: pip install -e '.[ray]'")
    configs = [
        make_config(n, ["mg-crb-cl", "fix1"], trials=3, steps=8, shard_size=2) for n in ("paper-1", "paper-2")
    ]
    folders = [tmp_path / "one", tmp_path / "two"]
    assert run_many(list(zip(configs, folders, strict=True)), backend="ray", progress=False) == [True, True]
    for config, folder in zip(configs, folders, strict=True):
        alone = run(config, folder.with_name(folder.name + "-alone"), workers=1, progress=False)
        together = load_per_trial(folder, config)
        for policy in config.policies:
            for key in ("trial_expected", "trial_squared_error", "trial_matches", "selections"):
                np.testing.assert_array_equal(alone[policy][key], together[policy][key])
