"""The demo: random against the oracle on a short episode."""

from benchmarks.cli import main


def test_the_demo_runs_random_against_the_oracle(capsys):
    assert main(["demo", "--steps", "5"]) == 0
    rows = capsys.readouterr().out.splitlines()[2:]
    assert [row.split()[0] for row in rows] == ["random", "best"]
    assert rows[1].startswith("best (oracle)") and float(rows[1].split()[-2]) == 0.0  # its regret
