"""The feature observation: each channel's age and latest samples."""

import numpy as np

from mimo_radar_env.wrappers import (
    RadarFeatureObservation,
    make_ppo_env,
)


def test_features_track_age_and_latest_samples():
    env = make_ppo_env("paper-1-v1")
    assert isinstance(env, RadarFeatureObservation)
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape and obs.dtype == np.float32
    features = env.features
    assert (features.age == 0).all()
    env.step(0)  # super arm 0: TX1, TX2; RX1, RX2, RX3
    probed = np.zeros((4, 6), bool)
    probed[np.ix_([0, 1], [0, 1, 2])] = True
    assert (features.age[0][probed] == 0).all() and (features.age[0][~probed] == 1).all()
