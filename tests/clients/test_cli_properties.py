"""No traceback reaches a user of the command line: hostile values in any argument of any
subcommand, in agent parameters and in hyperparameter files give success, or one line on
stderr with exit code 2 and nothing written (hypothesis)."""

import contextlib
import io
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmarks.cli import main

HOSTILE = [
    "-1", "0", "1", "2", "2.5", "1e309", "nan", "inf", "-inf", "", " ", "x", "\u00e9\u6f22\U0001f4a5",
    "99999999999999999999", "/dev/null", "..", "{", "[1,2", "a=b", "null", "true", "1,1", "paper-9", "9",
    "paper-1,paper-1", "average,average", "ucb1,ucb1", "-", "--", "{a: [1, 2}", "ppo:/etc", ".inf", ".nan",
    "-.inf", "1e308", "1.0e308", "{population: .nan}", "{iterations: 1.0e9}", "[]", "{}",
]  # fmt: skip
# small integers only: a large valid count (a million trials) is a legitimate, long run
VALUES = st.one_of(st.sampled_from(HOSTILE), st.text(min_size=0, max_size=12), st.integers(-5, 5).map(str))

#: Per command: arguments that make a quick valid invocation, and the flags hostile values go to.
COMMANDS = {
    "run": (
        ["--scenario", "paper-1-v1", "--policies", "random", "--trials", "2", "--steps", "2",
         "--workers", "1"],
        ["--scenario", "--policies", "--trials", "--steps", "--seed", "--shard-size", "--workers",
         "--fusion", "--lambda-scale", "--truth", "--env-version", "--invalid-action", "--horizon"],
    ),
    "paper": (
        ["--scenario", "1", "--trials", "2", "--steps", "2", "--workers", "1"],
        ["--scenario", "--trials", "--seed", "--env-version", "--fusion"],
    ),
    "demo": (["--steps", "3"], ["--scenario", "--seed", "--steps", "--fusion", "--env-version"]),
    "model-figures": (["--only", "bpso-set-optimal"], ["--only"]),
    "docs": (["--check"], ["--docs"]),
    "compile": ([], ["--workers"]),
}  # fmt: skip
#: The studies, the comparison of scorecards and the perf suite (each valid invocation takes
#: seconds); ``None`` sends the hostile value as a positional argument.
SCORECARD = str(Path(__file__).parents[2] / "docs" / "results" / "claims" / "v1-centralized.json")
STUDY_COMMANDS = {
    "claims": (
        ["--scenarios", "1", "--trials", "6", "--steps", "2", "--workers", "1"],
        ["--scenarios", "--trials", "--steps", "--seed", "--env-version", "--fusion", "--shard-size",
         "--max-hours", "--agent-param", "--backend"],
    ),
    "tracking": (
        ["--scenarios", "1", "--fusions", "average", "--trials", "6", "--steps", "2", "--workers", "1"],
        ["--scenarios", "--fusions", "--ppo", "--trials", "--steps", "--max-hours", "--env-version"],
    ),
    "calibrate-layout": (
        ["--candidates", "2", "--screen", "1", "--screen-trials", "6", "--final", "1", "--trials", "6",
         "--steps", "2", "--workers", "1"],
        ["--candidates", "--screen", "--screen-trials", "--final", "--trials", "--steps"],
    ),
    "planning": (
        ["--scenarios", "1", "--fusions", "centralized", "--trials", "6", "--steps", "3", "--workers", "1"],
        ["--scenarios", "--fusions", "--ppo", "--trials", "--steps", "--max-hours"],
    ),
    "compare-claims": ([f"a={SCORECARD}"], [None]),
    "perf": (["--quick", "--workers", "1"], ["--workers", None]),
    "agents": ([], [None]),
}  # fmt: skip
COMMANDS.update(STUDY_COMMANDS)
STUDIES_OUT = ("run", "paper", "claims", "tracking", "calibrate-layout", "planning")
AGENT_PARAMS = [
    "mg-crb-cl.alpha",
    "mg-crb-cl.beta",
    "mg-crb-cl.solver",
    "mg-crb-cl.solver_params",
    "ucb1.beta",
]


def _invoke(argv: list[str], out: Path) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 2
    return code, err.getvalue()


def _check(argv: list[str], out: Path) -> None:
    code, err = _invoke(argv, out)
    lines = [line for line in err.strip().splitlines() if line.strip()]
    assert code in (0, 2), (argv, code, err[-2000:])
    if code == 2:
        refusals = [line for line in lines if line.startswith("mimo-radar-bench") and "error" in line]
        assert len(refusals) == 1, (argv, err[-2000:])
        assert "Traceback" not in err, (argv, err[-2000:])
        assert not out.exists() or argv[0] in ("docs", "model-figures"), (argv, "wrote before refusing")


@st.composite
def invocations(draw, commands=tuple(COMMANDS)):
    command = draw(st.sampled_from(commands))
    base, flags = COMMANDS[command]
    flag = draw(st.sampled_from(flags))
    argv = [command, *base]
    value = draw(VALUES)
    if flag is None:  # a positional argument, or a LABEL=PATH of compare-claims
        return [*argv, draw(st.sampled_from([value, f"b={value}"]))]
    if flag in argv:
        i = argv.index(flag)
        argv = argv[:i] + argv[i + 2 :]
    return [*argv, flag, value]


def _with_out(argv: list[str], folder: Path) -> tuple[list[str], Path]:
    out = folder / "out"
    if argv[0] in STUDIES_OUT:
        return [*argv, "--out", str(out), "--quiet", "--no-figures"], out
    if argv[0] in ("model-figures", "perf"):
        return [*argv, "--out", str(out)], out
    if argv[0] == "docs" and "--docs" not in argv:
        return [*argv, "--docs", str(out)], out
    return argv, out


def _run_example(argv: list[str]) -> None:
    folder = Path(tempfile.mkdtemp())
    try:
        argv, out = _with_out(argv, folder)
        _check(argv, out)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(invocations(commands=tuple(c for c in COMMANDS if c not in STUDY_COMMANDS)))
def test_hostile_arguments_give_success_or_one_line(argv):
    _run_example(argv)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(invocations(commands=tuple(STUDY_COMMANDS)))
def test_hostile_arguments_to_studies_and_tools_give_success_or_one_line(argv):
    _run_example(argv)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(st.sampled_from(AGENT_PARAMS), VALUES)
def test_hostile_agent_parameters_give_success_or_one_line(name, value):
    policy = name.split(".")[0]
    argv = ["run", "--scenario", "paper-1-v1", "--policies", policy, "--trials", "2", "--steps", "2"]
    _run_example([*argv, "--workers", "1", "--agent-param", f"{name}={value}"])


HYPERPARAMS = {
    "n_envs": st.one_of(st.integers(-3, 3), st.sampled_from(["x", "2.5", "1e9"])),
    "n_steps": st.one_of(st.integers(-3, 40), st.sampled_from(["x", "null"])),
    "batch_size": st.one_of(st.integers(-3, 100), st.sampled_from(["[1]", "{}"])),
    "learning_rate": st.one_of(
        st.floats(allow_nan=True, allow_infinity=True), st.sampled_from(["lin_3e-4", "x"])
    ),
    "gamma": st.one_of(st.floats(-2, 2), st.just("nan")),
    "normalize": st.sampled_from(["true", "false", "x", "'dict(a=1)'", "'dict(norm_obs=True'", "[1]"]),
    "policy": st.sampled_from(["MlpPolicy", "CnnPolicy", "1", "null"]),
    "policy_kwargs": st.sampled_from(
        ["'dict(net_arch=[8])'", "'dict(net_arch=[0])'", "'x'", "'dict(net_arch=[8], a=b)'"]
    ),
    "nonsense": st.sampled_from(["1"]),
}


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(
    st.dictionaries(st.sampled_from(sorted(HYPERPARAMS)), st.just(None), min_size=1, max_size=3), st.data()
)
def test_hostile_hyperparameter_files_give_success_or_one_line(keys, data):
    pytest.importorskip("stable_baselines3", reason="train-ppo needs the rl extra")
    lines = ["MimoRadarSelectFlat-v1:", "  n_envs: 1", "  n_steps: 16", "  batch_size: 16", "  n_epochs: 1"]
    for key in keys:
        lines = [line for line in lines if not line.startswith(f"  {key}:")]
        lines.append(f"  {key}: {data.draw(HYPERPARAMS[key])}")
    folder = Path(tempfile.mkdtemp())
    try:
        (folder / "hp.yml").write_text("\n".join(lines) + "\n")
        argv = ["train-ppo", "--scenario", "paper-1-v1", "--timesteps", "16", "--quiet"]
        _check([*argv, "--hyperparams", str(folder / "hp.yml"), "--out", str(folder / "out")], folder / "out")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(invocations())
def test_hostile_arguments_give_success_or_one_line_many(argv):
    _run_example(argv)


def _damage(out: Path, how: str) -> None:
    """One damaged state of a run's output folder (issue: hostile file-system states)."""
    if how == "out-a-file":
        out.write_text("not a folder")
        return
    out.mkdir(exist_ok=True)
    target = {
        "config-wrong-shape": "config.json",
        "config-not-text": "config.json",
        "config-a-folder": "config.json",
        "summary-a-folder": "summary.json",
        "table-a-folder": "table.md",
        "shards-a-file": "shards",
    }[how]
    path = out / target
    if path.is_dir():
        shutil.rmtree(path)
    elif path.exists():
        path.unlink()
    if how == "config-wrong-shape":
        path.write_text('[1, {"trials": "x"}]')
    elif how == "config-not-text":
        path.write_bytes(b"\xff\xfe\x00\x81 not text")
    elif how in ("config-a-folder", "summary-a-folder", "table-a-folder"):
        path.mkdir()
        (path / "inside").write_text("kept")
    else:
        path.write_text("a file where a folder belongs")


def _snapshot(root: Path) -> dict[str, bytes | None]:
    if root.is_file():
        return {".": root.read_bytes()}
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() else None) for p in root.rglob("*")}


DAMAGES = (
    "config-wrong-shape", "config-not-text", "config-a-folder", "summary-a-folder", "table-a-folder",
    "shards-a-file", "out-a-file",
)  # fmt: skip


@settings(max_examples=14, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(st.sampled_from(DAMAGES), st.booleans())
def test_damaged_output_folders_give_success_or_one_line_and_lose_nothing(how, finished_first):
    """A run started into a damaged folder (of a finished run, or of none) succeeds, or is
    refused in one line with exit 2 and every file already there unchanged."""
    folder = Path(tempfile.mkdtemp())
    try:
        out = folder / "out"
        argv = ["run", "--scenario", "paper-1-v1", "--policies", "random", "--trials", "2", "--steps", "2"]
        argv += ["--workers", "1", "--out", str(out), "--quiet", "--no-figures"]
        if finished_first:
            assert _invoke(argv, out)[0] == 0
            if how == "out-a-file":
                shutil.rmtree(out)
        _damage(out, how)
        before = _snapshot(out)
        code, err = _invoke(argv, out)
        lines = [line for line in err.strip().splitlines() if line.strip()]
        assert code in (0, 2) and "Traceback" not in err, (how, finished_first, code, err[-2000:])
        if code == 2:
            assert len([line for line in lines if "error" in line]) == 1, (how, err)
            assert _snapshot(out) == before, (how, "changed a folder it refused")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
