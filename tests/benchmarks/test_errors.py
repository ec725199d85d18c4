"""The harness's errors name Python arguments; the command line shows them as its flags."""

import pytest

from benchmarks.cli import main
from benchmarks.errors import FLAGS, BenchError, HarnessError
from benchmarks.harness import make_config


def test_a_harness_error_names_arguments_in_python_and_flags_on_the_command_line():
    error = HarnessError("`trials` must be at least 1 and `shard_size` at most `trials`; `unknown` too")
    assert str(error) == "trials must be at least 1 and shard_size at most trials; unknown too"
    assert (
        error.for_command_line()
        == "--trials must be at least 1 and --shard-size at most --trials; unknown too"
    )
    assert isinstance(error, BenchError) and isinstance(error, ValueError)
    assert all(
        flag == "--" + name.replace("_", "-") for name, flag in FLAGS.items() if name != "agent_params"
    )


def test_the_api_raises_in_its_words_and_the_cli_exits_2_in_its_flags(tmp_path, capsys):
    with pytest.raises(HarnessError) as error:
        make_config("paper-1", ["random"], trials=0)
    assert str(error.value).startswith("trials ")
    with pytest.raises(SystemExit) as exit_info:
        main(
            [
                "run",
                "--scenario",
                "paper-1",
                "--policies",
                "random",
                "--trials",
                "0",
                "--out",
                str(tmp_path / "o"),
            ]
        )
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--trials" in err
    assert not any(tmp_path.iterdir())
