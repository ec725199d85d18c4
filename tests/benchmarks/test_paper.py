"""The paper command: every output of a short run of the paper's policies."""

import csv
import json
import re

import numpy as np
import pytest

from benchmarks.cli import main
from tests.helpers import SUMMARY_KEYS


def _read_curves(path):
    with open(path) as handle:
        return list(csv.DictReader(handle))


def test_paper_subcommand_writes_every_output(tmp_path, capsys):
    out = tmp_path / "paper"
    code = main(
        [
            "paper",
            "--scenario",
            "3",
            "--trials",
            "6",
            "--steps",
            "25",
            "--shard-size",
            "3",
            "--workers",
            "1",
            "--out",
            str(out),
            "--quiet",
        ]
    )
    assert code == 0
    printed = capsys.readouterr().out
    # v1's paper study gives MG-CRB-CL the standard BPSO rule, and its label says so
    assert "| mg-crb-cl (solver_params.rule=set) |" in printed
    assert "paper ARMSE" not in printed  # 25 steps: not the paper's 1000
    for name in (
        "summary.json",
        "curves.csv",
        "table.md",
        "sinr.png",
        "regret.png",
        "rmse.png",
        "geometry.png",
        "selection_mg-crb-cl.png",
        "selection_fix2.png",
        "config.json",
    ):
        assert (out / name).exists(), name
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary) >= {"scenario", "trials", "steps", "seed", "policies"}
    assert summary["scenario"] == "paper-3-v1" and summary["trials"] == 6 and summary["steps"] == 25
    assert list(summary["policies"]) == ["best", "mg-crb-cl", "ucb1", "epsilon-greedy", "fix1", "fix2"]
    rows = _read_curves(out / "curves.csv")
    for policy, row in summary["policies"].items():
        assert set(row) == SUMMARY_KEYS and 0.0 <= row["asr"] <= 1.0 and len(row["armse_per_target"]) == 2
        assert row["tracker_repairs"] == 0  # a healthy run repairs nothing
        # independent computation from the saved per-step data
        mine = [r for r in rows if r["policy"] == policy]
        assert len(mine) == 25
        per_target = [np.mean([float(r[f"rmse_target{k}"]) for r in mine]) for k in (1, 2)]
        assert row["armse_per_target"] == pytest.approx(per_target, rel=1e-9)
        assert row["armse"] == pytest.approx(np.mean(per_target), rel=1e-9)
        bounds = [np.mean([float(r[f"bound_target{k}"]) for r in mine]) for k in (1, 2)]
        assert row["bound_per_target"] == pytest.approx(bounds, rel=1e-9)
        assert row["armse_over_bound"] == pytest.approx(row["armse"] / np.mean(bounds), rel=1e-9)
        low, high = row["ci"]["bound"]  # from float32 per-trial values: equal to 1e-6
        assert 0 < row["bound"] and low * (1 - 1e-6) <= row["bound"] <= high * (1 + 1e-6)
        assert row["asr"] == pytest.approx(np.mean([float(r["asr"]) for r in mine]), rel=1e-9)
        assert row["final_regret"] == pytest.approx(float(mine[-1]["cumulative_regret"]), rel=1e-9, abs=1e-9)
        linear = np.mean([10 ** (float(r["mean_sinr_db"]) / 10) for r in mine])
        assert row["mean_sinr_db"] == pytest.approx(10 * np.log10(linear), rel=1e-9)
    best = summary["policies"]["best"]
    assert best["asr"] == pytest.approx(1.0, abs=1e-15) and best["final_regret"] == pytest.approx(0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"policies": "fix1"}, "policies must be a list of policy names, got the string 'fix1'"),
        ({"options": {"fusion": "x"}}, "options: fusion must be one of ['average', 'centralized'], got 'x'"),
        ({"version": "v3"}, "version must be one of ['v0', 'v1'], got 'v3'"),
        ({"scenario": "paper-1"}, "scenario 'paper-1' is MimoRadarSelect-v0's paper Scenario 1"),
        ({"options": [("fusion", "average")]}, "options must be an EnvOptions or a mapping of env options"),
        ({"agent_params": {"fix1": 3}}, "agent_params must map policy names to mappings of their parameters"),
        ({"progress": "yes"}, "progress must be True or False, got 'yes'"),
        ({"figures": 2}, "figures must be True or False, got 2"),
        ({"seed": 2**63 - 1}, "seed must be at most 2**63 - 2 for 2 trials"),
    ],
)
def test_benchmarks_run_refuses_in_one_line_naming_its_argument(tmp_path, kwargs, message):
    """``benchmarks.run`` (the run command as a Python call): a string of policies is not read as
    one-letter names, and a bad option is a HarnessError as make_config's are. Before, options
    not a mapping and agent_params of a number failed inside Python's ``**`` and ``in``, a flag of
    another type was read by its truth, and a seed whose trials' seeds pass 2**63 - 1 was taken
    and failed in its second shard."""
    from benchmarks.harness import HarnessError
    from benchmarks.paper import run_policies

    given = {
        "scenario": "paper-1-v1",
        "policies": ["fix1"],
        "trials": 2,
        "steps": 3,
        "progress": False,
        **kwargs,
    }
    with pytest.raises(HarnessError) as caught:
        run_policies(**given, out=tmp_path / "out")
    assert str(caught.value).startswith(message)
    assert not (tmp_path / "out").exists()


def test_an_unknown_env_option_is_a_type_error_naming_the_options_there_are(tmp_path):
    """As in Gymnasium, an unknown keyword is a TypeError; it was EnvOptions.__init__'s own."""
    from benchmarks.paper import run_policies
    from mimo_radar_env import env_version
    from mimo_radar_env.envs.options import option_names

    listed = re.escape(str(list(option_names())))
    unknown = rf"env options got an unexpected keyword argument 'foo'; env options are {listed}$"
    with pytest.raises(TypeError, match=unknown):
        env_version("v1").options(foo=1)
    with pytest.raises(TypeError, match=r"unexpected keyword argument 'foo'; env options are \["):
        run_policies("paper-1-v1", ["fix1"], trials=2, steps=3, options={"foo": 1}, out=tmp_path / "o")
    assert not (tmp_path / "o").exists()
