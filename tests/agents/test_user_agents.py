"""A user's agent in the benchmark without editing the project: docs/agents.md's example, run
through its three routes (module:Class, an installed entry point, the Python call), each with
two worker processes, giving the same numbers."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import agents
from benchmarks.errors import HarnessError
from benchmarks.harness import policy_name

DOCS = Path(__file__).resolve().parents[2] / "docs" / "agents.md"
SECTION = DOCS.read_text().split("## Write your own agent")[1]
EXAMPLE = re.search(r"```python\n(.*?)```", SECTION, re.DOTALL).group(1)
RUN = [
    "--scenario",
    "paper-1-v1",
    "--trials",
    "4",
    "--steps",
    "5",
    "--workers",
    "2",
    "--quiet",
    "--no-figures",
]


def _python(code_or_args: list[str], site: Path, cwd: Path) -> str:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")])}
    result = subprocess.run([sys.executable, *code_or_args], cwd=cwd, env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-3000:]
    return result.stdout


def _armse(folder: Path, label: str) -> dict:
    return json.loads((folder / "summary.json").read_text())["policies"][label]["armse"]


def test_the_docs_example_runs_by_module_class_entry_point_and_python_call(tmp_path):
    site = tmp_path / "site"
    site.mkdir()
    (site / "myagents.py").write_text(EXAMPLE)
    # an installed package listing the agent in the entry-point group
    dist = site / "myagents-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: myagents\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(
        '[mimo_radar_env.agents]\nexploit = "myagents:Exploit"\n'.replace('"', "")
    )

    by_module = tmp_path / "module"
    _python(
        ["-m", "benchmarks", "run", *RUN, "--policies", "myagents:Exploit,ucb1", "--out", str(by_module)],
        site,
        tmp_path,
    )
    by_name = tmp_path / "entry-point"
    _python(
        ["-m", "benchmarks", "run", *RUN, "--policies", "exploit,ucb1", "--out", str(by_name)], site, tmp_path
    )
    listed = _python(["-m", "benchmarks", "agents"], site, tmp_path)
    assert "exploit" in listed
    by_call = tmp_path / "python"
    code = (
        "import benchmarks\nfrom myagents import Exploit\n"
        "result = benchmarks.run('paper-1-v1', [Exploit, 'ucb1'], trials=4, steps=5, workers=2,"
        f" out={str(by_call)!r}, progress=False)\n"
        "print(sorted(result['policies']), result['table'].splitlines()[0])\n"
    )
    printed = _python(["-c", code], site, tmp_path)
    assert "['myagents:Exploit', 'ucb1']" in printed
    reference = _armse(by_module, "myagents:Exploit")
    assert _armse(by_name, "exploit") == reference == _armse(by_call, "myagents:Exploit")
    assert _armse(by_module, "ucb1") == _armse(by_call, "ucb1")
    # the call resumes in its folder: nothing left to run, the same numbers
    printed_again = _python(["-c", code], site, tmp_path)
    assert printed_again == printed


def test_the_command_finds_a_users_module_in_the_current_folder_as_the_docs_say(tmp_path):
    """docs/agents.md: the module of ``module:Class`` may be in the current folder. The installed
    command (not ``python -m``, which puts that folder on the path itself) finds it there, and so
    do its two worker processes."""
    command = Path(sys.executable).parent / "mimo-radar-bench"
    if not command.exists():
        pytest.skip("the mimo-radar-bench command is not installed beside this Python")
    (tmp_path / "myagents.py").write_text(EXAMPLE)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    result = subprocess.run(
        [str(command), "run", *RUN, "--shard-size", "2", "--policies", "myagents:Exploit", "--out", "o"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "myagents:Exploit" in json.loads((tmp_path / "o" / "summary.json").read_text())["policies"]


def test_a_policy_reference_that_does_not_name_an_agent_is_refused_by_name(tmp_path, monkeypatch):
    (tmp_path / "notagents.py").write_text("class Thing:\n    pass\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(
        ValueError, match=r"'notagents:Thing' is <class 'notagents.Thing'>, not a subclass of agents"
    ):
        agents.split_policy("notagents:Thing")
    with pytest.raises(ValueError, match=r"cannot import module 'nosuchmodule'"):
        agents.split_policy("nosuchmodule:Agent")
    with pytest.raises(ValueError, match=r"module 'notagents' has no 'Missing'"):
        agents.split_policy("notagents:Missing")
    assert agents.split_policy("ppo:runs/a/model.zip") == ("ppo", {"path": "runs/a/model.zip"})


def test_a_class_from_main_needs_one_worker():
    class Local(agents.UCB1):
        pass

    Local.__module__ = "__main__"
    with pytest.raises(HarnessError, match="defined in __main__, which worker processes cannot import"):
        policy_name(Local, workers=2)
    assert policy_name(Local, workers=1) == f"__main__:{Local.__qualname__}"
    assert agents.agent_class(f"__main__:{Local.__qualname__}") is Local


def test_a_users_agent_that_declares_env_option_params_without_their_attributes_is_named():
    """The rollout compares such parameters with the env's options; a declaration without the
    attributes was an AttributeError from inside the rollout."""
    import numpy as np

    from agents.costs import Needs

    class Declares(agents.IndexPolicy):
        needs = Needs(env_option_params=("fusion",))

        def compute_index(self, predicted, obs):
            return np.zeros((predicted.shape[0], self.num_tx, self.num_rx))

    agent = Declares("paper-1-v1")
    with pytest.raises(TypeError, match=r"Declares declares env_option_params \['fusion'\] but has no such"):
        agents.Rollout(agent, agents.make_env(agent, 2))
    agent.fusion = "average"
    assert agents.Rollout(agent, agents.make_env(agent, 2)).t == 0
