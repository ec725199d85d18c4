"""Runs that survive: locks, damaged shards, Ctrl-C, orphans,
strict JSON, PPO files, and results independent of the shard size."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from benchmarks.harness import HarnessError, make_config, output_lock, run
from benchmarks.report import summarize
from benchmarks.shards import policy_folder, shard_path

ROOT = Path(__file__).resolve().parents[2]


def _cli(*args, **kwargs):
    return subprocess.Popen(
        [sys.executable, "-m", "benchmarks", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        **kwargs,
    )


def test_a_second_run_into_the_same_out_is_refused_while_the_first_writes(tmp_path):
    config = make_config("paper-1", ["fix1"], trials=2, steps=5, shard_size=1)
    with output_lock(tmp_path), pytest.raises(HarnessError, match="another run is writing into"):
        run(config, tmp_path, progress=False)
    assert run(config, tmp_path, progress=False) is not None  # the lock is released with its holder
    assert not list(tmp_path.rglob("*.tmp.npz"))


@pytest.mark.parametrize("damage", ["truncate", "garbage", "empty", "copy", "edit"])
def test_damaged_shards_are_named_set_aside_and_recomputed(damage, tmp_path, capsys):
    config = make_config("paper-3", ["ucb1", "epsilon-greedy"], trials=4, steps=10, shard_size=2)
    clean = run(config, tmp_path / "clean", progress=False)
    out = tmp_path / "run"
    run(config, out, progress=False)
    target = shard_path(out, "ucb1", 1)
    if damage == "truncate":
        target.write_bytes(target.read_bytes()[:200])
    elif damage == "garbage":
        target.write_bytes(os.urandom(2000))
    elif damage == "empty":
        target.write_bytes(b"")
    elif damage == "copy":  # another shard copied over this one
        target.write_bytes(shard_path(out, "ucb1", 0).read_bytes())
    else:  # valid archive, altered numbers
        with np.load(target) as data:
            fields = {k: data[k] for k in data.files}
        fields["trial_expected"] = fields["trial_expected"] * 2
        np.savez(target, **fields)
    again = run(config, out, progress=False)
    err = capsys.readouterr()
    assert f"shard {target} is not valid" in err.out + err.err
    assert target.with_name(target.name + ".damaged").exists()
    for policy in config.policies:
        for key in ("trial_expected", "trial_optimal", "trial_squared_error", "trial_matches"):
            np.testing.assert_array_equal(again[policy][key], clean[policy][key])


def test_policy_folders_never_collide_and_model_files_are_part_of_the_configuration():
    assert policy_folder("ppo:R/a_b/model.zip") != policy_folder("ppo:R/a/b_model.zip")
    assert policy_folder("mg-crb-cl") == "mg-crb-cl"


def test_non_finite_metrics_are_errors_and_json_is_strict(tmp_path):
    config = make_config("paper-1", ["fix1"], trials=2, steps=5, shard_size=1)
    totals = run(config, tmp_path, progress=False)
    totals["fix1"]["trial_expected"][0, 2] = np.nan
    with pytest.raises(HarnessError, match=r"policy 'fix1': \w+ is not a finite number"):
        summarize(config, totals)
    summary = (tmp_path / "config.json").read_text()
    assert "NaN" not in summary and "Infinity" not in summary


def test_results_do_not_depend_on_the_shard_size(tmp_path):
    """Randomised policies (BPSO, exploration, Thompson, random) on the same 12 trials."""
    policies = ["mg-crb-cl", "epsilon-greedy", "cts", "random"]
    results = []
    for size in (3, 4, 12):
        config = make_config("paper-3", policies, trials=12, steps=15, shard_size=size)
        results.append(run(config, tmp_path / f"size{size}", progress=False))
    for other in results[1:]:
        for policy in policies:
            for key in ("trial_expected", "trial_matches", "selections", "trial_squared_error"):
                np.testing.assert_allclose(other[policy][key], results[0][policy][key], rtol=1e-12)


def _children(pid):
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    stat = Path(f"/proc/{pid}/stat").read_text() if Path(f"/proc/{pid}/stat").exists() else ""
    return " Z " not in stat  # a zombie has exited


BIG_RUN = ["paper", "--scenario", "3", "--trials", "40", "--steps", "300", "--shard-size", "5"]


@pytest.mark.parametrize(
    ("stop", "code", "said"), [(signal.SIGINT, 130, ""), (signal.SIGTERM, 143, "terminated (SIGTERM), ")]
)
def test_ctrl_c_or_sigterm_stops_within_seconds_keeps_finished_shards_and_says_so(tmp_path, stop, code, said):
    """Ctrl-C, and SIGTERM (a batch scheduler's time limit, which signals the whole group as Ctrl-C does),
    stop the command in one line that says how to resume, the finished shards kept."""
    out = tmp_path / "run"
    process = _cli(*BIG_RUN, "--workers", "2", "--quiet", "--out", str(out), start_new_session=True)
    deadline = time.time() + 120
    while not list(out.rglob("shard_*.npz")) and time.time() < deadline:
        time.sleep(0.2)
    assert list(out.rglob("shard_*.npz")), "no shard was finished"
    os.killpg(process.pid, stop)  # Ctrl-C reaches the whole process group
    start = time.time()
    _, err = process.communicate(timeout=60)
    assert time.time() - start < 10
    assert process.returncode == code
    lines = err.strip().splitlines()
    assert len(lines) == 1 and f"{said}interrupted:" in lines[0] and "resume" in lines[0], err
    kept = len(list(out.rglob("shard_*.npz")))
    resumed = _cli(*BIG_RUN, "--workers", "2", "--quiet", "--no-figures", "--out", str(out))
    out_text, err = resumed.communicate(timeout=600)
    assert resumed.returncode == 0, err
    assert "not valid" not in out_text + err and kept >= 1


def test_an_interrupted_command_exits_within_its_teardown_limit_when_a_thread_never_stops(tmp_path):
    """After Ctrl-C the finished tasks are saved and the message written; a thread (or process)
    that never stops then holds the exit for at most INTERRUPTED_TEARDOWN_S, and says so."""
    from benchmarks.cli import INTERRUPTED_TEARDOWN_S

    (tmp_path / "never_stops.py").write_text(
        "import threading\n"
        "threading.Thread(target=threading.Event().wait, name='never-stops').start()  # not a daemon\n"
    )
    out = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(ROOT)])}
    args = ["--import", "never_stops", *BIG_RUN, "--workers", "2", "--quiet", "--out", str(out)]
    process = _cli(*args, start_new_session=True, env=env)
    deadline = time.time() + 120
    while not list(out.rglob("shard_*.npz")) and time.time() < deadline:
        time.sleep(0.2)
    assert list(out.rglob("shard_*.npz")), "no shard was finished"
    os.killpg(process.pid, signal.SIGINT)
    start = time.time()
    _, err = process.communicate(timeout=60)
    assert INTERRUPTED_TEARDOWN_S <= time.time() - start < INTERRUPTED_TEARDOWN_S + 10
    assert process.returncode == 130
    lines = err.strip().splitlines()
    assert len(lines) == 2 and "interrupted:" in lines[0] and "resume" in lines[0], err
    forced = (
        f"exited {INTERRUPTED_TEARDOWN_S:g} s after the interrupt, without waiting for what had not stopped"
    )
    assert lines[1] == f"mimo-radar-bench: {forced}"


def test_workers_exit_when_their_parent_is_killed(tmp_path):
    out = tmp_path / "run"
    process = _cli(*BIG_RUN, "--workers", "2", "--quiet", "--out", str(out))
    deadline = time.time() + 120
    workers = []
    while len(workers) < 2 and time.time() < deadline:  # forked by the fork server, a child of the command
        workers = [w for child in _children(process.pid) for w in _children(child)]
        time.sleep(0.2)
    assert len(workers) == 2, "no worker process started"
    helpers = _children(process.pid)  # the fork server and multiprocessing's resource tracker
    process.kill()
    process.wait()
    deadline = time.time() + 10
    while any(_alive(p) for p in workers + helpers) and time.time() < deadline:
        time.sleep(0.2)
    assert not any(_alive(p) for p in workers + helpers)


def test_ppo_files_run_no_code(tmp_path):
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra")
    import base64
    import pickle
    import zipfile

    from agents import PPOAgent
    from benchmarks.training import train_ppo

    folder = tmp_path / "ppo"
    train_ppo("paper-1", 256, folder, seed=0, progress=False)
    marker = tmp_path / "pwned"

    class Payload:
        def __reduce__(self):
            return (Path.touch, (marker,))

    # a pickled payload in the model's data, where SB3 keeps cloudpickled entries
    model = folder / "model.zip"
    with zipfile.ZipFile(model) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    data = json.loads(members["data"])
    data["lr_schedule"] = {
        ":type:": "<class 'function'>",
        ":serialized:": base64.b64encode(pickle.dumps(Payload())).decode(),
    }
    members["data"] = json.dumps(data).encode()
    with zipfile.ZipFile(model, "w") as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    agent = PPOAgent("paper-1", model)
    assert agent.normalization is not None and not marker.exists()
    # a pickle beside the model is not loaded unless asked; without the npz the agent refuses clearly
    (folder / "vecnormalize.npz").unlink()
    (folder / "vecnormalize.pkl").write_bytes(pickle.dumps(Payload()))
    with pytest.raises(ValueError, match="normalisation as a pickle, which is not loaded unless asked"):
        PPOAgent("paper-1", model)
    assert not marker.exists()
    # asked, it is unpickled, with a warning: which is why the flag exists
    with pytest.warns(UserWarning, match="a pickle runs code from the file"):
        with pytest.raises(ValueError, match="is not a VecNormalize file SB3 can load"):
            PPOAgent("paper-1", model, allow_pickle=True)
    assert marker.exists()


def test_a_changed_model_file_is_a_different_run(tmp_path):
    pytest.importorskip("stable_baselines3", reason="PPO needs the rl extra")
    from benchmarks.training import train_ppo

    folder = tmp_path / "ppo"
    train_ppo("paper-1", 256, folder, seed=0, progress=False)
    policy = f"ppo:{folder / 'model.zip'}"
    config = make_config("paper-1", [policy], trials=1, steps=3)
    assert set(config.policy_files[policy]) == {str(folder / "model.zip"), str(folder / "vecnormalize.npz")}
    run(config, tmp_path / "out", progress=False)
    train_ppo("paper-1", 256, folder, seed=1, progress=False, overwrite=True)  # another model, same path
    changed = make_config("paper-1", [policy], trials=1, steps=3)
    with pytest.raises(HarnessError, match=r"differs in \['policy_files'\]"):
        run(changed, tmp_path / "out", progress=False)


def test_a_full_disk_is_one_line_and_a_rerun_resumes(tmp_path, monkeypatch, capsys):
    import errno

    import benchmarks.shards
    from benchmarks.cli import main

    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1,random", "--trials", "2", "--steps", "2"]
    argv += ["--shard-size", "1", "--workers", "1", "--quiet", "--no-figures", "--out", str(tmp_path / "run")]
    real_savez, calls = np.savez, []

    def full_after_one(file, **payload):
        calls.append(1)
        if len(calls) > 1:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_savez(file, **payload)

    monkeypatch.setattr(benchmarks.shards.np, "savez", full_after_one)
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write the shard" in err[0] and "No space left on device" in err[0]
    assert len(list((tmp_path / "run").glob("shards/*/*.npz"))) == 1  # the one written is kept
    assert not list((tmp_path / "run").glob("shards/*/*.tmp.npz"))  # no half-written file
    monkeypatch.setattr(benchmarks.shards.np, "savez", real_savez)
    assert main(argv) == 0
    assert "resumed: 1 of 4 tasks already done" in capsys.readouterr().err


def _damage(folder: Path, how: str) -> None:
    if how == "config-shape":
        (folder / "config.json").write_text("[1, 2]")
    elif how == "config-bytes":
        (folder / "config.json").write_bytes(bytes(range(128, 228)))
    elif how == "config-cut":
        (folder / "config.json").write_text("{")
    elif how == "summary-folder":
        (folder / "summary.json").unlink()
        (folder / "summary.json").mkdir()
    elif how == "table-folder":
        (folder / "table.md").unlink()
        (folder / "table.md").mkdir()


@pytest.mark.parametrize(
    ("how", "message"),
    [
        ("config-shape", "config.json is not a run's configuration"),
        ("config-bytes", "config.json is not a run's configuration (not JSON: 'utf-8' codec"),
        ("config-cut", "config.json is not a run's configuration (not JSON: Expecting property name"),
        ("summary-folder", "summary.json should be a file of a run"),
        ("table-folder", "table.md should be a file of a run"),
    ],
)
def test_a_damaged_run_folder_started_again_is_one_line_and_keeps_its_shards(tmp_path, capsys, how, message):
    from benchmarks.cli import main

    out = tmp_path / "run"
    argv = ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "2", "--steps", "2"]
    argv += ["--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    shards = sorted(p.read_bytes() for p in out.glob("shards/*/*.npz"))
    _damage(out, how)
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert sorted(p.read_bytes() for p in out.glob("shards/*/*.npz")) == shards  # nothing lost
