"""The value tables and table generators: values from the figures, each artefact read once per
rendering, the reading moves computed column against column."""

import json
import shutil
from pathlib import Path

import pytest

from benchmarks.cli import main

DOCS = Path(__file__).resolve().parents[3] / "docs"


def test_value_spans_are_filled_from_the_figures(tmp_path, capsys):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS, docs, ignore=shutil.ignore_patterns("_build", "*.png"))
    path = docs / "results" / "model" / "figures.json"
    record = json.loads(path.read_text())
    record["figures"]["nees-imm"].update(value=3.5, ci=[3.4, 3.6])
    path.write_text(json.dumps(record))
    assert main(["docs", "--docs", str(docs), "--check"]) == 1
    filled = "+  has <!-- value: model nees-imm -->3.50 [3.40, 3.60]<!-- end value -->"
    assert filled in capsys.readouterr().out
    page = docs / "model.md"
    page.write_text(page.read_text() + "\n<!-- value: model no-such-figure -->1<!-- end value -->\n")
    with pytest.raises(SystemExit) as exit_info:
        main(["docs", "--docs", str(docs)])
    assert exit_info.value.code == 2 and "no figure 'no-such-figure'" in capsys.readouterr().err


def test_a_value_table_is_read_once_per_rendering_and_names_its_keys(tmp_path):
    """A page's sentence quotes a value table's keys; a key the table lacks is named with the
    keys it has, and a value span inside a code span (whose comments Markdown would show) is
    refused."""
    from benchmarks.docs_tooling import generators
    from benchmarks.docs_tooling.pages import render
    from benchmarks.errors import BenchError

    calls = []

    @generators.values("test-table")
    def table(docs):
        calls.append(docs)
        return {"a": "1", "b": "two"}

    try:
        span = "<!-- value: test-table {} -->?<!-- end value -->"
        page = f"A {span.format('a')} and {span.format('b')}."
        assert render(page, tmp_path) == page.replace("?", "1", 1).replace("?", "two", 1)
        assert calls == [tmp_path]
        render(page, tmp_path)
        assert len(calls) == 2  # a new rendering reads the artefacts again
        with pytest.raises(BenchError, match="the values 'test-table' have no 'c'; they have: a, b"):
            render("<!-- value: test-table c -->?<!-- end value -->", tmp_path)
        with pytest.raises(BenchError, match="inside a code span"):
            render("`<!-- value: test-table a -->1<!-- end value -->`", tmp_path)
    finally:
        del generators.VALUE_SOURCES["test-table"]


def test_the_reading_moves_are_each_column_against_the_one_it_modifies(tmp_path):
    """Hand-made scorecards: each change lists exactly the claims whose verdict differs from the
    column it modifies (not from the column beside it), and the claims contradicted everywhere."""
    from benchmarks.docs_tooling import generators

    docs = tmp_path / "docs"
    (docs / "results" / "claims").mkdir(parents=True)
    base = {"S1": "holds", "S2": "contradicted", "A1": "consistent"}
    columns = {
        "v0": base,
        "v0 + dB": base | {"A1": "holds"},
        "v0 + shared truth": base,
        "v0 + set rule": base | {"S1": "consistent", "A1": "contradicted"},
        "v1, section 1 layout": base | {"A1": "holds"},
        "v1": base | {"A1": "holds", "S1": "contradicted"},
        "v1, centralised": base | {"A1": "holds", "S1": "contradicted"},
    }
    for label, path in generators.READINGS.items():
        card = [{"id": claim, "verdict": verdict} for claim, verdict in columns[label].items()]
        (docs / "results" / path).write_text(json.dumps(card))
    table = generators.reading_values(docs)
    assert (table["db.moves"], table["db.holds"], table["db.base-holds"]) == (
        "A1 (consistent to holds)",
        "2",
        "1",
    )
    assert table["shared-truth.moves"] == "no claim"
    assert table["set-rule.moves"] == "S1 (holds to consistent), A1 (consistent to contradicted)"
    assert table["set-rule.holds"] == "0"
    # the section 1 layout is against v0, the calibrated layout against the section 1 layout
    assert table["all-three.moves"] == "A1 (consistent to holds)"
    assert (table["layout.moves"], table["layout.holds"]) == ("S1 (holds to contradicted)", "1")
    assert table["centralized.moves"] == "no claim"
    assert (table["always"], table["always.count"]) == ("S2", "1")


def test_the_float32_table_and_figures_come_from_its_rows_and_float64s_figures_ignore_them(tmp_path):
    """The float32 run's rows give its table and its largest differences (entry by entry, over
    every row); the device figures of float64 skip float32 rows that a device run adds."""
    from benchmarks.docs_tooling import generators

    def row(version, precision, largest, track):
        differences = {
            "obs.track": track,
            "info.true_state": 1e-6,
            "reward": 2e-5,
            "info.position_bound": 3e-6,
            "obs.mode_prob": largest,
            "oracle_action": 0.25,
        }
        return {
            "version": version,
            "fusion": "average",
            "mode": "eager",
            "precision": precision,
            "trials": 64,
            "steps": 1000,
            "largest": largest,
            "largest_entry": "obs.mode_prob",
            "differences": differences,
        }

    perf = tmp_path / "results" / "perf"
    perf.mkdir(parents=True)
    float32 = {
        "machine": "2 cores",
        "device": "cpu",
        "equality": [row("v1", "float32", 3e-3, 4e-5), row("v0", "float32", 2e-2, 9e-5)],
    }
    (perf / "float32.json").write_text(json.dumps(float32))
    table = generators.float32_equality(tmp_path).splitlines()
    assert table[0].count("|") == table[1].count("|") == table[2].count("|") == 9
    assert table[3] == (
        "| MimoRadarSelect-v0 | average | 2.0e-02 | `obs.mode_prob` | 1.0e-06 | 9.0e-05 | 2.0e-05 | "
        "differ in 25 % of trial-steps |"
    )
    device_table = generators._equality_table(float32, tuple(generators.RUN_COLUMNS), {}).splitlines()
    assert device_table[2].startswith(
        "| MimoRadarSelect-v1 | average | eager | float32 | 64 | 1000 | 3.0e-03 |"
    )
    assert generators.float32_value(tmp_path, "largest.obs.track") == "9.0e-05"
    assert generators.float32_value(tmp_path, "largest") == "2.0e-02"
    assert generators.float32_value(tmp_path, "trials") == "64"
    assert generators.float32_value(tmp_path, "steps") == "1,000"
    with pytest.raises(generators.BenchError, match="unknown float32 figure 'largest.obs.nothing'"):
        generators.float32_value(tmp_path, "largest.obs.nothing")
    device = {"equality": [row("v1", "float32", 3e-3, 4e-5), {**row("v1", "float64", 1e-11, 1e-12)}]}
    device["equality"][1].pop("precision")  # a run from before the precisions: float64
    (perf / "device.json").write_text(json.dumps(device))
    assert generators.device_value(tmp_path, "largest-difference") == "1.0e-11"
    # the device's table: trials and steps are columns only where rows differ in them, else values
    assert generators.device_equality(tmp_path).splitlines()[0] == (
        "| env | fusion | form | precision | largest relative difference | in | oracle's actions |"
    )
    assert generators.device_value(tmp_path, "equality-steps") == "1,000"
    device["equality"][1]["steps"] = 50
    (perf / "device.json").write_text(json.dumps(device))
    assert "| steps |" in generators.device_equality(tmp_path).splitlines()[0]
    assert generators.device_value(tmp_path, "equality-trials") == "64"
    with pytest.raises(generators.BenchError, match=r"equality rows differ in equality-steps: \[50, 1000\]"):
        generators.device_value(tmp_path, "equality-steps")


def test_a_device_check_figure_is_read_from_its_record_by_path(tmp_path):
    from benchmarks.docs_tooling import generators

    perf = tmp_path / "results" / "perf"
    perf.mkdir(parents=True)
    checks = {"numpy_seconds": 14, "rl_study": {"trainings": 1300, "note": "read so", "span_s": 35.5}}
    (perf / "device-checks.json").write_text(json.dumps(checks))
    assert generators.device_value(tmp_path, "checks.numpy_seconds") == "14"
    assert generators.device_value(tmp_path, "checks.rl_study.trainings") == "1,300"
    assert generators.device_value(tmp_path, "checks.rl_study.span_s") == "35.5"
    with pytest.raises(generators.BenchError, match=r"no 'rl_study.wall' \('wall'; there: trainings, note"):
        generators.device_value(tmp_path, "checks.rl_study.wall")
    with pytest.raises(generators.BenchError, match=r"no 'numpy_seconds.x' \('x'; there: no fields\)"):
        generators.device_value(tmp_path, "checks.numpy_seconds.x")


def test_trainings_sharing_a_device_are_a_line_of_their_own_and_no_rate_reads_them(tmp_path):
    """The training table gives rows of several trainings at once (``--processes``) a line of
    their own, after the device's one-process line; ``rate`` figures read one-process rows only."""
    from benchmarks.docs_tooling import generators

    def row(trials, rate, processes=None):
        extra = {} if processes is None else {"processes": processes}
        return {"learner": "torch-ppo", "device": "cuda", "trials": trials, "n_steps": 64,
                "env_steps_per_s": rate, "peak_device_memory_gib": None, **extra}  # fmt: skip

    perf = tmp_path / "results" / "perf"
    perf.mkdir(parents=True)
    record = {"scenario": "paper-1-v1", "device_name": "GPU", "rows": [row(512, 1e4), row(512, 3e4, 4)]}
    (perf / "training.json").write_text(json.dumps(record))
    table = generators.ppo_training_rate(tmp_path).splitlines()
    assert table[2:] == [
        "| torch-ppo | GPU (cuda) | 10,000 |",
        "| torch-ppo | GPU (cuda), 4 trainings at once (their steps over their span) | 30,000 |",
    ]
    assert all(line.count("|") == 4 for line in table)
    assert generators.training_value(tmp_path, "rate.torch-ppo.cuda.512") == "10,000"


def test_the_compiled_steps_calls_are_read_at_the_rows_trial_count(tmp_path):
    """``launches compiled.KIND.FUSION`` reads the calls of the step compiled on the CPU at the
    trials of the operation rows, and its compile times; another count, device, kind or fusion
    is refused by name."""
    from benchmarks.docs_tooling import generators

    perf = tmp_path / "results" / "perf"
    perf.mkdir(parents=True)
    rows = [{"policy": "ucb1", "fusion": "average", "trials": 500, "env_step": 1456.0}]
    compiled = [
        {"fusion": "average", "trials": 64, "fused": 9, "library": 9},
        {
            "fusion": "average",
            "trials": 500,
            "fused": 20,
            "library": 26,
            "eager": 1330,
            "compile_s": 49.44,
            "again_s": 2.16,
            "new_process_s": 7.71,
        },  # fmt: skip
        {"fusion": "centralized", "trials": 500, "fused": 90, "library": 30, "device": "cuda"},
    ]
    (perf / "launches.json").write_text(json.dumps({"rows": rows, "compiled": compiled}))
    assert generators.launches_value(tmp_path, "compiled.fused.average") == "20"
    assert generators.launches_value(tmp_path, "compiled.library.average") == "26"
    assert generators.launches_value(tmp_path, "compiled.eager.average") == "1,330"
    assert generators.launches_value(tmp_path, "compiled.compile_s.average") == "49.4"
    assert generators.launches_value(tmp_path, "compiled.again_s.average") == "2.2"
    assert generators.launches_value(tmp_path, "compiled.new_process_s.average") == "7.7"
    for key in ("compiled.fused.centralized", "compiled.loops.average", "compiled.again_s.centralized"):
        with pytest.raises(generators.BenchError, match=r"compiled.\(fused\|library\|eager\|compile_s"):
            generators.launches_value(tmp_path, key)


def test_the_compiled_acts_counts_are_read_at_the_rows_trial_count(tmp_path):
    from benchmarks.docs_tooling import generators

    perf = tmp_path / "results" / "perf"
    perf.mkdir(parents=True)
    rows = [{"policy": "ucb1", "fusion": "average", "trials": 500, "env_step": 1456.0}]
    act = {"trials": 500, "act": 1779, "act_replayed": 563, "compiled_calls": 100, "fused": 1, "library": 0,
           "compile_s": 7.64}  # fmt: skip
    (perf / "launches.json").write_text(json.dumps({"rows": rows, "compiled_act": act}))
    assert generators.launches_value(tmp_path, "compiled-act.act") == "1,779"
    assert generators.launches_value(tmp_path, "compiled-act.compiled_calls") == "100"
    assert generators.launches_value(tmp_path, "compiled-act.compile_s") == "7.6"
    (perf / "launches.json").write_text(json.dumps({"rows": rows, "compiled_act": {**act, "trials": 6}}))
    for key in ("compiled-act.act", "compiled-act.ops"):
        with pytest.raises(generators.BenchError, match=r"compiled-act.FIELD, FIELD one of \('act'"):
            generators.launches_value(tmp_path, key)


def test_the_ray_table_gives_each_backends_serial_parts_where_every_run_recorded_them(tmp_path):
    """The Ray table's wall times, and each backend's mean time before the first task and after
    the last with Ray's minus local's paired by repeat (a t interval computed here with scipy);
    a record without those parts (runs measured before them) keeps the table of wall times."""
    from scipy import stats

    from benchmarks.docs_tooling import generators

    perf = tmp_path / "results" / "perf"
    perf.mkdir(parents=True)
    walls = {"local": [35.0, 36.0, 34.0], "ray": [36.5, 37.0, 36.0]}
    befores = {"local": [1.0, 1.2, 1.1], "ray": [2.0, 2.5, 2.3]}
    runs = [
        {"backend": b, "repeat": r, "wall_s": walls[b][r], "same_numbers": True,
         "before_first_task_s": befores[b][r], "after_last_task_s": 0.5}
        for r in range(3) for b in ("local", "ray")
    ]  # fmt: skip
    (perf / "ray.json").write_text(json.dumps({"study": ["x"], "workers": 2, "runs": runs}))
    lines = generators.ray_backend(tmp_path).splitlines()
    assert lines[0] == (
        "| backend | wall of each run (s) | mean (s) | before the first task (s) | after the last (s) |"
    )
    assert lines[2] == "| local | 35.0, 36.0, 34.0 | 35.0 | 1.10 | 0.50 |"
    assert lines[3] == "| ray | 36.5, 37.0, 36.0 | 36.5 | 2.27 | 0.50 |"
    before = [r - l for r, l in zip(befores["ray"], befores["local"], strict=True)]
    low, high = stats.t.interval(0.95, len(before) - 1, loc=sum(before) / 3, scale=stats.sem(before))
    assert lines[4].split(" | ")[3] == f"+{sum(before) / 3:.2f} [+{low:.2f}, +{high:.2f}]"
    assert lines[4].endswith("| +0.00 [+0.00, +0.00] |")
    assert generators.ray_value(tmp_path, "before.difference") == lines[4].split(" | ")[3]
    assert generators.ray_value(tmp_path, "before.shown") == "longer on Ray"
    # from the first task's start to the last's end: wall less both parts, Ray's minus local's
    between = [(36.5 - 2.0) - (35.0 - 1.0), (37.0 - 2.5) - (36.0 - 1.2), (36.0 - 2.3) - (34.0 - 1.1)]
    low, high = stats.t.interval(0.95, 2, loc=sum(between) / 3, scale=stats.sem(between))
    assert generators.ray_value(tmp_path, "between.difference") == (
        f"{sum(between) / 3:+.2f} [{low:+.2f}, {high:+.2f}]"
    )
    assert generators.ray_value(tmp_path, "between.shown") == "not told apart"
    assert generators.ray_value(tmp_path, "workers") == "2"
    for run in runs:
        del run["before_first_task_s"], run["after_last_task_s"]
    (perf / "ray.json").write_text(json.dumps({"study": ["x"], "workers": 2, "runs": runs}))
    assert generators.ray_backend(tmp_path).splitlines()[0] == "| backend | wall of each run (s) | mean (s) |"


def test_the_trial_coverage_values_are_the_lowest_and_highest_rate_over_the_policies(tmp_path):
    """ARMSE, the means (ASR, final regret) and mean SINR apart, for the policies and for the
    pairs' differences; each rate with its Wilson interval over its own count of studies (a
    metric constant over a study's trials is not counted)."""
    from scipy import stats

    from benchmarks.docs_tooling import generators

    coverage = {"a.armse": 0.75, "b.armse": 0.9, "a.asr": 0.5, "a.final_regret": 0.95, "b.mean_sinr_db": 0.92}
    studies = {name: 200 for name in coverage} | {"a.asr": 100}
    record = {
        "run": {"scenario": "paper-1-v1", "fusion": "centralized"},
        "population_trials": 300,
        "repeats": 200,
        "rows": [
            {
                "trials": 20,
                "confidence_level": 0.95,
                "coverage": coverage,
                "studies": studies,
                "extended": dict.fromkeys(coverage, 0) | {"a.armse": 3, "b.asr": 7},
                "differences": {
                    "coverage": {
                        "a - b.armse": 0.8,
                        "a - c.armse": 0.97,
                        "a - b.asr": 0.9,
                        "b - c.mean_sinr_db": 0.5,
                    },
                    "studies": {
                        "a - b.armse": 200,
                        "a - c.armse": 100,
                        "a - b.asr": 50,
                        "b - c.mean_sinr_db": 10,
                    },
                    "extended": {"a - b.armse": 9, "a - c.armse": 0, "a - b.asr": 0, "b - c.mean_sinr_db": 0},
                },
            }
        ],
    }
    (tmp_path / "results" / "uncertainty").mkdir(parents=True)
    path = tmp_path / "results" / "uncertainty" / "trial-coverage.json"
    path.write_text(json.dumps(record))
    assert "pairs.gap" not in generators.trial_coverage_values(tmp_path)  # no row of 40 trials or more
    many = json.loads(json.dumps(record["rows"][0])) | {"trials": 40}
    many["differences"]["coverage"] |= {"a - c.armse": 0.7, "a - b.asr": 0.45, "b - c.mean_sinr_db": 0.9}
    record["rows"].append(many)  # the pairs' lowest: 0.05 below the policies' for ARMSE and the means
    path.write_text(json.dumps(record))
    table = generators.trial_coverage_values(tmp_path)
    assert (table["pairs"], table["pairs.gap"]) == ("3", "5.0")
    assert (
        table["pairs.few"]
        == "in 1 of the 3 columns and counts, by up to 42.0 points (Δ mean SINR's on 20 trials)"
    )

    def wilson(rate, n):
        low, high = stats.binomtest(round(rate * n), n).proportion_ci(method="wilson")
        return f"{100 * rate:.1f} % [{100 * low:.1f}, {100 * high:.1f}]"

    assert table["armse.20"] == f"{wilson(0.75, 200)} to {wilson(0.9, 200)}"
    assert table["means.20"] == f"{wilson(0.5, 100)} to {wilson(0.95, 200)}"
    assert table["sinr.20"] == f"{wilson(0.92, 200)} to {wilson(0.92, 200)}"
    assert table["pairs.armse.20"] == f"{wilson(0.8, 200)} to {wilson(0.97, 100)}"
    assert table["pairs.means.20"] == f"{wilson(0.9, 50)} to {wilson(0.9, 50)}"
    assert table["pairs.sinr.20"] == f"{wilson(0.5, 10)} to {wilson(0.5, 10)}"
    assert (table["population"], table["scenario"], table["repeats"]) == ("300", "paper-1-v1", "200")
    assert table["fusion"] == "centralized"
    assert (table["extended.20"], table["level.20"]) == ("3 of 400", "95.0 %")  # ARMSE's only
