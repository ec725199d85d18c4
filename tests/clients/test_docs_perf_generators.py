"""The performance page's values on the study targets, against perf.json figures altered by hand."""

import json

import pytest

from benchmarks.docs_tooling import generators
from benchmarks.speed.perf import TARGETS


def write_perf(tmp_path, bpso, floor):
    docs = tmp_path / "docs"
    (docs / "results" / "perf").mkdir(parents=True)
    figures = {
        "workers": 2,
        "claims_v1_average_wall_s": bpso,
        "claims_v1_average_exact_solver_wall_s": floor,
        "exact_vs_bpso_speedup": 111.4,
    }
    (docs / "results" / "perf" / "perf.json").write_text(json.dumps(figures))
    return docs


@pytest.mark.parametrize(
    ("bpso", "floor", "added", "share", "against"),
    [
        (212.0, 135.0, "77.0", "36.3", "above"),
        (115.0, 100.0, "15.0", "13.0", "within"),
        (119.0, 125.0, "-6.0", "-5.0", "within"),
        (95.6, 95.5, "0.1", "0.1", "within"),
    ],
)
def test_the_study_floor_values(tmp_path, bpso, floor, added, share, against):
    """What BPSO adds to the study, its share and the study against its target."""
    assert TARGETS["claims_v1_average_wall_s"][1] == 120
    table = generators.floor_values(write_perf(tmp_path, bpso, floor))
    assert (table["bpso"], table["exact"]) == (f"{bpso:.0f}", f"{floor:.0f}")
    assert (table["added"], table["share"], table["against-target"]) == (added, share, against)
    assert (table["speedup"], table["target"], table["workers"]) == ("111", "120", "2")


def _breakdown(rule, kernel_ms, whole_ms, polynomial_without_ms, mean_iterations):
    parts = [
        {"part": "the exp polynomial of eq21", "without_ms": polynomial_without_ms},
        {"part": "the flip draws' hashes", "without_ms": whole_ms - 2.0},
    ]
    for part in parts:
        part["cost_ms"] = whole_ms - part["without_ms"]
        part["share"] = part["cost_ms"] / whole_ms
    return {
        "trials": 500,
        "rule": rule,
        "q_max": 100,
        "mean_iterations": mean_iterations,
        "share_all_iterations": 0.5,
        "kernel_ms": kernel_ms,
        "whole_swarm_ms": whole_ms,
        "reference_ms": 52.5,
        "parts": parts,
    }


@pytest.mark.parametrize(
    ("kernel_ms", "polynomial_without_ms", "within", "free_within"),
    [(4.0, 15.0, True, True), (20.0, 20.0, False, False), (20.0, 15.0, False, True)],
)
def test_the_bpso_breakdown_values(tmp_path, kernel_ms, polynomial_without_ms, within, free_within):
    """Each rule's parts side by side; per rule, the stop's share of the iterations, the estimate it
    gives beside the kernel's time, and whether the kernel, and a kernel whose eq21 decision cost
    nothing (the whole swarm without the polynomial, scaled the same), are within the budget of the
    speed target (the kernel it replaced over the target)."""
    docs = tmp_path / "docs"
    (docs / "results" / "perf").mkdir(parents=True)
    breakdowns = [
        _breakdown("xor", kernel_ms, 30.0, polynomial_without_ms, 60.0),
        _breakdown("set", 2.5, 29.5, 20.0, 7.0),
    ]
    figures = {"trials": 500, "breakdowns": breakdowns, "float32": {"trials": 500, "rules": {}}}
    (docs / "results" / "perf" / "bpso_parts.json").write_text(json.dumps(figures))
    text = generators.bpso_parts_table(docs)
    assert "| rule xor: without it (ms) | the part's cost (ms) | share | rule set: without it (ms) |" in text
    polynomial_cost = 30.0 - polynomial_without_ms
    assert (
        f"| the exp polynomial of eq21 | {polynomial_without_ms:.1f} | {polynomial_cost:.1f} | "
        f"{100 * polynomial_cost / 30:.0f} % | 20.0 | 9.5 | 32 % |" in text
    )
    budget = 52.5 / TARGETS["bpso_speedup_vs_reference_xor"][1]
    table = generators.bpso_parts_values(docs)
    assert (table["xor.iterations"], table["xor.q-max"], table["xor.all-iterations"]) == (
        "60.0",
        "100",
        "50.0",
    )
    assert (table["xor.estimate"], table["xor.kernel"]) == (f"{30.0 * 0.6:.1f}", f"{kernel_ms:.1f}")
    assert (table["xor.budget"], table["xor.kernel-against"]) == (
        f"{budget:.1f}",
        "within" if within else "above",
    )
    free = polynomial_without_ms * 0.6
    assert (table["xor.free"], table["xor.free-against"]) == (
        f"{free:.1f}",
        "within" if free_within else "above",
    )
    assert (table["set.estimate"], table["set.kernel"]) == ("2.1", "2.5")
    breakdowns[1]["parts"][1]["part"] = "another part"
    (docs / "results" / "perf" / "bpso_parts.json").write_text(json.dumps(figures))
    with pytest.raises(ValueError, match="the rules' parts differ"):
        generators.bpso_parts_table(docs)


def test_bpso_without_numba_values(tmp_path):
    """Each namespace's and rule's two times, and the second over the first, from the figures."""
    docs = write_perf(tmp_path, 1.0, 1.0)
    figures = {"trials": 1500, "repeats": 3, "machine": {"cores": 16}}
    for name, scale in (("numpy", 1.0), ("torch_cpu", 2.0)):
        for rule, stopping in (("xor", 300.4), ("set", 50.0)):
            figures[f"bpso_{name}_iterations_ms_{rule}"] = scale * stopping
            figures[f"bpso_{name}_every_iteration_ms_{rule}"] = scale * 600.0
    (docs / "results" / "perf" / "solver_speed.json").write_text(json.dumps(figures))
    table = generators.without_numba_values(docs)
    assert (table["trials"], table["repeats"], table["cores"]) == ("1,500", "3", "16")
    assert (table["numpy.xor.stopping"], table["numpy.xor.every"], table["numpy.xor.ratio"]) == (
        "300",
        "600",
        "2.0",
    )
    assert (table["torch_cpu.set.stopping"], table["torch_cpu.set.ratio"]) == ("100", "12.0")


def test_comparisons_across_commits_give_each_commits_median_and_the_paired_difference(tmp_path):
    docs = tmp_path / "docs"
    (docs / "results" / "perf" / "across").mkdir(parents=True)
    record = {
        "key": "after_last_task_s",
        "command": ["python", "-m", "x", "--study", "claims --trials 5"],
        "repeats": 3,
        "values": {"aaa": [1.0, 1.2, 1.1], "bbb": [0.5, 0.7, 0.6]},
        "medians": {"aaa": 1.1, "bbb": 0.6},
        "ratio": 1.1 / 0.6,
    }
    (docs / "results" / "perf" / "across" / "cut.json").write_text(json.dumps(record))
    record["values"] = {"aaa": [1.0, 2.0, 3.0], "bbb": [2.0, 1.0, 3.0]}
    (docs / "results" / "perf" / "across" / "same.json").write_text(json.dumps(record))
    table = generators.across_values(docs)
    assert (table["cut.first"], table["cut.second"], table["cut.repeats"]) == ("aaa", "bbb", "3")
    assert table["cut.command"] == "`python -m x --study 'claims --trials 5'`"
    assert (table["cut.first-median"], table["cut.second-median"], table["cut.ratio"]) == (
        "1.1",
        "0.6",
        "1.83",
    )
    assert table["cut.difference"] == "0.5 [0.5, 0.5]"  # every pair 0.5 apart
    assert (table["cut.shown"], table["same.shown"]) == ("lower at the second commit", "not told apart")
    assert (
        table["cut.call"]
        == "`python -m benchmarks.speed.across_commits aaa bbb --key after_last_task_s --repeats 3`"
    )
    (docs / "results" / "perf" / "across" / "warm.json").write_text(json.dumps({**record, "warmup": 1}))
    assert generators.across_values(docs)["warm.call"].endswith("--repeats 3 --warmup 1`")


def test_a_timeline_gives_its_parts_and_its_places_by_time(tmp_path):
    docs = tmp_path / "docs"
    (docs / "results" / "perf").mkdir(parents=True)
    record = {
        "command": ["mimo-radar-bench", "claims", "--trials", "5"],
        "wall_s": 10.04,
        "parts_s": {"before": 1.5, "waiting": 6.75, "statistics": 0.5, "other": 0.25, "after": 1.04},
        "totals_s": {"benchmarks/backends.py:run_processes | wait": 6.75, "benchmarks/metrics.py:f | g": 0.5},
    }
    (docs / "results" / "perf" / "timeline-two.json").write_text(json.dumps(record))
    table = generators.timeline_values(docs)
    assert table["two.command"] == "`mimo-radar-bench claims --trials 5`"
    assert (table["two.wall"], table["two.before"], table["two.after"]) == ("10.0", "1.50", "1.04")
    assert table["two.place.1"] == "6.75 s at `benchmarks/backends.py:run_processes` (in `wait`)"
    assert table["two.place.2"] == "0.50 s at `benchmarks/metrics.py:f` (in `g`)"
