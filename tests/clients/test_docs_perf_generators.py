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


@pytest.mark.parametrize(("bpso", "floor", "reachable"), [(212.0, 135.0, False), (212.0, 100.0, True)])
def test_the_floor_left_without_bpso_says_whether_the_target_is_reachable(tmp_path, bpso, floor, reachable):
    text = generators.study_floor(write_perf(tmp_path, bpso, floor))
    target = TARGETS["claims_v1_average_wall_s"][1]
    assert f"took {bpso:.0f} s with the paper's BPSO and {floor:.0f} s with MG-CRB-CL's exact solver" in text
    assert f"so BPSO is about {bpso - floor:.0f} s ({(bpso - floor) / bpso:.0%}) of the study" in text
    assert "111x cheaper" in text
    assert (f"within the {target:g} s target" in text) == reachable
    assert ("no BPSO kernel, however fast, meets it" in text) == (not reachable)
