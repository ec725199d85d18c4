"""This machine's speed against the developers' (benchmarks.machine_rate): compile keeps it, and
every time estimate after that is scaled by it and says whose speed it is."""

import json

import pytest

from benchmarks import machine_rate, resources
from mimo_radar_env import EnvOptions, load_scenario


@pytest.fixture
def rate_file(tmp_path, monkeypatch):
    path = tmp_path / "rate" / "machine-rate.json"
    monkeypatch.setenv(machine_rate.RATE_ENV, str(path))
    return path


def _estimate() -> float:
    sc = load_scenario("paper-1-v1")
    return resources.estimate_seconds(sc, EnvOptions(), {"ucb1": 1e-5}, trials=100, steps=50, shard_size=50)


def test_a_kept_factor_scales_every_estimate_and_says_so(rate_file):
    assert machine_rate.factor() is None  # none kept yet: the developers' speed
    before, said = _estimate(), resources.estimated_where()
    assert "like the developers'" in said
    rate_file.parent.mkdir(parents=True)
    seconds = 2.5 * machine_rate.REFERENCE_SECONDS
    rate_file.write_text(json.dumps({"factor": 2.5, "seconds": seconds}))
    assert machine_rate.factor() == pytest.approx(2.5)
    assert _estimate() == pytest.approx(2.5 * before)
    assert "on this machine" in resources.estimated_where()


def test_a_kept_time_is_read_against_todays_reference(rate_file, monkeypatch):
    """A record kept against an earlier reference gives this machine's speed against today's."""
    rate_file.parent.mkdir(parents=True)
    rate_file.write_text(json.dumps({"factor": 1.2, "seconds": 0.3, "reference_seconds": 0.25}))
    monkeypatch.setattr(machine_rate, "REFERENCE_SECONDS", 0.2)
    assert machine_rate.factor() == pytest.approx(1.5)


@pytest.mark.parametrize(
    "text", ["not json", '{"seconds": "x"}', '{"seconds": 1000}', "[]", '{"factor": 2}', '{"seconds": null}']
)
def test_a_damaged_or_implausible_file_is_no_factor(rate_file, text):
    rate_file.parent.mkdir(parents=True)
    rate_file.write_text(text)
    assert machine_rate.factor() is None


def test_compile_times_the_reference_step_and_keeps_its_ratio(rate_file, monkeypatch, capsys):
    from benchmarks.commands import Compile

    monkeypatch.setattr(machine_rate, "STEPS", 3)  # a short workload: its ratio is what is kept
    seconds = machine_rate.workload_seconds(1)
    monkeypatch.setattr(machine_rate, "REFERENCE_SECONDS", seconds)  # this machine, about 1x
    Compile.time_this_machine()
    out = capsys.readouterr().out
    record = json.loads(rate_file.read_text())
    assert record["factor"] == pytest.approx(record["seconds"] / seconds)
    assert machine_rate.PLAUSIBLE[0] <= record["factor"] <= machine_rate.PLAUSIBLE[1]
    assert "times the developers' machine: time estimates use that" in out and str(rate_file) in out
    # a factor far outside what a machine can be is a mismeasurement: not kept
    monkeypatch.setattr(machine_rate, "REFERENCE_SECONDS", seconds * 1e4)
    rate_file.unlink()
    Compile.time_this_machine()
    assert not rate_file.exists() and "not kept" in capsys.readouterr().out


def test_no_file_is_kept_where_the_environment_says_none(monkeypatch):
    monkeypatch.setenv(machine_rate.RATE_ENV, "")
    assert machine_rate.rate_file() is None and machine_rate.factor() is None
    monkeypatch.delenv(machine_rate.RATE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", "/tmp/xdg")
    assert str(machine_rate.rate_file()) == "/tmp/xdg/mimo-radar-env/machine-rate.json"
