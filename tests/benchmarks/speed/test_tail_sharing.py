"""The tail-sharing benchmark (``benchmarks/speed/tail_sharing.py``): its other command is the
command line with the tail's sharing switched off, and nothing else."""


def test_the_tail_benchmarks_other_command_runs_the_cli_with_the_tails_sharing_switched_off(monkeypatch):
    from benchmarks import backends, cli
    from benchmarks.speed import tail_sharing

    seen = []

    def main(argv):
        seen.append(argv)
        budget = [0, 0]
        backends.share_idle_cores(budget, [1], 2, 1)  # one task left of two: it would get both cores
        return budget[1]

    monkeypatch.setattr(cli, "main", main)
    assert tail_sharing.without_sharing(["claims", "--workers", "2"]) == 0  # not raised
    assert seen == [["claims", "--workers", "2"]]
    budget = [0, 0]
    backends.share_idle_cores(budget, [1], 2, 1)  # as shipped again afterwards
    assert budget == [0, 2]
    python, extra = tail_sharing.VARIANTS["not shared"]
    assert python[0] == "-c" and "without_sharing(sys.argv[1:])" in python[1] and extra == ()
    assert tail_sharing.VARIANTS["shared"] == (("-m", "benchmarks"), ())
