"""The command's timeline: where its main thread was, sampled."""

import json
import time
from pathlib import Path

import pytest

from benchmarks.speed import timeline


def _first():
    time.sleep(0.3)


def _second():
    time.sleep(0.3)


def test_each_stretch_of_time_is_put_where_the_main_thread_was():
    """Two helpers that sleep 0.3 s each, one after the other: the samples put about that much
    at each, in that order, at the innermost frame under the roots (here this folder)."""
    here = Path(__file__).resolve().parent

    def run():
        _first()
        _second()
        return 7

    result, spans, wall = timeline.sample(run, interval=0.01, roots=[here])
    assert result == 7 and wall >= 0.6
    first = [s for s in spans if s.where.endswith("test_timeline.py:_first")]
    second = [s for s in spans if s.where.endswith("test_timeline.py:_second")]
    assert first and second and max(s.end for s in first) <= min(s.start for s in second) + 1e-9
    totals = timeline.totals(spans)
    for name in ("_first", "_second"):
        seconds = sum(v for k, v in totals.items() if f"test_timeline.py:{name} |" in k)
        assert 0.15 <= seconds <= 0.5, (name, seconds)
    assert all(s.where.startswith("speed/") for s in spans if s.where.endswith(("_first", "_second")))
    assert sum(s.seconds for s in spans) <= wall + 1e-9


def test_a_frame_outside_the_roots_is_placed_at_the_innermost_frame_by_file_name():
    outer = Path("/nonexistent")

    def innermost():
        import sys

        return timeline.place(sys._getframe(), roots=[outer])

    assert innermost() == ("test_timeline.py:innermost", "innermost")


def test_spans_merge_consecutive_samples_at_one_place():
    samples = [(0.1, "a", "x"), (0.2, "a", "x"), (0.3, "b", "y"), (0.4, "a", "x")]
    merged = timeline.spans(samples, wall=0.5)
    assert [(s.start, s.end, s.where) for s in merged] == [(0.1, 0.3, "a"), (0.3, 0.4, "b"), (0.4, 0.5, "a")]


def test_the_command_line_runs_a_command_and_writes_its_timeline(tmp_path, capsys):
    out = tmp_path / "timeline.json"
    record = timeline.main(["--json", str(out), "--min-span", "0", "--", "agents"])
    assert record["exit_code"] == 0 and record["command"] == ["mimo-radar-bench", "agents"]
    assert json.loads(out.read_text())["wall_s"] == pytest.approx(record["wall_s"])
    # a command this short may end before the first sample (its attribution: the tests above)
    assert sum(record["totals_s"].values()) <= record["wall_s"] + 1e-9
    assert record["parts_s"] == {}  # it never waits for tasks
    assert "the main thread's time by place" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        timeline.main(["agents"])  # no '--'
    with pytest.raises(SystemExit):
        timeline.main(["--interval", "0", "--", "agents"])


def test_a_studys_wall_time_splits_into_its_parts_around_its_waits():
    S = timeline.Span
    wait, stats = "benchmarks/backends.py:run_processes", "benchmarks/metrics.py:_root_mean_square"
    spans = [
        S(0.0, 1.5, "benchmarks/harness.py:make_config", "x"),
        S(1.5, 5.0, wait, "wait"),
        S(5.0, 5.5, stats, "y"),
        S(5.5, 5.75, "benchmarks/shards.py:write_shard", "write"),
        S(5.75, 9.0, wait, "wait"),
        S(9.0, 9.75, "benchmarks/report.py:write_outputs", "z"),
    ]
    parts = timeline.parts(spans, wall=10.0)
    assert list(parts) == list(timeline.PARTS) == ["before", "waiting", "statistics", "other", "after"]
    assert list(parts.values()) == [1.5, 6.75, 0.5, 0.25, 1.0]
    assert sum(parts.values()) == 10.0
    assert timeline.parts(spans[:1], wall=1.5) == {}
