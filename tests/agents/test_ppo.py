"""The ppo agent: a model in rl-zoo3's layout runs with its statistics, as the harness records them."""

import numpy as np
import pytest

# ---------------------------------------------------------------- normalisation, the ecosystem's way


def test_a_model_in_rl_zoo3s_layout_runs_with_its_statistics_or_is_refused(small_model, tmp_path):
    import shutil

    from agents import PPOAgent

    # rl-zoo3: logs/ppo/ENV_1/ENV.zip, the statistics in logs/ppo/ENV_1/ENV/vecnormalize.pkl
    run = tmp_path / "MimoRadarSelectFlat-v1_1"
    (run / "MimoRadarSelectFlat-v1").mkdir(parents=True)
    model = run / "MimoRadarSelectFlat-v1.zip"
    shutil.copy(small_model / "model.zip", model)
    stats = run / "MimoRadarSelectFlat-v1" / "vecnormalize.pkl"
    shutil.copy(small_model / "vecnormalize.pkl", stats)
    with pytest.raises(
        ValueError, match=rf"statistics in {stats} \(rl-zoo3's layout\), which are not beside it"
    ):
        PPOAgent("paper-1-v1", model)
    with pytest.raises(ValueError, match="is a pickle .* pass allow_pickle=true"):
        PPOAgent("paper-1-v1", model, normalization=stats)
    with pytest.warns(UserWarning, match="unpickling"):
        agent = PPOAgent("paper-1-v1", model, normalization=stats, allow_pickle=True)
    reference = PPOAgent("paper-1-v1", small_model)  # train-ppo's folder: the npz beside the model
    np.testing.assert_array_equal(agent.normalization.obs_rms.mean, reference.normalization.obs_rms.mean)
    assert reference.normalization_file == small_model / "vecnormalize.npz"
    named = PPOAgent("paper-1-v1", model, normalization=small_model / "vecnormalize.npz")
    assert named.normalization_file == small_model / "vecnormalize.npz"
    with pytest.raises(ValueError, match="normalization file .* does not exist"):
        PPOAgent("paper-1-v1", model, normalization=tmp_path / "none.npz")


def test_the_harness_records_the_statistics_the_agent_applies(small_model, tmp_path):
    from benchmarks.harness import make_config

    config = make_config("paper-1-v1", [f"ppo:{small_model}"], trials=2, steps=2)
    files = config.policy_files[f"ppo:{small_model}"]
    assert set(files) == {str(small_model / "model.zip"), str(small_model / "vecnormalize.npz")}


@pytest.mark.parametrize("name", ["ppo", "maskable-ppo", "recurrent-ppo", "torch-ppo"])
def test_a_missing_model_is_named_by_its_own_agent(name, tmp_path):
    """Each learner names itself and what a path may be (every SB3 learner said "expected
    ppo:PATH/TO/model.zip", the command line's syntax, from the Python API too)."""
    pytest.importorskip("stable_baselines3", reason="needs the rl extra")
    import re

    import agents

    file = "model.pt" if name == "torch-ppo" else "model.zip"
    with pytest.raises(
        ValueError, match=rf"^{re.escape(name)} model {re.escape(str(tmp_path / file))} does not exist: give "
    ):
        agents.make_agent(name, "paper-1-v1", path=tmp_path)
