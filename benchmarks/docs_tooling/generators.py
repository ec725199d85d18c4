"""What the docs' pages quote (:mod:`benchmarks.docs_tooling.pages`): a generator per table, and
a value source or value table per set of values (numbers, intervals, verdicts, computed lists),
each reading the committed artefacts it names under ``docs/results``. The sentences around them
are written in the pages."""

from __future__ import annotations

import json
import operator
import re
import shlex
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import uncertainty, verdicts
from ..errors import BenchError
from ..report import (
    METHOD_LEGEND,
    PAPER_ARMSE,
    PAPER_ASR,
    format_cell,
    format_estimate,
    format_judged,
    paired_difference,
    paper_armse,
)
from ..studies import claims, tracking
from . import model_figures
from .model_figures import FIGURES_FILE, format_figure

#: The scorecards of the claims table: label -> artefact.
SCORECARDS = {"v1": "claims/v1.json", "v1, centralised": "claims/v1-centralized.json", "v0": "claims/v0.json"}
#: The scorecards of the single-reading changes, in the order each builds on the last.
READINGS = {
    "v0": "claims/v0.json",
    "v0 + dB": "claims/v0+db.json",
    "v0 + shared truth": "claims/v0+shared-truth.json",
    "v0 + set rule": "claims/v0+set-rule.json",
    "v1, section 1 layout": "claims/v1-reconstructed-layout.json",
    "v1": "claims/v1.json",
    "v1, centralised": "claims/v1-centralized.json",
}

Generator = Callable[[Path], str]
GENERATORS: dict[str, Generator] = {}
#: Value sources: name -> function(docs, key) giving the text of one quoted number.
VALUE_SOURCES: dict[str, Callable[[Path, str], str]] = {}


def generator(name: str) -> Callable[[Generator], Generator]:
    """Register a block generator under ``name``."""

    def register(function: Generator) -> Generator:
        GENERATORS[name] = function
        return function

    return register


def value_source(name: str) -> Callable[[Callable[[Path, str], str]], Callable[[Path, str], str]]:
    """Register the source of value spans ``<!-- value: NAME KEY -->``."""

    def register(function: Callable[[Path, str], str]) -> Callable[[Path, str], str]:
        VALUE_SOURCES[name] = function
        return function

    return register


#: Value tables: name -> function(docs) giving every value of one finding, ``{key: text}``.
ValueTable = Callable[[Path], dict[str, str]]
_TABLES: dict[tuple[str, Path], dict[str, str]] = {}


def values(name: str) -> Callable[[ValueTable], ValueTable]:
    """Register a value table: the spans ``<!-- value: NAME KEY -->`` quote its ``KEY``. The
    sentences around them are the page's; a table gives only values (numbers, intervals, verdicts,
    policy names, computed lists of claims), read once per rendering."""

    def register(function: ValueTable) -> ValueTable:
        def lookup(docs: Path, key: str) -> str:
            table = _TABLES.get((name, docs))
            if table is None:
                table = _TABLES[(name, docs)] = function(docs)
            if key not in table:
                raise BenchError(f"the values {name!r} have no {key!r}; they have: {', '.join(table)}")
            return table[key]

        VALUE_SOURCES[name] = lookup
        return function

    return register


def forget_values() -> None:
    """Drop the value tables read so far (a new rendering reads the artefacts again)."""
    _TABLES.clear()


def _machine(m: dict[str, Any]) -> str:
    """A measuring machine as the captions name it: ``2 cores (x86_64, Python 3.11.7)``."""
    return f"{m['cores']} cores ({m['machine']}, Python {m['python']})"


def read_json(docs: Path, relative: str) -> Any:
    path = docs / "results" / relative
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise BenchError(f"the docs read {path}, which is missing or not JSON ({exc})") from None


def markdown_table(head: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    """A Markdown table: the header, its rule, and a line per row of cells (each ``str``-ed)."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(map(str, row)) + " |" for row in rows]
    return "\n".join(lines)


def _scorecards(docs: Path, files: dict[str, str]) -> dict[str, list]:
    return {label: read_json(docs, path) for label, path in files.items()}


@generator("claims-verdicts")
def claims_verdicts(docs: Path) -> str:
    """Every claim's verdict under v1 (both fusions) and v0, with the counts."""
    return claims.comparison_markdown(_scorecards(docs, SCORECARDS))


#: The key of each scorecard of :data:`SCORECARDS` in the values ``claims``.
SCORECARD_KEYS = {"v1": "v1", "v1, centralised": "v1-centralized", "v0": "v0"}


@values("claims")
def claims_values(docs: Path) -> dict[str, str]:
    """Per scorecard of :data:`SCORECARDS` (``v1``, ``v1-centralized``, ``v0``), ``KEY.VERDICT``
    the number of claims with that verdict; ``total`` the claims; ``scorecards`` how many
    scorecards give a verdict per claim (:func:`every_scorecard`) and ``always-contradicted`` the
    claims contradicted in each of them."""
    table = {}
    for label, results in _scorecards(docs, SCORECARDS).items():
        counts = verdicts.count(r["verdict"] for r in results)
        table |= {f"{SCORECARD_KEYS[label]}.{v}": str(counts[v]) for v in verdicts.VERDICTS}
        table["total"] = str(len(results))
    cards = every_scorecard(docs)
    table["scorecards"] = str(len(cards))
    table["always-contradicted"] = ", ".join(_always_contradicted(cards)) or "none"
    return table


def _always_contradicted(scorecards: dict[str, dict[str, str]]) -> list[str]:
    """The claims contradicted in every scorecard (``{label: {claim: verdict}}``), in claim order."""
    ids = list(next(iter(scorecards.values())))
    return [c for c in ids if all(card[c] == verdicts.CONTRADICTED for card in scorecards.values())]


def _by_claim(results: list[dict]) -> dict[str, str]:
    return {r["id"]: r["verdict"] for r in results}


def every_scorecard(docs: Path) -> dict[str, dict[str, str]]:
    """Every scorecard with a verdict per claim, ``{label: {claim: verdict}}``: the readings and
    fusions, the other master seeds (of v1 and of the shipped search-5 set) and every searched
    layout scored in full (the calibration's candidates record counts only)."""
    files = {path: label for label, path in reversed([*READINGS.items(), *SEED_SCORECARDS.items(),
                                                       *SET_SEED_SCORECARDS.items()])}  # fmt: skip
    cards = {label: _by_claim(read_json(docs, path)) for path, label in files.items()}
    return cards | {f["name"]: f["verdicts"] for f in _long_scorecards(docs)}


#: The readings table's first columns: the default, then its centralised fusion (then from the
#: last change back to v0).
READING_COLUMNS = ("v1", "v1, centralised")
#: A verdict in a table too wide for the words (the page gives the legend).
SHORT_VERDICTS = {verdicts.HOLDS: "H", verdicts.CONSISTENT: "c", verdicts.CONTRADICTED: "X"}


@generator("readings")
def readings(docs: Path) -> str:
    """The verdicts under each single reading change, the default (v1) first, then its
    centralised fusion, then back to v0 one change at a time, each verdict by its letter
    (:data:`SHORT_VERDICTS`)."""
    read = _scorecards(docs, READINGS)
    labels = [*READING_COLUMNS, *(label for label in reversed(read) if label not in READING_COLUMNS)]
    cards = {label: _by_claim(read[label]) for label in labels}
    lines = ["| claim | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    for claim in cards["v1"]:
        lines.append(
            f"| {claim} | " + " | ".join(SHORT_VERDICTS[cards[label][claim]] for label in labels) + " |"
        )
    for verdict in verdicts.VERDICTS:
        counts = [str(verdicts.count(cards[label].values())[verdict]) for label in labels]
        lines.append(f"| **{verdict}** | " + " | ".join(counts) + " |")
    return "\n".join(lines)


#: Each change of the readings table: its key in the values ``readings`` -> (its column, the
#: column it modifies).
READING_CHANGES = {
    "db": ("v0 + dB", "v0"),
    "shared-truth": ("v0 + shared truth", "v0"),
    "set-rule": ("v0 + set rule", "v0"),
    "all-three": ("v1, section 1 layout", "v0"),
    "layout": ("v1", "v1, section 1 layout"),
    "centralized": ("v1, centralised", "v1"),
}


@values("readings")
def reading_values(docs: Path) -> dict[str, str]:
    """Per change of :data:`READING_CHANGES`, ``CHANGE.moves`` the claims whose verdict it moves
    against the column it modifies (``claim (old to new)``), ``CHANGE.holds`` and
    ``CHANGE.base-holds`` the claims holding in its column and in that one; ``always`` the claims
    contradicted in every column and ``always.count`` how many."""
    cards = _scorecards(docs, READINGS)
    table = {}
    for change, (column, base) in READING_CHANGES.items():
        before = _by_claim(cards[base])
        moved = [
            (r["id"], before[r["id"]], r["verdict"]) for r in cards[column] if r["verdict"] != before[r["id"]]
        ]
        table[f"{change}.moves"] = (
            ", ".join(f"{claim} ({old} to {new})" for claim, old, new in moved) or "no claim"
        )
        table[f"{change}.holds"] = str(verdicts.count(r["verdict"] for r in cards[column])["holds"])
        table[f"{change}.base-holds"] = str(verdicts.count(before.values())["holds"])
    always = _always_contradicted({label: _by_claim(results) for label, results in cards.items()})
    table["always"] = ", ".join(always) or "none"
    table["always.count"] = str(len(always))
    return table


@generator("calibration-summary")
def calibration_summary(docs: Path) -> str:
    """The layouts judged by full scorecards, with their counts at both sizes."""
    report = read_json(docs, "calibration/calibration.json")
    screen, final = str(report["stages"]["screen_trials"]), str(report["stages"]["final_trials"])
    lines = [
        f"| layout | holds / consistent / contradicted at {screen} trials | at {final} trials |",
        "|---|---|---|",
    ]
    for c in report["candidates"]:
        if final not in c["scorecards"]:
            continue
        name = "0 (section 1's reconstruction)" if c["index"] == 0 else str(c["index"])
        if c["index"] == report["best"] and report["adopted"]:
            name += " (adopted)"
        cells = [" / ".join(str(c["scorecards"][t][v]) for v in verdicts.VERDICTS) for t in (screen, final)]
        lines.append(f"| {name} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines)


@values("calibration")
def calibration_values(docs: Path) -> dict[str, str]:
    """The calibration's figures: ``count`` jittered layouts, ``seed``, ``met`` of ``candidates``
    meeting the text's constraints, ``screened`` and ``final`` judged at ``screen-trials`` and
    ``final-trials``, ``best`` the adopted layout and ``moves`` how far it moves the reference's
    stations (km, smallest to largest)."""
    report = read_json(docs, "calibration/calibration.json")
    screen, final = str(report["stages"]["screen_trials"]), str(report["stages"]["final_trials"])
    best = next(c for c in report["candidates"] if c["index"] == report["best"])
    reference = report["candidates"][0]
    moves = [
        float(np.hypot(*(np.array(p) - np.array(q))))
        for key in ("tx_km", "rx_km")
        for p, q in zip(best[key], reference[key], strict=True)
    ]
    return {
        "count": str(report["count"]),
        "seed": str(report["seed"]),
        "candidates": str(report["count"] + 1),
        "met": str(sum(1 for c in report["candidates"] if c["rejected"] is None)),
        "screened": str(sum(1 for c in report["candidates"] if screen in c["scorecards"])),
        "final": str(sum(1 for c in report["candidates"] if final in c["scorecards"])),
        "screen-trials": screen,
        "final-trials": final,
        "best": str(best["index"]),
        "moves": f"{min(moves):.1f} to {max(moves):.1f}",
    }


@generator("tracking-targets")
def tracking_targets(docs: Path) -> str:
    """The tracking study's targets, one row per scenario and fusion."""
    text = tracking.targets_markdown(read_json(docs, "tracking/targets.json"))
    return text.split("\n", 2)[2].lstrip("\n")  # without its own title


# ------------------------------------------------------------------ the v1 study
FUSION_LABELS = {"average": "eq22 average", "centralized": "centralised"}
PAIRS = ("best - mg-crb-cl", "mg-crb-cl - ucb1", "mg-crb-cl - epsilon-greedy", "best - epsilon-greedy")


#: Where each version's paper-study summaries are committed, and their scenario names.
STUDIES = {"v1": ("v1", "paper-{n}-v1"), "v0": ("v0", "paper-{n}")}


def study_summary(docs: Path, number: int, fusion: str, version: str = "v1") -> dict:
    """The summary.json of ``version``'s paper study of scenario ``number`` under ``fusion``."""
    folder, name = STUDIES[version]
    return read_json(docs, f"{folder}/{name.format(n=number)}-{fusion}.summary.json")


def _ratio(row: dict, key: str, paper: float | None, target: int | None = None) -> str:
    """Ours / the paper's, with our interval divided by the paper's number."""
    if paper is None:
        return "—"
    value, ci = row[key], row["ci"][key]
    if target is not None:
        value, ci = value[target], ci[target]
    return format_estimate(value / paper, [ci[0] / paper, ci[1] / paper], "{:.2f}")


def v1_table(
    docs: Path, number: int, version: str = "v1", fusions: tuple[str, ...] = tuple(FUSION_LABELS)
) -> str:
    """The paper's six policies in scenario ``number`` of ``version`` under ``fusions``, beside
    the paper's numbers."""
    summaries = {f: study_summary(docs, number, f, version) for f in fusions}
    average = summaries["average"]
    key = f"paper-{number}"
    labels = [FUSION_LABELS[f] for f in fusions]
    head = ["policy", *(f"ARMSE, {label} (m)" for label in labels)]
    head += ["paper ARMSE (m)", *(f"ours / paper, {label}" for label in labels)]
    head += ["ASR (%)", "paper ASR (%)", "final regret", "mean SINR (dB)"]
    rows_a = []
    for policy, row in average["policies"].items():
        paper = paper_armse(key, policy)
        rows = [summaries[f]["policies"][policy] for f in fusions]
        paper_asr = PAPER_ASR.get(key, {}).get(policy)
        cells = [policy, *(format_cell(r, "armse", "{:.3f}") for r in rows)]
        cells += [f"{paper:.4f}" if paper is not None else "—", *(_ratio(r, "armse", paper) for r in rows)]
        cells += [
            format_cell(row, "asr", "{:.2f}", 100),
            f"{paper_asr:.2f}" if paper_asr is not None else "—",
        ]
        cells += [format_cell(row, "final_regret", "{:.1f}"), format_cell(row, "mean_sinr_db", "{:.2f}")]
        rows_a.append(cells)
    pair_head = ["A - B", *(f"Δ ARMSE, {label} (m)" for label in labels)]
    pair_head += ["Δ ASR (pp)", "Δ final regret", "Δ mean SINR (dB)"]
    rows_b = []
    for pair in PAIRS:
        a = average["paired_differences"][pair]
        cells = [
            pair,
            *(format_judged(summaries[f]["paired_differences"][pair]["armse"], "{:.3f}") for f in fusions),
        ]
        cells += [format_judged(a["asr"], "{:.2f}", 100), format_judged(a["final_regret"], "{:.1f}")]
        cells += [format_judged(a["mean_sinr_db"], "{:.2f}")]
        rows_b.append(cells)
    return markdown_table(head, rows_a) + "\n\n" + markdown_table(pair_head, rows_b)


def v1_targets_table(docs: Path) -> str:
    """Scenario 3 per target (the paper's Table 4), both fusions."""
    summaries = {f: study_summary(docs, 3, f) for f in FUSION_LABELS}
    head = ["policy"]
    for k in (1, 2):
        head += [f"T{k}, {label} (m)" for label in FUSION_LABELS.values()]
        head += [f"T{k} paper (m)", f"T{k} ours / paper, {FUSION_LABELS['centralized']}"]
    lines = []
    for policy in summaries["average"]["policies"]:
        rows = {f: s["policies"][policy] for f, s in summaries.items()}
        paper = PAPER_ARMSE["paper-3"].get(policy)
        cells = [policy]
        for k in (0, 1):
            cells += [format_cell(rows[f], "armse_per_target", "{:.3f}", target=k) for f in FUSION_LABELS]
            ref = paper[k] if paper else None
            cells += [
                f"{ref:.4f}" if ref is not None else "—",
                _ratio(rows["centralized"], "armse_per_target", ref, k),
            ]
        lines.append(cells)
    return markdown_table(head, lines)


for _number in (1, 2, 3):
    generator(f"v1-scenario-{_number}")(lambda docs, n=_number: v1_table(docs, n))
    generator(f"v0-scenario-{_number}")(lambda docs, n=_number: v1_table(docs, n, "v0", ("average",)))
generator("v1-scenario-3-targets")(v1_targets_table)


def _diff_text(summary: dict, a: str, b: str, metric: str, fmt: str, scale: float = 1.0) -> str:
    return format_judged(paired_difference(summary, a, b, metric), fmt, scale)


def study_values(docs: Path, version: str) -> dict[str, str]:
    """What ``version``'s paper-study tables show, from their summaries (eq22 average fusion
    unless a key names the fusion): ``trials``, ``steps`` and ``seed`` (one for every table),
    ``legend`` (the interval marks); per scenario N, ``regret.N.B`` MG-CRB-CL's final regret
    minus B's, ``asr.N`` MG-CRB-CL's ASR (%), ``paper-asr.N`` the paper's and
    ``asr.N.epsilon-greedy``; ``lowest.N.FUSION`` the policy of lowest ARMSE, ``runner-up.N.FUSION``
    the next and ``margin.N.FUSION`` its paired excess (m); ``highest-regret.N`` and
    ``second-regret.N``, ``best-rank.N`` Best's rank by ARMSE of ``policies``; ``armse-ratio``
    our ARMSE over the paper's (every policy and scenario); with both fusions, ``central-drop``
    (%) how much centralised fusion lowers every policy's ARMSE and ``widest`` (m) the farthest
    an ARMSE interval reaches from its value."""
    fusions = ("average", "centralized") if version == "v1" else ("average",)
    summaries = {(n, f): study_summary(docs, n, f, version) for n in (1, 2, 3) for f in fusions}
    shape = {(s["trials"], s["steps"], s["seed"]) for s in summaries.values()}
    if len(shape) != 1:
        raise BenchError(f"the {version} studies ran different trials, steps or seeds: {sorted(shape)}")
    ((trials, steps, seed),) = shape
    table = {"trials": str(trials), "steps": str(steps), "seed": str(seed), "legend": METHOD_LEGEND}
    for (n, fusion), s in summaries.items():
        rows = s["policies"]
        by_armse = sorted(rows, key=lambda p: rows[p]["armse"])
        table |= {
            f"lowest.{n}.{fusion}": by_armse[0],
            f"runner-up.{n}.{fusion}": by_armse[1],
            f"margin.{n}.{fusion}": _diff_text(s, by_armse[1], by_armse[0], "armse", "{:.3f}"),
        }
        if fusion != "average":
            continue
        by_regret = sorted(rows, key=lambda p: rows[p]["final_regret"])
        table |= {
            f"regret.{n}.{b}": _diff_text(s, "mg-crb-cl", b, "final_regret", "{:.0f}")
            for b in ("epsilon-greedy", "ucb1")
        }
        table |= {
            f"asr.{n}": format_cell(rows["mg-crb-cl"], "asr", "{:.1f}", 100),
            f"paper-asr.{n}": f"{PAPER_ASR[f'paper-{n}']['mg-crb-cl']:.2f}",
            f"asr.{n}.epsilon-greedy": format_cell(rows["epsilon-greedy"], "asr", "{:.1f}", 100),
            f"highest-regret.{n}": by_regret[-1],
            f"second-regret.{n}": by_regret[-2],
            f"best-rank.{n}": str(by_armse.index("best") + 1),
            "policies": str(len(rows)),
        }
    table["armse-ratio"] = _span(
        [
            row["armse"] / paper_armse(f"paper-{n}", p)
            for (n, f), s in summaries.items()
            if f == "average"
            for p, row in s["policies"].items()
        ],
        "{:.1f}",
    )
    if "centralized" in fusions:
        drops, widths = [], []
        for n in (1, 2, 3):
            for policy, row in summaries[(n, "average")]["policies"].items():
                central = summaries[(n, "centralized")]["policies"][policy]
                drops.append(1 - central["armse"] / row["armse"])
                widths += [
                    max(r["ci"]["armse"][1] - r["armse"], r["armse"] - r["ci"]["armse"][0])
                    for r in (row, central)
                ]
        table["central-drop"] = f"{100 * min(drops):.0f} to {100 * max(drops):.0f}"
        table["widest"] = f"{max(widths):.3f}"
    return table


for _version in STUDIES:
    values(_version)(lambda docs, v=_version: study_values(docs, v))


# ------------------------------------------------------------------ the summary and the timings
def _margin(target: dict) -> str:
    """A "lower ARMSE" target's margin ``-(a - b)`` (m) with its interval."""
    return format_estimate(-target["difference"], [-target["ci"][1], -target["ci"][0]], "{:.3f}")


def _margins(comparisons: list[dict]) -> str:
    """The smallest and the largest of targets' margins, each with its interval."""
    ordered = sorted(comparisons, key=lambda c: -c["difference"])
    return f"{_margin(ordered[0])} to {_margin(ordered[-1])}"


def _span(values: list[float], fmt: str = "{:.2f}") -> str:
    low, high = min(values), max(values)
    return (
        fmt.format(low) if fmt.format(low) == fmt.format(high) else f"{fmt.format(low)} to {fmt.format(high)}"
    )


@values("summary")
def summary_values(docs: Path) -> dict[str, str]:
    """The page's opening figures: ``layout`` (v1's calibrated layout) and ``judged`` (the layouts
    judged by scorecards); the tracking targets' margins, smallest to largest
    (``best-tracking.margins``: below Best, ``tracking-ucb.margins``: below MG-CRB-CL),
    ``targets`` and ``targets.held``; ``armse-ratio.FUSION`` our ARMSE over the paper's, over
    every policy and scenario; ``asr.N`` MG-CRB-CL's ASR in Scenario N (with its interval) and
    ``paper-asr.N`` the paper's."""
    report = read_json(docs, "calibration/calibration.json")
    targets = read_json(docs, "tracking/targets.json")
    comparisons = [c for r in targets for c in r["best_tracking_lower"] + r["tracking_ucb_lower"]]
    table = {
        "layout": str(report["best"]),
        "judged": str(sum(1 for c in report["candidates"] if c["scorecards"])),
        "best-tracking.margins": _margins(
            [c for r in targets for c in r["best_tracking_lower"] if c["b"] == "best"]
        ),
        "tracking-ucb.margins": _margins(
            [c for r in targets for c in r["tracking_ucb_lower"] if c["b"] == "mg-crb-cl"]
        ),
        "targets": str(len(comparisons)),
        "targets.held": str(sum(c["holds"] for c in comparisons)),
    }
    for fusion in FUSION_LABELS:
        ratios = [
            row["armse"] / paper_armse(f"paper-{n}", p)
            for n in (1, 2, 3)
            for p, row in study_summary(docs, n, fusion)["policies"].items()
        ]
        table[f"armse-ratio.{fusion}"] = _span(ratios, "{:.1f}")
    for n in (1, 2, 3):
        table[f"asr.{n}"] = format_cell(
            study_summary(docs, n, "average")["policies"]["mg-crb-cl"], "asr", "{:.1f}", 100
        )
        table[f"paper-asr.{n}"] = f"{PAPER_ASR[f'paper-{n}']['mg-crb-cl']:.1f}"
    return table | _rests_on(docs) | _missed_targets(docs)


def _one(values: set[Any], what: str) -> str:
    """The one value ``values`` hold (every study of a kind ran the same count), as text."""
    if len(values) != 1:
        raise BenchError(f"the studies' {what} differ: {sorted(values)}")
    return str(next(iter(values)))


def _rests_on(docs: Path) -> dict[str, str]:
    """What each study's results rest on: ``claims.trials``, ``tracking.trials``,
    ``rl.trials`` and ``rl.seeds`` (seeds per learner), ``planning.trials``, ``screen.trials``
    (the layout screen) and ``scorecards`` (master seeds of v1's scorecard)."""
    rl = read_json(docs, "rl/rl.json")
    seeds: dict[int, list[str]] = {}
    for key in rl["scenarios"][0]["learners"]:
        count = int(_one({e["learners"][key]["seeds"] for e in rl["scenarios"]}, f"{key} seeds"))
        seeds.setdefault(count, []).append(f"`{key}`")
    return {
        "claims.trials": _one(
            {study_summary(docs, n, f)["trials"] for n in (1, 2, 3) for f in FUSION_LABELS}, "trials"
        ),
        "tracking.trials": _one({s["trials"] for s in tracking_summaries(docs).values()}, "trials"),
        "rl.trials": _one({e["trials"] for e in rl["scenarios"]}, "trials"),
        "rl.seeds": "; ".join(
            f"{n} for {', '.join(keys)}" for n, keys in sorted(seeds.items(), reverse=True)
        ),
        "planning.trials": _one({r["trials"] for r in read_json(docs, "planning/planning.json")}, "trials"),
        "screen.trials": str(read_json(docs, LAYOUT_TOP)["trials"]),
        "scorecards": str(len(SEED_SCORECARDS)),
    }


def _missed_targets(docs: Path) -> dict[str, str]:
    """The speed targets missed: ``missed`` the figures of perf.json below their target (each
    with its value and target), and the beam planner's act time as a multiple of
    best-tracking's (``beam``) against its target (``beam.target``)."""
    from ..speed.perf import TARGETS, format_value, target_met

    results = read_json(docs, "perf/perf.json")
    missed = [
        f"`{key}` {format_value(results[key])} (target {op} {bound:g})"
        for key, (op, bound) in TARGETS.items()
        if key in results and not target_met(key, results[key])
    ]
    cost = read_json(docs, "perf/planning_cost.json")
    return {
        "missed": _listed(missed),
        "beam": f"{cost['figures']['plan-tracking:10-beam_over_best_tracking']:.0f}",
        "beam.target": f"{cost['target_ratio']:g}",
    }


@generator("results-summary")
def results_summary(docs: Path) -> str:
    """The README's copy of the summary of docs/results.md (between ``<!-- summary -->`` and
    ``<!-- end summary -->``), its links made relative to the repository's root; the page is
    the summary's one home."""
    text = (docs / "results.md").read_text()
    start, end = "<!-- summary -->\n", "<!-- end summary -->"
    if start not in text or end not in text:
        raise BenchError(f"{docs / 'results.md'} has no {start.strip()} ... {end} section")
    summary = text.split(start, 1)[1].split(end, 1)[0]
    return re.sub(r"\]\((?!https?:|#)([^)]+)\)", lambda m: f"]({docs.name}/{m.group(1)})", summary)


#: The timing artefacts of the studies the page reports: label -> file.
TIMINGS = {
    "v1 claims, eq22 average": "claims/v1.timing.json",
    "v1 claims, centralised": "claims/v1-centralized.timing.json",
    "v0 claims": "claims/v0.timing.json",
    "v0 + dB claims": "claims/v0+db.timing.json",
    "v0 + shared truth claims": "claims/v0+shared-truth.timing.json",
    "v0 + set rule claims": "claims/v0+set-rule.timing.json",
    "v1 readings on section 1's layout, claims": "claims/v1-reconstructed-layout.timing.json",
    "tracking study": "tracking/timing.json",
    "RL study": "rl/timing.json",
    "RL study, torch-ppo on an H200 (the invocation that resumed it: its trainings ran before)": (
        "rl-device/timing.json"
    ),
    "planning study": "planning/timing.json",
    "mechanisms study": "mechanisms/timing.json",
    "layout search, 2 layouts scored at 500 trials": "layout-search/timing.json",
    "layout search, ranks 4, 5 and 10 re-scored at 500 trials": "layout-search/rescored.timing.json",
    "ablations study": "mechanisms/ablations.timing.json",
}


@generator("timings")
def timings(docs: Path) -> str:
    """Each study's wall time, command and machine, from its ``timing.json``."""
    lines = [
        "| study | command | wall time (s) | machine | load average before / after |",
        "|---|---|---|---|---|",
    ]
    for label, path in TIMINGS.items():
        if not (docs / "results" / path).exists():
            continue
        t = read_json(docs, path)
        # quoted as a shell needs it (an agent parameter holds spaces and braces)
        command = shlex.join("DIR" if a.startswith("/") else a for a in t["command"])
        m = t["machine"]
        lines.append(
            f"| {label} | `{command}` | {t['wall_s']:.0f} | {m['cores']} cores, {m['machine']}, Python "
            f"{m['python']} | {m['load_average_1min']:.2f} / {m['load_average_1min_after']:.2f} |"
        )
    return "\n".join(lines)


# ------------------------------------------------------------------ the tracking study
def tracking_summaries(docs: Path) -> dict[tuple[int, str], dict]:
    return {
        (n, f): read_json(docs, f"tracking/paper-{n}-v1-{f}.summary.json")
        for n in (1, 2, 3)
        for f in FUSION_LABELS
    }


@generator("tracking-studies")
def tracking_studies(docs: Path) -> str:
    """Every policy's ARMSE, bound, final regret and mean SINR in each tracking study."""
    text = tracking.studies_markdown(tracking_summaries(docs))
    return text.split("\n", 2)[2].lstrip("\n")


def _where(key: tuple[int, str]) -> str:
    return f"Scenario {key[0]}, {FUSION_LABELS[key[1]]}"


@values("tracking")
def tracking_values(docs: Path) -> dict[str, str]:
    """What the tracking study shows, from its targets and summaries (WHERE: ``Scenario N,
    fusion``). ``best-tracking.held`` of ``best-tracking.compared`` comparisons below Best and
    every SINR-driven policy, the smallest margin (m) ``best-tracking.smallest`` against
    ``.against`` in ``.where``; for B in best, mg-crb-cl, tracking-ucb's ``ucb.B.held`` of
    ``ucb.B.studies``, its margins ``ucb.B.low``/``ucb.B.high`` with ``.where``; ``cost`` the
    compute-time ratios to MG-CRB-CL; per N.FUSION, ``sinr-cost.N.FUSION.regret``/``.sinr``
    (tracking-ucb minus MG-CRB-CL) and ``trade.N.FUSION.armse``/``.regret`` (tracking-ucb:0.75
    minus MG-CRB-CL); per FUSION, the range of ARMSE / bound: ``bound.FUSION.low``/``.high``,
    each with ``.policy`` and ``.scenario``."""
    targets = read_json(docs, "tracking/targets.json")
    summaries = tracking_summaries(docs)
    by_key = {(r["scenario"], r["fusion"]): r for r in targets}
    comparisons = [(k, c) for k, r in by_key.items() for c in r["best_tracking_lower"]]
    key, smallest = max(comparisons, key=lambda kc: kc[1]["difference"])
    table = {
        "best-tracking.held": str(sum(c["verdict"] == verdicts.HOLDS for _, c in comparisons)),
        "best-tracking.compared": str(len(comparisons)),
        "best-tracking.smallest": _margin(smallest),
        "best-tracking.smallest.against": smallest["b"],
        "best-tracking.smallest.where": _where(key),
    }
    for b in ("best", "mg-crb-cl"):
        cs = [(k, c) for k, r in by_key.items() for c in r["tracking_ucb_lower"] if c["b"] == b]
        table[f"ucb.{b}.held"] = str(sum(c["verdict"] == verdicts.HOLDS for _, c in cs))
        table[f"ucb.{b}.studies"] = str(len(cs))
        for end, (k, c) in (("low", max(cs, key=lambda kc: kc[1]["difference"])),
                            ("high", min(cs, key=lambda kc: kc[1]["difference"]))):  # fmt: skip
            table[f"ucb.{b}.{end}"], table[f"ucb.{b}.{end}.where"] = _margin(c), _where(k)
    ratios = [c["ratio"] for r in by_key.values() for c in r["cost"].values()]
    table["cost"] = f"{min(ratios):.2f} to {max(ratios):.2f}"
    for (n, fusion), s in summaries.items():
        where = f"{n}.{fusion}"
        table[f"sinr-cost.{where}.regret"] = _diff_text(
            s, "tracking-ucb", "mg-crb-cl", "final_regret", "{:.0f}"
        )
        table[f"sinr-cost.{where}.sinr"] = _diff_text(
            s, "tracking-ucb", "mg-crb-cl", "mean_sinr_db", "{:.2f}"
        )
        table[f"trade.{where}.armse"] = _diff_text(s, "tracking-ucb:0.75", "mg-crb-cl", "armse", "{:.3f}")
        table[f"trade.{where}.regret"] = _diff_text(
            s, "tracking-ucb:0.75", "mg-crb-cl", "final_regret", "{:.0f}"
        )
    for fusion in FUSION_LABELS:
        rows = [(k, p, r) for k, s in summaries.items() if k[1] == fusion for p, r in s["policies"].items()]
        for end, pick in (("low", min), ("high", max)):
            (n, _), policy, row = pick(rows, key=lambda x: x[2]["armse_over_bound"])
            table[f"bound.{fusion}.{end}"] = format_cell(row, "armse_over_bound", "{:.3f}")
            table[f"bound.{fusion}.{end}.policy"], table[f"bound.{fusion}.{end}.scenario"] = (
                f"`{policy}`",
                str(n),
            )
    return table


# ------------------------------------------------------------------ performance
@generator("perf-figures")
def perf_figures(docs: Path) -> str:
    """``mimo-radar-bench perf``'s figures and targets, from its committed perf.json."""
    from ..speed.perf import FIGURES, TARGETS, format_value, target_met

    results = read_json(docs, "perf/perf.json")
    lines = ["| figure | what | measured | target |", "|---|---|---|---|"]
    for key, unit, what in FIGURES:
        value = results[key]
        text = format_value(value)
        target = "—"
        if key in TARGETS:
            op, bound = TARGETS[key]
            target = f"{op} {bound:g}: {'met' if target_met(key, value) else '**missed**'}"
        lines.append(f"| `{key}` | {what} | {text} {unit} | {target} |")
    return "\n".join(lines)


@values("perf-figures")
def perf_figure_values(docs: Path) -> dict[str, str]:
    """perf.json's run: ``workers``, ``cores``, ``machine``, ``load-before`` and ``load-after``."""
    results = read_json(docs, "perf/perf.json")
    return {
        "workers": str(results["workers"]),
        "cores": str(results["cores"]),
        "machine": results["machine"],
        "load-before": f"{results['load_average_1min_before']:.2f}",
        "load-after": f"{results['load_average_1min_after']:.2f}",
    }


@values("floor")
def floor_values(docs: Path) -> dict[str, str]:
    """The v1 claims study with MG-CRB-CL's exact solver against the same study with the paper's
    BPSO, from perf.json: ``workers``, ``bpso`` and ``exact`` (s), ``speedup`` (the exact solver
    over BPSO per selection), ``added`` (s) and ``share`` (%) what BPSO added, ``target`` (s) and
    ``against-target`` (within or above)."""
    from ..speed.perf import TARGETS

    results = read_json(docs, "perf/perf.json")
    bpso, floor = results["claims_v1_average_wall_s"], results["claims_v1_average_exact_solver_wall_s"]
    _, target = TARGETS["claims_v1_average_wall_s"]
    return {
        "workers": str(results["workers"]),
        "bpso": f"{bpso:.0f}",
        "exact": f"{floor:.0f}",
        "speedup": f"{results['exact_vs_bpso_speedup']:.0f}",
        "added": f"{bpso - floor:.1f}",
        "share": f"{100 * (bpso - floor) / bpso:.1f}",
        "target": f"{target:g}",
        "against-target": "within" if bpso <= target else "above",
    }


@generator("scaling")
def scaling_table(docs: Path) -> str:
    """``python -m benchmarks.speed.scaling --json``'s rows."""
    head = ["M x N", "Ms, Ns", "K", "B", "solver", "ms/step", "us/trial-step", "peak MiB"]
    rows = [
        [f"{r['M']} x {r['N']}", f"{r['Ms']}, {r['Ns']}", r["K"], r["B"], r["solver"]]
        + [f"{r['ms_per_step']:.1f}", f"{r['us_per_trial_step']:.1f}", f"{r['peak_mib']:.1f}"]
        for group in read_json(docs, "perf/scaling.json").values()
        for r in group
    ]
    return markdown_table(head, rows)


@values("growth")
def growth_values(docs: Path) -> dict[str, str]:
    """The fitted growth (log-log slope) of the time per step in ``trials``, ``targets`` and
    ``stations`` (``python -m benchmarks.speed.scaling``)."""
    from ..speed.scaling import fitted_growth

    slopes = fitted_growth(read_json(docs, "perf/scaling.json"))
    keys = {"trials": "trials B", "targets": "targets K", "stations": "stations M*N"}
    return {key: f"{slopes[name]:.2f}" for key, name in keys.items()}


@generator("solver-figures")
def solver_figures(docs: Path) -> str:
    """The super-arm solvers at the paper's size, from the committed perf.json."""
    r = read_json(docs, "perf/perf.json")
    return "\n".join(
        [
            "| figure | value |",
            "|---|---|",
            f"| `exact`, paper size, B = 500, per batched selection | {r['exact_ms']:.3f} ms |",
            f"| `bpso` (numba), paper size, B = 500, per batched selection | {r['bpso_ms']:.1f} ms |",
            f"| `exact` speed-up over `bpso` | {r['exact_vs_bpso_speedup']:.0f}x |",
            "| BPSO optimality rate against `exact` (eq21 as written) | "
            f"{100 * r['bpso_optimality_rate']:.1f} % |",
        ]
    )


@value_source("model")
def model_figure(docs: Path, key: str) -> str:
    """A figure of ``mimo-radar-bench model-figures`` (results/model/figures.json), with its interval."""
    figures = read_json(docs, FIGURES_FILE)["figures"]
    if key not in figures:
        raise BenchError(f"{FIGURES_FILE} has no figure {key!r}; it has: {', '.join(figures)}")
    return format_figure(figures[key])


@generator("policy-cost")
def policy_cost(docs: Path) -> str:
    """``python -m benchmarks.speed.policy_cost``'s rows: every policy's measured / estimated time
    per trial-step at each trial count, and its peak memory per trial beside the declared at the
    largest, one column per layout and target count."""
    from ..speed.policy_cost import time_ratio

    record = read_json(docs, "perf/policy_cost.json")
    rows = record["rows"]
    largest = max(record["trials"])
    configs = sorted(
        {(r["M"], r["N"], r["Ms"], r["Ns"], r["K"]) for r in rows}, key=lambda c: (c[0] * c[1], c[4])
    )
    cells: dict[tuple, list[dict]] = {}
    for r in rows:
        cells.setdefault((r["policy"], (r["M"], r["N"], r["Ms"], r["Ns"], r["K"])), []).append(r)
    policies = sorted({r["policy"] for r in rows})
    header = " | ".join(f"{m} x {n}, K = {k}" for m, n, _, _, k in configs)
    lines = [f"| policy | {header} |", "|---|" + "---|" * len(configs)]
    for policy in policies:
        values = []
        for config in configs:
            measured = sorted(cells.get((policy, config), []), key=lambda r: r["trials"])
            if not measured:
                values.append("—")
                continue
            times = " · ".join(f"{time_ratio(r):.2f}" for r in measured)
            memory = next(r for r in measured if r["trials"] == largest)
            mib = f"{memory['measured_mib_per_trial']:.2f} / {memory['declared_mib_per_trial']:.2f} MiB"
            values.append(f"{times}; {mib}")
        lines.append(f"| `{policy}` | " + " | ".join(values) + " |")
    return "\n".join(lines)


@values("policy-cost")
def policy_cost_values(docs: Path) -> dict[str, str]:
    """policy_cost.json's run (``trials``: its trial counts, ``steps``, ``machine``), the largest
    measured / declared memory (``worst-memory``), measured / estimated time's ``time-range``
    and ``time-median`` over every row, and the rows outside 0.5 to 2 (``outside``: their
    count)."""
    from ..speed.policy_cost import time_ratio

    record = read_json(docs, "perf/policy_cost.json")
    rows = record["rows"]
    times = sorted(time_ratio(r) for r in rows)
    counts = [str(t) for t in record["trials"]]
    return {
        "trials": ", ".join(counts[:-1]) + " and " + counts[-1] if len(counts) > 1 else counts[0],
        "steps": str(record["steps"]),
        "machine": _machine(record["machine"]),
        "rows": str(len(rows)),
        "worst-memory": f"{max(r['measured_mib_per_trial'] / r['declared_mib_per_trial'] for r in rows):.2f}",
        "time-range": f"{times[0]:.2f} to {times[-1]:.2f}",
        "time-median": f"{times[len(times) // 2]:.2f}",
        "outside": str(sum(not 0.5 <= t <= 2 for t in times)),
    }


def _recipe_costs(docs: Path, page: str) -> str:
    """``python -m benchmarks.speed.recipes``' rows of ``page``: each Python recipe's wall time
    when run alone in a fresh interpreter (the interpreter's start and imports included)."""
    from ..speed.recipes import recipes

    record = read_json(docs, "perf/recipes.json")
    rows = [r for r in record["rows"] if r["page"] == page]
    current = [r for r in recipes(docs) if r.page == page]
    rerun = "run python -m benchmarks.speed.recipes --json docs/results/perf/recipes.json"
    if [(r["section"], r.get("sha256")) for r in rows] != [(r.section, r.digest) for r in current]:
        raise BenchError(f"the Python recipes of {page} changed since perf/recipes.json timed them: {rerun}")
    lines = ["| recipe | section | wall time, run alone |", "|---|---|---|"]
    for r in rows:
        cost = f"{r['seconds']:.1f} s" if "seconds" in r else f"not run here ({r['not_run']})"
        lines.append(f"| {r['index'] + 1} | {r['section']} | {cost} |")
    return "\n".join(lines)


@values("recipes")
def recipe_values(docs: Path) -> dict[str, str]:
    """recipes.json's ``command`` (as code) and ``machine``."""
    record = read_json(docs, "perf/recipes.json")
    return {"command": f"`{record['command']}`", "machine": _machine(record["machine"])}


for _page in ("clients.md", "ppo.md"):
    generator(f"recipe-costs-{_page.removesuffix('.md')}")(lambda docs, page=_page: _recipe_costs(docs, page))


#: The RL studies' committed results, each in its results folder of the same name: the SB3
#: learners' (``rl``) and torch-ppo's (``rl-device``).
RL_STUDIES = ("rl", "rl-device")


def rl_tables(docs: Path, folder: str = "rl") -> str:
    """An RL study's tables (``mimo-radar-bench rl``'s rl.md), from its committed rl.json."""
    from ..studies.rl import rl_markdown

    text = rl_markdown(read_json(docs, f"{folder}/rl.json"))
    body = text.split("\n", 2)[2].lstrip("\n")  # the page has its own headings, a level up
    return body.replace("\n## ", "\n### ").rstrip("\n")


#: The verdicts of a learner-minus-X ARMSE interval, by their keys in the values ``rl``.
AGAINST = {verdicts.HOLDS: "better", verdicts.CONTRADICTED: "worse", verdicts.CONSISTENT: "same"}
#: A longer training's ARMSE against the same seeds' at the study's budget, in words.
LONGER = {
    verdicts.HOLDS: "lower",
    verdicts.CONTRADICTED: "higher",
    verdicts.CONSISTENT: "not shown to differ",
}


def rl_values(docs: Path, folder: str = "rl") -> dict[str, str]:
    """What an RL study shows, from its rl.json and timing.json: ``wall``, ``cores``,
    ``training``, ``evaluation``, ``worker`` (the trainings' worker time), ``training-busy`` (the
    wall time in which a training ran, where rl.json records it), ``trials``, ``seeds``
    (where every learner has the same) and, where rl.json records them, ``training.device``,
    ``training.key`` (the hyperparameter entry), ``training.n-envs``, ``training.timesteps``
    and ``training.steps-per-trial``.

    Against X of the study's comparisons: ``X.pairs`` (learner, scenario and fusion triples)
    and, per verdict (``better``, ``worse``, ``same``: no difference shown), ``X.VERDICT`` how
    many and ``X.VERDICT.which``. The learning curves: ``flat-change`` (%), ``curves``,
    ``flat``, ``flat.which`` and ``moving.which``. With a budget sweep: ``sweep.budgets`` (those
    past the study's own), ``sweep.flat.which``, ``sweep.moving.which`` and, per budget T past
    the study's, ``sweep.T.minus-study`` (lower, higher, not shown to differ),
    ``sweep.T.difference`` (m), ``sweep.T.trained`` (T rounded up to whole rollouts, as trained),
    ``sweep.T.steps-per-trial``, and against best-tracking
    ``sweep.T.best-tracking`` (better, worse, same) with its ``.difference`` (m)."""
    from ..resources import duration

    judged = read_json(docs, f"{folder}/rl.json")
    timing = read_json(docs, f"{folder}/timing.json")
    parts = timing["parts_s"]
    table = {
        "wall": duration(timing["wall_s"]),
        "cores": str(timing["machine"]["cores"]),
        "training": duration(parts["training"]),
        "evaluation": duration(parts["evaluation"]),
        "worker": duration(judged["training_worker_s"]),
    }

    if "training_busy_s" in judged:  # the trainings' wall time over every invocation
        table["training-busy"] = duration(judged["training_busy_s"])
    table["trials"] = _one({e["trials"] for e in judged["scenarios"]}, "trials")
    counts = {r["seeds"] for e in judged["scenarios"] for r in e["learners"].values()}
    if len(counts) == 1:
        table["seeds"] = str(counts.pop())
    if "training" in judged:  # how the learners trained (recorded since the device study)
        record = judged["training"]
        table |= {
            "training.device": str(record["device"]),
            "training.key": f"`{record['hyperparams_key']}`",
            "training.n-envs": f"{record['n_envs']:,}",
            "training.timesteps": f"{record['trained_timesteps']:,}",
            "training.steps-per-trial": f"{record['trained_timesteps'] // record['n_envs']:,}",
        }

    return table | _rl_comparisons(judged) | _rl_curves(judged) | _rl_sweep(judged)


def _rl_where(entry: dict[str, Any]) -> str:
    return f"Scenario {entry['scenario']}, {entry['fusion']}"


def _rl_comparisons(judged: dict[str, Any]) -> dict[str, str]:
    """:func:`rl_values`' ``X.pairs``, ``X.VERDICT`` and ``X.VERDICT.which``."""
    from ..studies.rl import MINUS_ORDER

    table = {}
    for other in MINUS_ORDER:
        which: dict[str, list[str]] = {key: [] for key in AGAINST.values()}
        for entry in judged["scenarios"]:
            for key, row in entry["learners"].items():
                verdict = verdicts.verdict(row["minus"][other]["ci"], -1)
                which[AGAINST[verdict]].append(f"`{key}` in {_rl_where(entry)}")
        table[f"{other}.pairs"] = str(sum(map(len, which.values())))
        for verdict, listed in which.items():
            table[f"{other}.{verdict}"], table[f"{other}.{verdict}.which"] = str(len(listed)), _listed(listed)
    return table


def _rl_curves(judged: dict[str, Any]) -> dict[str, str]:
    """:func:`rl_values`' figures of the learning curves."""
    from ..studies.rl import FLAT_CHANGE

    curves = [(_rl_where(e), k, c) for e in judged["scenarios"] for k, c in e["curves"].items()]
    return {
        "flat-change": f"{100 * FLAT_CHANGE:.0f}",
        "curves": str(len(curves)),
        "flat": str(sum(bool(c["flat"]) for _, _, c in curves)),
        "flat.which": _listed([f"`{k}` ({w})" for w, k, c in curves if c["flat"]]),
        "moving.which": _listed(
            [f"`{k}` ({w}, {100 * c['change']:+.1f} %)" for w, k, c in curves if c["flat"] is False]
        ),
    }


def _rl_sweep(judged: dict[str, Any]) -> dict[str, str]:
    """:func:`rl_values`' figures of a budget sweep (none without one)."""
    if "sweep" not in judged:
        return {}
    rows = judged["sweep"]["budgets"]
    table = {
        "sweep.budgets": _listed([f"{row['timesteps']:,}" for row in rows[1:]]),
        "sweep.flat.which": _listed([f"{row['timesteps']:,}" for row in rows if row["curve"]["flat"]]),
        "sweep.moving.which": _listed(
            [
                f"{r['timesteps']:,} ({100 * r['curve']['change']:+.1f} %)"
                for r in rows
                if r["curve"]["flat"] is False
            ]
        ),
    }
    rollout = None
    if "training" in judged:  # a training runs whole rollouts: its budget rounded up to one
        from ..training import load_hyperparams

        record, algo = judged["training"], judged["sweep"]["learner"].rsplit("-", 1)[0]  # ALGO-REWARD
        rollout = record["n_envs"] * load_hyperparams(None, record["hyperparams_key"], algo)["n_steps"]
    for row in rows[1:]:
        budget, against = row["timesteps"], row["minus_best_tracking"]
        table[f"sweep.{budget}.minus-study"] = LONGER[verdicts.verdict(row["minus_study"]["ci"], -1)]
        if rollout is not None:
            trained = -(-budget // rollout) * rollout
            table[f"sweep.{budget}.trained"] = f"{trained:,}"
            table[f"sweep.{budget}.steps-per-trial"] = f"{trained // judged['training']['n_envs']:,}"
        table[f"sweep.{budget}.best-tracking"] = AGAINST[verdicts.verdict(against["ci"], -1)]
        for key, stat in (("difference", row["minus_study"]), ("best-tracking.difference", against)):
            table[f"sweep.{budget}.{key}"] = format_estimate(stat["value"], stat["ci"], "{:.3f}")
    return table


for _folder in RL_STUDIES:
    generator(f"{_folder}-tables")(lambda docs, folder=_folder: rl_tables(docs, folder))
    values(_folder)(lambda docs, folder=_folder: rl_values(docs, folder))


@values("coverage")
def coverage_values(docs: Path) -> dict[str, str]:
    """How often the across-seed interval covers (``python -m benchmarks.uncertainty``,
    results/rl/seed-coverage.json), with its Wilson interval over the simulated studies:
    ``GROUPS.N.STATISTIC`` (GROUPS ``one`` or ``three`` scenarios, N runs per scenario,
    STATISTIC ``mean`` or ``iqm``) and ``repeats``."""
    record = read_json(docs, "rl/seed-coverage.json")
    table = {"repeats": str(record["one_group"]["repeats"])}
    for groups, key in (("one_group", "one"), ("three_groups", "three")):
        entry = record[groups]
        for row in entry["coverage"]:
            for statistic in ("mean", "iqm"):
                table[f"{key}.{row['runs_per_group']}.{statistic}"] = _rate_with_interval(
                    row[statistic], entry["repeats"], unit=""
                )
    return table


#: The coverage tables' columns: the metrics each holds, and its paired differences' name.
_COVERAGE_COLUMNS = {
    "armse": (("armse",), "Δ ARMSE's"),
    "means": (("asr", "final_regret"), "Δ ASR's or Δ final regret's"),
    "sinr": (("mean_sinr_db",), "Δ mean SINR's"),
}


@values("trial-coverage")
def trial_coverage_values(docs: Path) -> dict[str, str]:
    """How often the intervals of runs of fewer trials cover the value of the run they are drawn
    from (``python -m benchmarks.uncertainty --run DIR``, results/uncertainty/trial-coverage.json):
    ``armse.N``, ``means.N`` (ASR, final regret) and ``sinr.N`` (mean SINR), the lowest and the
    highest rate over the policies on N trials, each with its Wilson interval, and
    ``pairs.armse.N``, ``pairs.means.N`` and ``pairs.sinr.N`` the same over the pairs' paired
    differences (``pairs``, how many pairs; ``pairs.gap``, in points, how far the pairs' lowest
    rate in a column is at most below the policies' from :data:`~benchmarks.uncertainty.FEW_TRIALS`
    trials on; ``pairs.few``, below it, in how many columns and counts the pairs' lowest rate is
    below the policies', and the largest such gap); ``extended.N``, how many of
    the ARMSE intervals on N trials were extended to their value, of how many; ``level.N``, the
    bootstrap's confidence level on N trials; ``population`` (its trials), ``scenario``,
    ``fusion`` and ``repeats``."""
    record = read_json(docs, "uncertainty/trial-coverage.json")
    table = {
        "population": str(record["population_trials"]),
        "scenario": record["run"]["scenario"],
        "fusion": record["run"]["fusion"],
        "repeats": str(record["repeats"]),
    }
    # how far each column's lowest rate of a pair is below a policy's, from FEW_TRIALS on and below
    gaps: list[tuple[float, str, int]] = []
    few_gaps: list[tuple[float, str, int]] = []
    for row in record["rows"]:
        lowest_of = {}
        for prefix, counts in (("", row), ("pairs.", row["differences"])):
            for key, (names, _) in _COVERAGE_COLUMNS.items():
                rates = {n: r for n, r in counts["coverage"].items() if n.rsplit(".", 1)[1] in names}
                lowest, highest = min(rates, key=rates.__getitem__), max(rates, key=rates.__getitem__)
                table[f"{prefix}{key}.{row['trials']}"] = " to ".join(
                    _rate_with_interval(rates[n], counts["studies"][n]) for n in (lowest, highest)
                )
                lowest_of[prefix, key] = round(100 * rates[lowest], 1)  # as printed
        for key in _COVERAGE_COLUMNS:
            gap = lowest_of["", key] - lowest_of["pairs.", key]
            (gaps if row["trials"] >= uncertainty.FEW_TRIALS else few_gaps).append((gap, key, row["trials"]))
        armse = [n for n in row["coverage"] if n.endswith(".armse")]
        extended, judged = (sum(row[field][n] for n in armse) for field in ("extended", "studies"))
        table[f"extended.{row['trials']}"] = f"{extended:,} of {judged:,}"
        table[f"level.{row['trials']}"] = f"{100 * row['confidence_level']:.1f} %"
    table["pairs"] = str(len({n.rsplit(".", 1)[0] for n in record["rows"][0]["differences"]["coverage"]}))
    if gaps:
        table["pairs.gap"] = f"{max(gaps)[0]:.1f}"
    if few_gaps:
        gap, key, trials = max(few_gaps)
        lower = sum(g > 0 for g, _, _ in few_gaps)
        table["pairs.few"] = (
            f"in {lower} of the {len(few_gaps)} columns and counts, by up to {gap:.1f} points "
            f"({_COVERAGE_COLUMNS[key][1]} on {trials} trials)"
        )
    return table


def _rate_with_interval(rate: float, trials: int, unit: str = " %") -> str:
    """A fraction of ``trials`` as a percentage with its 95 % Wilson interval (``model_figures.rate``);
    ``unit`` after the value (empty where the page writes the % after the interval)."""
    figure = model_figures.rate(np.arange(trials) < round(rate * trials), "")
    low, high = figure["ci"]
    return f"{100 * rate:.1f}{unit} [{100 * low:.1f}, {100 * high:.1f}]"


@generator("bpso-parts")
def bpso_parts_table(docs: Path) -> str:
    """``bpso_parts.json`` (measured at commit bb595a0): under each position rule, what each part of
    the whole swarm costs."""

    r = read_json(docs, "perf/bpso_parts.json")
    breakdowns = r["breakdowns"]
    header = "| part knocked out of the whole swarm |"
    rule_line = "|---|"
    for b in breakdowns:
        header += f" rule {b['rule']}: without it (ms) | the part's cost (ms) | share |"
        rule_line += "---|---|---|"
    lines = [header, rule_line]
    for i, row in enumerate(breakdowns[0]["parts"]):
        line = f"| {row['part']} |"
        for b in breakdowns:
            part = b["parts"][i]
            if part["part"] != row["part"]:
                raise ValueError(
                    f"bpso_parts.json: the rules' parts differ ({part['part']!r}, {row['part']!r})"
                )
            line += f" {part['without_ms']:.1f} | {part['cost_ms']:.1f} | {100 * part['share']:.0f} % |"
        lines.append(line)
    return "\n".join(lines)


@values("bpso-parts")
def bpso_parts_values(docs: Path) -> dict[str, str]:
    """``bpso_parts.json``: ``trials``; per rule R, ``R.whole`` the whole swarm (ms), its trials'
    ``R.iterations`` of ``R.q-max`` on average and ``R.all-iterations`` (%) running them all,
    ``R.estimate`` the kernel so estimated against ``R.kernel`` measured (ms), ``R.less`` the
    whole swarm over the kernel, ``R.reference`` the kernel it replaced (ms), ``R.speedup`` the
    target, ``R.budget`` (ms) what it leaves and ``R.kernel-against`` (within or above it);
    ``R.without-polynomial`` (ms) the whole swarm without eq21's polynomial, ``R.free`` (ms) a
    kernel whose eq21 decision cost nothing and ``R.free-against``; ``float32-trials``."""
    from ..speed.perf import TARGETS

    r = read_json(docs, "perf/bpso_parts.json")
    table = {"trials": str(r["trials"])}
    for b in r["breakdowns"]:
        rule, whole, kernel, q_max = b["rule"], b["whole_swarm_ms"], b["kernel_ms"], b["q_max"]
        share = b["mean_iterations"] / q_max
        speedup = TARGETS[f"bpso_speedup_vs_reference_{rule}"][1]
        budget = b["reference_ms"] / speedup
        without = next(row for row in b["parts"] if "polynomial" in row["part"])["without_ms"]
        table |= {
            f"{rule}.whole": f"{whole:.1f}",
            f"{rule}.iterations": f"{b['mean_iterations']:.1f}",
            f"{rule}.q-max": str(q_max),
            f"{rule}.all-iterations": f"{100 * b['share_all_iterations']:.1f}",
            f"{rule}.estimate": f"{whole * share:.1f}",
            f"{rule}.kernel": f"{kernel:.1f}",
            f"{rule}.less": f"{whole / kernel:.1f}",
            f"{rule}.reference": f"{b['reference_ms']:.1f}",
            f"{rule}.speedup": f"{speedup:g}",
            f"{rule}.budget": f"{budget:.1f}",
            f"{rule}.kernel-against": "within" if kernel <= budget else "above",
            f"{rule}.without-polynomial": f"{without:.1f}",
            f"{rule}.free": f"{without * share:.1f}",
            f"{rule}.free-against": "within" if without * share <= budget else "above",
        }
    table["float32-trials"] = str(r["float32"]["trials"])
    return table


@generator("bpso-float32")
def bpso_float32_table(docs: Path) -> str:
    """``bpso_parts.json``'s float32 transcription of the kernel beside the kernel and the kernel
    it replaced, under each rule."""
    from ..speed.perf import TARGETS

    r = read_json(docs, "perf/bpso_parts.json")
    lines = [
        "| rule | the kernel (ms) | in float32 (ms) | the kernel it replaced (ms) | speed-up over it: "
        "the kernel, in float32 | target | optimal selections (95 % Wilson interval): the kernel, "
        "in float32, the kernel it replaced |",
        "|---|---|---|---|---|---|---|",
    ]
    for rule, row in r["float32"]["rules"].items():
        target = TARGETS[f"bpso_speedup_vs_reference_{rule}"][1]
        kernel, float32 = (row["reference_ms"] / row[f"{k}_ms"] for k in ("kernel", "float32"))
        rates = ", ".join(
            _rate_with_interval(row[f"{k}_optimality_rate"], r["float32"]["trials"])
            for k in ("kernel", "float32", "reference")
        )
        reach = (
            "both reach it"
            if min(kernel, float32) >= target
            else ("float32 alone reaches it" if float32 >= target else "neither reaches it")
        )
        lines.append(
            f"| {rule} | {row['kernel_ms']:.1f} | {row['float32_ms']:.1f} | {row['reference_ms']:.1f} | "
            f"{kernel:.1f}x, {float32:.1f}x | >= {target:g}x: {reach} | {rates} |"
        )
    return "\n".join(lines)


@values("without-numba")
def without_numba_values(docs: Path) -> dict[str, str]:
    """``solver_speed.json`` (``solver_speed --write``): ``trials``, ``repeats``, ``cores``; per
    namespace N (``numpy``, ``torch_cpu``) and rule R, BPSO's iterations with each trial stopping
    at its optimum, ``N.R.stopping``, and every trial running every iteration, ``N.R.every`` (ms),
    and ``N.R.ratio``, the second over the first."""
    r = read_json(docs, "perf/solver_speed.json")
    table = {"trials": f"{r['trials']:,}", "repeats": str(r["repeats"]), "cores": str(r["machine"]["cores"])}
    for name in ("numpy", "torch_cpu"):
        for rule in ("xor", "set"):
            stopping = r[f"bpso_{name}_iterations_ms_{rule}"]
            every = r[f"bpso_{name}_every_iteration_ms_{rule}"]
            table |= {
                f"{name}.{rule}.stopping": f"{stopping:.0f}",
                f"{name}.{rule}.every": f"{every:.0f}",
                f"{name}.{rule}.ratio": f"{every / stopping:.1f}",
            }
    return table


@values("first-run")
def first_run_values(docs: Path) -> dict[str, str]:
    """``python -m benchmarks.speed.first_run``: the quickstart's first run against its second,
    after the README's compile step and without it, each from an empty numba cache. ``command``,
    ``compile-command`` (as code), ``repeats``, ``load``; per repeat, ``compile``, ``after-compile`` and
    ``without`` (first against second, s); ``median-after``, ``largest-after``, ``target`` and
    ``met``; ``median-without`` and ``largest-without`` (first / second)."""
    from ..speed.first_run import TARGET

    r = read_json(docs, "perf/first_run.json")
    repeats = r["repeats"]
    return {
        "command": f"`{' '.join(r['command'])}`",
        "compile-command": f"`{' '.join(r['compile_command'])}`",
        "repeats": str(len(repeats)),
        "load": f"{r['machine']['load_average_1min']:.2f}",
        "compile": "; ".join(f"{p['compile_s']:.1f} s" for p in repeats),
        "after-compile": "; ".join(f"{p['first_after_compile_s']:.1f} s" for p in repeats),
        "without": "; ".join(f"{p['first_s']:.1f} s against {p['second_s']:.1f} s" for p in repeats),
        "median-after": f"{r['median_ratio_after_compile']:.2f}",
        "largest-after": f"{r['max_ratio_after_compile']:.2f}",
        "target": f"{TARGET:g}",
        "met": "met" if r["max_ratio_after_compile"] <= TARGET else "**missed**",
        "median-without": f"{r['median_ratio']:.2f}",
        "largest-without": f"{r['max_ratio']:.2f}",
    }


@generator("step-stages")
def step_stages(docs: Path) -> str:
    """``python -m benchmarks.speed.stages``' rows: each stage's time per step, its share, the
    arithmetic it declares and the rate that makes, and the floor the same arithmetic would take
    at an assumed accelerator rate."""
    from ..speed.stages import ASSUMED_ACCELERATOR_OPS

    record = read_json(docs, "perf/stages.json")
    rows = record["rows"]
    totals = {f: sum(r["ms_per_step"] for r in rows if r["fusion"] == f) for f in ("average", "centralized")}
    lines = [
        "| fusion | stage | ms per step | share of the env step | declared operations per trial | "
        "achieved rate (operations/s) | arithmetic alone at the assumed accelerator rate (ms) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        share = f"{100 * r['ms_per_step'] / totals[r['fusion']]:.0f} %" if r["fusion"] in totals else "—"
        ops = r.get("declared_operations_per_trial")
        rate = r.get("achieved_operations_per_s")
        floor = "—" if ops is None else f"{1e3 * ops * record['trials'] / ASSUMED_ACCELERATOR_OPS:.3f}"
        lines.append(
            f"| {r['fusion']} | {r['stage']} | {r['ms_per_step']:.2f} | {share} | "
            f"{'—' if ops is None else f'{ops:,.0f}'} | {'—' if rate is None else f'{rate:.2e}'} | {floor} |"
        )
    return "\n".join(lines)


@values("stages")
def stage_values(docs: Path) -> dict[str, str]:
    """stages.json's run (``scenario``, ``trials``, ``steps``, ``machine``), per fusion the env
    step's largest stage ``largest.FUSION`` and its ``largest.FUSION.share`` (%), and the
    ``accelerator-rate`` assumed (float64 operations per second)."""
    from ..speed.stages import ASSUMED_ACCELERATOR_OPS

    record = read_json(docs, "perf/stages.json")
    rows = record["rows"]
    table = {
        "scenario": record["scenario"],
        "trials": str(record["trials"]),
        "steps": str(record["steps"]),
        "machine": _machine(record["machine"]),
        "accelerator-rate": f"{ASSUMED_ACCELERATOR_OPS:.0e}",
    }
    for fusion in ("average", "centralized"):
        mine = [r for r in rows if r["fusion"] == fusion]
        largest = max(mine, key=lambda r: r["ms_per_step"])
        table[f"largest.{fusion}"] = largest["stage"]
        table[f"largest.{fusion}.share"] = (
            f"{100 * largest['ms_per_step'] / sum(r['ms_per_step'] for r in mine):.0f}"
        )
    return table


# ------------------------------------------------------------------ the engine on a device
DEVICE_FILE = "perf/device.json"
DEVICE_CHECKS_FILE = "perf/device-checks.json"
#: The speed rows' backends by a short key (value spans name them): the backend's label begins so.
#: A backend of the device figures: the start of its rows' name, the form of the step and the
#: precision.
DEVICE_BACKENDS = {
    "numpy": ("numpy + numba", "eager", "float64"),
    "torch-cpu": ("torch cpu", "eager", "float64"),
    "device": ("torch cuda", "eager", "float64"),
    "device-graph": ("torch cuda", "graph", "float64"),
    "device-compiled": ("torch cuda", "compiled", "float64"),
    "device-float32": ("torch cuda", "eager", "float32"),
    "device-graph-float32": ("torch cuda", "graph", "float32"),
}


def _trials_grid(
    rows: list[dict[str, Any]], keys: tuple[str, ...], labels: tuple[str, str] | None = None
) -> tuple[list[int], list[str], dict[tuple[Any, ...], dict[int, dict[str, Any]]]]:
    """A table with a column per trial count B: the counts, its header lines, and the rows grouped
    by ``keys`` and then by B; two first columns, headed ``labels`` (default the keys, two)."""
    sizes = sorted({r["trials"] for r in rows})
    header = " | ".join(labels or keys)
    lines = [
        f"| {header} | " + " | ".join(f"B = {b:,d}" for b in sizes) + " |",
        "|---|---|" + "---|" * len(sizes),
    ]
    groups: dict[tuple[Any, ...], dict[int, dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in keys), {})[r["trials"]] = r
    return sizes, lines, groups


def _rate(rate: float) -> str:
    return f"{rate / 1e6:.2f} M" if rate >= 1e6 else f"{rate / 1e3:,.0f} k"


#: The float32 run's equality rows (``--precisions float32 --skip-speed``), on CPU torch.
FLOAT32_FILE = "perf/float32.json"
#: The entries the float32 table gives beside the largest, by column.
FLOAT32_ENTRIES = {"truth": "info.true_state", "tracks": "obs.track", "SINR reward": "reward"}
#: The columns of an equality table that say how a row ran: (header, the row's cell).
RUN_COLUMNS: dict[str, Callable[[dict[str, Any]], Any]] = {
    "form": lambda e: e.get("mode", "eager"),
    "precision": lambda e: e.get("precision", "float64"),
    "trials": lambda e: e["trials"],
    "steps": lambda e: e["steps"],
}


def _oracle_agreement(share: float) -> str:
    return "identical" if share == 0 else f"differ in {100 * share:.2g} % of trial-steps"


def _equality_table(record: dict[str, Any], run: tuple[str, ...], entries: dict[str, str]) -> str:
    """The equality rows of a ``benchmarks.speed.device`` run: per version and fusion, the
    ``run`` columns of :data:`RUN_COLUMNS` (rows from before forms or precisions were recorded
    are eager float64), the largest normwise relative difference from numpy and the entry it was
    found in, the ``entries`` columns, and whether the oracle's actions agreed."""
    head = ["env", "fusion", *run, "largest relative difference", "in", *entries, "oracle's actions"]
    rows = []
    for e in record["equality"]:
        cells = [f"MimoRadarSelect-{e['version']}", e["fusion"], *(RUN_COLUMNS[c](e) for c in run)]
        cells += [f"{e['largest']:.1e}", f"`{e['largest_entry']}`"]
        cells += [f"{e['differences'][key]:.1e}" for key in entries.values()]
        rows.append([*cells, _oracle_agreement(e["differences"]["oracle_action"])])
    return markdown_table(head, rows)


@generator("device-equality")
def device_equality(docs: Path) -> str:
    """``python -m benchmarks.speed.device``'s equality on the device: the torch engine against the
    numpy engine over episodes (:func:`_equality_table`), with the trials and the steps as columns
    where they differ between rows (else said under the table: ``equality-trials`` and
    ``equality-steps`` of :func:`device_value`)."""
    record = read_json(docs, DEVICE_FILE)
    varying = [c for c in RUN_COLUMNS if len({RUN_COLUMNS[c](e) for e in record["equality"]}) > 1]
    run = tuple(c for c in RUN_COLUMNS if c in ("form", "precision") or c in varying)
    return _equality_table(record, run, {})


@generator("float32-equality")
def float32_equality(docs: Path) -> str:
    """The float32 engine against the numpy engine over whole episodes (:func:`_equality_table`;
    its trials and steps are said under it), with the truth, the tracks and the reward apart."""
    return _equality_table(read_json(docs, FLOAT32_FILE), (), FLOAT32_ENTRIES)


@value_source("float32")
def float32_value(docs: Path, key: str) -> str:
    """A figure of the float32 run (results/perf/float32.json): ``machine``, ``device``,
    ``trials``, ``steps``, or ``largest.ENTRY`` the largest difference of an entry
    (``obs.track``...) over its rows, ``largest`` over every entry."""
    record = read_json(docs, FLOAT32_FILE)
    rows = record["equality"]
    if key in ("machine", "device"):
        return str(record[key])
    if key in ("trials", "steps"):
        return f"{rows[0][key]:,}"
    if key == "largest":
        return f"{max(r['largest'] for r in rows):.1e}"
    entry = key.removeprefix("largest.")
    if key.startswith("largest.") and all(entry in r["differences"] for r in rows):
        return f"{max(r['differences'][entry] for r in rows):.1e}"
    raise BenchError(
        f"unknown float32 figure {key!r}: machine, device, trials, largest, largest.ENTRY "
        f"(an entry of {FLOAT32_FILE}'s differences)"
    )


@generator("device-speed")
def device_speed(docs: Path) -> str:
    """``python -m benchmarks.speed.device``'s speed rows: trial-steps per second of the whole v1
    step per backend, fusion and trial count, with the time of a step and the device's peak
    memory."""
    record = read_json(docs, DEVICE_FILE)
    sizes, lines, groups = _trials_grid(record["speed"], ("backend", "fusion"))
    for (backend, fusion), rows in groups.items():
        cells = []
        for b in sizes:
            r = rows.get(b)
            if r is None:
                cells.append("—")
            elif "skipped" in r:
                cells.append(f"not run ({r['skipped']})")
            else:
                memory = r.get("peak_device_memory_gib")
                extra = "" if memory is None else f", {memory:.1f} GiB"
                cells.append(f"{_rate(r['trial_steps_per_s'])} ({1e3 * r['seconds_per_step']:.1f} ms{extra})")
        lines.append(f"| {backend} | {fusion} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


@value_source("device")
def device_value(docs: Path, key: str) -> str:
    """A figure of ``python -m benchmarks.speed.device`` (results/perf/device.json):
    ``rate.BACKEND.FUSION.TRIALS`` (BACKEND one of DEVICE_BACKENDS), ``ratio.BACKEND.BACKEND.
    FUSION.TRIALS`` (the first's rate over the second's), ``largest-difference`` (float64's),
    ``equality-trials`` and ``equality-steps`` (the same in every equality row), ``device`` (its
    name), ``device-id``, ``tolerance``, ``scenario``, ``machine``, and
    ``checks.FIELD`` a field of results/perf/device-checks.json (``checks.RECORD.FIELD`` one of
    its records')."""
    if key in ("device-id", "tolerance", "scenario", "machine"):  # the run's own fields
        record = read_json(docs, DEVICE_FILE)
        field = {
            "device-id": "device",
            "tolerance": "tolerance",
            "scenario": "scenario",
            "machine": "machine",
        }[key]
        return f"{record[field]:.0e}" if key == "tolerance" else str(record[field])
    if key.startswith("checks."):  # results/perf/device-checks.json: what device runs recorded
        found: Any = read_json(docs, DEVICE_CHECKS_FILE)
        for field in key.split(".")[1:]:
            if not isinstance(found, dict) or field not in found:
                have = ", ".join(found) if isinstance(found, dict) else "no fields"
                raise BenchError(f"{DEVICE_CHECKS_FILE} has no {key[7:]!r} ({field!r}; there: {have})")
            found = found[field]
        return f"{found:,}" if isinstance(found, int) else str(found)
    record = read_json(docs, DEVICE_FILE)
    if key in ("equality-trials", "equality-steps"):  # the same in every equality row
        values = {e[key.split("-")[1]] for e in record["equality"]}
        if len(values) != 1:
            raise BenchError(f"{DEVICE_FILE}'s equality rows differ in {key}: {sorted(values)}")
        return f"{values.pop():,}"
    if key == "largest-difference":
        double = [e["largest"] for e in record["equality"] if e.get("precision", "float64") == "float64"]
        return f"{max(double):.1e}"
    if key == "device":
        return record["device_name"]
    kind, *parts = key.split(".")

    def rate(backend: str, fusion: str, trials: str) -> float:
        prefix, mode, precision = DEVICE_BACKENDS.get(backend, ("", "", ""))
        for r in record["speed"]:
            if (
                prefix
                and r["backend"].startswith(prefix)
                and r.get("mode", "eager") == mode
                and r.get("precision", "float64") == precision
                and "products" not in r  # a row timed with another's products (--library-products)
                and r["fusion"] == fusion
                and r["trials"] == int(trials)
            ):
                if "trial_steps_per_s" in r:
                    return r["trial_steps_per_s"]
        raise BenchError(f"{DEVICE_FILE} has no measured row {backend}, {fusion}, B = {trials}")

    if kind == "rate" and len(parts) == 3:
        return _rate(rate(*parts))
    if kind == "ratio" and len(parts) == 4:
        return f"{rate(parts[0], *parts[2:]) / rate(parts[1], *parts[2:]):.1f}"
    raise BenchError(
        f"unknown device figure {key!r}: rate:BACKEND:FUSION:B, ratio:A:B:FUSION:B, largest-difference"
    )


LAUNCHES_FILE = "perf/launches.json"
#: The counts of a row of results/perf/launches.json, in its table's order.
LAUNCH_COUNTS = (
    "act",
    "act_replayed",
    "act_dispatches_on_cuda",
    "update",
    "env_step",
    "env_step_bytes_per_trial",
    "env_step_bandwidth_bound",
)


@generator("device-launches")
def device_launches(docs: Path) -> str:
    """``python -m benchmarks.speed.launches``: torch operations per step of each policy's act
    (those in a replayed graph apart, and the dispatches left on CUDA), its update and the env's
    eager step, with the bytes that step moves per trial and the rate an H200's bandwidth allows
    it, per fusion."""
    head = [
        "policy",
        "fusion",
        "operations per act",
        "of them replayed as one graph on CUDA",
        "dispatches per act on CUDA (a graph's replay one)",
        "operations per update",
        "operations per env step (eager)",
        "bytes an env step reads and writes, per trial",
        "trial-steps/s an H200's bandwidth allows it",
    ]
    rows = [
        [r["policy"], r["fusion"], *(f"{r[c]:,.0f}" for c in LAUNCH_COUNTS[:-1])]
        + [f"{r['env_step_bandwidth_bound'] / 1e6:.1f} M"]
        for r in read_json(docs, LAUNCHES_FILE)["rows"]
    ]
    return markdown_table(head, rows)


#: The fields of MG-CRB-CL's compiled act in results/perf/launches.json (``compiled_act``).
COMPILED_ACT = ("act", "act_replayed", "compiled_calls", "fused", "library", "compile_s")


@value_source("launches")
def launches_value(docs: Path, key: str) -> str:
    """A count of results/perf/launches.json: ``FIELD.POLICY.FUSION`` (FIELD one of
    :data:`LAUNCH_COUNTS`: the operations, and the eager step's bytes per trial and the rate an
    H200's bandwidth allows it), ``trials``, or the
    calls of the step compiled on the CPU, ``compiled.fused.FUSION`` and ``compiled.library.FUSION``,
    with the same env's eager operations, ``compiled.eager.FUSION``, and the seconds of the
    compiled env's first step, of a second one's and of a new process's,
    ``compiled.compile_s.FUSION``, ``compiled.again_s.FUSION`` and
    ``compiled.new_process_s.FUSION``; MG-CRB-CL's act in the compiled form, ``compiled-act.FIELD``
    (FIELD one of :data:`COMPILED_ACT`)."""
    record = read_json(docs, LAUNCHES_FILE)
    if key == "trials":
        return f"{record['rows'][0]['trials']:,}"
    if key.startswith("compiled-act."):
        field = key.partition(".")[2]
        act = record.get("compiled_act", {})
        if field not in COMPILED_ACT or field not in act or act["trials"] != record["rows"][0]["trials"]:
            raise BenchError(
                f"{LAUNCHES_FILE} has no {key!r}: compiled-act.FIELD, FIELD one of {COMPILED_ACT}"
            )
        return f"{act[field]:.1f}" if field == "compile_s" else f"{act[field]:,}"
    if key.startswith("compiled."):
        _, kind, fusion = key.split(".", 2)
        for r in record.get("compiled", []):
            at = (r["fusion"], r["trials"], r.get("device", "cpu"))
            if at != (fusion, record["rows"][0]["trials"], "cpu"):
                continue
            if kind in ("fused", "library", "eager"):
                return f"{r[kind]:,}"
            if kind in ("compile_s", "again_s", "new_process_s") and kind in r:
                return f"{r[kind]:.1f}"
        raise BenchError(
            f"{LAUNCHES_FILE} has no {key!r}: "
            "compiled.(fused|library|eager|compile_s|again_s|new_process_s).FUSION"
        )
    field, _, rest = key.partition(".")
    policy, _, fusion = rest.rpartition(".")
    for r in record["rows"]:
        if (r["policy"], r["fusion"]) == (policy, fusion) and field in LAUNCH_COUNTS:
            return f"{r[field]:,.0f}"
    raise BenchError(
        f"{LAUNCHES_FILE} has no {key!r}: FIELD.POLICY.FUSION, FIELD one of {LAUNCH_COUNTS}, or trials"
    )


# ------------------------------------------------------------------ PPO training throughput
TRAINING_FILE = "perf/training.json"
TRAININGS_FILE = "perf/torch-ppo-trainings.json"


def _training_rate(record: dict[str, Any], learner: str, device: str, trials: int) -> float:
    for r in record["rows"]:
        row = (r["learner"], r["device"], r["trials"], r.get("processes", 1))
        if row == (learner, device, trials, 1) and "env_steps_per_s" in r:
            return r["env_steps_per_s"]
    raise BenchError(f"{TRAINING_FILE} has no measured row {learner}, {device}, B = {trials}")


@generator("ppo-training-rate")
def ppo_training_rate(docs: Path) -> str:
    """``python -m benchmarks.speed.training_rate``'s rows: env steps per second of PPO training
    end to end, per learner, where it runs (and how many trainings at once share the device) and
    parallel trials B, with the device's peak memory."""
    record = read_json(docs, TRAINING_FILE)
    measured = [{"processes": 1, **r} for r in record["rows"]]
    sizes, lines, groups = _trials_grid(measured, ("learner", "device", "processes"), ("learner", "runs on"))
    names = {"numpy": "CPU, numpy env, 1 thread", "cpu": "CPU torch, 1 thread"}
    for (learner, device, processes), rows in groups.items():
        cells = []
        for b in sizes:
            r = rows.get(b)
            if r is None or "env_steps_per_s" not in r:
                cells.append("not run" if r is None else f"not run ({r['skipped']})")
                continue
            memory = r.get("peak_device_memory_gib")
            cells.append(f"{r['env_steps_per_s']:,.0f}" + ("" if memory is None else f" ({memory:.1f} GiB)"))
        where = names.get(device, f"{record.get('device_name', device)} ({device})")
        if processes > 1:
            where += f", {processes} trainings at once (their steps over their span)"
        lines.append(
            f"| {'SB3 PPO' if learner == 'sb3' else learner} | {where} | " + " | ".join(cells) + " |"
        )
    return "\n".join(lines)


@value_source("training")
def training_value(docs: Path, key: str) -> str:
    """A figure of the PPO training benchmark (results/perf/training.json): ``rate.LEARNER.DEVICE.B``
    and ``ratio.LEARNER.DEVICE.B.LEARNER.DEVICE.B`` (the first's rate over the second's); or of
    the 48 device trainings (results/perf/torch-ppo-trainings.json): ``trainings.FIELD``; the
    benchmark's ``scenario`` and ``n-steps`` (a rollout's steps per trial)."""
    if key in ("scenario", "n-steps"):
        record = read_json(docs, TRAINING_FILE)
        return record["scenario"] if key == "scenario" else str(record["rows"][0]["n_steps"])
    if key.startswith("trainings."):
        record = read_json(docs, TRAININGS_FILE)
        field = key.split(".", 1)[1]
        if field not in record or isinstance(record[field], dict):
            raise BenchError(f"{TRAININGS_FILE} has no figure {field!r}")
        value = record[field]
        return (
            f"{value:,}"
            if isinstance(value, int)
            else f"{value:,.0f}"
            if isinstance(value, float)
            else str(value)
        )
    record = read_json(docs, TRAINING_FILE)
    kind, *parts = key.split(".")
    if kind == "rate" and len(parts) == 3:
        return f"{_training_rate(record, parts[0], parts[1], int(parts[2])):,.0f}"
    if kind == "ratio" and len(parts) == 6:
        first = _training_rate(record, parts[0], parts[1], int(parts[2]))
        return f"{first / _training_rate(record, parts[3], parts[4], int(parts[5])):.0f}"
    raise BenchError(
        f"unknown training figure {key!r}: rate.LEARNER.DEVICE.B, ratio.(LEARNER.DEVICE.B)x2, trainings.FIELD"
    )


# ------------------------------------------------------------------ strong scaling
SCALING_FILES = {
    "2 cores": "perf/strong-scaling.json",
    # before the fork server, and each policy's intervals and judge terms computed as it ends
    "2 cores, at 764dcf1": "perf/strong-scaling-764dcf1.json",
    # before a run's end joined its shards from memory and its workers exited at once
    "2 cores, at 496aa87": "perf/strong-scaling-496aa87.json",
    "2 cores, at 601a6e2": "perf/strong-scaling-601a6e2.json",  # before a run's end read its shards once
    "2 cores, at ef5e440": "perf/strong-scaling-ef5e440.json",  # before the report shared its terms
    "16 cores": "perf/strong-scaling-16-cores.json",
    "16 cores, centralised, at a0aed49": "perf/strong-scaling-16-cores-centralized.json",
}
#: The value spans' names of the strong-scaling runs (``scaling MACHINE.KIND.W``).
SCALING_MACHINES = {
    "2": "2 cores",
    "2-764dcf1": "2 cores, at 764dcf1",
    "2-496aa87": "2 cores, at 496aa87",
    "2-601a6e2": "2 cores, at 601a6e2",
    "2-ef5e440": "2 cores, at ef5e440",
    "16": "16 cores",
    "16-centralized": "16 cores, centralised, at a0aed49",
}


@generator("strong-scaling")
def strong_scaling(docs: Path) -> str:
    """``python -m benchmarks.speed.strong_scaling``'s measured rows on each machine, with the
    worker-seconds by where they went, and the model's predictions."""
    lines = [
        "| machine | workers | wall (s) | efficiency | shard | us per trial-step in tasks | "
        "in the tasks | idle at the tail | outside the tasks |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for machine, relative in SCALING_FILES.items():
        record = read_json(docs, relative)
        alone = len(record["measured"]) == 1  # its efficiency is against itself: none shown
        for r in record["measured"]:
            parts = r["breakdown"]
            total = parts["worker_seconds"]
            share = {k: f"{100 * parts[k] / total:.0f} %" for k in parts}
            tasks = 100 * (parts["task_steps_s"] + parts["task_fixed_s"]) / total
            lines.append(
                f"| {machine} | {r['workers']} | {_with_interval(r, 'wall_s', '.1f')} | "
                f"{'—' if alone else _with_interval(r, 'efficiency', '.2f')} | "
                f"{r['shard_trials']} | {r['us_per_trial_step_in_tasks']:.1f} | {tasks:.0f} % | "
                f"{share['tail_idle_s']} | {share['outside_tasks_s']} |"
            )
    lines += [
        "",
        "| machine | model from | workers | schedule | shards (trials) | predicted wall (s) | measured (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for machine, relative in SCALING_FILES.items():
        record = read_json(docs, relative)
        measured = {(r["workers"], r.get("schedule", "uniform")): r["wall_s"] for r in record["measured"]}
        for m in record["model"]:
            schedule = m.get("schedule", "uniform")
            seen = measured.get((m["workers"], schedule))
            lines.append(
                f"| {machine} | {record['model_from_workers']} workers | {m['workers']} | {schedule} | "
                f"{_shard_sizes(m)} | {m['wall_s']:.1f} | {'—' if seen is None else f'{seen:.1f}'} |"
            )
    return "\n".join(lines)


def _with_interval(row: dict[str, Any], key: str, fmt: str) -> str:
    """A measured row's mean and, where it was measured more than once, its 95 % t interval."""
    interval = row.get(f"{key}_ci")
    value = format(row[key], fmt)
    if interval is None or interval[0] == interval[1]:  # one run, or the base count's own efficiency
        return value
    return f"{value} [{format(interval[0], fmt)}, {format(interval[1], fmt)}]"


def _shard_sizes(row: dict[str, Any]) -> str:
    """A model row's shard sizes: one number where every policy's are the same."""
    sizes = row.get("shard_sizes") or {}
    largest = row["shard_size"]
    smaller = [f"{p} {n}" for p, n in sizes.items() if n != largest]
    return ", ".join([*smaller, f"the rest {largest}"]) if smaller else str(largest)


@value_source("scaling")
def scaling_value(docs: Path, key: str) -> str:
    """A figure of the strong-scaling runs: ``MACHINE.wall.W``, ``MACHINE.efficiency.W``,
    ``MACHINE.model.W`` (predicted wall, every policy's trials in as many shards),
    ``MACHINE.model-by-cost.W`` (predicted wall, shards sized by cost), ``MACHINE.us.W`` (us per
    trial-step in the tasks),
    ``MACHINE.outside-per-worker.W`` (seconds outside the tasks per worker), ``MACHINE.before.W``
    and ``MACHINE.after.W`` (wall seconds before the first task and after the last),
    ``MACHINE.probe-ratio.W`` (the tasks probed on one core at W's shard size over those at the
    shard size of the count the model starts from), ``MACHINE.fixed.W`` (the seconds of all the
    tasks' fixed parts: agent, env, first step), ``MACHINE.tasks.W`` (how many tasks) and
    ``MACHINE.runs.W`` (how many runs the figures are the means of), MACHINE a key of
    :data:`SCALING_MACHINES`;
    ``study`` the study's command (as code)."""
    if key == "study":
        return f"`{' '.join(read_json(docs, SCALING_FILES['2 cores'])['study'])}`"
    machine, kind, workers = key.split(".")
    if machine not in SCALING_MACHINES:
        raise BenchError(f"unknown strong-scaling run {machine!r}: {', '.join(SCALING_MACHINES)}")
    relative = SCALING_FILES[SCALING_MACHINES[machine]]
    record = read_json(docs, relative)
    rows = {r["workers"]: r for r in record["measured"]}
    model = {m["workers"]: m for m in record["model"] if m.get("schedule", "uniform") == "uniform"}
    by_cost = {m["workers"]: m for m in record["model"] if m.get("schedule") == "by cost"}
    w = int(workers)
    try:
        if kind == "model":
            return f"{model[w]['wall_s']:.1f}"
        if kind == "model-by-cost":
            return f"{by_cost[w]['wall_s']:.1f}"
        if kind == "probe-ratio":  # the probed tasks' seconds at W's shard size over the model's own
            return f"{model[w]['task_seconds'] / model[record['model_from_workers']]['task_seconds']:.1f}"
        r = rows[w]
    except KeyError:
        raise BenchError(f"{relative} has no {kind} at {w} workers") from None
    if kind == "wall":
        return f"{r['wall_s']:.1f}"
    if kind == "efficiency":
        return f"{r['efficiency']:.2f}"
    if kind == "us":
        return f"{r['us_per_trial_step_in_tasks']:.1f}"
    if kind == "fixed":
        return f"{r['breakdown']['task_fixed_s']:.2f}"
    if kind == "tasks":
        return str(r["tasks"])
    if kind == "runs":
        return str(len(r.get("wall_s_each", [r["wall_s"]])))
    if kind == "outside-per-worker":
        return f"{r['breakdown']['outside_tasks_s'] / w:.1f}"
    if kind in ("before", "after"):  # wall seconds before the first task, after the last
        field = f"{kind}_{'first' if kind == 'before' else 'last'}_task_s"
        if field not in r:
            raise BenchError(f"{relative} predates {field!r}: measure it again")
        return f"{r[field]:.1f}"
    raise BenchError(f"unknown scaling figure {key!r}")


@generator("threads")
def threads_table(docs: Path) -> str:
    """``python -m benchmarks.speed.threads``'s runs: one task on all the cores, on one thread
    and on the threads the harness chose, with the speed-up it predicted."""
    record = read_json(docs, "perf/threads.json")
    head = ["fusion", "threads chosen", "the task, one thread (s)", "the task, chosen (s)"]
    head += ["speed-up of the task", "predicted", "the run, one thread (s)", "the run, chosen (s)"]
    runs = []
    for row in record["fusions"]:
        one, chosen = row["runs"]["one thread"], row["runs"]["chosen"]
        cells = [
            row["fusion"],
            str(row["predicted"]["threads"]),
            f"{one['task_s']:.1f}",
            f"{chosen['task_s']:.1f}",
            f"{row['measured_task_speedup']:.2f}",
            f"{row['predicted']['speedup']:.2f}",
            f"{one['wall_s']:.1f}",
            f"{chosen['wall_s']:.1f}",
            "yes" if row["same_numbers"] else "NO",
        ]
        runs.append(cells)
    plans = [
        [p["fusion"], p["workers"], p["shards"], p["tasks"], p["threads"], f"{p['seconds']:.1f}"]
        + [f"{p['one_thread_seconds']:.1f}"]
        for p in record["plans"]
    ]
    plan_head = ["fusion", "cores", "shards", "tasks", "threads chosen", "predicted (s)"]
    plan_head.append("one thread each (s)")
    return markdown_table([*head, "same numbers"], runs) + "\n\n" + markdown_table(plan_head, plans)


@value_source("threads")
def threads_value(docs: Path, key: str) -> str:
    """A figure of the threads runs: ``workers``, ``machine``, ``run`` (its command, as code),
    ``said`` (what the harness said when it chose, under the average fusion)."""
    record = read_json(docs, "perf/threads.json")
    if key == "workers":
        return str(record["workers"])
    if key == "run":
        return f"`{' '.join(record['run'])}`"
    if key == "said":
        said = record["fusions"][0]["runs"]["chosen"]["said"]
        return f'"{said[0]}"' if said else "nothing"
    raise BenchError(f"unknown threads figure {key!r}: workers, run, said")


@values("across")
def across_values(docs: Path) -> dict[str, str]:
    """Each ``perf/across/NAME.json`` that ``benchmarks.speed.across_commits --json`` wrote:
    ``NAME.first`` and ``NAME.second`` (the commits), ``NAME.repeats``, ``NAME.command`` (as
    code), ``NAME.call`` (the comparison's command line, as code), ``NAME.first-median`` and
    ``NAME.second-median`` (``--warmup``'s runs not among them), ``NAME.ratio`` (the first's
    over the second's), ``NAME.difference``, the first's value minus the second's, the mean over
    the interleaved pairs with its 95 % t interval, and ``NAME.shown``, what the interval shows."""
    table: dict[str, str] = {}
    for path in sorted((docs / "results" / "perf" / "across").glob("*.json")):
        record, name = json.loads(path.read_text()), path.stem
        first, second = record["values"]
        differences, low, high, side = _paired_difference(record["values"][first], record["values"][second])
        shown = {"above": "lower at the second commit", "below": "higher at the second commit"}.get(
            side, "not told apart"
        )
        table |= {
            f"{name}.first": first,
            f"{name}.second": second,
            f"{name}.repeats": str(record["repeats"]),
            f"{name}.command": f"`{shlex.join(record['command'])}`",
            f"{name}.call": "`python -m benchmarks.speed.across_commits "
            f"{first} {second} --key {record['key']} --repeats {record['repeats']}"
            + (f" --warmup {record['warmup']}`" if record.get("warmup") else "`"),
            f"{name}.first-median": f"{record['medians'][first]:.3g}",
            f"{name}.second-median": f"{record['medians'][second]:.3g}",
            f"{name}.ratio": f"{record['ratio']:.2f}",
            f"{name}.difference": " ".join(
                [_two_digits(differences.mean()), f"[{_two_digits(low)}, {_two_digits(high)}]"]
            ),
            f"{name}.shown": shown,
        }
    return table


@values("timeline")
def timeline_values(docs: Path) -> dict[str, str]:
    """Each ``perf/timeline-NAME.json`` that ``benchmarks.speed.timeline --json`` wrote:
    ``NAME.command`` (as code), ``NAME.wall`` (s), ``NAME.PART`` for each of its parts
    (:data:`benchmarks.speed.timeline.PARTS`: ``before``, ``waiting``, ``statistics``,
    ``other``, ``after``; s), and ``NAME.place.I`` for its ``I``-th place by time (from 1):
    seconds and the place."""
    table: dict[str, str] = {}
    for path in sorted((docs / "results" / "perf").glob("timeline-*.json")):
        record, name = json.loads(path.read_text()), path.stem.removeprefix("timeline-")
        table[f"{name}.command"] = f"`{shlex.join(record['command'])}`"
        table[f"{name}.wall"] = f"{record['wall_s']:.1f}"
        table |= {f"{name}.{part}": f"{seconds:.2f}" for part, seconds in record["parts_s"].items()}
        for rank, (place, seconds) in enumerate(record["totals_s"].items(), start=1):
            where, leaf = place.split(" | ")
            table[f"{name}.place.{rank}"] = f"{seconds:.2f} s at `{where}` (in `{leaf}`)"
    return table


def _two_digits(value: float) -> str:
    """Two significant digits, without an exponent (``0.058``, ``350``)."""
    return np.format_float_positional(value, precision=2, unique=False, fractional=False, trim="-")


def _paired_difference(a: Sequence[float], b: Sequence[float]) -> tuple[np.ndarray, float, float, str | None]:
    """``a`` minus ``b``, paired by position, with the 95 % t interval of their mean, and
    ``"above"`` or ``"below"`` where that interval lies above or below 0 (None where it holds 0)."""
    from ..speed import t_interval

    differences = np.subtract(a, b)
    low, high = t_interval(differences)
    return differences, low, high, "above" if low > 0 else "below" if high < 0 else None


def _by_variant(
    record: dict[str, Any], key: str, of_run: Callable[[dict[str, Any]], float]
) -> dict[str, list[float]]:
    """``of_run(run)`` of each alternating run (``ray_cluster.alternate``), by its variant
    (``run[key]``), in the order of the repeats."""
    values: dict[str, list[float]] = {}
    for run in record["runs"]:
        values.setdefault(run[key], []).append(of_run(run))
    return values


def _paired_runs(record: dict[str, Any], key: str, other: str, base: str, difference: str) -> str:
    """Alternating runs of a study (``benchmarks.speed.ray_cluster.alternate``): each variant's
    (``key``) wall times, and ``other``'s minus ``base``'s paired by repeat with a 95 % t interval
    (the row named ``difference``), what the interval shows, and whether every run wrote the same
    numbers; where every run recorded them, the mean wall seconds before the first task and
    after the last, and their paired differences."""
    parts = [p for p in ("before_first_task_s", "after_last_task_s") if all(p in r for r in record["runs"])]
    walls = _by_variant(record, key, lambda run: run["wall_s"])
    serial = {part: _by_variant(record, key, operator.itemgetter(part)) for part in parts}
    rows = [
        [name, ", ".join(f"{v:.1f}" for v in values), f"{np.mean(values):.1f}"]
        + [f"{np.mean(serial[part][name]):.2f}" for part in parts]
        for name, values in walls.items()
    ]
    differences, low, high, side = _paired_difference(walls[other], walls[base])
    row = [
        difference,
        ", ".join(f"{d:+.1f}" for d in differences),
        f"{differences.mean():+.1f} [{low:+.1f}, {high:+.1f}]",
    ]
    for part in parts:
        part_differences, part_low, part_high, _ = _paired_difference(serial[part][other], serial[part][base])
        row.append(f"{part_differences.mean():+.2f} [{part_low:+.2f}, {part_high:+.2f}]")
    rows.append(row)
    if side == "above":
        reading = f"{other} took longer than {base}: the interval lies above 0."
    elif side == "below":
        reading = f"{other} took less time than {base}: the interval lies below 0."
    else:
        reading = (
            f"The interval contains 0: at these repeats the wall times of {other} and {base} are not "
            "told apart, so neither is shown faster."
        )
    same = all(run["same_numbers"] for run in record["runs"])
    headings = {"before_first_task_s": "before the first task (s)", "after_last_task_s": "after the last (s)"}
    table = markdown_table([key, "wall of each run (s)", "mean (s)", *(headings[p] for p in parts)], rows)
    return "\n".join(
        [table, "", reading, f"Every run wrote the numbers of the first: {'yes' if same else 'NO'}."]
    )


@generator("ray-backend")
def ray_backend(docs: Path) -> str:
    """``python -m benchmarks.speed.ray_cluster``'s runs: Ray's wall times against the local
    backend's (:func:`_paired_runs`)."""
    return _paired_runs(
        read_json(docs, "perf/ray.json"), "backend", "ray", "local", "Ray minus local, paired by repeat"
    )


@generator("tail-sharing")
def tail_sharing(docs: Path) -> str:
    """``python -m benchmarks.speed.tail_sharing``'s runs: the study's wall times with the tail
    shared and not (:func:`_paired_runs`)."""
    record = read_json(docs, "perf/tail-sharing.json")
    return _paired_runs(record, "tail", "shared", "not shared", "shared minus not shared, paired by repeat")


@value_source("tail")
def tail_value(docs: Path, key: str) -> str:
    """A figure of the tail-sharing runs: ``study`` (its command, as code), ``workers``, ``repeats``."""
    return _alternating_value(read_json(docs, "perf/tail-sharing.json"), key)


@value_source("ray")
def ray_value(docs: Path, key: str) -> str:
    """A figure of the Ray runs: ``study`` (its command, as code), ``workers``, ``repeats``; or
    Ray's minus local's seconds paired by repeat, with their 95 % t interval, of a part of the
    wall time: ``before.difference`` (before the first task), ``after.difference`` (after the
    last) and ``between.difference`` (from the first task's start to the last's end), and what
    that interval shows (``PART.shown``: "longer on Ray", "shorter on Ray" or "not told apart")."""
    record = read_json(docs, "perf/ray.json")
    part, _, rest = key.partition(".")
    if rest not in ("difference", "shown") or part not in ("before", "after", "between"):
        return _alternating_value(record, key)
    of_run = {
        "before": operator.itemgetter("before_first_task_s"),
        "after": operator.itemgetter("after_last_task_s"),
        "between": lambda run: run["wall_s"] - (run["before_first_task_s"] + run["after_last_task_s"]),
    }[part]
    seconds = _by_variant(record, "backend", of_run)
    differences, low, high, side = _paired_difference(seconds["ray"], seconds["local"])
    if rest == "shown":
        return {"above": "longer on Ray", "below": "shorter on Ray", None: "not told apart"}[side]
    return f"{differences.mean():+.2f} [{low:+.2f}, {high:+.2f}]"


def _alternating_value(record: dict[str, Any], key: str) -> str:
    if key == "study":
        return f"`{' '.join(record['study'])}`"
    if key == "workers":
        return str(record["workers"])
    if key == "repeats":
        return str(max(run["repeat"] for run in record["runs"]) + 1)
    raise BenchError(f"unknown figure {key!r} of alternating runs: study, workers, repeats")


# ------------------------------------------------------------------ the planning study
#: The planners the planning targets judge, chosen before the study ran: the oracle and the
#: learning planner at their default horizon and search.
PLANNING_ORACLE = "plan-tracking:5"
PLANNING_LEARNERS = ("plan-tracking-ucb:2", "plan-tracking-ucb:5")
#: The target: the best policy's ARMSE within this fraction of the best achievable bound.
BEST_BOUND_MARGIN = 0.10


@generator("planning-cost")
def planning_cost(docs: Path) -> str:
    """``python -m benchmarks.speed.planning_cost``' ratios: each search's act time at H = 10
    against best-tracking's, measured in the same run."""
    record = read_json(docs, "perf/planning_cost.json")
    figures = record["figures"]
    lines = [
        "| policy | act time per step (ms) | as a multiple of best-tracking's | target |",
        "|---|---|---|---|",
    ]
    for key, value in figures.items():
        if not key.endswith("_over_best_tracking"):
            continue
        policy = key.removesuffix("_over_best_tracking")
        verdict = "holds" if value <= record["target_ratio"] else "**missed**"
        target = f"<= {record['target_ratio']:g}: {verdict}" if policy.endswith("-beam") else "-"
        ms = figures.get(f"{policy}_ms_per_step")  # recorded since the planners' times are kept too
        lines.append(f"| `{policy}` | {'-' if ms is None else f'{ms:.1f}'} | {value:.2f} | {target} |")
    return "\n".join(lines)


@values("planning-cost")
def planning_cost_values(docs: Path) -> dict[str, str]:
    """planning_cost.json's run: best-tracking's ``ms`` per step, ``trials``, ``scenario`` (as
    code), ``steps``, ``command`` (as code), ``machine``, ``load-before`` and ``load-after``."""
    record = read_json(docs, "perf/planning_cost.json")
    return {
        "ms": f"{record['figures']['best-tracking_ms_per_step']:.1f}",
        "trials": str(record["trials"]),
        "scenario": f"`{record['scenario']}`",
        "steps": str(record["steps"]),
        "command": f"`{record['command']}`",
        "machine": _machine(record["machine"]),
        "load-before": str(record["machine"]["load_average_1min"]),
        "load-after": str(record["load_average_1min_after"]),
    }


@generator("planning-tables")
def planning_tables(docs: Path) -> str:
    """The planning study's tables (``mimo-radar-bench planning``'s planning.md), from its
    committed planning.json."""
    from ..studies.planning import planning_markdown

    text = planning_markdown(read_json(docs, "planning/planning.json"))
    body = text.split("\n", 2)[2].lstrip("\n")
    return body.rstrip("\n")


def _run_where(run: dict) -> str:
    return _where((run["scenario"], run["fusion"]))


def _signed(stat: dict) -> str:
    return format_estimate(stat["estimate"], stat["ci"], "{:.3f}")


@values("planning")
def planning_values(docs: Path) -> dict[str, str]:
    """The planning targets, judged from planning.json (and rl.json for the learners that beat
    best-tracking), and the study's ``wall``, ``cores``, ``load-before`` and ``load-after``. Per
    study N.FUSION: ``oracle.N.FUSION`` (better, worse, no difference shown) and its
    ``.difference`` (m), :data:`PLANNING_ORACLE` minus best-tracking, with ``.beaten-by`` the
    policies that beat best-tracking there; per learner L of :data:`PLANNING_LEARNERS` (its ``:``
    a ``-``), ``L.better`` of ``L.studies`` against tracking-ucb and ``L.N.FUSION`` each
    difference (m); per centralised study N, ``bound.N.best`` the best policy, ``bound.N.ratio``
    its ARMSE over the best achievable bound and ``bound.N.within`` (within or not shown within
    ``bound-margin`` %)."""
    from ..resources import duration

    runs = read_json(docs, "planning/planning.json")
    timing = read_json(docs, "planning/timing.json")
    rl = read_json(docs, "rl/rl.json") if (docs / "results" / "rl" / "rl.json").is_file() else None
    machine = timing["machine"]
    table = {
        "wall": duration(timing["wall_s"]),
        "cores": str(machine["cores"]),
        "load-before": f"{machine['load_average_1min']:.2f}",
        "load-after": f"{machine['load_average_1min_after']:.2f}",
        "bound-margin": f"{100 * BEST_BOUND_MARGIN:.0f}",
    }
    word = {
        verdicts.HOLDS: "better",
        verdicts.CONTRADICTED: "worse",
        verdicts.CONSISTENT: "no difference shown",
    }
    for run in runs:
        where = f"{run['scenario']}.{run['fusion']}"
        winners = [
            f"`{p}`"
            for p, d in run["minus_best_tracking"].items()
            if not p.startswith("plan-tracking:") and verdicts.verdict(d["ci"], -1) == verdicts.HOLDS
        ]
        if rl is not None:
            winners += [
                f"`{key} (RL study)`"
                for entry in rl["scenarios"]
                if (entry["scenario"], entry["fusion"]) == (run["scenario"], run["fusion"])
                for key, row in entry["learners"].items()
                if verdicts.verdict(row["minus"]["best-tracking"]["ci"], -1) == verdicts.HOLDS
            ]
        oracle = run["minus"][PLANNING_ORACLE]["best-tracking"]
        table[f"oracle.{where}"] = word[verdicts.verdict(oracle["ci"], -1)]
        table[f"oracle.{where}.difference"] = _signed(oracle)
        table[f"oracle.{where}.beaten-by"] = _listed(winners)
    for learner in PLANNING_LEARNERS:
        key = learner.replace(":", "-")
        differences = [run["minus"][learner]["tracking-ucb"] for run in runs]
        table[f"{key}.better"] = str(
            sum(verdicts.verdict(d["ci"], -1) == verdicts.HOLDS for d in differences)
        )
        table[f"{key}.studies"] = str(len(runs))
        table |= {
            f"{key}.{run['scenario']}.{run['fusion']}": _signed(d)
            for run, d in zip(runs, differences, strict=True)
        }
    table |= _planner_gains(runs)
    for run in runs:
        if run["fusion"] != "centralized":
            continue
        best = min(run["policies"], key=lambda p: run["policies"][p]["armse"]["value"])
        ratio = run["policies"][best]["armse_over_best_bound"]
        table[f"bound.{run['scenario']}.best"] = f"`{best}`"
        table[f"bound.{run['scenario']}.ratio"] = _signed(ratio)
        within = ratio["ci"][1] <= 1 + BEST_BOUND_MARGIN
        table[f"bound.{run['scenario']}.within"] = "within" if within else "not shown within"
    return table


def _one_step(planner: str) -> str:
    """The one-step policy a planner extends: tracking-ucb for the learning planner, else
    best-tracking."""
    return "tracking-ucb" if planner.startswith("plan-tracking-ucb:") else "best-tracking"


def _planner_gains(runs: list[dict[str, Any]]) -> dict[str, str]:
    """The planners against their one-step policies (checked: under eq22 average fusion every
    planner looking more than one step ahead tracks better than its one-step policy, and the
    rollout by the largest margin); per fusion, ``gain.FUSION`` the largest ARMSE margin (m) of
    a planner over best-tracking; ``best-tracking.bound`` the range of best-tracking's centralised
    ARMSE / best achievable bound."""
    ahead = {
        (run["scenario"], p): d[_one_step(p)]
        for run in runs
        if run["fusion"] == "average"
        for p, d in run["minus"].items()
        if not p.endswith(":1")
    }
    _require(
        all(verdicts.verdict(d["ci"], -1) == verdicts.HOLDS for d in ahead.values()),
        "every planner looking ahead beats its one-step policy under eq22 average fusion",
    )
    for n in {n for n, _ in ahead}:
        mine = {p: d["estimate"] for (m, p), d in ahead.items() if m == n}
        _require(
            min(mine, key=mine.__getitem__).startswith("plan-tracking-rollout"), "the rollout gains most"
        )
    table = {}
    for fusion in sorted({run["fusion"] for run in runs}):
        gains = [
            -d["best-tracking"]["estimate"]
            for run in runs
            if run["fusion"] == fusion
            for p, d in run["minus"].items()
            if not p.startswith("plan-tracking-ucb:")
        ]
        table[f"gain.{fusion}"] = f"{max(gains):.3f}"
    ratios = [
        r["policies"]["best-tracking"]["armse_over_best_bound"]["estimate"]
        for r in runs
        if r["fusion"] == "centralized"
    ]
    if ratios:
        table["best-tracking.bound"] = f"{min(ratios):.3f} to {max(ratios):.3f}"
    return table


# ------------------------------------------------------------------ mechanisms of the failing claims
MECHANISMS = "mechanisms/mechanisms.json"
#: The lead below which mechanisms.json counts a step's best super arm as nearly tied.
LEAD_THRESHOLD = 0.02


def _best_window(entry: dict, key: str) -> tuple[str, dict]:
    """The window width of oracle ``key`` with the highest ASR, and that ASR's estimate."""
    return max(entry[key].items(), key=lambda item: item[1]["estimate"])


def _best_width(entry: dict, key: str) -> str:
    """The window width with the highest ASR, with that ASR (%) and its interval."""
    width, best = _best_window(entry, key)
    return f"{format_judged(best, '{:.0f}', 100)} (W = {width})"


def _v1_mg_crb_cl(docs: Path, scenario: str) -> dict:
    """MG-CRB-CL's row of the v1 study of ``scenario`` (``paper-N-v1``), eq22 average fusion."""
    return study_summary(docs, int(scenario.split("-")[1]), "average")["policies"]["mg-crb-cl"]


def _verdicts(docs: Path, path: str) -> dict[str, str]:
    """A scorecard's verdicts by claim."""
    return {r["id"]: r["verdict"] for r in read_json(docs, path)}


@generator("mechanisms-asr")
def mechanisms_asr(docs: Path) -> str:
    """Per ASR claim: the best super arm's lead, the oracles' ASR caps, MG-CRB-CL's ASR and the
    paper's, from mechanisms.json and the v1 study's summaries."""
    m = read_json(docs, MECHANISMS)
    lines = [
        "| claim | median lead (%) | steps with a lead below 2 % (%) "
        "| sampling oracle, n = 1 / 10 / 100 (ASR %) | window oracle, best W (ASR %) "
        "| probing window oracle, best W (ASR %) | MG-CRB-CL (ASR %) "
        "| the paper's MG-CRB-CL (ASR %) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for scenario, entry in m["lead"].items():
        ours = _v1_mg_crb_cl(docs, scenario)
        sampling = " / ".join(
            format_judged(entry["sampling_oracle_asr"][n], "{:.0f}", 100) for n in ("1", "10", "100")
        )
        paper = m["paper_asr"].get(entry["claim"], {}).get("mg-crb-cl")
        lines.append(
            f"| {entry['claim']} ({scenario}) | {format_judged(entry['median_lead'], '{:.2f}', 100)} "
            f"| {format_judged(entry['fraction_lead_below_0.02'], '{:.0f}', 100)} | {sampling} "
            f"| {_best_width(entry, 'window_oracle_asr')} "
            f"| {_best_width(entry, 'probing_window_oracle_asr')} "
            f"| {format_cell(ours, 'asr', '{:.1f}', 100)} | {'—' if paper is None else f'{paper:.2f}'} |"
        )
    return "\n".join(lines)


@generator("mechanisms-armse")
def mechanisms_armse(docs: Path) -> str:
    """Every ARMSE comparison of the claims beside the bound's and SINR's differences."""
    m = read_json(docs, MECHANISMS)
    lines = [
        "| claim | comparison (A < B) | verdict | ARMSE A - B (m) | bound A - B (m) | mean SINR A - B (dB) "
        "| follows the bound | follows SINR |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in m["armse_comparisons"]:
        bound = f"{row['bound_difference']:.3f}" + ("" if row["bound_settled"] else " (intervals overlap)")
        armse = row["armse_difference"]
        lines.append(
            f"| {row['claim']} | {row['comparison'].split(': ', 1)[1]}"
            f"{' (' + row['comparison'].split(':')[0] + ')' if 'target' in row['comparison'] else ''} "
            f"| {row['verdict']} | {format_estimate(armse['estimate'], armse['ci'], '{:.3f}')} "
            f"| {bound} | {format_judged(row['sinr_db_difference'], '{:.2f}')} "
            f"| {'yes' if row['follows_bound'] else 'no'} | {'yes' if row['follows_sinr'] else 'no'} |"
        )
    return "\n".join(lines)


@values("mechanisms")
def mechanisms_values(docs: Path) -> dict[str, str]:
    """What the mechanisms tables show, from mechanisms.json and the v1 study's summaries: the
    ARMSE comparisons' counts (``comparisons``, ``follow-bound``, ``follow-sinr``,
    ``contradicted``, ``contradicted-follow-bound``, ``contradicted-follow-sinr``); per ASR claim
    of Scenario N, ``N.lead-below`` the steps (%) whose best super arm leads by less than
    ``lead-threshold`` %,
    ``N.cap`` and ``N.width`` the probing window oracle's best ASR (%) and its window,
    ``N.paper`` the paper's MG-CRB-CL ASR (%), ``N.where`` where it lies against the cap, and
    ``N.ours`` ours (%)."""
    m = read_json(docs, MECHANISMS)
    s = m["armse_summary"]
    table = {
        "comparisons": str(s["comparisons"]),
        "follow-bound": str(s["follow_bound"]),
        "follow-sinr": str(s["follow_sinr"]),
        "contradicted": str(s["contradicted"]),
        "contradicted-follow-bound": str(s["contradicted_follow_bound"]),
        "contradicted-follow-sinr": str(s["contradicted_follow_sinr"]),
    }
    table["lead-threshold"] = f"{100 * LEAD_THRESHOLD:g}"
    for scenario, entry in m["lead"].items():
        n = scenario.split("-")[1]
        width, cap = _best_window(entry, "probing_window_oracle_asr")
        paper = m["paper_asr"][entry["claim"]]["mg-crb-cl"] / 100
        low, high = cap["ci"]
        table |= {
            f"{n}.lead-below": f"{100 * entry[f'fraction_lead_below_{LEAD_THRESHOLD}']['estimate']:.0f}",
            f"{n}.cap": format_judged(cap, "{:.1f}", 100),
            f"{n}.width": str(width),
            f"{n}.paper": f"{100 * paper:.2f}",
            f"{n}.where": "below" if paper < low else "above" if paper > high else "within the interval of",
            f"{n}.ours": format_cell(_v1_mg_crb_cl(docs, scenario), "asr", "{:.1f}", 100),
        }
    return table


# ------------------------------------------------------------------ the ablations
ABLATIONS = "mechanisms/ablations.json"
#: The ASR claim of each v1 paper scenario.
ASR_CLAIM_OF = {"paper-1-v1": "S1.10", "paper-2-v1": "S2.5", "paper-3-v1": "S3.4"}


def _ablation_scenarios(a: dict) -> dict[str, dict]:
    return {k: v for k, v in a.items() if k != "variants"}


def _pp(judged: dict) -> str:
    """A difference of fractions in percentage points, signed, with its interval."""
    return format_judged(judged, "{:+.1f}", 100)


@generator("ablations-asr")
def ablations_asr(docs: Path) -> str:
    """MG-CRB-CL's ASR under each one-parameter change, with its paired difference to the paper's
    MG-CRB-CL, from ablations.json."""
    a = read_json(docs, ABLATIONS)
    mechanisms = read_json(docs, MECHANISMS)
    scenarios = _ablation_scenarios(a)
    labels = [k for k in next(iter(scenarios.values()))["asr"] if k != "paper"]
    lines = [
        "| claim | MG-CRB-CL as in the paper (ASR %) | "
        + " | ".join(
            f"{label.removeprefix('mg-crb-cl, ')} (ASR %; minus the paper's, pp)" for label in labels
        )
        + " | the paper's MG-CRB-CL (ASR %) |",
        "|---|---|" + "---|" * len(labels) + "---|",
    ]
    for scenario, entry in scenarios.items():
        claim = ASR_CLAIM_OF[scenario]
        asr = entry["asr"]
        cells = [
            f"{format_judged(asr[k]['asr'], '{:.1f}', 100)}; {_pp(asr[k]['asr_minus_paper'])}" for k in labels
        ]
        paper = mechanisms["paper_asr"][claim]["mg-crb-cl"]
        lines.append(
            f"| {claim} ({scenario}) | {format_judged(asr['paper']['asr'], '{:.1f}', 100)} | "
            + " | ".join(cells)
            + f" | {paper:.2f} |"
        )
    return "\n".join(lines)


#: Short names of the ablations' MG-CRB-CL variants for value spans.
ABLATION_VARIANTS = {"paper": "paper", "exact": "mg-crb-cl, exact solver"}


@value_source("ablations")
def ablations_value(docs: Path, key: str) -> str:
    """``SCENARIO.VARIANT.METRIC`` of ablations.json's ``asr`` entries: MG-CRB-CL's ``asr`` or
    ``final_regret`` with its interval, VARIANT ``paper`` (the paper's BPSO) or ``exact`` (the
    exact solver); ``trials`` (every scenario's), ``crossing`` (the step from which UCB1's mean
    regret stays above epsilon-greedy's, Scenario 1), ``rising`` of ``super-arms`` (with a higher
    mean reward over 400-500 s than over 300-400 s, Scenario 2) and ``best-changes`` (how often
    the best super arm changes over 300-500 s)."""
    a = read_json(docs, ABLATIONS)
    if key == "trials":
        return _listed([str(t) for t in sorted({e["trials"] for e in _ablation_scenarios(a).values()})])
    if key == "crossing":
        crossing = a["paper-1-v1"]["exploration"]["crossing"]
        if not crossing:
            raise BenchError(f"{ABLATIONS}: UCB1's mean regret now ends below epsilon-greedy's")
        return str(crossing)
    maneuver = {"rising": "super_arms_rising", "super-arms": "super_arms", "best-changes": "best_arm_changes"}
    if key in maneuver:
        return str(a["paper-2-v1"]["maneuver"][maneuver[key]])
    scenario, variant, metric = key.split(".")
    try:
        judged = read_json(docs, ABLATIONS)[scenario]["asr"][ABLATION_VARIANTS[variant]][metric]
    except KeyError:
        raise BenchError(
            f"{ABLATIONS} has no {key!r} (SCENARIO.{'|'.join(ABLATION_VARIANTS)}.METRIC)"
        ) from None
    return format_judged(judged, "{:.1f}", 100 if metric == "asr" else 1)


@generator("ablations-s17")
def ablations_s17(docs: Path) -> str:
    """S1.7: UCB1's and epsilon-greedy's regret and what each way of exploring costs over the
    greedy core, from ablations.json (Scenario 1)."""
    entry = read_json(docs, ABLATIONS)["paper-1-v1"]["exploration"]
    lines = [
        "| regret at | UCB1 | epsilon-greedy | greedy core (UCB1, beta = 0) | UCB1 minus greedy "
        "| epsilon-greedy minus greedy | UCB1 minus epsilon-greedy |",
        "|---|---|---|---|---|---|---|",
    ]
    keys = ("ucb1", "epsilon-greedy", "greedy", "ucb1_minus_greedy", "epsilon_greedy_minus_greedy")
    for at, row in entry["at"].items():
        lines.append(
            f"| {at} s | "
            + " | ".join(format_judged(row[k], "{:.0f}") for k in (*keys, "ucb1_minus_epsilon_greedy"))
            + " |"
        )
    return "\n".join(lines)


@generator("ablations-s18")
def ablations_s18(docs: Path) -> str:
    """S1.8: every policy's ARMSE and bound in the claim's windows, from ablations.json
    (Scenario 1)."""
    rows = read_json(docs, ABLATIONS)["paper-1-v1"]["rmse_windows"]
    policies = list(rows[0]["armse"])
    lines = [
        "| window | the claim | "
        + " | ".join(f"{p}: ARMSE (m); bound (m)" for p in policies)
        + " | the extreme ARMSE | the extreme bound |",
        "|---|---|" + "---|" * len(policies) + "---|---|",
    ]
    for row in rows:
        a, b = row["window"]
        cells = [
            f"{format_judged(row['armse'][p], '{:.2f}')}; {format_judged(row['bound'][p], '{:.2f}')}"
            for p in policies
        ]
        lines.append(
            f"| {a}-{b} s | {row['policy']} {row['extreme']} | "
            + " | ".join(cells)
            + f" | {row['extreme']}: {row['armse_extreme']} | {row['extreme']}: {row['bound_extreme']} |"
        )
    return "\n".join(lines)


@generator("ablations-s22")
def ablations_s22(docs: Path) -> str:
    """S2.2: every policy's SINR change across the maneuver and its SINR below Best's, and the
    super arms that gain mean reward, from ablations.json (Scenario 2)."""
    m = read_json(docs, ABLATIONS)["paper-2-v1"]["maneuver"]
    lines = [
        "| policy | SINR 400-500 s minus 300-400 s (dB) | below Best, 300-400 s (dB) "
        "| below Best, 400-500 s (dB) |",
        "|---|---|---|---|",
    ]
    for policy, row in m["policies"].items():
        lines.append(
            f"| {policy} | {format_judged(row['change_db'], '{:+.2f}')} "
            f"| {format_judged(row['below_best_before_db'], '{:.2f}')} "
            f"| {format_judged(row['below_best_after_db'], '{:.2f}')} |"
        )
    return "\n".join(lines)


def _m(judged: dict, fmt: str = "{:.2f}", scale: float = 1.0) -> str:
    return format_judged(judged, fmt, scale)


def _require(shown: bool, statement: str) -> None:
    """Refuse to fill a page whose sentence ``statement`` the artefacts no longer show."""
    if not shown:
        raise BenchError(f"the artefacts no longer show that {statement}: rewrite the sentence that says so")


def _rmse_window_values(windows: list[dict[str, Any]]) -> dict[str, str]:
    """S1.8's values per RMSE window (:func:`per_claim_values` lists them)."""
    table = {}
    for w, row in enumerate(windows, 1):
        top, claimed, worst = row["bound_extreme"], row["policy"], row["armse_extreme"]
        table |= {
            f"S1.8.{w}.span": "-".join(map(str, row["window"])),
            f"S1.8.{w}.extreme": row["extreme"],
            f"S1.8.{w}.top": top,
            f"S1.8.{w}.top-bound": _m(row["bound"][top]),
            f"S1.8.{w}.claimed": claimed,
            f"S1.8.{w}.claimed-bound": _m(row["bound"][claimed]),
            f"S1.8.{w}.worst": worst,
            f"S1.8.{w}.ratio-worst": _m(row["armse_over_bound"][worst]),
            f"S1.8.{w}.ratio-top": _m(row["armse_over_bound"][top]),
        }
    table["S1.8.windows"] = str(len(windows))
    table["S1.8.follow"] = str(sum(r["armse_extreme"] == r["bound_extreme"] for r in windows))
    return table


@values("per-claim")
def per_claim_values(docs: Path) -> dict[str, str]:
    """One measured mechanism per claim contradicted under v1, from mechanisms.json and
    ablations.json; each lead phrase of the page is checked against its intervals (``CLAIM``: its
    v1 verdict). S1.7 (Scenario 1's exploration at ``S1.7.at`` s): ``S1.7.ucb1`` and
    ``S1.7.epsilon-greedy`` above the greedy core, ``S1.7.crossing``. S1.8, per window W (1, 2,
    ...): ``S1.8.W.span``, ``.extreme`` (lowest or highest), ``.top`` the policy of the extreme
    bound and ``.top-bound``, ``.claimed`` the claim's policy and ``.claimed-bound``, ``.worst``
    the policy of the extreme ARMSE, ``.ratio-worst`` and ``.ratio-top`` (ARMSE / bound);
    ``S1.8.follow`` of ``S1.8.windows``. Per ARMSE claim: ``CLAIM.follow`` of ``CLAIM.compared``,
    ``CLAIM.broken-follow`` of ``CLAIM.broken``. Per ASR claim: ``CLAIM.greedy`` and
    ``CLAIM.greedy-gain``, ``CLAIM.paper``, ``CLAIM.exact-gain``, ``CLAIM.memory-gain``,
    ``CLAIM.cap`` with ``CLAIM.width``. S2.2: ``S2.2.rising`` of ``S2.2.super-arms``,
    ``S2.2.POLICY`` the SINR change of fix1, fix2, best, mg-crb-cl, ``S2.2.behind-before`` and
    ``S2.2.behind-after``."""
    a = read_json(docs, ABLATIONS)
    m = read_json(docs, MECHANISMS)
    table = dict(_verdicts(docs, SCORECARDS["v1"]))
    explore = a["paper-1-v1"]["exploration"]
    at = min(explore["at"], key=int)
    early = explore["at"][at]
    _require(early["ucb1_minus_epsilon_greedy"]["ci"][0] > 0, "exploring costs UCB1 more from the start")
    _require(bool(explore["crossing"]), "UCB1's mean regret stays above epsilon-greedy's")
    table |= {
        "S1.7.at": at,
        "S1.7.ucb1": _m(early["ucb1_minus_greedy"], "{:.0f}"),
        "S1.7.epsilon-greedy": _m(early["epsilon_greedy_minus_greedy"], "{:.0f}"),
        "S1.7.crossing": str(explore["crossing"]),
    }
    table |= _rmse_window_values(a["paper-1-v1"]["rmse_windows"])
    for claim in ("S1.9", "S2.4", "S3.2", "S3.3"):
        mine = [r for r in m["armse_comparisons"] if r["claim"] == claim]
        broken = [r for r in mine if r["verdict"] == "contradicted"]
        table |= {
            f"{claim}.follow": str(sum(r["follows_bound"] for r in mine)),
            f"{claim}.compared": str(len(mine)),
            f"{claim}.broken-follow": str(sum(r["follows_bound"] for r in broken)),
            f"{claim}.broken": str(len(broken)),
        }
    for scenario, claim in ASR_CLAIM_OF.items():
        asr = a[scenario]["asr"]
        greedy = asr["mg-crb-cl, exact, beta = 0"]
        _require(
            greedy["asr_minus_paper"]["ci"][0] > 0, f"eq18's optimism keeps MG-CRB-CL's ASR low in {claim}"
        )
        width, cap = _best_window(m["lead"][scenario], "probing_window_oracle_asr")
        table |= {
            f"{claim}.greedy": _m(greedy["asr"], "{:.1f}", 100),
            f"{claim}.greedy-gain": _pp(greedy["asr_minus_paper"]),
            f"{claim}.paper": _m(asr["paper"]["asr"], "{:.1f}", 100),
            f"{claim}.exact-gain": _pp(asr["mg-crb-cl, exact solver"]["asr_minus_paper"]),
            f"{claim}.memory-gain": _pp(asr["mg-crb-cl, exact, alpha_bar = 0.05"]["asr_minus_paper"]),
            f"{claim}.cap": _m(cap, "{:.1f}", 100),
            f"{claim}.width": str(width),
        }
    man = a["paper-2-v1"]["maneuver"]
    pol = man["policies"]
    mg = pol["mg-crb-cl"]
    _require(all(pol[p]["change_db"]["ci"][0] > 0 for p in ("fix1", "fix2")), "fix1 and fix2 gain SINR")
    _require(
        mg["below_best_after_db"]["ci"][0] > mg["below_best_before_db"]["ci"][1], "MG-CRB-CL falls behind"
    )
    table |= {
        "S2.2.rising": str(man["super_arms_rising"]),
        "S2.2.super-arms": str(man["super_arms"]),
        "S2.2.behind-before": _m(mg["below_best_before_db"]),
        "S2.2.behind-after": _m(mg["below_best_after_db"]),
    }
    table |= {f"S2.2.{p}": _m(pol[p]["change_db"], "{:+.2f}") for p in ("fix1", "fix2", "best", "mg-crb-cl")}
    return table


# ------------------------------------------------------------------ the global layout search
LAYOUT_SEARCH = "layout-search/search.json"


#: The searched layouts re-scored at 500 trials (``search-layouts --score``), by rank of top10.json.
LAYOUT_RESCORED = "layout-search/rescored.json"


def _long_trials(docs: Path) -> int:
    """The trials of the long scorecards (rescored.json records them; search.json, written before
    the search recorded its trials, is checked against them where it has them)."""
    trials = read_json(docs, LAYOUT_RESCORED)["trials"]
    if read_json(docs, LAYOUT_SEARCH).get("trials", trials) != trials:
        raise BenchError(f"{LAYOUT_SEARCH} and {LAYOUT_RESCORED} scored their layouts at different trials")
    return trials


def _long_scorecards(docs: Path) -> list[dict]:
    """Every searched layout with a long scorecard (search.json's finalists, then the re-scored
    ranks), by rank; each must be the layout of that rank in top10.json (same search, same seed)."""
    top = [f for f in read_json(docs, LAYOUT_TOP)["finalists"] if f["name"] != "v1"]
    scored = [f for f in read_json(docs, LAYOUT_SEARCH)["finalists"] if f["name"] != "v1"]
    scored += read_json(docs, LAYOUT_RESCORED)["finalists"]
    by_rank: dict[int, dict] = {}
    for f in scored:
        rank = f.get("rank") or int(f["name"].rsplit("-", 1)[1])
        if not np.allclose(f["vector"], top[rank - 1]["vector"]):
            raise BenchError(f"{f['name']} of the 500-trial scorecards is not layout {rank} of {LAYOUT_TOP}")
        by_rank[rank] = {**f, "name": f"search-{rank}"}
    return [by_rank[r] for r in sorted(by_rank)]


@generator("layout-search")
def layout_search_table(docs: Path) -> str:
    """Each claim's verdict under v1's layout and every searched layout with a 500-trial
    scorecard, from search.json, rescored.json and the v1 claims study."""
    v1 = _verdicts(docs, SCORECARDS["v1"])
    finalists = _long_scorecards(docs)
    lines = [
        "| claim | v1's layout (layout 116) | " + " | ".join(f["name"] for f in finalists) + " |",
        "|---|---|" + "---|" * len(finalists),
    ]
    for claim, verdict in v1.items():
        lines.append(f"| {claim} | {verdict} | " + " | ".join(f["verdicts"][claim] for f in finalists) + " |")
    counts = verdicts.count(v1.values())
    for kind in ("holds", "consistent", "contradicted"):
        lines.append(
            f"| **{kind}** | {counts[kind]} | " + " | ".join(str(f["counts"][kind]) for f in finalists) + " |"
        )
    return "\n".join(lines)


@values("layouts")
def layout_values(docs: Path) -> dict[str, str]:
    """The layout search's figures. The search: ``evaluations``, ``wall``, ``rate``,
    ``population``, ``generations``, ``seed``, ``v1-objective``, ``best-objective``. Its long
    scorecards (``long-trials`` trials): ``most-holding`` and ``most-holding.under``, ``gained``
    (holding under a searched layout, not under v1's), ``lost`` (holding under v1's, not under
    every searched one), ``never``, the predictors' ``agree`` of ``compared``; per scored layout
    NAME, ``NAME.VERDICT`` its counts, ``NAME.won`` and ``NAME.lost`` against v1's; ``better``
    the layouts with more claims holding than v1's, ``better.count`` of ``scored``. The ten best
    at ``screen-trials`` trials: ``once`` and ``none-of-ten``, ``could`` (the ranks whose holding
    or consistent claims outnumber v1's holding ones) and ``could.unscored``."""
    found = read_json(docs, LAYOUT_SEARCH)
    v1 = _verdicts(docs, SCORECARDS["v1"])
    v1_holds = verdicts.count(v1.values())["holds"]
    finalists = _long_scorecards(docs)
    most = max(f["counts"]["holds"] for f in finalists)
    table = {
        "evaluations": str(found["evaluations"]),
        "wall": f"{found['wall_s']:.0f}",
        "rate": f"{found['layouts_per_s']:.1f}",
        "population": str(found["population"]),
        "generations": str(found["generations"]),
        "seed": str(found["seed"]),
        "v1-objective": f"{found['v1_objective']:.3f}",
        "best-objective": f"{found['ranked'][0]['objective']:.3f}",
        "long-trials": str(_long_trials(docs)),
        "most-holding": str(most),
        "most-holding.under": ", ".join(f["name"] for f in finalists if f["counts"]["holds"] == most),
        "agree": str(sum(f["agreement"]["agree"] for f in finalists)),
        "compared": str(sum(f["agreement"]["compared"] for f in finalists)),
        "scored": str(len(finalists)),
    }
    held = {c: [f["verdicts"][c] == "holds" for f in finalists] for c in v1}
    table["gained"] = _listed([c for c in v1 if v1[c] != "holds" and any(held[c])])
    table["lost"] = _listed([c for c in v1 if v1[c] == "holds" and not all(held[c])])
    table["never"] = _listed([c for c in v1 if v1[c] != "holds" and not any(held[c])])
    for f in finalists:
        table |= {f"{f['name']}.{v}": str(f["counts"][v]) for v in verdicts.VERDICTS}
        table[f"{f['name']}.won"] = _listed(
            [c for c in v1 if v1[c] != "holds" and f["verdicts"][c] == "holds"]
        )
        table[f"{f['name']}.lost"] = _listed(
            [c for c in v1 if v1[c] == "holds" and f["verdicts"][c] != "holds"]
        )
    better = [f["name"] for f in finalists if f["counts"]["holds"] > v1_holds]
    table["better"], table["better.count"] = _listed(better), str(len(better))
    top = read_json(docs, LAYOUT_TOP)
    ten = [f for f in top["finalists"] if f["name"] != "v1"]
    table["screen-trials"] = str(top["trials"])
    count = {c: sum(f["verdicts"][c] == "holds" for f in ten) for c in ten[0]["verdicts"]}
    table["once"] = _listed([c for c, n in count.items() if n == 1])
    table["none-of-ten"] = _listed([c for c, n in count.items() if n == 0])
    long = {int(f["name"].rsplit("-", 1)[1]) for f in finalists}
    could = [i + 1 for i, f in enumerate(ten) if f["counts"]["holds"] + f["counts"]["consistent"] > v1_holds]
    table["could"] = _listed([str(rank) for rank in could])
    table["could.unscored"] = _listed([str(rank) for rank in could if rank not in long])
    return table | _shipped_values(docs, finalists) | _seed_values(docs, finalists)


def _listed(items: list[str]) -> str:
    """A computed list of a sentence: its items, or "none"."""
    return ", ".join(items) or "none"


LAYOUT_TOP = "layout-search/top10.json"
#: Master seeds 1000 apart: trial i is seeded seed + i, so the three share no trial.
SEED_SCORECARDS = {
    "layout 116, seed 0": "claims/v1.json",
    "layout 116, seed 1000": "claims/v1-seed1000.json",
    "layout 116, seed 2000": "claims/v1-seed2000.json",
}


@generator("layout-sensitivity")
def layout_sensitivity(docs: Path) -> str:
    """Each claim's verdict under the ten best searched layouts (short scorecards)."""
    found = read_json(docs, LAYOUT_TOP)
    finalists = [f for f in found["finalists"] if f["name"] != "v1"]
    claims_ids = list(finalists[0]["verdicts"])
    lines = [
        "| claim | " + " | ".join(str(i + 1) for i in range(len(finalists))) + " | holds in |",
        "|---|" + "---|" * len(finalists) + "---|",
    ]
    for claim in claims_ids:
        row = [f["verdicts"][claim] for f in finalists]
        lines.append(
            f"| {claim} | "
            + " | ".join(SHORT_VERDICTS[v] for v in row)
            + f" | {row.count('holds')} of {len(row)} |"
        )
    lines.append("| **holds** | " + " | ".join(str(f["counts"]["holds"]) for f in finalists) + " | |")
    long = {int(f["name"].rsplit("-", 1)[1]): f for f in _long_scorecards(docs)}
    long_trials = _long_trials(docs)
    lines.append(
        f"| **holds at {long_trials} trials** | "
        + " | ".join(
            str(long[i + 1]["counts"]["holds"]) if i + 1 in long else "—" for i in range(len(finalists))
        )
        + " | |"
    )
    return "\n".join(lines)


#: The shipped scenario set's scorecards under the other master seeds (seed 0: rescored.json).
SET_SEED_SCORECARDS = {
    "search-5, seed 1000": "claims/search5-seed1000.json",
    "search-5, seed 2000": "claims/search5-seed2000.json",
}
#: The layout shipped as a scenario set, by its rank in top10.json.
SHIPPED_RANK, SHIPPED_SET = 5, "search-5"


def _shipped_values(docs: Path, finalists: list[dict]) -> dict[str, str]:
    """``shipped``, the layout shipped as :data:`SHIPPED_SET`, checked to have the most claims
    holding and the fewest contradicted among those tied with it, and the stations of each of
    its scenarios (``shipped.scenarios``)."""
    from mimo_radar_env import SCENARIO_SETS, load_scenario

    shipped = next(f for f in finalists if f["name"] == f"search-{SHIPPED_RANK}")
    tied = [f for f in finalists if f["counts"]["holds"] == shipped["counts"]["holds"]]
    if shipped["counts"]["holds"] < max(f["counts"]["holds"] for f in finalists) or shipped["counts"][
        "contradicted"
    ] > min(f["counts"]["contradicted"] for f in tied):
        raise BenchError(
            f"{shipped['name']} no longer has the most claims holding with the fewest contradicted"
        )
    km = np.array(shipped["vector"]).reshape(-1, 2) * 1e3
    names = SCENARIO_SETS[SHIPPED_SET].paper_scenarios
    for name in names:
        sc = load_scenario(name)
        if not np.allclose(np.vstack([sc.tx_positions, sc.rx_positions]), km, rtol=0, atol=1e-6):
            raise BenchError(f"scenario {name} does not have the stations of {shipped['name']}")
    return {"shipped": shipped["name"], "shipped.scenarios": ", ".join(names)}


@generator("seed-sensitivity")
def seed_sensitivity(docs: Path) -> str:
    """The v1 scorecard (500 trials, average fusion) under three master seeds, and the shipped
    scenario set's under the same seeds."""
    cards = _seed_cards(docs, _long_scorecards(docs))
    labels = list(cards)
    lines = ["| claim | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    for claim in cards[labels[0]]:
        lines.append(f"| {claim} | " + " | ".join(cards[label][claim] for label in labels) + " |")
    for kind in ("holds", "consistent", "contradicted"):
        lines.append(
            f"| **{kind}** | "
            + " | ".join(str(verdicts.count(cards[label].values())[kind]) for label in labels)
            + " |"
        )
    return "\n".join(lines)


def _seed_cards(docs: Path, finalists: list[dict]) -> dict[str, dict[str, str]]:
    """The verdicts of v1's layout and of the shipped set under each master seed, by label."""
    cards = {label: _verdicts(docs, path) for label, path in SEED_SCORECARDS.items()}
    shipped = next(f for f in finalists if f["name"] == f"search-{SHIPPED_RANK}")
    cards[f"{SHIPPED_SET}, seed {read_json(docs, LAYOUT_RESCORED)['seed']}"] = shipped["verdicts"]
    return cards | {label: _verdicts(docs, path) for label, path in SET_SEED_SCORECARDS.items()}


def _seed_values(docs: Path, finalists: list[dict]) -> dict[str, str]:
    """Per layout of the seed table (``layout-116``, ``search-5``): ``seeds.LAYOUT`` its seeds,
    ``seeds.LAYOUT.holds`` the claims holding under each and ``seeds.LAYOUT.moving`` the claims
    whose verdict changes with the seed."""
    cards = _seed_cards(docs, finalists)
    table = {}
    for layout in dict.fromkeys(label.split(",")[0] for label in cards):
        mine = [label for label in cards if label.split(",")[0] == layout]
        key = f"seeds.{layout.replace(' ', '-')}"
        table[key] = str(len(mine))
        table[f"{key}.holds"] = ", ".join(
            str(verdicts.count(cards[label].values())["holds"]) for label in mine
        )
        table[f"{key}.moving"] = _listed(
            [c for c in cards[mine[0]] if len({cards[label][c] for label in mine}) > 1]
        )
    return table
