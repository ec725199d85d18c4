"""The figures the model and agent pages quote: measured as stated, with intervals that hold."""

import json

import numpy as np
import pytest
from scipy import stats

from benchmarks.cli import main
from benchmarks.docs_tooling.model_figures import FIGURES, format_figure, measure, rate
from mimo_radar_env.core.superarm import subset_masks


def test_alternating_optimality_equals_brute_force_over_every_super_arm():
    figures = measure(["alternating-optimal"], progress=lambda _: None)
    # the same 400 instances, every one of the C(10,3) C(12,4) super arms valued at once
    index = np.random.default_rng(3).exponential(size=(400, 10, 12))
    tx, rx = subset_masks(10, 3).astype(float), subset_masks(12, 4).astype(float)
    brute = np.einsum("sm,bmn,rn->bsr", tx, index, rx).reshape(400, -1).max(axis=1)
    from agents.solvers import AlternatingSolver
    from mimo_radar_env.core.streams import TrialRandom

    atx, arx = AlternatingSolver(3, 4).solve(index, TrialRandom.for_batch(0, 400))
    found = np.einsum("bm,bmn,bn->b", atx.astype(float), index, arx.astype(float))
    optimal = np.isclose(found, brute, rtol=1e-12)
    assert figures["alternating-optimal"]["value"] == optimal.mean()
    gap = figures["alternating-gap"]
    assert gap["value"] == pytest.approx(np.mean(1 - found / brute), rel=1e-12)
    assert gap["ci"][0] <= gap["value"] <= gap["ci"][1]


def test_a_rate_carries_the_wilson_interval():
    figure = rate(np.array([True] * 192 + [False] * 8), "x")
    # Wilson's score interval by its formula
    z, n, p = stats.norm.ppf(0.975), 200, 0.96
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z / (1 + z**2 / n) * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    np.testing.assert_allclose(figure["ci"], [centre - half, centre + half], rtol=1e-10)
    assert format_figure(figure) == "96.0 % [92.3, 98.0]"
    assert format_figure({"kind": "seconds", "value": 0.3714, "ci": None}) == "0.37 s"
    assert format_figure({"kind": "ratio", "value": 1.1938, "ci": [1.1837, 1.2036]}) == "1.19x [1.18, 1.20]"


def test_the_nees_figures_bracket_the_filter_dimension():
    figures = measure(["nees-ncv"], progress=lambda _: None)
    ncv, imm = figures["nees-ncv"], figures["nees-imm"]
    assert ncv["ci"][0] < 4 < ncv["ci"][1]  # the true-model UKF is consistent
    assert imm["ci"][1] < 4  # the IMM is conservative on straight tracks


def test_the_command_merges_only_what_it_remeasures(tmp_path, capsys):
    out = tmp_path / "model"
    assert main(["model-figures", "--out", str(out), "--only", "bpso-set-optimal"]) == 0
    first = json.loads((out / "figures.json").read_text())
    assert set(first["figures"]) == {"bpso-set-optimal", "bpso-xor-optimal"}
    assert first["machine"]["cores"] >= 1 and first["wall_s"] > 0
    assert main(["model-figures", "--out", str(out), "--only", "greedy-optimal-average"]) == 0
    second = json.loads((out / "figures.json").read_text())["figures"]
    assert second["bpso-set-optimal"] == first["figures"]["bpso-set-optimal"]
    # each figure says the command it was measured with, whichever run wrote the file last
    assert second["bpso-set-optimal"]["command"].endswith("--only bpso-set-optimal")
    assert second["greedy-optimal-average"]["command"].endswith("--only greedy-optimal-average")
    assert list(second) == [name for name in FIGURES if name in second]  # the registry's order
    for figure in second.values():
        assert figure["ci"][0] <= figure["value"] <= figure["ci"][1]
    with pytest.raises(SystemExit) as exit_info:
        main(["model-figures", "--out", str(out), "--only", "nope"])
    assert exit_info.value.code == 2
    assert "unknown figure(s) ['nope']" in capsys.readouterr().err
