"""The command registry: the agents listing, and bad arguments answered in one line before anything runs."""

import pytest

from benchmarks.cli import main


def test_the_agents_command_lists_every_policy_in_plain_text(capsys):
    assert main(["agents"]) == 0
    listing = capsys.readouterr().out
    assert "mg-crb-cl" in listing and "alpha_bar=0.2" in listing and "epsilon=0.1" in listing
    assert "tx (required)" in listing and "solver='bpso'" in listing  # MG-CRB-CL's own solver
    assert "``" not in listing and ":class:" not in listing  # plain text, no reST
    # every summary is a whole paragraph: what ends an agent's entry ends a sentence
    import agents

    shipped = [n for n in agents.available_agents() if agents.agent_class(n).__module__.startswith("agents.")]
    for name in shipped:
        assert agents.agent_summary(name).endswith((".", ")", "]")), name


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "--scenario", "paper-9", "--policies", "ucb1"], "unknown scenario 'paper-9'"),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb2"],
            "unknown policy 'ucb2'; available policies are",
        ),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--agent-param", "ucb1.gamma=2"],
            r"unknown parameter\(s\) \['gamma'\] for agent 'ucb1'; allowed:",
        ),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--agent-param", "ucb1gamma"],
            "must look like agent.key=value",
        ),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--steps", "5000"],
            "--steps must be between 1 and",
        ),
        (
            ["run", "--scenario", "paper-1-v1", "--policies", "ucb1", "--trials", "0"],
            "--trials: must be an integer >= 1, got 0",
        ),
        (["run", "--scenario", "paper-1-v1", "--policies", "ppo:/nonexistent.zip"], "does not exist"),
    ],
)
def test_bad_arguments_give_their_errors(argv, message, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(tmp_path / "x"), "--quiet"])
    assert exit_info.value.code == 2
    import re

    assert re.search(message, capsys.readouterr().err)
