"""The step's stages add up to the step and name their declared arithmetic."""

import pytest


def test_the_step_stages_add_up_to_the_step_and_name_their_arithmetic():
    from benchmarks.speed import stages

    record = stages.measure(trials=4, steps=2)
    rows = record["rows"]
    env_stages = {"simulation", "tracker", "bound", "oracle search", "observation and info"}
    for fusion in ("average", "centralized"):
        assert {r["stage"] for r in rows if r["fusion"] == fusion} == env_stages
        timed = [r for r in rows if r["fusion"] == fusion and r["stage"] != "observation and info"]
        assert all(r["ms_per_step"] > 0 for r in timed)
    tracker = next(r for r in rows if r["stage"] == "tracker" and r["fusion"] == "average")
    assert tracker["achieved_operations_per_s"] == pytest.approx(
        tracker["declared_operations_per_trial"] * 4 / (tracker["ms_per_step"] / 1e3)
    )
    assert {r["stage"] for r in rows if r["fusion"] == "-"} == {
        "MG-CRB-CL act, BPSO (paper, rule set)",
        "MG-CRB-CL act, exact solver",
    }
