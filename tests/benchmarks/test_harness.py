"""The Monte-Carlo harness and its CLI on small runs."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from benchmarks.cli import main
from benchmarks.harness import HarnessError, make_config, run, shard_path
from benchmarks.report import write_outputs
from tests.helpers import SUMMARY_KEYS


def test_run_subcommand_with_agent_params_and_a_scenario_file(tmp_path, capsys):
    scenario = tmp_path / "tiny.yaml"
    scenario.write_text(
        "tx_positions: [[0, 0], [20000, 0], [0, 20000]]\n"
        "rx_positions: [[20000, 20000], [10000, 0], [0, 10000]]\n"
        "tx_per_step: 2\nrx_per_step: 2\nhorizon: 40\ntargets:\n  - initial_state: [5000, 50, 7000, 20]\n"
    )
    out = tmp_path / "run"
    main(
        [
            "run",
            "--scenario",
            str(scenario),
            "--policies",
            "mg-crb-cl,discounted-thompson,random",
            "--agent-param",
            "mg-crb-cl.solver=exact",
            "--agent-param",
            "discounted-thompson.discount=0.95",
            "--trials",
            "3",
            "--seed",
            "7",
            "--fusion",
            "centralized",
            "--workers",
            "1",
            "--no-figures",
            "--out",
            str(out),
            "--quiet",
        ]
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"] == "tiny" and summary["seed"] == 7 and summary["steps"] == 40
    assert list(summary["policies"]) == ["mg-crb-cl", "discounted-thompson", "random"]
    config = json.loads((out / "config.json").read_text())
    assert config["agent_params"] == {
        "mg-crb-cl": {"solver": "exact"},
        "discounted-thompson": {"discount": 0.95},
    }
    assert not (out / "sinr.png").exists()


def test_a_changed_configuration_in_the_same_dir_is_refused(tmp_path):
    config = make_config("paper-1", ["fix1"], trials=2, steps=5, shard_size=1)
    run(config, tmp_path, progress=False)
    other = make_config("paper-1", ["fix1"], trials=2, steps=6, shard_size=1)
    with pytest.raises(HarnessError, match=r"different configuration \(differs in \['steps'\]\)"):
        run(other, tmp_path, progress=False)


def test_resume_after_a_partial_run_gives_the_same_numbers(tmp_path):
    config = make_config("paper-3", ["mg-crb-cl", "epsilon-greedy"], trials=6, steps=20, shard_size=2)
    whole = run(config, tmp_path / "whole", progress=False)
    assert run(config, tmp_path / "part", progress=False, max_tasks=3) is None  # stops after 3 of 6 tasks
    assert len(list((tmp_path / "part" / "shards").rglob("*.npz"))) == 3
    resumed = run(config, tmp_path / "part", progress=False)
    for policy in config.policies:
        for key, value in whole[policy].items():
            if key != "wall_s":
                np.testing.assert_array_equal(resumed[policy][key], value)


def test_a_killed_run_restarted_gives_exactly_the_uninterrupted_numbers(tmp_path):
    args = [
        "run",
        "--scenario",
        "paper-1-v1",
        "--policies",
        "ucb1,fix1",
        "--trials",
        "8",
        "--shard-size",
        "1",
        "--steps",
        "300",
        "--workers",
        "1",
        "--no-figures",
        "--quiet",
    ]
    killed = tmp_path / "killed"
    proc = subprocess.Popen(
        [sys.executable, "-m", "benchmarks", *args, "--out", str(killed)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.time() + 120
    while time.time() < deadline and len(list(killed.glob("shards/*/*.npz"))) < 3:
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done = len(list(killed.glob("shards/*/*.npz")))
    assert 3 <= done < 16, "the run must be killed part-way"
    assert main([*args, "--out", str(killed)]) == 0
    assert main([*args, "--out", str(tmp_path / "whole")]) == 0
    a = json.loads((killed / "summary.json").read_text())["policies"]
    b = json.loads((tmp_path / "whole" / "summary.json").read_text())["policies"]
    for policy in a:
        for key in SUMMARY_KEYS - {"wall_s"}:
            assert a[policy][key] == b[policy][key], (policy, key)


def test_outputs_regenerate_from_saved_shards(tmp_path):
    config = make_config("paper-1", ["fix1", "best"], trials=2, steps=10, shard_size=1)
    totals = run(config, tmp_path, progress=False)
    first = write_outputs(config, totals, tmp_path, figures=False)
    again = write_outputs(config, None, tmp_path, figures=False)
    assert first == again
    assert shard_path(tmp_path, "fix1", 1).exists()


@pytest.mark.parametrize(
    ("kwargs", "python", "flag"),
    [
        ({"trials": 0}, "trials must be an integer >= 1, got 0", "--trials must be"),
        ({"seed": -1}, "seed must be an integer >= 0, got -1", "--seed must be"),
        ({"steps": 5000}, "steps must be between 1 and the scenario horizon", "--steps must be"),
        ({"shard_size": 0}, "shard_size must be an integer >= 1", "--shard-size must be"),
        (
            {"agent_params": {"ucb1": {"seed": 3}}},
            "agent_params ucb1.seed: agents' seeds are set by the run (seed)",
            "--agent-param ucb1.seed",
        ),
        (
            {"agent_params": {"cts": {}}},
            "agent_params names policy 'cts', which is not in the run",
            "--agent-param names",
        ),
        (
            {"max_hours": 1e-9, "trials": 500},
            "more than max_hours 1e-09: use fewer trials or steps, more workers",
            "more than --max-hours",
        ),
    ],
)
def test_the_library_api_names_its_arguments_and_the_command_line_its_flags(kwargs, python, flag):
    """make_config's refusals speak Python (its arguments); the command line translates them to
    its flags, and nothing else in the message changes."""
    given = {"trials": 2, **kwargs}
    with pytest.raises(HarnessError) as caught:
        make_config("paper-1-v1", ["ucb1"], say=lambda message: None, **given)
    assert python in str(caught.value) and "--" not in str(caught.value)
    assert flag in caught.value.for_command_line()
