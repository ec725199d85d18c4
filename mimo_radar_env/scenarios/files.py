"""Scenario files: the shipped scenarios by name, and users' YAML or TOML files."""

from __future__ import annotations

import os
import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from .scenario import Scenario
from .validation import ScenarioError, name_from

#: Bounds that protect the machine from hostile scenario files.
MAX_FILE_BYTES = 1 << 20
MAX_YAML_ALIASES = 100
MAX_YAML_DEPTH = 32
MAX_YAML_NODES = 100_000


class _StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses duplicate keys instead of keeping the last one."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                line = key_node.start_mark.line + 1
                raise ScenarioError(f"duplicate key {key!r} at line {line} (each key once)")
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _check_yaml_structure(text: str, path: Path) -> None:
    """Refuse alias bombs and deep nesting from the event stream, before anything is built:
    the size of the document once every alias is expanded is counted, not built."""
    aliases = 0
    sizes: dict[str, int] = {}
    stack: list[list[Any]] = [[None, 0]]  # [anchor, expanded node count] of open collections

    def add(count: int) -> None:
        stack[-1][1] += count
        if stack[-1][1] > MAX_YAML_NODES:
            raise ScenarioError(f"scenario file {path} expands to more than {MAX_YAML_NODES} YAML nodes")

    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.AliasEvent):
            aliases += 1
            if aliases > MAX_YAML_ALIASES:
                raise ScenarioError(f"scenario file {path} uses more than {MAX_YAML_ALIASES} YAML aliases")
            add(sizes.get(event.anchor, 1))
        elif isinstance(event, yaml.ScalarEvent):
            if event.anchor:
                sizes[event.anchor] = 1
            add(1)
        elif isinstance(event, yaml.CollectionStartEvent):
            if len(stack) > MAX_YAML_DEPTH:
                raise ScenarioError(f"scenario file {path} nests deeper than {MAX_YAML_DEPTH} levels")
            stack.append([event.anchor, 1])
        elif isinstance(event, yaml.CollectionEndEvent):
            anchor, count = stack.pop()
            if anchor:
                sizes[anchor] = count
            add(count)


def available_scenarios() -> list[str]:
    """Names of the scenarios shipped with the package."""
    folder = resources.files(__package__)
    return sorted(p.name.removesuffix(".toml") for p in folder.iterdir() if p.name.endswith(".toml"))


def _read_file(path: Path) -> dict[str, Any]:
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".yaml", ".yml"):
        raise ScenarioError(f"scenario file {path} must end in .toml, .yaml or .yml")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise ScenarioError(f"scenario file {path} has {size} bytes; the limit is {MAX_FILE_BYTES}")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(
            f"scenario file {path} is not UTF-8 text ({exc.reason} at byte {exc.start})"
        ) from exc
    try:
        if suffix == ".toml":
            data = tomllib.loads(text)
        else:
            _check_yaml_structure(text, path)
            data = yaml.load(text, Loader=_StrictLoader)  # a SafeLoader: no Python objects
    except (tomllib.TOMLDecodeError, yaml.YAMLError) as exc:
        raise ScenarioError(f"cannot parse scenario file {path}: {exc}") from exc
    if not isinstance(data, Mapping):
        raise ScenarioError(f"scenario file {path} must hold a table of scenario keys")
    data = dict(data)
    data.setdefault("name", name_from(path.stem))
    return data


def load_scenario(name_or_path: str | Path | Scenario, **overrides: Any) -> Scenario:
    """Load a shipped scenario by name (``paper-1``...) or a YAML/TOML file.

    Keyword overrides replace fields before validation, e.g.
    ``load_scenario("paper-1", horizon=200)``.
    """
    if isinstance(name_or_path, Scenario):
        return name_or_path.replace(**overrides) if overrides else name_or_path
    if not isinstance(name_or_path, str | os.PathLike):
        raise ScenarioError(
            f"scenario must be a shipped scenario's name ({', '.join(available_scenarios())}), a path to "
            f"a .toml/.yaml file or a Scenario, got {type(name_or_path).__name__} {name_or_path!r}"
        )
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
