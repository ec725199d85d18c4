"""Scenario files: the shipped scenarios by name, and users' YAML or TOML files."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from .scenario import Scenario
from .validation import ScenarioError


def available_scenarios() -> list[str]:
    """Names of the scenarios shipped with the package."""
    folder = resources.files(__package__)
    return sorted(p.name.removesuffix(".toml") for p in folder.iterdir() if p.name.endswith(".toml"))


def _read_file(path: Path) -> dict[str, Any]:
    text = path.read_text()
    suffix = path.suffix.lower()
    try:
        if suffix == ".toml":
            data = tomllib.loads(text)
        elif suffix in (".yaml", ".yml"):
            data = yaml.safe_load(text)
        else:
            raise ScenarioError(f"scenario file {path} must end in .toml, .yaml or .yml")
    except (tomllib.TOMLDecodeError, yaml.YAMLError) as exc:
        raise ScenarioError(f"cannot parse scenario file {path}: {exc}") from exc
    if not isinstance(data, Mapping):
        raise ScenarioError(f"scenario file {path} must hold a table of scenario keys")
    data = dict(data)
    data.setdefault("name", path.stem)
    return data


def load_scenario(name_or_path: str | Path | Scenario, **overrides: Any) -> Scenario:
    """Load a shipped scenario by name (``paper-1``...) or a YAML/TOML file.

    Keyword overrides replace fields before validation, e.g.
    ``load_scenario("paper-1", horizon=200)``.
    """
    if isinstance(name_or_path, Scenario):
        return name_or_path.replace(**overrides) if overrides else name_or_path
    text = str(name_or_path)
    if text in available_scenarios():
        resource = resources.files(__package__) / f"{text}.toml"
        data = tomllib.loads(resource.read_text())
    else:
        path = Path(text)
        if not path.is_file():
            raise ScenarioError(
                f"unknown scenario {text!r}: not a shipped scenario ({', '.join(available_scenarios())}) "
                "and not an existing .toml/.yaml file"
            )
        data = _read_file(path)
    data.update(overrides)
    return Scenario.from_dict(data)
