"""The study engine: a new study is one module; every run is checked before any is written."""

import json
import sys

import pytest

from benchmarks.cli import COMMANDS, GROUPS, Command, build_parser, main, register_command
from benchmarks.settings import Settings
from benchmarks.study import Run, configure


def test_a_new_study_in_one_module_runs_through_the_command_line(tmp_path, capsys):
    argv = ["--import", "tests.benchmarks.toy_study", "toy", "--out", str(tmp_path / "toy"), "--steps", "20"]
    assert main([*argv, "--workers", "1", "--quiet", "--no-figures"]) == 0
    from tests.benchmarks import toy_study

    assert COMMANDS["toy"].load() is toy_study.ToyStudy and COMMANDS["toy"].group == "studies"
    out = tmp_path / "toy"
    printed = capsys.readouterr().out
    judged = json.loads((out / "toy.json").read_text())
    for name in ("paper-1-v1", "paper-3-v1"):
        summary = json.loads((out / name / "summary.json").read_text())
        assert summary["trials"] == 6 and list(summary["policies"]) == ["best", "random"]
        rows = summary["policies"]
        difference = rows["best"]["final_regret"] - rows["random"]["final_regret"]
        assert judged[name]["estimate"] == pytest.approx(difference, rel=1e-9)
        assert judged[name]["verdict"] == "holds"  # Best's regret is 0, random's is not
        assert f"{name}: best - random regret {judged[name]['estimate']:.1f} holds" in printed
    timing = json.loads((out / "timing.json").read_text())  # timings are artefacts too
    assert timing["study"] == "toy" and timing["wall_s"] > 0 and timing["machine"]["cores"] >= 1
    assert "load_average_1min" in timing["machine"] and "load_average_1min_after" in timing["machine"]


def test_every_run_is_checked_before_any_is_written(tmp_path):
    settings = Settings(out=tmp_path, trials=6, steps=3, workers=1)
    good = Run("a", "paper-1-v1", ("best",), tmp_path / "a")
    bad = Run("b", "paper-1-v1", ("no-such-agent",), tmp_path / "b")
    with pytest.raises(ValueError, match="unknown policy 'no-such-agent'"):
        configure([good, bad], settings)
    with pytest.raises(ValueError, match="lists a run twice"):
        configure([good, good], settings)
    assert list(tmp_path.iterdir()) == []


def test_the_command_line_is_built_from_the_registry():
    parser = build_parser()
    choices = parser._subparsers._group_actions[0].choices  # argparse keeps them there
    assert set(COMMANDS) <= set(choices)
    for name, entry in COMMANDS.items():
        command = choices[name].get_default("command_class")
        assert command is entry.load() and issubclass(command, Command)
        assert command.name == name and entry.group in GROUPS


def test_two_commands_may_not_share_a_name():
    with pytest.raises(ValueError, match="two commands are called 'paper'"):
        register_command("paper", "elsewhere:Another", "another paper")
    with pytest.raises(ValueError, match="group must be one of"):
        register_command("another", "elsewhere:Another", "another", group="extras")


def test_help_and_a_mistyped_command_import_nothing_heavy():
    """``--help`` lists the commands in their groups, and it and a mistyped command name answer
    before numpy, numba, scipy, torch or matplotlib (or any command's module) are imported; a
    command's help and its argument errors before numba, scipy, torch or matplotlib."""
    import subprocess
    import sys

    heavy = ("numpy", "numba", "scipy", "torch", "matplotlib", "mimo_radar_env", "benchmarks.harness")
    code = (
        "import sys\nfrom benchmarks.cli import main\n"
        "try:\n    main(sys.argv[1:])\nexcept SystemExit:\n    pass\n"
        f"print(sorted(m for m in {heavy!r} if m in sys.modules))"
    )
    for argv in (["--help"], ["no-such-command"]):
        result = subprocess.run(
            [sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=60
        )
        assert result.stdout.strip().splitlines()[-1] == "[]", result.stdout + result.stderr
    # a command's own help and its refusals of arguments and policy names come before numba,
    # scipy, torch and matplotlib (the env's compiled kernels load when a run first steps)
    compiled = ("numba", "scipy", "torch", "matplotlib")
    code = code.replace(repr(heavy), repr(compiled))
    run = ["run", "--scenario", "paper-1-v1", "--out", "never-written"]
    for argv, said in (
        (["run", "--help"], ""),
        ([*run, "--policies", "ucb1", "--trials", "abc"], "argument --trials"),
        ([*run, "--policies", "no-such-policy"], "unknown policy 'no-such-policy'"),
    ):
        result = subprocess.run(
            [sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=60
        )
        assert result.stdout.strip().splitlines()[-1] == "[]", result.stdout + result.stderr
        assert said in result.stderr
    listing = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--help"], capture_output=True, text=True, timeout=60
    ).stdout
    positions = [listing.index(f"{group}:\n") for group in GROUPS]
    assert positions == sorted(positions)
    first_steps = listing[positions[0] : positions[1]]
    for name in ("demo", "agents", "paper", "run", "compile", "train-ppo"):
        assert f"  {name} " in first_steps


def test_the_study_written_in_the_docs_runs_as_written(tmp_path):
    """docs/benchmark.md's example study, as a module of its own, through the command line."""
    import subprocess
    import sys
    from pathlib import Path

    text = (Path(__file__).parents[2] / "docs" / "benchmark.md").read_text()
    start = text.index("```python\nfrom benchmarks import verdicts") + len("```python\n")
    (tmp_path / "docs_study.py").write_text(text[start : text.index("```", start)])
    argv = ["best-vs-random", "--out", str(tmp_path / "out"), "--trials", "6", "--steps", "10"]
    argv += ["--quiet", "--no-figures", "--workers", "1"]
    code = (
        f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import docs_study; "
        f"from benchmarks.cli import main; sys.exit(main({argv!r}))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == "Best's regret is below random's: holds"


def test_without_a_shard_size_the_trials_are_split_over_the_workers_and_a_resumed_run_keeps_its_own(
    tmp_path,
):
    from benchmarks.harness import make_config, run
    from benchmarks.resources import MAX_AUTO_SHARD_SIZE, auto_shard_size

    # one policy: the trials split evenly over the tasks at once, capped, never below one
    assert [auto_shard_size(t, w) for t, w in ((500, 2), (20, 2), (7, 2), (3, 8), (10_000, 2))] == [
        250,
        10,
        4,
        1,
        MAX_AUTO_SHARD_SIZE,
    ]
    # several: the fewest shards per policy that make the tasks a multiple of the tasks at once
    cases = {(500, 2, 6): 500, (500, 2, 3): 250, (200, 2, 12): 200, (500, 4, 6): 250, (500, 3, 2): 167}
    assert {case: auto_shard_size(*case) for case in cases} == cases
    for (trials, parallel, policies), size in cases.items():
        assert policies * -(-trials // size) % parallel == 0
    assert auto_shard_size(10_000, 2, 6) == MAX_AUTO_SHARD_SIZE == 500
    quiet = dict(say=lambda message: None)
    six = ["fix1", "fix2", "ucb1", "random", "best", "epsilon-greedy"]
    assert make_config("paper-1-v1", six, trials=9, steps=3, workers=2, **quiet).shard_size == 9
    assert make_config("paper-1-v1", ["fix1"], trials=9, steps=3, workers=2, **quiet).shard_size == 5
    assert make_config("paper-1-v1", ["fix1"], 9, 3, workers=1, parallel=3, **quiet).shard_size == 3
    assert make_config("paper-1-v1", ["fix1"], 9, 3, shard_size=2, workers=2, **quiet).shard_size == 2
    # a run started with one worker is resumed with three: it keeps its shards of 6, not 2
    folder = tmp_path / "a"
    first = configure(
        [Run("a", "paper-1-v1", ("fix1",), folder)], Settings(out=tmp_path, trials=6, steps=3, workers=1)
    )
    assert first[0].shard_size == 6
    run(first[0], folder, progress=False, max_tasks=0)  # writes config.json only
    again = configure(
        [Run("a", "paper-1-v1", ("fix1",), folder)], Settings(out=tmp_path, trials=6, steps=3, workers=3)
    )
    assert again[0].shard_size == 6
    fresh = configure(
        [Run("b", "paper-1-v1", ("fix1",), tmp_path / "b")],
        Settings(out=tmp_path, trials=6, steps=3, workers=3),
    )
    assert fresh[0].shard_size == 2


def test_a_command_whose_module_is_not_installed_says_where_it_runs(monkeypatch, capsys):
    """The wheel leaves the docs' tooling out: its command answers with one line, not a traceback."""
    from benchmarks.cli import CommandEntry

    monkeypatch.setitem(
        COMMANDS,
        "ghost",
        CommandEntry("ghost", "maintenance", "not installed", "benchmarks.no_such_module:Ghost"),
    )
    with pytest.raises(SystemExit) as exit_:
        main(["ghost"])
    assert "'ghost' runs from a source checkout" in str(exit_.value)
    assert "benchmarks.no_such_module is not installed" in str(exit_.value)


def test_every_import_before_the_command_is_imported_and_a_missing_one_is_named(tmp_path, monkeypatch):
    from benchmarks.cli import _leading

    assert _leading(["--import", "a", "--import=b", "--import", "c", "toy", "--out", "x"]) == (
        ["a", "b", "c"],
        "toy",
    )
    (tmp_path / "first_module.py").write_text("LOADED = True\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    argv = ["--import", "first_module", "--import", "tests.benchmarks.toy_study", "toy", "--help"]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 0 and "first_module" in sys.modules and COMMANDS["toy"].group == "studies"
    with pytest.raises(SystemExit, match="--import no_such_module_here: No module named"):
        main(["--import", "no_such_module_here", "demo"])


def test_the_machine_record_counts_physical_cores_apart_from_hardware_threads(tmp_path):
    """Two sockets of two cores with two hardware threads each: eight processors, four cores; a
    cgroup quota of 400 ms per 100 ms is four cores, ``max`` none; no cpuinfo, nothing claimed."""
    from benchmarks.study import _processor

    blocks = [
        f"processor\t: {n}\nmodel name\t: Test CPU\nphysical id\t: {n // 4}\ncore id\t\t: {n % 4 // 2}\n"
        for n in range(8)
    ]
    cpuinfo, quota = tmp_path / "cpuinfo", tmp_path / "cpu.max"
    cpuinfo.write_text("\n".join(blocks))
    quota.write_text("400000 100000\n")
    record = _processor(str(cpuinfo), str(quota))
    assert record["processor"] == "Test CPU" and record["physical_cores"] == 4
    assert record["cpu_quota_cores"] == 4.0
    quota.write_text("max 100000\n")
    assert _processor(str(cpuinfo), str(quota))["cpu_quota_cores"] is None
    assert _processor(str(tmp_path / "none"), str(quota)) == {}


def test_no_interval_is_computed_while_scipy_loads_in_the_studys_thread(tmp_path, monkeypatch):
    """The intervals hold BLAS to one thread through threadpoolctl, which walks the loaded
    libraries under the dynamic loader's lock: beside a thread loading scipy's extensions with the
    GIL held, that deadlocked (a policy whose tasks ended before scipy had loaded hung its run).
    Here scipy's load lasts until an interval is asked for, or 2 s: every interval waits for it."""
    import threading

    from benchmarks import study, uncertainty

    asked, loaded, early = threading.Event(), threading.Event(), []

    def slow_load():
        asked.wait(timeout=2)
        loaded.set()

    real = uncertainty.policy_estimates

    def policy_estimates(*args, **kwargs):
        early.append(not loaded.is_set())
        asked.set()
        return real(*args, **kwargs)

    monkeypatch.setattr(study, "load_statistics", slow_load)
    monkeypatch.setattr(uncertainty, "policy_estimates", policy_estimates)
    argv = ["--import", "tests.benchmarks.toy_study", "toy", "--out", str(tmp_path / "toy"), "--steps", "5"]
    assert main([*argv, "--workers", "1", "--quiet", "--no-figures"]) == 0
    assert early and not any(early)
