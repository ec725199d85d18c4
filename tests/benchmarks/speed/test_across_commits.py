"""A figure compared across two commits of a repository, each checked out in a worktree."""

import json
import sys

import pytest


def test_a_figure_is_compared_across_two_commits_of_a_repository(tmp_path):
    """Two commits of a small repository whose benchmark prints a known number: the comparison
    checks each out, runs it there and takes the number from its JSON line."""
    import subprocess

    from benchmarks.speed import across_commits

    repo = tmp_path / "repo"
    repo.mkdir()

    def git(*args):
        subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)

    git("init", "-q")
    commits = []
    for value in (6.0, 2.0):
        (repo / "bench.py").write_text(
            f"import json\nprint('warming up')\nprint(json.dumps({{'ms': {value}}}))\n"
        )
        git("add", "bench.py")
        git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", f"ms {value}")
        commits.append(
            subprocess.run(
                ["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True, text=True
            ).stdout.strip()
        )
    out = tmp_path / "compare.json"
    argv = [commits[0], commits[1], "--key", "ms", "--repeats", "2", "--repo", str(repo), "--json", str(out)]
    result = across_commits.main([*argv, "--", sys.executable, "bench.py"])
    assert result["values"] == {commits[0]: [6.0, 6.0], commits[1]: [2.0, 2.0]}
    assert result["ratio"] == pytest.approx(3.0)
    assert json.loads(out.read_text())["ratio"] == pytest.approx(3.0)
    assert (
        subprocess.run(
            ["git", "-C", str(repo), "worktree", "list"], capture_output=True, text=True
        ).stdout.count("\n")
        == 1
    )
    with pytest.raises(RuntimeError, match="did not end with a JSON object holding 'nope'"):
        across_commits.compare(repo, (commits[0], commits[1]), [sys.executable, "bench.py"], "nope", 1)


def test_warm_up_runs_are_run_first_and_not_recorded(tmp_path):
    """A benchmark slow on its first run in a checkout (as numba compiles into a new checkout's
    cache): with ``warmup=1`` each commit's first run is left out of its figures."""
    import subprocess

    from benchmarks.speed import across_commits

    repo = tmp_path / "repo"
    repo.mkdir()
    (repo / "bench.py").write_text(
        "import json, pathlib\n"
        "runs = pathlib.Path('runs')\n"
        "count = int(runs.read_text()) + 1 if runs.exists() else 1\n"
        "runs.write_text(str(count))\n"
        "print(json.dumps({'s': 100.0 if count == 1 else float(count)}))\n"
    )
    for args in (
        ("init", "-q"),
        ("add", "bench.py"),
        ("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "b"),
    ):
        subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)
    result = across_commits.compare(repo, ("HEAD", "HEAD~0"), [sys.executable, "bench.py"], "s", 2, warmup=1)
    assert result["values"] == {"HEAD": [2.0, 3.0], "HEAD~0": [2.0, 3.0]}
    assert result["warmup"] == 1
    with pytest.raises(SystemExit):
        across_commits.main(["HEAD", "--key", "s", "--warmup", "-1", "--", sys.executable, "bench.py"])
