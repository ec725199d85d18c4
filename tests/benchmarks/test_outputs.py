"""Where a command writes: its output folder and its JSON files, refused as the arguments are
parsed."""

import argparse
import json
import subprocess
import sys

import pytest

from benchmarks.outputs import folder, output_file, write_json


def test_an_output_file_is_named_and_is_neither_a_folder_nor_under_a_file(tmp_path):
    (tmp_path / "a file").write_text("")
    for text, message in (
        ("", "must name a file, got ''"),
        (str(tmp_path), f"must be a file, and {str(tmp_path)!r} is a folder"),
        (str(tmp_path / "a file" / "x.json"), f"is under the file {tmp_path / 'a file'}"),
    ):
        with pytest.raises(argparse.ArgumentTypeError, match=message.replace("(", r"\(").replace(")", r"\)")):
            output_file(text)
    assert output_file(str(tmp_path / "new" / "x.json")) == tmp_path / "new" / "x.json"
    assert not (tmp_path / "new").exists()  # checked, not made


def test_a_folder_is_named_and_is_not_a_file(tmp_path):
    (tmp_path / "a file").write_text("")
    with pytest.raises(argparse.ArgumentTypeError, match="must name a folder"):
        folder(" ")
    with pytest.raises(argparse.ArgumentTypeError, match="is under the file"):
        folder(str(tmp_path / "a file" / "run"))
    assert folder(str(tmp_path / "new" / "run")) == str(tmp_path / "new" / "run")


def test_write_json_makes_the_folders_and_keeps_the_format_it_is_given(tmp_path):
    record = {"a": [1, 2.5], "b": "c"}
    write_json(tmp_path / "x" / "y" / "r.json", record)
    assert (tmp_path / "x" / "y" / "r.json").read_text() == json.dumps(record, indent=2) + "\n"
    write_json(tmp_path / "s.json", record, indent=1, end="")
    assert (tmp_path / "s.json").read_text() == json.dumps(record, indent=1)
    write_json(None, record)  # nothing to write


def test_a_coverage_run_refuses_an_output_it_could_not_write_before_it_draws_anything(tmp_path):
    """python -m benchmarks.uncertainty: an output under a file, or --counts without --run, is one
    line of argparse's, at once (not a traceback after the runs were drawn)."""
    (tmp_path / "a file").write_text("")
    for args, message in (
        ([str(tmp_path / "a file" / "out.json")], "argument out: must be a file"),
        (["--counts", "10"], "--counts and --repeats are the drawn runs' and need --run"),
    ):
        done = subprocess.run(
            [sys.executable, "-m", "benchmarks.uncertainty", *args],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert done.returncode == 2 and message in done.stderr.strip().splitlines()[-1], done.stderr
