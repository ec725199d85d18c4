"""The torchrl env: torchrl's spec check, and a rollout that is the Flat vector env's on the same
device, step for step.

torchrl installs a top-level ``benchmarks`` package of its own, so it is never in the test
environment: these tests run where torchrl is (``pip install torchrl``), and `.ci/wheel-check`
runs the same check from the installed wheel on every CI run."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("torchrl")

from torchrl.envs.utils import check_env_specs  # noqa: E402

from mimo_radar_env.torchrl_env import MimoRadarSelectTorchRLEnv  # noqa: E402
from mimo_radar_env.wrappers import MimoRadarSelectFlatVectorEnv  # noqa: E402


def test_the_specs_pass_torchrls_check_and_the_trials_end_together():
    env = MimoRadarSelectTorchRLEnv(num_envs=4, device="cpu", horizon=12)
    check_env_specs(env)
    rollout = env.rollout(12)
    assert tuple(rollout.batch_size) == (4, 12) and rollout.device == torch.device("cpu")
    assert bool(rollout["next", "truncated"][:, -1].all()) and not bool(rollout["next", "done"][:, :-1].any())


def test_a_rollout_is_the_flat_vector_envs_step_for_step():
    env = MimoRadarSelectTorchRLEnv(num_envs=3, device="cpu", seed=7, horizon=8)
    flat = MimoRadarSelectFlatVectorEnv(
        num_envs=3, action="discrete", device="cpu", autoreset_mode="disabled", horizon=8
    )
    generator = torch.Generator().manual_seed(0)
    actions = torch.randint(0, int(flat.single_action_space.n), (8, 3), generator=generator)
    td = env.reset()
    features, _ = flat.reset(seed=7)
    np.testing.assert_array_equal(td["observation"].numpy(), features.numpy())
    for action in actions:
        td["action"] = action
        td = env.step(td)["next"]
        features, reward, *_ = flat.step(action)
        np.testing.assert_array_equal(td["observation"].numpy(), features.numpy())
        np.testing.assert_array_equal(td["reward"][:, 0].numpy(), reward.to(torch.float32).numpy())


def test_a_device_of_none_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"device must be a torch device .*, got None"):
        MimoRadarSelectTorchRLEnv(num_envs=2, device=None)
