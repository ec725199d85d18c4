"""The registered versions of ``MimoRadarSelect``: one definition each.

An :class:`EnvVersion` is everything a version means: its env ids (``MimoRadarSelect-vN`` and
the flat ``MimoRadarSelectFlat-vN``), the option defaults that differ from
:class:`~mimo_radar_env.EnvOptions`' own (v0's), its three paper scenarios (the first is its
default scenario), and the agent parameters of its paper study. Registration, the benchmark
harness, the command line and the layout calibration all read :data:`VERSIONS`; a new version
is one more entry here (and, where it moves any number, a new name: versions are promises).
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from .options import EnvOptions, option_names


def _frozen(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(mapping))


@dataclass(frozen=True)
class EnvVersion:
    """One registered version of the env.

    Attributes
    ----------
    name : str
        ``"v0"``, ``"v1"``.
    summary : str
        One line on what the version reads the paper as.
    option_defaults : mapping
        The option defaults that differ from :class:`EnvOptions`' (docs/model.md, section 13).
    paper_scenarios : tuple of str
        The paper's Scenarios 1, 2 and 3 as this version ships them; the first is its default.
    """

    name: str
    summary: str
    option_defaults: Mapping[str, Any] = field(default_factory=dict)
    paper_scenarios: tuple[str, str, str] = ("paper-1", "paper-2", "paper-3")

    def __post_init__(self) -> None:
        EnvOptions(**self.option_defaults)  # the defaults are valid options
        object.__setattr__(self, "option_defaults", _frozen(self.option_defaults))

    @property
    def env_id(self) -> str:
        return f"MimoRadarSelect-{self.name}"

    @property
    def flat_env_id(self) -> str:
        """The same env with a valid Discrete action and a flat float32 observation
        (``mimo_radar_env.wrappers.make_flat_env``), for tools that take an env id."""
        return f"MimoRadarSelectFlat-{self.name}"

    @property
    def default_scenario(self) -> str:
        return self.paper_scenarios[0]

    def options(self, **overrides: Any) -> EnvOptions:
        """The version's options, some overridden; an unknown option is a ``TypeError`` naming
        the options there are."""
        unknown = sorted(set(overrides) - set(option_names()))
        if unknown:
            raise TypeError(
                f"env options got an unexpected keyword argument {unknown[0]!r}; env options are "
                f"{list(option_names())}"
            )
        return EnvOptions(**{**self.option_defaults, **overrides})

    def paper_scenario(self, number: int) -> str:
        """The name of paper scenario ``number`` (1, 2, 3) of this version."""
        if number not in (1, 2, 3):
            raise ValueError(f"paper scenarios are 1, 2 and 3, got {number!r}")
        return self.paper_scenarios[number - 1]

    def registration_kwargs(self) -> dict[str, Any]:
        """The ``gym.make`` keywords the version's ids are registered with (``env_version``: which
        version's paper scenarios a scenario name may be, :func:`check_scenario_version`)."""
        return {**self.option_defaults, "scenario": self.default_scenario, "env_version": self.name}

    def default_config(self) -> dict[str, Any]:
        """Every ``gym.make`` keyword besides scenario fields, with the version's defaults
        (highway-env's ``default_config``)."""
        return {"scenario": self.default_scenario, **self.options().to_dict()}


def by_name(*entries: Any) -> dict[str, Any]:
    """``{entry.name: entry}``, in the order given; two entries of one name are a ``ValueError``
    (a dict built by name would keep the last silently)."""
    table: dict[str, Any] = {}
    for entry in entries:
        if entry.name in table:
            raise ValueError(f"two entries are called {entry.name!r}")
        table[entry.name] = entry
    return table


VERSIONS: dict[str, EnvVersion] = by_name(
    EnvVersion(
        "v0",
        "reading 0: the first reading of the paper's ambiguous points, unchanged since release",
    ),
    EnvVersion(
        "v1",
        "reading 1 of the paper's ambiguous points (eq32 on dB, a shared truth, BPSO's standard "
        "rule in the paper study, the calibrated layout)",
        option_defaults={"lambda_scale": "db", "truth": "shared"},
        paper_scenarios=("paper-1-v1", "paper-2-v1", "paper-3-v1"),
    ),
)
#: The version ``mimo-radar-bench`` runs unless told otherwise.
DEFAULT_VERSION = "v1"


@dataclass(frozen=True)
class ScenarioSet:
    """A version's paper scenarios with another station layout, shipped beside the version's own
    (which it leaves unchanged: a layout is scenario data, and the version's numbers are promises).

    Attributes
    ----------
    name : str
        What ``mimo-radar-bench claims --scenario-set`` takes.
    version : str
        The env version whose options and paper study the set is meant for.
    summary : str
        Where the layout comes from.
    paper_scenarios : tuple of str
        The shipped scenarios standing for the paper's Scenarios 1, 2 and 3.
    """

    name: str
    version: str
    summary: str
    paper_scenarios: tuple[str, str, str]

    def paper_scenario(self, number: int) -> str:
        """The name of paper scenario ``number`` (1, 2, 3) of this set."""
        if number not in (1, 2, 3):
            raise ValueError(f"paper scenarios are 1, 2 and 3, got {number!r}")
        return self.paper_scenarios[number - 1]


#: Named calibrations shipped as scenario sets (docs/results-layouts.md, "A global layout search").
SCENARIO_SETS: dict[str, ScenarioSet] = by_name(
    ScenarioSet(
        "search-5",
        "v1",
        "v1's paper scenarios with layout 5 of the global layout search (search-layouts, seed 0): "
        "12 claims hold at 500 trials, against layout 116's 11",
        ("paper-1-v1-search5", "paper-2-v1-search5", "paper-3-v1-search5"),
    ),
)

# Views of VERSIONS, by version name.
ENV_IDS = {name: v.env_id for name, v in VERSIONS.items()}
FLAT_ENV_IDS = {name: v.flat_env_id for name, v in VERSIONS.items()}
PAPER_SCENARIOS = {name: v.paper_scenarios for name, v in VERSIONS.items()}
VERSION_DEFAULTS = {name: dict(v.option_defaults) for name, v in VERSIONS.items()}


def env_version(name: str) -> EnvVersion:
    """The version called ``name``; ``ValueError`` naming the versions there are."""
    if name not in VERSIONS:
        raise ValueError(f"env version must be one of {sorted(VERSIONS)}, got {name!r}")
    return VERSIONS[name]


@dataclass(frozen=True)
class VersionConflict:
    """A scenario name of another env version than the one asked for: that ``version``, the
    scenario ``set`` it belongs to (None: one of the version's paper scenarios), and the asking
    version's ``own`` name of the same paper scenario (None for a scenario set's)."""

    version: EnvVersion
    set: str | None
    own: str | None


def _owner(scenario: Any) -> tuple[EnvVersion, ScenarioSet | None] | None:
    """The version, and scenario set (None: one of its paper scenarios), that a shipped
    scenario *name* belongs to; None for any other name, a file or a :class:`Scenario`."""
    if isinstance(scenario, str):
        for version in VERSIONS.values():
            if scenario in version.paper_scenarios:
                return version, None
        for scenario_set in SCENARIO_SETS.values():
            if scenario in scenario_set.paper_scenarios:
                return env_version(scenario_set.version), scenario_set
    return None


def version_conflict(scenario: Any, version: str | None) -> VersionConflict | None:
    """The conflict of a scenario *name* with env ``version`` (:class:`VersionConflict`), or None:
    a name of the version's own, any other name, a file or a :class:`Scenario` object."""
    if version is None or not isinstance(scenario, str):
        return None
    own = env_version(version)
    owner = _owner(scenario)
    if owner is None or owner[0].name == version:
        return None
    other, scenario_set = owner
    if scenario_set is None:
        return VersionConflict(other, None, own.paper_scenario(other.paper_scenarios.index(scenario) + 1))
    return VersionConflict(other, scenario_set.name, None)


def shipped_version(scenario: Any) -> str | None:
    """The env version whose paper scenario, or scenario set, a shipped scenario *name* is; None
    for any other name, a file or a :class:`Scenario` object."""
    owner = _owner(scenario)
    return None if owner is None else owner[0].name


def scenario_version(scenario: Any) -> str:
    """:func:`shipped_version`, or :data:`DEFAULT_VERSION` where there is none."""
    return shipped_version(scenario) or DEFAULT_VERSION


def check_scenario_version(scenario: Any, version: str | None) -> None:
    """Refuses a scenario *name* that is another version's paper scenario (or in another version's
    scenario set) under env ``version``, naming the version's own: v0's ``paper-3`` under v1 would
    run v0's layout with v1's options, a hybrid of the two. A :class:`Scenario` object or a file
    is taken as given: the explicit way to run one version's layout under another's options."""
    conflict = version_conflict(scenario, version)
    if conflict is None:
        return
    own, other = env_version(version).env_id, conflict.version.env_id
    if conflict.set is None:
        number = conflict.version.paper_scenarios.index(scenario) + 1
        raise ValueError(
            f"scenario {scenario!r} is {other}'s paper Scenario {number}; {own}'s is {conflict.own!r} (to "
            f"run that layout under {own}'s options on purpose, pass the Scenario object: "
            f"scenario=load_scenario({scenario!r}))"
        )
    raise ValueError(
        f"scenario {scenario!r} belongs to scenario set {conflict.set!r} of {other}, not of {own} (to run "
        f"it anyway, pass the Scenario object: scenario=load_scenario({scenario!r}))"
    )


def paper_scenario(number: int, version: str) -> str:
    """The name of paper scenario ``number`` (1, 2, 3) of env ``version``."""
    return env_version(version).paper_scenario(number)


def paper_key(name: str) -> str:
    """``"paper-N"`` for paper scenario N of any version or scenario set; other names unchanged."""
    for names in (*PAPER_SCENARIOS.values(), *(s.paper_scenarios for s in SCENARIO_SETS.values())):
        if name in names:
            return f"paper-{names.index(name) + 1}"
    return name


def versions_markdown(indent: str = "") -> str:
    """A paragraph per version: its paper scenarios and the option defaults that differ (the env
    docstring's Arguments)."""
    paragraphs = []
    for v in VERSIONS.values():
        defaults = (
            ", ".join(f"``{k}={v!r}``" for k, v in v.option_defaults.items()) or "the options' defaults"
        )
        text = f"``{v.env_id}`` ({v.summary}): paper scenarios " + ", ".join(
            f"``{name}``" for name in v.paper_scenarios
        )
        text += f" (default ``{v.default_scenario}``); ``{v.flat_env_id}`` is the same env with a "
        text += "Discrete super-arm action and a flat float32 observation, for deep-RL tools; " + (
            f"option defaults {defaults}" if defaults else "the options' own defaults"
        )
        paragraphs.append(
            textwrap.fill(
                text + ".", width=92, initial_indent=indent, subsequent_indent=indent, break_on_hyphens=False
            )
        )
    return "\n\n".join(paragraphs)


def default_config(version: str = DEFAULT_VERSION) -> dict[str, Any]:
    """The defaults of every ``gym.make`` keyword of ``version`` besides scenario fields."""
    return env_version(version).default_config()
