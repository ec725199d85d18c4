"""Tracking-UCB: MG-CRB-CL's SINR learning, selecting the super arm that tracks best."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mimo_radar_env import Scenario
from mimo_radar_env.core.arrays import NumpyNamespace, TorchNamespace, namespace
from mimo_radar_env.core.model import RadarModel
from mimo_radar_env.core.motion import positions
from mimo_radar_env.core.superarm import super_arm_count
from mimo_radar_env.envs.options import option_choices
from mimo_radar_env.tracking.fusion import DEFAULT_FUSION
from mimo_radar_env.tracking.information import channel_information
from mimo_radar_env.tracking.selection import (
    CRITERIA,
    MAX_ENUMERATED_SUPER_ARMS,
    select_for_tracking,
)

from .base import Agent, Observation, fuse_targets
from .costs import BOOKKEEPING, TRACKING_SEARCH, Needs
from .mg_crb_cl import LearningParameters, MGCRBCLEstimator
from .parameters import check_parameter

#: The observation key the policy scores super arms with (env option ``prediction_covariance``).
PREDICTED_COVARIANCE = "track_pred_pos_cov"


class TrackingSelector:
    """The super arm with the smallest predicted posterior position error, from a measurement
    quality per target and channel (docs/model.md, section 14).

    ``select`` maps SINR values (B, K, M, N) through eq32 to ``lambda`` (or takes the constant
    ``measurement_quality``), builds each channel's position information at the tracker's
    prediction and searches the super arms (:func:`~mimo_radar_env.tracking.selection.select_for_tracking`)
    under ``fusion``; with ``sinr_weight`` > 0 it trades the criterion against a fused SINR
    index.
    """

    def __init__(
        self,
        scenario: Scenario,
        criterion: str = "trace",
        fusion: str = DEFAULT_FUSION,
        lambda_scale: str = "db",
        measurement_quality: float | None = None,
        sinr_weight: float = 0.0,
    ) -> None:
        if criterion not in CRITERIA:
            raise ValueError(f"criterion must be one of {list(CRITERIA)}, got {criterion!r}")
        choices = option_choices()  # the env options' own choices
        for option, value in (("fusion", fusion), ("lambda_scale", lambda_scale)):
            if value not in choices[option]:
                raise ValueError(f"{option} must be one of {list(choices[option])}, got {value!r}")
        check_parameter("sinr_weight", sinr_weight, 0.0, 1.0)
        if measurement_quality is not None:
            check_parameter("measurement_quality", measurement_quality, 0.0, low_open=True)
        count = super_arm_count(scenario.num_tx, scenario.num_rx, scenario.tx_per_step, scenario.rx_per_step)
        if sinr_weight > 0 and count > MAX_ENUMERATED_SUPER_ARMS:
            raise ValueError(
                f"sinr_weight > 0 scores every super arm: at most {MAX_ENUMERATED_SUPER_ARMS:,}, "
                f"this layout has {count:,}"
            )
        self.scenario = scenario
        self.criterion, self.fusion, self.lambda_scale = criterion, fusion, lambda_scale
        self.measurement_quality = measurement_quality
        self.sinr_weight = float(sinr_weight)
        self.model = RadarModel.from_scenario(scenario)
        self._models: dict[str, RadarModel] = {}

    def model_in(self, xp: NumpyNamespace | TorchNamespace) -> RadarModel:
        """The scenario's model with its arrays in namespace ``xp`` (made once per device)."""
        if not xp.is_torch:
            return self.model
        key = str(xp.device)
        if key not in self._models:
            self._models[key] = self.model.to(xp)
        return self._models[key]

    def variance(self, sinr: NDArray[np.float64]) -> NDArray[np.float64]:
        """The channels' measurement variances (..., 2) for SINR values: eq32's ``lambda`` (or the
        constant ``measurement_quality``), then ``Sigma0 / lambda``."""
        xp = namespace(sinr)
        model = self.model_in(xp)
        if self.measurement_quality is None:
            quality = model.quality(sinr, scale=self.lambda_scale)  # eq32
        else:
            quality = xp.full(tuple(sinr.shape), float(self.measurement_quality))
        return model.measurement_variance(quality)

    def select(
        self, obs: Observation, sinr: NDArray[np.float64], sinr_index: NDArray[np.float64] | None = None
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """TX and RX masks (B, M), (B, N) for the coming step."""
        variance = self.variance(sinr)
        model = self.model_in(namespace(sinr))
        predicted = positions(obs["track_pred"])
        information = channel_information(predicted, model.tx, model.rx, variance)
        return select_for_tracking(
            obs[PREDICTED_COVARIANCE],
            information,
            self.scenario.weights,
            self.scenario.tx_per_step,
            self.scenario.rx_per_step,
            self.criterion,
            self.fusion,
            sinr_index=sinr_index,
            sinr_weight=self.sinr_weight,
        )


class TrackingUCB(Agent):
    """Tracking-UCB: learns the channels' SINR as MG-CRB-CL does and selects for tracking.

    It is composed of MG-CRB-CL's SINR learning (:class:`~agents.mg_crb_cl.MGCRBCLEstimator`:
    eq16's geometric prediction ``Y_bar``, eq14's update, eq15's counts and eq18's optimism,
    ``Y_up = Y_bar + sqrt(beta ln t / d)``) and a :class:`TrackingSelector`: instead of
    maximising the summed index it turns ``Y_up`` into a measurement quality
    ``lambda_hat = eq32(Y_up)`` and picks the super arm with the smallest predicted posterior
    position error (docs/model.md, section 14): ``sum_k Omega_k trace`` (or ``log det``) of the
    position block of ``(P_bar^-1 + sum_{(m, n) in A} H_mn' R_mn^-1 H_mn)^-1``, where
    ``R_mn = Sigma0 / lambda_hat_mn``, ``H_mn`` is eq6's Jacobian at the tracker's prediction
    (observation ``track_pred``) and ``P_bar`` the tracker's predicted position covariance
    (observation ``track_pred_pos_cov``: make the env with ``prediction_covariance=True``).
    It reads no truth. Optimism makes it probe channels it knows little about: a larger
    SINR means a smaller predicted error.

    Parameters
    ----------
    alpha, alpha_bar, beta : float
        MG-CRB-CL's estimator parameters (:class:`~agents.mg_crb_cl.LearningParameters`).
    criterion : {"trace", "logdet"}
        The predicted position MSE (m^2) or the log-determinant of the position covariance.
    fusion : {"average", "centralized"}
        The fusion whose posterior is predicted (as the env's ``fusion`` option; the harness
        passes the run's). ``"average"`` averages the channels' single-channel posteriors
        (eq22), ``"centralized"`` adds their information.
    lambda_scale : {"linear", "db"}
        The scale of eq32's SINR-to-quality mapping (as the env's option; the harness passes
        the run's).
    measurement_quality : float or None
        As the env's option (the harness passes the run's): ``None`` maps the optimistic SINR
        through eq32; a number is the constant ``lambda`` of every channel, so only geometry
        is scored.
    sinr_weight : float
        In [0, 1]: 0 selects for tracking only; ``w`` > 0 minimises ``(1 - w) c(A) - w s(A)``,
        the criterion ``c`` and MG-CRB-CL's index sum ``s`` (eq34), each rescaled to [0, 1]
        over the step's super arms; 1 is MG-CRB-CL with exact search. Needs at most
        5,000 super arms when above 0.
    seed : int, optional
        Unused (the policy draws nothing); accepted like every agent's.
    """

    name = "tracking-ucb"
    needs = Needs(
        tracking=True,
        observation_options={"prediction_covariance": True},
        env_option_params=("fusion", "lambda_scale", "measurement_quality"),
        tracking_search=True,
        device=True,
    )
    costs = (BOOKKEEPING, TRACKING_SEARCH)
    keyword_parameters = LearningParameters

    def __init__(
        self,
        scenario: Scenario | str,
        seed: int | None = None,
        criterion: str = "trace",
        fusion: str = DEFAULT_FUSION,
        lambda_scale: str = "db",
        sinr_weight: float = 0.0,
        measurement_quality: float | None = None,
        **learning: float,
    ) -> None:
        super().__init__(scenario, seed, **learning)
        #: What it learns (MG-CRB-CL's estimates) and how it selects.
        self.learning = MGCRBCLEstimator(self.scenario, self.parameters)
        self.selector = TrackingSelector(
            self.scenario, criterion, fusion, lambda_scale, measurement_quality, sinr_weight
        )

    def env_option_values(self) -> dict[str, Any]:
        return {key: getattr(self.selector, key) for key in self.needs.env_option_params}

    def _reset(self, obs: Observation) -> None:
        if PREDICTED_COVARIANCE not in obs:
            raise ValueError(
                f"{self.name} scores super arms with the tracker's predicted covariance: "
                "make the env with prediction_covariance=True"
            )
        self.learning.reset(obs)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        self.learning.predict(obs)  # eq16
        optimistic = self.learning.optimistic(self.t)  # eq18, per target
        index = fuse_targets(self.weights, optimistic) if self.selector.sinr_weight > 0 else None  # eq34
        tx, rx = self.selector.select(obs, optimistic, sinr_index=index)
        return self.actions_from_masks(tx, rx)

    def _update(self, obs: Observation, reward: NDArray[np.float64]) -> None:
        self.learning.update(obs)
