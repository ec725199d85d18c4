"""Figures: distinct colours, readable labels, every file written."""

from benchmarks import plots
from benchmarks.cli import main


def test_up_to_twenty_policies_get_distinct_colours():
    for count in (1, 6, 10, 13, 20):
        colours = plots.palette(count)
        assert len(colours) == count == len(set(colours))


def test_long_labels_are_elided_in_the_middle():
    label = plots.short_label("ppo:runs/ppo-info/paper-1-average/model.zip")
    assert len(label) == 28 and label.startswith("ppo:runs/p") and label.endswith("model.zip")
    assert plots.short_label("mg-crb-cl") == "mg-crb-cl"


def test_a_run_writes_every_figure(tmp_path):
    argv = ["run", "--scenario", "paper-3-v1", "--policies", "best,random", "--trials", "2"]
    assert main([*argv, "--steps", "5", "--workers", "1", "--quiet", "--out", str(tmp_path)]) == 0
    for name in ("sinr", "regret", "rmse", "geometry", "selection_best", "selection_random"):
        path = tmp_path / f"{name}.png"
        assert path.stat().st_size > 5000, name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
