"""The command line on bad input: one line naming the input and what is allowed, exit 2,
nothing written."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from benchmarks.cli import main


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["demo", "--steps", "-4"], "argument --steps: must be an integer >= 1, got -4"),
        (["train-ppo", "--timesteps", "0", "--out", "X"], "argument --timesteps: must be an integer >= 1"),
        (["train-ppo", "--timesteps", "-5", "--out", "X"], "argument --timesteps: must be an integer >= 1"),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--workers", "0", "--out", "X"],
            "argument --workers: must be an integer >= 1, got 0",
        ),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--seed", "-1", "--out", "X"],
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
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "mg-crb-cl", "--agent-param", param]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("policies", "message"),
    [
        ("ppo:/etc", "ppo model /etc/model.zip does not exist: give a model's .zip file or the folder"),
        ("fixed", "needs the parameter(s) ['rx', 'tx']"),
    ],
)
def test_models_and_missing_parameters(policies, message, tmp_path, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit):
        main(["run", "--scenario", "paper-1-v1", "--policies", policies, "--out", str(out), "--quiet"])
    assert message in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,,best"],
        ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,"],
        ["tracking", "--scenarios", "1", "--fusions", "average,"],
    ],
)
def test_an_empty_entry_of_a_comma_list_is_refused_not_dropped(argv, tmp_path, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    flag = argv[-2]
    assert len(err) == 1 and f"{flag} has an empty entry in {argv[-1]!r}" in err[0]
    assert not out.exists()


def test_an_unknown_argument_names_its_command_and_the_commands_help(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["demo", "--policy", "xyz"])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "mimo-radar-bench demo: error: unrecognized arguments: --policy xyz "
        "(see 'mimo-radar-bench demo --help')"
    ]


def test_an_unreachable_ray_address_fails_within_seconds(tmp_path, capsys):
    pytest.importorskip("ray", reason="the ray extra")
    import socket

    with socket.socket() as probe:  # a loopback port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    start = time.perf_counter()
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--backend", "ray", "--address", f"127.0.0.1:{port}", "--out", str(tmp_path / "o")])
    assert time.perf_counter() - start < 10
    assert exit_info.value.code == 2
    assert f"cannot reach the Ray cluster at '127.0.0.1:{port}'" in capsys.readouterr().err


def test_a_web_server_given_as_the_ray_address_is_one_line_and_writes_nothing(tmp_path, capsys):
    """The dashboard's port (8265), or any server that is not a Ray cluster, is named before
    anything is written: ``ray.init`` would wait on it for minutes."""
    pytest.importorskip("ray", reason="the ray extra")
    import http.server
    import threading

    class Quiet(http.server.BaseHTTPRequestHandler):
        def log_message(self, *arguments):  # the server's own log would share stderr
            pass

    web = http.server.HTTPServer(("127.0.0.1", 0), Quiet)
    threading.Thread(target=web.serve_forever, daemon=True).start()
    address = f"127.0.0.1:{web.server_address[1]}"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    try:
        with pytest.raises(SystemExit) as exit_info:
            main([*argv, "--backend", "ray", "--address", address, "--out", str(tmp_path / "o")])
    finally:
        web.shutdown()
        web.server_close()
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"mimo-radar-bench: error: what answers at '{address}' is not a Ray cluster (not a gRPC server): "
        "give the cluster's address (the port 'ray start --head' printed, 6379 by default, not the "
        "dashboard's 8265)"
    ]
    assert not (tmp_path / "o").exists()


def test_ray_address_auto_without_a_cluster_is_named_before_anything_is_written(
    tmp_path, capsys, monkeypatch
):
    pytest.importorskip("ray", reason="the ray extra")
    from ray._private import services

    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path / "no-ray"))  # no cluster file to find
    # nor a cluster another test runs meanwhile (auto takes any GCS process it finds on the machine)
    monkeypatch.setattr(services, "find_gcs_addresses", lambda: [])
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "fix1", "--trials", "1", "--steps", "2"]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--backend", "ray", "--address", "auto", "--out", str(tmp_path / "o")])
    assert exit_info.value.code == 2
    assert "--address auto: no Ray cluster is running on this machine" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


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


@pytest.mark.parametrize(
    ("param", "message"),
    [
        (
            "mg-crb-cl.solver_params={population: 2.5}",
            "policy 'mg-crb-cl': population must be an integer in [1, 10,000], got 2.5",
        ),
        (
            "mg-crb-cl.solver_params={iterations: 100000000}",
            "policy 'mg-crb-cl': iterations must be in [1, 20,000], got 100,000,000",
        ),
        (
            "mg-crb-cl.solver_params={velocity_clamp: 0}",
            "policy 'mg-crb-cl': velocity_clamp must be in (0, 100], got 0",
        ),
        ("ucb1.beta=inf", "policy 'ucb1': beta must be a number in [0, inf), got 'inf'"),
        ("ucb1.beta=nan", "policy 'ucb1': beta must be a number in [0, inf), got 'nan'"),
        ("ucb1.beta=.inf", "policy 'ucb1': beta must be a finite number in [0, inf), got inf"),
        ("ucb1.beta=1e3", "got '1e3' (text: YAML reads an exponent without a dot as text; write 1.0e+03)"),
    ],
)
def test_solver_parameters_are_checked_when_the_agent_is_made(param, message, tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", param.split(".")[0], "--agent-param", param]
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--trials", "2", "--steps", "3", "--out", str(out), "--quiet"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    if param.endswith(("=inf", "=nan")):  # text too, but no exponent to write otherwise
        assert err[0].endswith(message), err
    assert not out.exists()


def test_an_exact_search_too_large_for_the_layout_is_refused_before_running(tmp_path, capsys):
    import yaml

    from mimo_radar_env import random_scenario

    path = tmp_path / "big.yaml"
    path.write_text(yaml.safe_dump(random_scenario(64, 64, 1, 4, 4, horizon=5, seed=0).to_dict()))
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as exit_info:
        main(
            [
                "run",
                "--scenario",
                str(path),
                "--policies",
                "ucb1",
                "--trials",
                "2",
                "--out",
                str(out),
                "--quiet",
            ]
        )
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "exact solver would enumerate 635,376 subsets" in err and "solver='alternating'" in err
    assert not out.exists()


@pytest.mark.parametrize(
    "study",
    ["tracking", "claims", "calibrate-layout", "planning", "ablations", "search-layouts", "rl", "mechanisms"],
)
def test_judged_studies_need_the_trials_of_an_interval(study, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([study, "--trials", "5", "--out", str(tmp_path / "x"), "--quiet"])
    assert exit_info.value.code == 2
    assert "must be an integer >= 6 (a paired 95 % interval needs 6 trials or more), got 5" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "x").exists()


def test_a_run_of_policies_takes_a_single_trial(tmp_path):
    for command in (["run", "--scenario", "paper-1-v1", "--policies", "best"], ["paper", "--scenario", "1"]):
        out = tmp_path / command[0]
        assert (
            main([*command, "--trials", "1", "--steps", "2", "--quiet", "--no-figures", "--out", str(out)])
            == 0
        )


def test_workers_beyond_the_cores_are_capped_with_a_message(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("os.cpu_count", lambda: 2)
    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "random", "--trials", "2", "--steps", "2"]
    assert main([*argv, "--workers", "16", "--out", str(out), "--quiet", "--no-figures"]) == 0
    assert "--workers 16 is more than this machine's 2 cores; using 2" in capsys.readouterr().err


def test_claims_refuse_a_run_that_is_not_a_paper_study(tmp_path, capsys):
    run = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "2", "--steps", "2"]
    assert main([*argv, "--out", str(run), "--quiet", "--no-figures"]) == 0
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(["claims", str(run), "--out", str(tmp_path / "card"), "--quiet"])
    assert exit_info.value.code == 2
    assert "ran ucb1; the claims need the paper study's policies" in capsys.readouterr().err
    (run / "config.json").write_text('{"policies": 5}')
    with pytest.raises(SystemExit):
        main(["claims", str(run), "--out", str(tmp_path / "card"), "--quiet"])
    assert "config.json is not a run's configuration" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("{", "is not a JSON scorecard"),
        ('{"x": 1}', "is not a scorecard: expected a list of judged claims"),
        ("[1, 2]", "claim 0 lacks id, scenario, claim, verdict"),
        ('[{"id": "S1.1", "scenario": "p", "claim": "c", "verdict": "maybe"}]', "has verdict 'maybe'"),
    ],
)
def test_compare_claims_on_a_foreign_file_is_one_line(content, message, tmp_path, capsys):
    path = tmp_path / "card.json"
    path.write_text(content)
    with pytest.raises(SystemExit) as exit_info:
        main(["compare-claims", f"A={path}"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    with pytest.raises(SystemExit):
        main(["compare-claims", f"A={path}", f"A={path}"])
    assert "two scorecards are labelled 'A'" in capsys.readouterr().err


@pytest.mark.parametrize(
    "command",
    [
        ["run", "--scenario", "paper-1-v1", "--policies", "ucb1"],
        ["paper", "--scenario", "1"],
        ["claims"],
        ["tracking"],
        ["train-ppo", "--timesteps", "16"],
    ],
)
@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (
            ["--reward", "information", "--no-tracking"],
            "--reward='information' is the tracker's information gain",
        ),
        (["--prediction-covariance", "--no-tracking"], "--prediction-covariance=True observes the tracker's"),
    ],
)
def test_env_option_combinations_are_refused_in_one_line_by_every_command(
    command, flags, message, capsys, tmp_path
):
    out = tmp_path / "X"
    with pytest.raises(SystemExit) as exit_info:
        main([*command, *flags, "--out", str(out)])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and "needs --tracking=True" in err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--out", ""],
            "argument --out: must name a folder, got ''",
        ),
        (
            ["mechanisms", "--claims", "/nonexistent", "--out", "X"],
            "--claims '/nonexistent' is not a claims study's JSON",
        ),
        (
            ["mechanisms", "--claims", "/etc/hostname", "--out", "X"],
            "--claims '/etc/hostname' is not a claims study's JSON",
        ),
        (
            ["mechanisms", "--scenarios", "paper-1-v1", "paper-1-v1", "--out", "X"],
            "--scenarios lists a scenario twice",
        ),
        (["mechanisms", "--out", "/etc/passwd"], "must be a folder, and '/etc/passwd' is a file"),
        (["planning", "--rl", "/nonexistent", "--out", "X"], "--rl '/nonexistent' is not a folder"),
    ],
)
def test_referenced_files_and_folders_are_checked_before_anything_runs(
    argv, message, capsys, tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert list(tmp_path.iterdir()) == []  # nothing written


OUT_COMMANDS = [
    ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "6", "--steps", "3"],
    ["train-ppo", "--timesteps", "64"],
    ["mechanisms", "--trials", "6"],
    ["calibrate-layout", "--screen-trials", "6", "--candidates", "2", "--screen", "1", "--final", "1"],
    ["search-layouts", "--trials", "6", "--generations", "1"],
    ["model-figures"],
    ["perf", "--quick"],
    ["rl", "--trials", "6", "--ppo-seeds", "1", "--contrib-seeds", "1", "--timesteps", "64"],
]


@pytest.mark.parametrize("argv", OUT_COMMANDS, ids=lambda argv: argv[0])
def test_an_out_that_cannot_be_a_folder_is_refused_before_any_work(argv, capsys, tmp_path, monkeypatch):
    """A file, a path under a file, and a folder that cannot be made: one line each, before the
    command measures anything (mechanisms, model-figures and perf wrote at the end of their
    work; they and the layout studies ended in a traceback)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file").write_text("x")
    unmakeable = [] if not Path("/proc/self").is_dir() else [("/proc/x", "cannot write into --out /proc/x")]
    for out, message in [
        ("file", "argument --out: must be a folder, and 'file' is a file"),
        ("file/run", "argument --out: must be a folder, and 'file/run' is under the file file"),
        *unmakeable,
    ]:
        with pytest.raises(SystemExit) as exit_info:
            main([*argv, "--out", out])
        assert exit_info.value.code == 2
        assert message in capsys.readouterr().err.strip().splitlines()[-1]
        assert [p.name for p in tmp_path.iterdir()] == ["file"] and Path("file").read_text() == "x"


def test_the_help_marks_commands_whose_module_is_not_installed(monkeypatch):
    """From a wheel the studies' modules are absent: their group's heading says they run from a
    source checkout; one absent command in a group of present ones is marked on its own line."""
    from benchmarks import cli

    assert all(entry.installed for entry in cli.COMMANDS.values())  # a source checkout has them all
    assert not cli.CommandEntry("x", "studies", "", "no_such_package.mod:X").installed
    assert not cli.CommandEntry("x", "studies", "", "benchmarks.no_such_module:X").installed
    built_in = {name: e for name, e in cli.COMMANDS.items() if e.target.startswith("benchmarks.")}
    ghost = cli.CommandEntry("ghost", "maintenance", "a command", "no_such_package.mod:X")
    monkeypatch.setattr(cli, "COMMANDS", built_in | {"ghost": ghost})  # not another test's commands
    monkeypatch.setattr(
        cli.CommandEntry,
        "installed",
        property(lambda entry: not entry.target.startswith(("benchmarks.studies.", "no_such_package."))),
    )
    listing = cli._listing()
    assert f"studies ({cli.NOT_INSTALLED}):" in listing
    assert "  claims " in listing and f"scorecards side by side ({cli.NOT_INSTALLED})" not in listing
    assert f"  ghost             a command ({cli.NOT_INSTALLED})" in listing
    assert "first steps:\n" in listing and "maintenance:\n" in listing


def test_a_command_that_runs_tasks_starts_its_workers_fork_server_before_it_parses(monkeypatch, capsys):
    """The fork server imports what the workers need while the command imports its module and
    parses: started as a study is named with local workers, from a first reading of its options,
    and not for one worker, Ray, --help, an option it cannot read, or a command that runs no tasks."""
    from benchmarks import backends, cli

    calls = []
    monkeypatch.setattr(backends, "start_fork_server", lambda device=False: calls.append(("fork", device)))
    build = cli.build_parser
    monkeypatch.setattr(cli, "build_parser", lambda *a: calls.append(("parse",)) or build(*a))
    with pytest.raises(SystemExit):  # the full parse refuses the unknown option: nothing runs
        main(["claims", "--workers", "2", "--device", "cuda", "--no-such-option"])
    assert calls[:2] == [("fork", True), ("parse",)]
    capsys.readouterr()
    for argv, starts in [
        (["claims", "--workers", "2"], True),
        (["claims", "--trials", "9"], True),  # by default, every core (two or more)
        (["run", "--workers=3", "--backend", "local"], True),
        (["claims", "--workers", "1"], False),
        (["claims", "--device", "cpu"], False),  # one worker on a device by default
        (["claims", "--workers", "2", "--backend", "ray"], False),
        (["claims", "--workers", "2", "--help"], False),
        (["claims", "--workers", "two"], False),
    ]:
        calls.clear()
        monkeypatch.setattr(cli.os, "cpu_count", lambda: 2)
        cli._start_workers_early(argv)
        assert calls == ([("fork", False)] if starts else []), argv
    assert capsys.readouterr().err == ""  # the first reading says nothing


def test_the_commands_that_run_tasks_are_those_with_a_backend():
    import argparse

    from benchmarks import cli

    for entry in cli.COMMANDS.values():
        parser = argparse.ArgumentParser()
        entry.load().add_arguments(parser)
        options = {option for action in parser._actions for option in action.option_strings}
        assert entry.runs_tasks == ("--backend" in options), entry.name


KEPT = "every task finished is kept in its run's folder: run the same command again to resume"
SEARCH_KEPT = (
    "the search runs again from its start (the same --seed finds the same layouts) and every "
    "scorecard task finished is kept: run the same command again to resume"
)


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["demo"], ""),
        (["claims", "--workers", "1", "--out", "x"], f"; {KEPT}"),
        (["search-layouts", "--workers", "1", "--out", "x"], f"; {SEARCH_KEPT}"),
    ],
)
def test_a_command_stopped_outside_a_runs_tasks_says_what_it_keeps(monkeypatch, capsys, argv, said):
    """Ctrl-C outside a run's tasks (whose own message counts what they saved): a study says that
    its finished tasks are kept and how to resume, the layout search that its search starts over;
    a command that keeps nothing says only that it was interrupted (exit 130)."""
    from benchmarks import cli

    def stopped(self):
        raise KeyboardInterrupt

    command = cli.COMMANDS[argv[0]].load()
    monkeypatch.setattr(command, "main", stopped)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 130
    assert capsys.readouterr().err.splitlines()[-1] == f"mimo-radar-bench: interrupted{said}"


def test_a_process_forked_during_a_command_ends_on_sigterm_as_by_default():
    """A command stops on SIGTERM as on Ctrl-C; a process forked meanwhile with that handler (scipy's
    differential evolution's pool, in search-layouts) ends on its pool's SIGTERM as by default: raising
    KeyboardInterrupt there left a pool worker that its pool waited on forever."""
    import multiprocessing
    import signal

    from benchmarks.cli import _stop_on_sigterm

    terminated: list[int] = []
    previous = _stop_on_sigterm(terminated)
    try:
        child = multiprocessing.get_context("fork").Process(target=time.sleep, args=(60,))
        child.start()
        time.sleep(0.5)
        child.terminate()
        child.join(10)
        assert child.exitcode == -signal.SIGTERM and terminated == []
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)
        assert terminated == [signal.SIGTERM]
    finally:
        signal.signal(signal.SIGTERM, previous)
