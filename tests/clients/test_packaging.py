"""Packaging: the wheel carries every file its commands need."""

import re
import subprocess
from pathlib import Path

import pytest

from tests.helpers import readme_demo_table

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_the_wheel_in_a_fresh_venv_runs_demo_and_a_short_train_ppo():
    """Builds the wheel, installs it with the rl extra into a new venv, runs the commands (~1 min)."""
    result = subprocess.run(
        ["bash", str(ROOT / ".ci" / "wheel-check")], capture_output=True, text=True, timeout=1200
    )
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-4000:]
    assert "oracle" in result.stdout and "steps (300 asked, in whole rollouts)" in result.stdout
    assert (
        "wheel check: 'docs', 'claims' and 'perf' say they run from a source checkout, and so does --help"
        in result.stdout
    )
    assert "torchrl: GymEnv('MimoRadarSelectFlat-v1') checked and rolled out" in result.stdout
    assert "torchrl: MimoRadarSelectTorchRLEnv checked and rolled out" in result.stdout
    assert result.stdout.count("torchrl: the docs' recipe clients.md-") == 3


@pytest.mark.slow
def test_the_lowest_declared_versions_run_the_demo_and_their_tests():
    """Every core dependency, numba, the rl extra's learners and torch, Ray and the docs extra at
    pyproject.toml's lower bound, in a new venv (~8 min): the demo, the tests, the docs site."""
    result = subprocess.run(
        ["bash", str(ROOT / ".ci" / "lowest-check")], capture_output=True, text=True, timeout=1800
    )
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-4000:]
    assert readme_demo_table() in result.stdout
    ran = "lowest check: the demo and the env's, agents', trainings' and backends' tests ran on"
    assert ran in result.stdout
    torch_bound = re.search(r'"torch>=([0-9.]+)"', (ROOT / "pyproject.toml").read_text())[1]
    assert f" torch=={torch_bound} " in result.stdout.split(ran)[1].splitlines()[0] + " "
    assert result.stdout.rstrip().endswith(", and the docs site built")


def test_the_hyperparameters_are_package_data():
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert "hyperparams/*.yml" in config["package-data"]["benchmarks"]
    from benchmarks.training import load_hyperparams

    assert load_hyperparams()["policy"] == "MlpPolicy"  # read through importlib.resources


def test_the_wheel_leaves_out_exactly_the_commands_that_run_from_a_checkout():
    """The first steps' modules ship; every study's and maintenance command's module is in a
    package the wheel leaves out (and nothing else is left out)."""
    import tomllib

    from benchmarks.cli import COMMANDS

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    left_out = [pattern.removesuffix("*") for pattern in config["packages"]["find"]["exclude"]]
    assert sorted(left_out) == ["benchmarks.docs_tooling", "benchmarks.speed", "benchmarks.studies"]
    for entry in COMMANDS.values():
        module = entry.target.partition(":")[0]
        if not module.startswith("benchmarks."):
            continue  # a command another test registered (a study of one's own)
        shipped = not any(module == p or module.startswith(p + ".") for p in left_out)
        assert shipped == (entry.group == "first steps"), (entry.name, entry.group, module)


def test_the_cli_names_a_foreign_agents_package(tmp_path):
    """Another distribution's 'agents' first on the path: a one-line error, exit 2."""
    (tmp_path / "agents").mkdir()
    (tmp_path / "agents" / "__init__.py").write_text("")
    code = "import sys; sys.path.insert(0, sys.argv[1]); from benchmarks.cli import main; main(['agents'])"
    result = subprocess.run(
        ["python", "-c", code, str(tmp_path)], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )
    assert result.returncode == 2
    assert "another installed distribution provides agents" in result.stderr
    assert "dedicated virtual environment" in result.stderr


def test_citation_file_cites_the_project_and_the_paper():
    import tomllib

    import yaml

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software" and cff["license"] == "MIT"
    paper = cff["preferred-citation"]
    assert paper["type"] == "article" and paper["title"].startswith("Combinatorial-restless-bandit-based")
    assert [a["family-names"] for a in paper["authors"]] == ["Hao", "Wang", "Fu", "Bai", "Li", "Pan"]
    # the version is written once, in mimo_radar_env/__init__.py: pyproject.toml reads it, the
    # citation file (where a version is optional) does not repeat it
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in cff and "version" not in project["project"]
    assert "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "mimo_radar_env.__version__"}
    from importlib.metadata import version

    import mimo_radar_env

    assert version("mimo-radar-env") == mimo_radar_env.__version__
