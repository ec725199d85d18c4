"""The command line on bad input: one line naming the input and what is allowed, exit 2,
nothing written."""

import subprocess
import sys
import time

import pytest

from benchmarks.cli import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["demo", "--steps", "-4"], "argument --steps: must be an integer >= 1, got -4"),
        (["train-ppo", "--timesteps", "0", "--out", "X"], "argument --timesteps: must be an integer >= 1"),
        (["train-ppo", "--timesteps", "-5", "--out", "X"], "argument --timesteps: must be an integer >= 1"),
        (
            ["run", "--scenario", "paper-1", "--policies", "ucb1", "--workers", "0", "--out", "X"],
            "argument --workers: must be an integer >= 1, got 0",
        ),
        (
            ["run", "--scenario", "paper-1", "--policies", "ucb1", "--seed", "-1", "--out", "X"],
            "argument --seed: must be an integer >= 0, got -1",
        ),
    ],
)
def test_cli_numbers_out_of_range(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err.strip().splitlines()[-1]
    assert not (tmp_path / "X").exists()


@pytest.mark.parametrize(
    ("param", "message"),
    [
        ("mg-crb-cl.alpha=-1", "policy 'mg-crb-cl': alpha must be in [0, 1], got -1"),
        ("mg-crb-cl.alpha=[1,2", "--agent-param 'mg-crb-cl.alpha=[1,2': the value is"),
        ("mg-crb-cl.seed=5", "agents' seeds are set by the run (--seed)"),
    ],
)
def test_bad_values_fail_before_config_json_is_written(param, message, tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1", "--policies", "mg-crb-cl", "--agent-param", param]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("policies", "message"),
    [
        ("ppo:/etc", "PPO model /etc/model.zip does not exist"),
        ("fixed", "needs the parameter(s) ['rx', 'tx']"),
    ],
)
def test_models_and_missing_parameters(policies, message, tmp_path, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit):
        main(["run", "--scenario", "paper-1", "--policies", policies, "--out", str(out), "--quiet"])
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_an_unusable_out_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    argv = ["run", "--scenario", "paper-1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(blocker / "out"), "--quiet", "--no-figures"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write into --out" in err[0]


def test_an_unreachable_ray_address_fails_within_seconds(tmp_path, capsys):
    pytest.importorskip("ray", reason="the ray extra")
    import socket

    with socket.socket() as probe:  # a loopback port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    argv = ["run", "--scenario", "paper-1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    start = time.perf_counter()
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--backend", "ray", "--address", f"127.0.0.1:{port}", "--out", str(tmp_path / "o")])
    assert time.perf_counter() - start < 10
    assert exit_info.value.code == 2
    assert f"cannot reach the Ray cluster at '127.0.0.1:{port}'" in capsys.readouterr().err


# ------------------------------------------------------------------ fuzz
def test_subprocess_cli_scenario_errors_are_one_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(
        "tx_positions: [[0, 0]]\nrx_positions: [[1, 1]]\ntx_per_step: 1\nrx_per_step: 1\n"
        "targets: [{initial_state: [5, 1, 5, 1], maneuvers: 5}]\n"
    )
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmarks",
            "run",
            "--scenario",
            str(path),
            "--policies",
            "fix1",
            "--out",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "maneuvers must be a list" in result.stderr
