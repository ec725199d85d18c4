"""A study's settings and the arguments they are read from."""

import pytest

from benchmarks.cli import build_parser
from benchmarks.errors import BenchError
from benchmarks.settings import Settings, paper_numbers, parse_agent_params


def test_parse_agent_params_reads_yaml_values():
    assert parse_agent_params(
        ["mg-crb-cl.beta=1.5", "mg-crb-cl.solver=exact", "sliding-window-ucb.window=20"]
    ) == {"mg-crb-cl": {"beta": 1.5, "solver": "exact"}, "sliding-window-ucb": {"window": 20}}


def test_settings_come_from_the_arguments_once():
    args = build_parser().parse_args(
        ["claims", "--out", "o", "--trials", "7", "--workers", "2", "--threads", "2", "--fusion",
         "centralized", "--quiet"]
    )  # fmt: skip
    settings = Settings.from_args(args, paper_study=True)
    assert (settings.trials, settings.workers, settings.progress, settings.figures) == (7, 2, False, True)
    assert settings.options.fusion == "centralized" and settings.options.lambda_scale == "db"
    assert settings.agent_params == {"mg-crb-cl": {"solver_params": {"rule": "set"}}}
    execution = {"workers": 2, "threads": 2, "backend": "local", "address": None, "device": None}
    assert settings.execution() == {**execution, "device_mode": "eager"}
    args = ["claims", "--out", "o", "--device", "cuda", "--device-mode", "graph"]
    on_device = Settings.from_args(build_parser().parse_args(args))
    assert on_device.execution() == {
        **execution,
        "workers": 1,
        "threads": None,
        "device": "cuda",
        "device_mode": "graph",
    }


def test_paper_numbers_are_checked():
    assert paper_numbers("3,1") == [3, 1]
    for bad in ("4", "1,x", "", "2,2"):
        with pytest.raises(BenchError, match="--scenarios"):
            paper_numbers(bad)
