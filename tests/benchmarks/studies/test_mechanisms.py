"""The mechanisms study: leads and sampling oracles against brute force, the bound-versus-SINR
table on hand-made inputs, the command end to end."""

import itertools
import json

import numpy as np

from benchmarks.cli import main as cli_main
from benchmarks.studies import mechanisms
from mimo_radar_env import load_scenario
from mimo_radar_env.envs.mimo_radar_select import MimoRadarSelectVectorEnv


def brute_force_leads(scenario: str, trials: int, seed: int) -> list[float]:
    """Each trial's first-step lead, every super arm enumerated with itertools."""
    sc = load_scenario(scenario)
    env = MimoRadarSelectVectorEnv(
        num_envs=trials, scenario=sc, truth="shared", lambda_scale="db", tracking=False
    )
    env.reset(seed=seed)
    leads = []
    for mean in env.engine.model.mean_sinr(env.engine.simulation.upcoming_state()[..., [0, 2]]):
        weighted = np.tensordot(np.asarray(env.engine.model.weights), mean, axes=1)  # (M, N)
        values = sorted(
            (
                sum(weighted[m, n] for m in tx for n in rx)
                for tx in itertools.combinations(range(sc.num_tx), sc.tx_per_step)
                for rx in itertools.combinations(range(sc.num_rx), sc.rx_per_step)
            ),
            reverse=True,
        )
        leads.append(values[0] / values[1] - 1.0)
    return leads


def test_lead_matches_brute_force_and_oracles_order_by_information():
    out = mechanisms.lead_and_sampling_oracles("paper-2-v1", trials=6, seed=3, samples=(1, 10**6), steps=1)
    assert np.isclose(out["median_lead"]["estimate"], np.mean(brute_force_leads("paper-2-v1", 6, 3)))
    # v1's shared truth: every trial sees the same channels, so the lead is constant over trials
    assert out["median_lead"]["method"] == "constant over trials"
    asr = out["sampling_oracle_asr"]
    assert np.isclose(asr[str(10**6)]["estimate"], 1.0, rtol=0, atol=1e-15)  # the true best every time


def test_more_samples_give_a_higher_asr_and_it_reproduces():
    kwargs = dict(trials=20, seed=1, samples=(1, 30), steps=40)
    a = mechanisms.lead_and_sampling_oracles("paper-1-v1", **kwargs)
    b = mechanisms.lead_and_sampling_oracles("paper-1-v1", **kwargs)
    assert a == b
    asr = a["sampling_oracle_asr"]
    assert asr["30"]["ci"][0] > asr["1"]["ci"][1]
    for key in ("window_oracle_asr", "probing_window_oracle_asr"):
        assert all(0.0 <= entry["estimate"] <= 1.0 for entry in a[key].values())
    # a window of one step is one fresh sample of every channel: the n = 1 sampling oracle's law
    assert abs(a["window_oracle_asr"]["1"]["estimate"] - asr["1"]["estimate"]) < 0.1


def test_bound_versus_sinr_reads_signs_both_ways(tmp_path):
    claims = [
        {
            "id": "S9.9",
            "scenario": "paper-1",
            "comparisons": [
                {"comparison": "armse: a < b", "estimate": 0.3, "ci": [0.2, 0.4], "verdict": "contradicted"},
                {"comparison": "armse: b < c", "estimate": -0.1, "ci": [-0.2, -0.05], "verdict": "holds"},
                {"comparison": "regret: a < b", "estimate": 1.0, "ci": [0.5, 1.5], "verdict": "contradicted"},
            ],
        }
    ]

    def policy(bound):
        return {"bound": bound, "bound_per_target": [bound], "ci": {"bound": [bound - 0.01, bound + 0.01]}}

    summary = {
        "policies": {"a": policy(2.0), "b": policy(1.0), "c": policy(1.5)},
        "paired_differences": {
            "a - b": {"mean_sinr_db": {"estimate": 1.0, "ci": [0.5, 1.5]}},  # a: more SINR, worse ARMSE
            "c - b": {
                "mean_sinr_db": {"estimate": -2.0, "ci": [-2.5, -1.5], "method": "BCa"}
            },  # b: more SINR than c
        },
    }
    (tmp_path / "paper-1-v1-average.summary.json").write_text(json.dumps(summary))
    rows = mechanisms.bound_versus_sinr(claims, tmp_path)
    assert [r["comparison"] for r in rows] == ["armse: a < b", "armse: b < c"]
    first, second = rows
    assert first["follows_bound"] and not first["follows_sinr"] and first["bound_settled"]
    assert second["sinr_db_difference"]["estimate"] == 2.0 and second["sinr_db_difference"]["ci"] == [
        1.5,
        2.5,
    ]
    assert second["follows_bound"] and second["follows_sinr"]
    assert mechanisms.summarise(rows) == {
        "comparisons": 2,
        "follow_bound": 2,
        "follow_sinr": 1,
        "contradicted": 1,
        "contradicted_follow_bound": 1,
        "contradicted_follow_sinr": 0,
    }


def test_command_writes_its_results(tmp_path, capsys):
    code = cli_main(
        ["mechanisms", "--trials", "6", "--steps", "5", "--scenarios", "paper-3-v1", "--out", str(tmp_path)]
    )
    assert code == 0
    result = json.loads((tmp_path / "mechanisms.json").read_text())
    assert list(result["lead"]) == ["paper-3-v1"] and result["lead"]["paper-3-v1"]["claim"] == "S3.4"
    assert result["armse_summary"]["comparisons"] > 0 and (tmp_path / "timing.json").exists()
    assert "sampling-oracle ASR" in capsys.readouterr().out
