"""The Flat ids' vector entry point: the batch engine with the Flat env's action and features,
equal to N single Flat envs trial for trial, across the next-step autoreset."""

import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import mimo_radar_env  # noqa: F401  (registers the ids)
from mimo_radar_env.wrappers import MimoRadarSelectFlatVectorEnv
from tests.helpers import vector_env


@pytest.mark.parametrize("action", ["discrete", "scores"])
def test_the_flat_vector_env_equals_single_flat_envs_trial_for_trial(action):
    trials, horizon, seed = 3, 4, 11
    venv = vector_env(
        "MimoRadarSelectFlat-v1",
        trials,
        horizon=horizon,
        action=action,
    )
    assert isinstance(venv.unwrapped, MimoRadarSelectFlatVectorEnv)
    singles = [gym.make("MimoRadarSelectFlat-v1", horizon=horizon, action=action) for _ in range(trials)]
    assert venv.single_action_space == singles[0].action_space
    assert venv.single_observation_space == singles[0].observation_space
    rng = np.random.default_rng(0)
    obs, _ = venv.reset(seed=seed)
    single_obs = [env.reset(seed=seed + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(single_obs))
    for step in range(2 * horizon + 1):  # two episodes: the step after the first resets all trials
        if action == "scores":
            actions = rng.uniform(-1, 1, venv.action_space.shape).astype(np.float32)
        else:
            actions = rng.integers(0, venv.single_action_space.n, trials)
        obs, reward, terminated, truncated, _ = venv.step(actions)
        if step == horizon:  # the autoreset step: single envs are reset without a seed
            expected = [env.reset()[0] for env in singles]
            np.testing.assert_array_equal(obs, np.stack(expected))
            assert not truncated.any() and (reward == 0).all()
            continue
        for i, env in enumerate(singles):
            o, r, te, tr, _ = env.step(actions[i])
            np.testing.assert_array_equal(obs[i], o)
            assert reward[i] == r and terminated[i] == te and truncated[i] == tr
    assert truncated.all()


def test_the_flat_vector_env_gives_masks_and_refuses_a_bad_action_form():
    venv = MimoRadarSelectFlatVectorEnv(num_envs=2, scenario="paper-1-v1")
    assert venv.action_form == "discrete" and venv.action_masks().shape == (2, 6 * 20)  # C(4, 2) C(6, 3)
    assert venv.action_masks().all()
    with pytest.raises(ValueError, match=r"action must be one of \['auto', 'discrete', 'scores'\], got 'x'"):
        MimoRadarSelectFlatVectorEnv(num_envs=2, action="x")
    scores = MimoRadarSelectFlatVectorEnv(num_envs=2, action="scores")
    with pytest.raises(ValueError, match="station-score actions have no mask"):
        scores.action_masks()
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"super-arm index must be in \[0, 120\)"):
        venv.step(np.array([0, 120]))


# ---------------------------------------------------------------- guard rails on the raw id
def test_an_episode_of_mostly_invalid_actions_warns_once_naming_the_flat_id():
    env = gym.make("MimoRadarSelect-v1", horizon=4)
    nothing = np.zeros(env.action_space.shape, dtype=np.int8)
    for episode in range(2):
        env.reset(seed=episode)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            for _ in range(4):
                env.step(nothing)
        messages = [str(w.message) for w in caught if "probed nothing" in str(w.message)]
        assert len(messages) == (1 if episode == 0 else 0)  # once per env
        if messages:
            assert "4 of the episode's 4 actions" in messages[0]
            assert "MimoRadarSelectFlat-v1" in messages[0] and "invalid_action='raise'" in messages[0]


def test_the_invalid_actions_warning_names_the_line_that_stepped_the_vector_env():
    """The warning points at the caller's step, through the engine's precision wrapper."""
    env = gym.make_vec("MimoRadarSelect-v1", num_envs=2, vectorization_mode="vector_entry_point", horizon=3)
    env.reset(seed=0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(3):
            env.step(np.zeros((2, env.single_action_space.n), dtype=np.int8))
    (warning,) = [w for w in caught if "probed nothing" in str(w.message)]
    assert warning.filename == __file__


def test_an_episode_of_mostly_valid_actions_does_not_warn():
    env = gym.make("MimoRadarSelect-v1", horizon=4)
    nothing = np.zeros(env.action_space.shape, dtype=np.int8)
    env.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for step in range(4):  # two of four invalid: not most of them
            env.step(nothing if step < 2 else env.unwrapped.oracle_action())


def test_render_human_without_a_display_says_so(monkeypatch):
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "get_backend", lambda: "agg")
    env = gym.make("MimoRadarSelect-v1", horizon=4, render_mode="human")
    with pytest.warns(
        UserWarning, match=r"render_mode='human' shows nothing here: matplotlib's backend is 'agg'"
    ):
        env.reset(seed=0)
    env.close()


#: SB3's check_env warnings on the raw id, each explained in docs/clients.md: the Dict
#: observation's entries of 2 or 3 axes look to SB3 like vectors of odd shape or like images.
EXPLAINED = (
    "has an unconventional shape (neither an image, nor a 1D vector)",
    "is an image but its `dtype` is (float64)",
    "is an image but the upper and lower bounds are not in [0, 255]",
    "The minimal resolution for an image is 36x36",
    "probed nothing (reward 0)",  # ours: check_env's random MultiBinary actions are mostly invalid
)


def test_check_env_warns_on_the_raw_id_only_as_the_docs_explain():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.env_checker import check_env

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(gym.make("MimoRadarSelect-v1", horizon=5).unwrapped, warn=True)
    messages = {str(w.message) for w in caught if w.category is UserWarning}
    assert messages, "check_env gave no warning: update docs/clients.md"
    unexplained = [m for m in messages if not any(e in m for e in EXPLAINED)]
    assert not unexplained
    docs = (Path(__file__).parents[3] / "docs" / "clients.md").read_text()
    for phrase in ("unconventional shape", "looks like an image", "probed nothing"):
        assert phrase in docs
    with warnings.catch_warnings(record=True) as caught:  # the Flat id: none at all
        warnings.simplefilter("always")
        check_env(gym.make("MimoRadarSelectFlat-v1", horizon=5), warn=True)
    assert not caught


def test_with_autoreset_disabled_the_caller_resets_every_trial_at_once():
    venv = vector_env(
        "MimoRadarSelectFlat-v1",
        2,
        horizon=2,
        autoreset_mode="disabled",
    )
    assert venv.unwrapped.autoreset_mode is gym.vector.AutoresetMode.DISABLED
    first, _ = venv.reset(seed=3)
    for _ in range(2):
        *_, truncated, _ = venv.step(np.array([0, 1]))
    assert truncated.all()
    with pytest.raises(RuntimeError, match=r"call reset\(\) \(autoreset_mode='disabled'\)"):
        venv.step(np.array([0, 1]))
    with pytest.raises(ValueError, match="reset_mask must select every trial"):
        venv.reset(options={"reset_mask": np.array([True, False])})
    again, _ = venv.reset(seed=3, options={"reset_mask": np.array([True, True])})
    np.testing.assert_array_equal(first, again)
    with pytest.raises(ValueError, match=r"autoreset_mode must be one of \['next-step', 'disabled'\]"):
        vector_env("MimoRadarSelectFlat-v1", 2, autoreset_mode="x")


#: Gymnasium's check_env warnings, each explained in docs/clients.md: the checker's own notice
#: that it was given a wrapped env, the Flat features' unbounded Box, and the headless notice.
GYMNASIUM_EXPLAINED = {
    "MimoRadarSelect-v1": ("render_mode='human' shows nothing here",),
    "MimoRadarSelectFlat-v1": (
        "is different from the unwrapped version",
        "A Box observation space minimum value is -infinity",
        "A Box observation space maximum value is infinity",
        "render_mode='human' shows nothing here",
    ),
}


@pytest.mark.parametrize("env_id", sorted(GYMNASIUM_EXPLAINED))
def test_gymnasiums_check_env_warns_only_as_the_docs_explain(env_id):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(env_id, horizon=5)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped if env_id == "MimoRadarSelect-v1" else env)
    messages = {str(w.message) for w in caught}
    unexplained = [m for m in messages if not any(e in m for e in GYMNASIUM_EXPLAINED[env_id])]
    assert not unexplained
    docs = (Path(__file__).parents[3] / "docs" / "clients.md").read_text()
    assert "Gymnasium's own `check_env`" in docs and "unbounded" in docs


def test_the_flat_ids_oracle_acts_in_their_own_action_space():
    env = gym.make("MimoRadarSelectFlat-v1", horizon=5)
    env.reset(seed=0)
    for _ in range(3):
        action = env.get_wrapper_attr("oracle_action")()
        assert env.action_space.contains(action)
        _, _, _, _, info = env.step(action)
        assert np.isclose(info["expected_reward"], info["optimal_reward"])
    scores = gym.make("MimoRadarSelectFlat-v1", horizon=5, action="scores")
    scores.reset(seed=0)
    assert scores.action_space.contains(scores.get_wrapper_attr("oracle_action")())
    venv = vector_env("MimoRadarSelectFlat-v1", 3, horizon=5)
    venv.reset(seed=0)
    index = venv.oracle_action()
    assert venv.action_space.contains(index) and index.shape == (3,)
    np.testing.assert_array_equal(venv.to_env_actions(index), venv.oracle_env_action())
    _, _, _, _, info = venv.step(index)
    assert np.allclose(info["expected_reward"], info["optimal_reward"])


def test_the_super_arm_index_converts_both_ways():
    from mimo_radar_env import load_scenario
    from mimo_radar_env.wrappers import SuperArmIndex

    index = SuperArmIndex(load_scenario("paper-1-v1"))
    every = np.arange(index.size)
    np.testing.assert_array_equal(index.to_index(index.to_action(every)), every)
    assert index.to_index(index.to_action(7)) == 7
    with pytest.raises(ValueError, match="not a valid super arm"):
        index.to_index(np.ones(10, dtype=np.int8))


@pytest.mark.parametrize("env_id", ["MimoRadarSelect-v1", "MimoRadarSelectFlat-v1"])
def test_every_vector_id_takes_autoreset_mode_and_has_the_horizon_in_its_spec(env_id):
    venv = vector_env(env_id, 2, horizon=3, autoreset_mode="disabled")
    assert venv.spec.max_episode_steps == 3 and venv.metadata["autoreset_mode"] == AutoresetMode.DISABLED
    venv.reset(seed=0)
    for _ in range(3):
        venv.step(venv.action_space.sample() if "Flat" in env_id else venv.sample_action())
    with pytest.raises(RuntimeError, match="call reset"):
        venv.step(venv.action_space.sample() if "Flat" in env_id else venv.sample_action())
    with pytest.raises(ValueError, match="autoreset_mode must be one of"):
        vector_env(env_id, 2, autoreset_mode="sometimes")


@pytest.mark.parametrize(
    ("action", "message"),
    [
        (2.7, r"must be an integer super-arm index in \[0, 120\), got .*2\.7"),
        ("3", r"got .*'3'"),
        (True, r"got .*True"),
        (float("nan"), r"got .*nan"),
        (120, r"index must be in \[0, 120\), got \[120"),
        (-1, r"got \[-1"),
    ],
)
def test_a_bad_discrete_action_is_refused_as_given_by_the_single_and_the_vector_flat_env(action, message):
    env = gym.make("MimoRadarSelectFlat-v1", horizon=5)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)
    venv = vector_env("MimoRadarSelectFlat-v1", 2, horizon=5)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        venv.step(
            np.array([action, action], dtype=object)
            if isinstance(action, str)
            else np.array([action, action])
        )


@pytest.mark.parametrize(
    ("scores", "message"),
    [
        (np.full(10, 1e9), r"finite and in \[-1, 1\], got \[1000000000.0"),
        (np.full(10, np.inf), r"got \[inf"),
        (np.zeros(3), r"must have shape \(10,\), got shape \(3,\)"),
        ("x", r"real numbers in \[-1, 1\], got 'x'"),
    ],
)
def test_out_of_space_scores_are_refused_not_clipped(scores, message):
    env = gym.make("MimoRadarSelectFlat-v1", horizon=5, action="scores")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(scores)


@pytest.mark.parametrize(
    ("env_id", "seed", "options", "message"),
    [
        ("MimoRadarSelect-v1", "7", None, r"seed must be None or an integer >= 0.*, got '7'"),
        ("MimoRadarSelect-v1", True, None, "got True"),
        ("MimoRadarSelectFlat-v1", -1, None, "got -1"),
        ("MimoRadarSelect-v1", 0, {"horizon": 5}, r"reset takes no options here, got \{'horizon': 5\}"),
    ],
)
def test_reset_arguments_are_checked_on_single_and_vector_envs(env_id, seed, options, message):
    with pytest.raises(ValueError, match=message):
        gym.make(env_id).reset(seed=seed, options=options)
    with pytest.raises(ValueError, match=message):
        vector_env(env_id, 2).reset(seed=seed, options=options)
