"""The performance page's generated sentence on the study targets, against perf.json figures
altered by hand."""

import json

import pytest

from benchmarks import docs_generators as generators
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
    ("bpso", "floor", "verdict"),
    [
        (212.0, 135.0, "no BPSO kernel, however fast, meets it"),
        (212.0, 100.0, "The 100 s left is within the 120 s target: a faster BPSO kernel could meet it"),
        (115.0, 100.0, "The study with BPSO is within the 120 s target."),
        (119.0, 125.0, "The study with BPSO is within the 120 s target."),
        (95.6, 95.5, "The study with BPSO is within the 120 s target."),
    ],
)
def test_the_study_floor_sentence(tmp_path, bpso, floor, verdict):
    """The sentence says whether the study meets its target, else whether a faster BPSO could."""
    assert TARGETS["claims_v1_average_wall_s"][1] == 120
    text = generators.study_floor(write_perf(tmp_path, bpso, floor))
    assert f"took {bpso:.0f} s with the paper's BPSO and {floor:.0f} s with MG-CRB-CL's exact solver" in text
    if bpso - floor >= 0.02 * bpso:
        assert f"so BPSO is about {bpso - floor:.0f} s ({(bpso - floor) / bpso:.0%}) of the study" in text
    elif bpso >= floor:  # no "about 0 s (0%)"
        assert f"so BPSO adds less than 2 % to the study ({bpso - floor:.1f} s)" in text
    else:  # two timings of one study differ by more than BPSO's share: no negative share is printed
        assert "below the difference between two timings" in text and "about -" not in text
    assert "111x cheaper" in text
    assert verdict in text
    assert sum(v in text for v in ("within the 120 s target", "no BPSO kernel")) == 1


@pytest.mark.parametrize(("kernel_ms", "within"), [(4.0, True), (20.0, False)])
def test_the_bpso_breakdown_sentence(tmp_path, kernel_ms, within):
    """The whole swarm's parts and the stop's saving, and whether the kernel with its stop is
    within the speed target's budget (the kernel it replaced over the target)."""
    docs = tmp_path / "docs"
    (docs / "results" / "perf").mkdir(parents=True)
    parts = [
        {"part": "the exp polynomial of eq21", "without_ms": 20.0, "cost_ms": 9.5, "share": 0.32},
        {"part": "the flip draws' hashes", "without_ms": 27.5, "cost_ms": 2.0, "share": 0.07},
    ]
    figures = {"trials": 500, "rule": "set", "kernel_ms": kernel_ms, "whole_swarm_ms": 29.5}
    figures |= {"reference_ms": 52.5, "parts": parts}
    (docs / "results" / "perf" / "bpso_parts.json").write_text(json.dumps(figures))
    text = generators.bpso_parts_table(docs)
    budget = 52.5 / TARGETS["bpso_speedup_vs_reference_set"][1]
    assert "| the exp polynomial of eq21 | 20.0 | 9.5 | 32 % |" in text
    saving = f"({29.5 / kernel_ms:.1f}x less)"
    assert f"the kernel with its stop at the optimum {kernel_ms:.1f} ms {saving}" in text
    assert f"leaves {budget:.1f} ms: the kernel with its stop is {'within' if within else 'above'} it" in text
    assert f"the exp polynomial alone costs 9.5 ms, {'more' if 9.5 > budget else 'less'} than that" in text
