"""The running normalisation is VecNormalize's."""

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="torch-ppo needs the rl extra")

from agents.networks import RunningNormalization  # noqa: E402


def test_running_normalisation_is_vecnormalizes():
    from stable_baselines3.common.running_mean_std import RunningMeanStd

    rng = np.random.default_rng(1)
    ours, sb3 = RunningNormalization(5), RunningMeanStd(shape=(5,))
    for size in (3, 1, 17, 8):
        batch = rng.normal(2.0, 3.0, (size, 5))
        ours.update(torch.as_tensor(batch))
        sb3.update(batch)
    np.testing.assert_allclose(ours.mean.numpy(), sb3.mean, rtol=1e-12)
    np.testing.assert_allclose(ours.var.numpy(), sb3.var, rtol=1e-12)
    x = rng.normal(0, 30, (4, 5))
    expected = np.clip((x - sb3.mean) / np.sqrt(sb3.var + 1e-8), -10, 10).astype(np.float32)
    np.testing.assert_allclose(ours(torch.as_tensor(x)).numpy(), expected, rtol=1e-6)
