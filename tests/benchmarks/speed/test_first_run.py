"""The first-run benchmark: a run from an empty cache writes the numba cache, and bad repeats are
refused."""

import pytest


@pytest.mark.slow
def test_a_first_run_from_an_empty_cache_writes_the_numba_cache(tmp_path):
    from benchmarks.speed import first_run

    args = ("paper", "--scenario", "1", "--trials", "2", "--steps", "2", "--quiet", "--no-figures")
    seconds = first_run.timed_run(tmp_path / "out", tmp_path / "cache", args)
    assert seconds > 0 and (tmp_path / "out" / "summary.json").is_file()
    # the kernels the run called are cached for the next run: BPSO's one-thread kernel among them
    assert any(
        p.name.startswith("_bpso_kernels.run_numba_serial") for p in (tmp_path / "cache").rglob("*.nbi")
    )


def test_first_run_refuses_no_repeats(capsys):
    from benchmarks.speed import first_run

    with pytest.raises(SystemExit):
        first_run.main(["--repeats", "0"])
    assert "argument --repeats: must be an integer >= 1, got 0" in capsys.readouterr().err
