"""The options of ``MimoRadarSelect``: one typed, documented, validated set.

:class:`EnvOptions` is the one home of every env option, its choices, its default and its
help text. The single env, the native vector env, the benchmark harness (``config.json``)
and the command line (``mimo-radar-bench run --fusion ...``) all read them from here.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from ..core.superarm import SUPER_ARM_METHODS
from ..scenarios import Scenario, load_scenario
from ..tracking import FUSIONS

#: The scenario of the env class made without a ``scenario`` keyword (each registered version
#: names its own: :mod:`mimo_radar_env.envs.versions`).
DEFAULT_SCENARIO = "paper-1"


FusionName = Literal[tuple(FUSIONS)]  # type: ignore[valid-type]
FilterNoise = Literal["true", "estimated"]
InvalidAction = Literal["probe-nothing", "raise"]
LambdaScale = Literal["linear", "db"]
Truth = Literal["per-trial", "shared"]
Reward = Literal["sinr", "information"]
OracleSolver = Literal[SUPER_ARM_METHODS]  # type: ignore[valid-type]


def _option(default: Any, help: str) -> Any:
    return field(default=default, metadata={"help": help})


@dataclass(frozen=True)
class EnvOptions:
    """Options of ``MimoRadarSelect`` (any of them is a keyword of ``gym.make``).

    Attributes
    ----------
    fusion : {"average", "centralized"}
        How the tracker fuses the selected channels: the paper's ``"average"`` (eq22) or
        ``"centralized"`` (one update with the stacked measurements).
    tracking : bool
        ``True`` runs the IMM-UKF in the loop; ``False`` drops it (and the ``track*`` and
        ``mode_prob`` keys of the observation) for pure bandit studies.
    filter_noise : {"true", "estimated"}
        The measurement covariance the tracker uses: each channel's true ``Sigma0 / lambda``,
        or ``Sigma0 / lambda_hat`` with ``lambda_hat`` from the SINR the channel observed.
    measurement_quality : float or None
        ``None``: eq32's ``lambda`` from the mean SINR. A number in (0, inf): that constant
        ``lambda`` on every channel, which decouples accuracy from the selection (ablations).
    invalid_action : {"probe-nothing", "raise"}
        An action that does not select exactly ``Ms`` TX and ``Ns`` RX probes nothing
        (reward 0, the tracker only predicts), or raises ``ValueError``.
    oracle_solver : {"auto", "exact", "alternating"}
        How ``optimal_reward``, ``optimal_action`` and ``oracle_action()`` are found: exact
        enumeration, alternating maximisation (a lower bound of the optimum), or ``"auto"``:
        exact up to 20,000 subsets on the smaller side, alternating beyond.
    lambda_scale : {"linear", "db"}
        The scale eq32 maps SINR to measurement quality on: linear SINR (reading 0, v0's
        default) or dB (reading 1, v1's default).
    truth : {"per-trial", "shared"}
        A true trajectory per trial, drawn from ``N(X1_hat, P1_hat)`` (reading 0), or one
        trajectory shared by every trial, started at ``X1_hat`` and drawn from the scenario's
        ``truth_seed``, with each trial's tracker started at ``X1_hat + N(0, P1_hat)``
        (reading 1).
    measurements : bool
        ``True`` puts each step's raw measurements in ``info`` for external trackers:
        ``measurement`` (K, Ms*Ns, 2), range sum (m) and azimuth (rad) per target and selected
        channel; ``measurement_covariance`` (K, Ms*Ns, 2, 2), the covariance the env's tracker
        uses (per ``filter_noise``); ``measurement_tx``/``measurement_rx`` (Ms*Ns,), each
        channel's stations. NaN after an action that probes nothing.
    reward : {"sinr", "information"}
        The reward a step returns: eq17's weighted sum of the selected channels' SINR samples,
        or the realised reduction of the tracker's position uncertainty,
        ``sum_k Omega_k (log det P_pos,pred - log det P_pos,post)`` in nats (needs the
        tracker). ``info`` carries both terms at every step (``reward_sinr``,
        ``reward_information``, the latter with the tracker only).
    """

    fusion: FusionName = _option("average", "tracker fusion: the paper's eq22 'average' or 'centralized'")
    tracking: bool = _option(True, "run the IMM-UKF tracker in the loop")
    filter_noise: FilterNoise = _option(
        "true", "tracker's measurement covariance: the channel's 'true' one or 'estimated' from its SINR"
    )
    measurement_quality: float | None = _option(
        None, "constant lambda on every channel instead of eq32's (ablation); none: eq32"
    )
    invalid_action: InvalidAction = _option(
        "probe-nothing", "an action with the wrong number of TX/RX probes nothing, or raises"
    )
    oracle_solver: OracleSolver = _option(
        "auto", "how the optimal super arm is found: exact, alternating, or auto by size"
    )
    lambda_scale: LambdaScale = _option("linear", "the scale eq32 maps SINR to measurement quality on")
    truth: Truth = _option("per-trial", "a true trajectory per trial, or one shared by all trials")
    measurements: bool = _option(False, "put each step's raw measurements and their covariances in info")
    reward: Reward = _option(
        "sinr", "the step reward: eq17's 'sinr' sum, or the tracker's position 'information' gain (nats)"
    )
    prediction_covariance: bool = _option(
        False, "add the tracker's predicted position covariance 'track_pred_pos_cov' to the observation"
    )

    @classmethod
    def for_version(cls, version: str, **options: Any) -> EnvOptions:
        """The options of env version ``version`` (``"v0"``, ``"v1"``) with some overridden."""
        from .versions import env_version

        return env_version(version).options(**options)

    def __post_init__(self) -> None:
        for name, choices in option_choices().items():
            value = getattr(self, name)
            if not isinstance(value, str) or value not in choices:
                raise ValueError(f"{name} must be one of {list(choices)}, got {value!r}")
        for name in ("tracking", "measurements", "prediction_covariance"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be True or False, got {getattr(self, name)!r}")
        if self.reward == "information" and not self.tracking:
            raise ValueError("reward='information' is the tracker's information gain: it needs tracking=True")
        if self.prediction_covariance and not self.tracking:
            raise ValueError(
                "prediction_covariance=True observes the tracker's predicted covariance: "
                "it needs tracking=True"
            )
        quality = self.measurement_quality
        if quality is not None:
            if isinstance(quality, bool) or not isinstance(quality, int | float):
                raise ValueError(f"measurement_quality must be None or a number > 0, got {quality!r}")
            if not (math.isfinite(quality) and quality > 0):
                raise ValueError(f"measurement_quality must be None or a finite number > 0, got {quality!r}")
            object.__setattr__(self, "measurement_quality", float(quality))

    # ------------------------------------------------------------ views
    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    def changed(self) -> dict[str, Any]:
        """The options that differ from their defaults."""
        default = EnvOptions()
        return {k: v for k, v in self.to_dict().items() if getattr(default, k) != v}

    @classmethod
    def from_kwargs(cls, kwargs: Mapping[str, Any]) -> tuple[EnvOptions, dict[str, Any]]:
        """Split ``gym.make`` keywords into options and scenario-field overrides.

        A keyword that is neither raises ``TypeError`` naming it, as a Gymnasium env does
        for an unexpected keyword (clients such as torchrl probe keywords and rely on it).
        """
        names = option_names()
        scenario_fields = {f.name for f in dataclasses.fields(Scenario)}
        unknown = sorted(set(kwargs) - set(names) - scenario_fields - {"scenario"})
        if unknown:
            raise TypeError(
                f"MimoRadarSelect got an unexpected keyword argument {unknown[0]!r}; env options are "
                f"{list(names)}, scenario fields are {sorted(scenario_fields)}"
            )
        options = cls(**{k: v for k, v in kwargs.items() if k in names})
        overrides = {k: v for k, v in kwargs.items() if k not in names and k != "scenario"}
        return options, overrides


def option_names() -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(EnvOptions))


def option_choices() -> dict[str, tuple[str, ...]]:
    """``{option: its allowed values}`` for the options typed as a ``Literal``."""
    hints = typing.get_type_hints(EnvOptions)
    return {name: typing.get_args(hint) for name, hint in hints.items() if typing.get_origin(hint) is Literal}


def option_help() -> dict[str, str]:
    """One line of help per option."""
    return {f.name: f.metadata["help"] for f in dataclasses.fields(EnvOptions)}


def resolve(kwargs: Mapping[str, Any]) -> tuple[EnvOptions, Scenario]:
    """The options and the scenario (with its field overrides) of ``gym.make`` keywords."""
    options, overrides = EnvOptions.from_kwargs(kwargs)
    return options, load_scenario(kwargs.get("scenario", DEFAULT_SCENARIO), **overrides)
