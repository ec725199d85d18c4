"""Wrappers for learning agents (PPO and other deep RL): valid actions and flat features.

* :mod:`.actions`: :class:`SuperArmDiscreteAction` (one ``Discrete`` action per super arm) and
  :class:`StationScoreAction` (station scores, the top ``Ms`` and ``Ns`` selected);
* :mod:`.features`: :class:`RadarFeatures` and :class:`RadarFeatureObservation`, a flat
  ``Box`` an MLP can learn from (docs/ppo.md);
* :mod:`.flat`: :func:`make_flat_env`, the entry point of the registered
  ``MimoRadarSelectFlat-v0``/``-v1``, and :class:`MimoRadarSelectFlatVectorEnv`, their vector
  entry point.

All of them keep every action valid by construction: a policy never has to learn the
``Ms``/``Ns`` constraint.
"""

from .actions import (
    MAX_DISCRETE_SUPER_ARMS,
    StationScoreAction,
    SuperArmDiscreteAction,
    SuperArmIndex,
    check_discrete_actions,
    check_score_actions,
    scores_to_action,
)
from .features import RadarFeatureObservation, RadarFeatures
from .flat import (
    ACTION_FORMS,
    AUTO_DISCRETE_SUPER_ARMS,
    MimoRadarSelectFlatVectorEnv,
    action_form,
    make_flat_env,
    make_ppo_env,
    wrap_for_learning,
)

__all__ = [
    "ACTION_FORMS",
    "AUTO_DISCRETE_SUPER_ARMS",
    "MAX_DISCRETE_SUPER_ARMS",
    "MimoRadarSelectFlatVectorEnv",
    "RadarFeatureObservation",
    "RadarFeatures",
    "StationScoreAction",
    "SuperArmDiscreteAction",
    "SuperArmIndex",
    "action_form",
    "make_flat_env",
    "make_ppo_env",
    "check_discrete_actions",
    "check_score_actions",
    "scores_to_action",
    "wrap_for_learning",
]
