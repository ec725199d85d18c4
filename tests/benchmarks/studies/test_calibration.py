"""Layout calibration: constraints from the text, the noise-free screen, the adoption rule."""

import json

import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.settings import study_agent_params
from benchmarks.studies import calibration, claims
from mimo_radar_env import RadarModel, load_scenario


def test_candidates_are_reproducible_and_inside_the_region():
    a, b = calibration.candidates(30, seed=4), calibration.candidates(30, seed=4)
    assert [c.tx_km for c in a] == [c.tx_km for c in b] and [c.rx_km for c in a] == [c.rx_km for c in b]
    assert a[0].jitter_km is None and a[0].tx_km == (load_scenario("paper-1").tx_positions / 1e3).tolist()
    coords = np.array([c.tx_km + c.rx_km for c in a])
    assert coords.min() >= 0 and coords.max() <= 100
    assert calibration.candidates(30, seed=5)[1].tx_km != a[1].tx_km


def test_the_reference_layout_meets_the_constraints():
    reference = calibration.candidates(0, seed=0)[0]
    assert calibration.constraint_failure(reference) is None
    assert set(claims.best_selection_windows(load_scenario("paper-1")).values()) == {1.0}


def test_a_station_near_a_track_or_moving_best_is_rejected():
    reference = calibration.candidates(0, seed=0)[0]
    near = calibration.Candidate(1, reference.tx_km, [list(r) for r in reference.rx_km], 1.0)
    near.rx_km[5] = [30.0, 31.0]  # 0.7 km from Scenario 1's diagonal track
    assert "km from a nominal track of paper-1" in calibration.constraint_failure(near)
    moved = calibration.Candidate(2, [list(t) for t in reference.tx_km], reference.rx_km, 1.0)
    moved.tx_km[0] = [100.0, 0.0]  # TX1 far from the track's start: Best no longer picks it early
    assert "Best selects the paper's super arm" in calibration.constraint_failure(moved)


def test_scan_bound_is_the_explicit_fisher_information_inverse():
    model = RadarModel.from_scenario(load_scenario("paper-1", horizon=20))
    steps = model.nominal.shape[1]
    tx = np.zeros((steps, 4), bool)
    rx = np.zeros((steps, 6), bool)
    tx[:, [0, 1]], rx[:, [0, 1, 2]] = True, True
    bound = calibration.scan_bound(model, tx, rx, "db")
    t = 7
    p = model.nominal[0, t, [0, 2]]
    sigma0 = model.scenario.measurement_covariance
    info = np.zeros((2, 2))
    for m in (0, 1):
        for n in (0, 1, 2):
            sinr = model.gain[0, m, n] / (np.sum((p - model.tx[m]) ** 2) * np.sum((p - model.rx[n]) ** 2))
            lam = np.clip(
                (10 * np.log10(sinr / model.min_sinr[0])) / (10 * np.log10(10 / model.min_sinr[0])) + 0.2,
                0.2,
                1.2,
            )
            d_tx, d_rx = p - model.tx[m], p - model.rx[n]
            h = np.array(
                [
                    d_tx / np.linalg.norm(d_tx) + d_rx / np.linalg.norm(d_rx),
                    [-d_rx[1], d_rx[0]] / (d_rx @ d_rx),
                ]
            )
            info += h.T @ np.linalg.inv(sigma0 / lam) @ h
    assert bound[t, 0] == pytest.approx(np.sqrt(np.trace(np.linalg.inv(info))), rel=1e-10)


def _fake_scorecard(holds_by_layout):
    """A scorecard runner that returns fixed verdict counts per layout folder, and records calls."""
    calls = []

    def run(scenarios, folder, trials):
        index = int(folder.name.split("-")[1])
        calls.append((index, trials, folder.parent.name))
        holds, contradicted = holds_by_layout.get(index, (5, 10))
        verdicts = ["holds"] * holds + ["contradicted"] * contradicted
        return [{"verdict": v} for v in verdicts]

    return run, calls


def test_calibrate_adopts_only_a_layout_that_beats_the_reference(tmp_path):
    pool = calibration.candidates(40, seed=0)
    passing = [c.index for c in pool[1:] if calibration.constraint_failure(c) is None]
    better = passing[0]

    def calibrate(out, run):
        sizes = dict(count=40, screen=len(passing), screen_trials=3, final=2, final_trials=7)
        return calibration.calibrate(out, run, **sizes, log=lambda _: None)

    run, calls = _fake_scorecard({0: (8, 13), better: (9, 12)})
    report = calibrate(tmp_path, run)
    assert report["best"] == better and report["adopted"]
    assert (
        (0, 7, "final") in calls
        and (better, 7, "final") in calls
        and len([c for c in calls if c[2] == "final"]) == 3
    )
    saved = json.loads((tmp_path / "calibration.json").read_text())
    assert len(saved["candidates"]) == 41 and all("noise_free_score" in c for c in saved["candidates"])
    assert "adopted" in (tmp_path / "calibration.md").read_text()

    run, _ = _fake_scorecard({0: (8, 13), better: (8, 13)})  # a tie keeps the reference
    report = calibrate(tmp_path / "tie", run)
    assert report["best"] == 0 and not report["adopted"]
    assert "not adopted" in (tmp_path / "tie" / "calibration.md").read_text()


def test_calibrate_layout_command_runs_end_to_end(tmp_path, capsys):
    argv = ["calibrate-layout", "--candidates", "6", "--screen", "1", "--screen-trials", "6", "--final", "1"]
    argv += [
        "--trials",
        "7",
        "--steps",
        "20",
        "--workers",
        "1",
        "--quiet",
        "--no-figures",
        "--out",
        str(tmp_path),
    ]
    assert main(argv) == 0
    report = json.loads((tmp_path / "calibration.json").read_text())
    assert report["candidates"][0]["scorecards"].keys() == {"6", "7"}
    assert (tmp_path / "final" / "layout-0000" / "claims.md").exists()
    assert "best layout" in capsys.readouterr().out


def test_agent_param_goes_over_the_versions_reading():
    assert study_agent_params("v1", []) == {"mg-crb-cl": {"solver_params": {"rule": "set"}}}
    assert study_agent_params("v0", ["mg-crb-cl.solver_params={rule: set}"]) == {
        "mg-crb-cl": {"solver_params": {"rule": "set"}}
    }
    assert study_agent_params("v1", ["mg-crb-cl.beta=0.5"]) == {
        "mg-crb-cl": {"solver_params": {"rule": "set"}, "beta": 0.5}
    }
