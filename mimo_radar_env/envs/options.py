"""The options of ``MimoRadarSelect``: one typed, documented, validated set.

:class:`EnvOptions` is the one home of every env option, its choices, its default and its
help text. The single env, the native vector env, the benchmark harness (``config.json``)
and the command line (``mimo-radar-bench run --fusion ...``) all read them from here.
"""

from __future__ import annotations

import dataclasses
import math
import textwrap
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from ..core.superarm import SUPER_ARM_METHODS
from ..scenarios import Scenario, load_scenario
from ..tracking.fusion import DEFAULT_FUSION, FUSIONS

#: The scenario of the env class made without a ``scenario`` keyword (each registered version
#: names its own: :mod:`mimo_radar_env.envs.versions`).
DEFAULT_SCENARIO = "paper-1"


#: The fusion option's choices are the fusion registry's at the time of asking
#: (:func:`option_choices`), so a fusion registered later is a valid option.
FusionName = str
FilterNoise = Literal["true", "estimated"]
InvalidAction = Literal["probe-nothing", "raise"]
LambdaScale = Literal["linear", "db"]
Truth = Literal["per-trial", "shared"]
Reward = Literal["sinr", "information"]
OracleSolver = Literal[SUPER_ARM_METHODS]  # type: ignore[valid-type]


def _option(default: Any, help: str, doc: str) -> Any:
    """A field of :class:`EnvOptions`: ``help`` is its one line (the command line's),
    ``doc`` its full description (the env's and EnvOptions' docstrings are built from it)."""
    return field(default=default, metadata={"help": help, "doc": " ".join(doc.split())})


@dataclass(frozen=True)
class EnvOptions:
    # the docstring is built from the fields' metadata below the class (options_docstring)

    fusion: FusionName = _option(
        DEFAULT_FUSION,
        "tracker fusion: the paper's eq22 'average' or 'centralized'",
        """``"average"`` (the paper's eq22 averaging of per-channel IMM-UKF updates) or
        ``"centralized"`` (one update with the stacked measurements)""",
    )
    tracking: bool = _option(
        True,
        "run the IMM-UKF tracker in the loop",
        """``True`` runs the IMM-UKF in the loop; ``False`` drops it and the ``track*``/``mode_prob``
        keys of the observation (pure bandit studies, about 3x faster)""",
    )
    filter_noise: FilterNoise = _option(
        "true",
        "tracker's measurement covariance: the channel's 'true' one or 'estimated' from its SINR",
        """``"true"`` (the tracker uses each channel's true ``Sigma0 / lambda``) or ``"estimated"``
        (``Sigma0 / lambda_hat`` with ``lambda_hat`` from the SINR the channel observed)""",
    )
    measurement_quality: float | None = _option(
        None,
        "constant lambda on every channel instead of eq32's (ablation); none: eq32",
        """``None`` (eq32's ``lambda`` from the mean SINR) or a number in (0, inf): that constant
        ``lambda`` on every channel, which decouples accuracy from the selection (ablations)""",
    )
    invalid_action: InvalidAction = _option(
        "probe-nothing",
        "an action with the wrong number of TX/RX probes nothing, or raises",
        """``"probe-nothing"`` (an action that does not select exactly ``Ms`` TX and ``Ns`` RX
        probes nothing: reward 0, the tracker only predicts) or ``"raise"`` (``ValueError``)""",
    )
    oracle_solver: OracleSolver = _option(
        "auto",
        "how the optimal super arm is found: exact, alternating, or auto by size",
        """``"auto"``, ``"exact"`` or ``"alternating"``: how ``optimal_reward``,
        ``optimal_action`` and ``oracle_action()`` are found; ``"auto"`` is exact enumeration up
        to 20,000 subsets on the smaller side and alternating maximisation (a lower bound of the
        optimum) beyond""",
    )
    lambda_scale: LambdaScale = _option(
        "linear",
        "the scale eq32 maps SINR to measurement quality on",
        """``"linear"`` (reading 0, v0's default) or ``"db"`` (reading 1, v1's default): the scale
        on which eq32 maps the mean SINR to measurement quality""",
    )
    truth: Truth = _option(
        "per-trial",
        "a true trajectory per trial, or one shared by all trials",
        """``"per-trial"`` (each trial's truth starts at a draw from ``N(X1_hat, P1_hat)``,
        reading 0) or ``"shared"`` (one true trajectory per target, from ``X1_hat`` and the
        scenario's ``truth_seed``, the same in every trial; each trial's tracker starts at
        ``X1_hat + N(0, P1_hat)``, reading 1)""",
    )
    measurements: bool = _option(
        False,
        "put each step's raw measurements and their covariances in info",
        """``False`` or ``True``: after each step ``info`` also carries the raw measurements for
        external trackers: ``measurement`` (K, Ms*Ns, 2), the range sum (m) and azimuth (rad,
        from the receiver) of each target on each selected channel;
        ``measurement_covariance`` (K, Ms*Ns, 2, 2), the diagonal covariance the env's tracker
        uses (``Sigma0 / lambda``, per ``filter_noise``); ``measurement_tx`` and
        ``measurement_rx`` (Ms*Ns,), the stations of each channel (TX-major order). After an
        action that probes nothing the measurements and covariances are NaN""",
    )
    reward: Reward = _option(
        "sinr",
        "the step reward: eq17's 'sinr' sum, or the tracker's position 'information' gain (nats)",
        """``"sinr"`` (eq17's weighted sum of the selected channels' SINR samples) or
        ``"information"``: the realised reduction of the tracker's position uncertainty,
        ``sum_k Omega_k (log det P_pos,pred - log det P_pos,post)`` in nats, for learning to
        select for tracking (needs ``tracking=True``); ``info`` carries both terms at every step
        (``reward_sinr``, and with the tracker ``reward_information``)""",
    )
    prediction_covariance: bool = _option(
        False,
        "add the tracker's predicted covariance ('track_pred_pos_cov', 'track_pred_cov') to the observation",
        """``False`` or ``True``: the observation also carries ``track_pred_pos_cov``, the
        position block of the tracker's predicted (IMM mixture) covariance for the coming step,
        which tracking-aware policies score super arms with, and ``track_pred_cov``, the whole
        4 x 4 covariance, which planning policies carry over several steps (needs
        ``tracking=True``; no number of the env changes)""",
    )

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
    """``{option: its allowed values}`` for the options with choices: those typed as a
    ``Literal``, and ``fusion`` (the fusion registry's names)."""
    hints = typing.get_type_hints(EnvOptions)
    choices = {
        name: typing.get_args(hint) for name, hint in hints.items() if typing.get_origin(hint) is Literal
    }
    return {"fusion": tuple(FUSIONS), **choices}


def option_help() -> dict[str, str]:
    """One line of help per option."""
    return {f.name: f.metadata["help"] for f in dataclasses.fields(EnvOptions)}


def option_docs() -> dict[str, str]:
    """The full description of each option."""
    return {f.name: f.metadata["doc"] for f in dataclasses.fields(EnvOptions)}


def _option_type(name: str) -> str:
    choices = option_choices().get(name)
    if choices:
        return "{" + ", ".join(f'"{c}"' for c in choices) + "}"
    default = EnvOptions.__dataclass_fields__[name].default
    return "bool" if isinstance(default, bool) else "float or None"


def options_markdown(indent: str = "") -> str:
    """Every option as a Markdown bullet ``* ``name``: description``, in field order (the env
    docstring's Arguments)."""
    docs = list(option_docs().items())
    return "\n".join(
        textwrap.fill(
            f"* ``{name}``: {doc}" + (";" if i < len(docs) - 1 else "."),
            width=92,
            initial_indent=indent,
            subsequent_indent=indent + "  ",
            break_on_hyphens=False,
        )
        for i, (name, doc) in enumerate(docs)
    )


def options_docstring() -> str:
    """EnvOptions' numpydoc docstring, from the fields' metadata."""
    lines = [
        "Options of ``MimoRadarSelect`` (any of them is a keyword of ``gym.make``).",
        "",
        "Attributes",
        "----------",
    ]
    for name, doc in option_docs().items():
        lines.append(f"{name} : {_option_type(name)}")
        lines += textwrap.wrap(
            doc + ".", width=92, initial_indent="    ", subsequent_indent="    ", break_on_hyphens=False
        )
    return "\n".join(lines) + "\n"


EnvOptions.__doc__ = options_docstring()


def resolve(kwargs: Mapping[str, Any]) -> tuple[EnvOptions, Scenario]:
    """The options and the scenario (with its field overrides) of ``gym.make`` keywords."""
    options, overrides = EnvOptions.from_kwargs(kwargs)
    return options, load_scenario(kwargs.get("scenario", DEFAULT_SCENARIO), **overrides)
