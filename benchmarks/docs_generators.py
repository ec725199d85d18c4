"""The generators of the docs' blocks (:mod:`benchmarks.doctables`), one per table or set of
numbers, each reading the committed artefacts it names under ``docs/results``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import verdicts
from .doctables import generator, read_json
from .studies import claims, tracking

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


def _scorecards(docs: Path, files: dict[str, str]) -> dict[str, list]:
    return {label: read_json(docs, path) for label, path in files.items()}


@generator("claims-verdicts")
def claims_verdicts(docs: Path) -> str:
    """Every claim's verdict under v1 (both fusions) and v0, with the counts."""
    return claims.comparison_markdown(_scorecards(docs, SCORECARDS))


@generator("claims-counts")
def claims_counts(docs: Path) -> str:
    """One sentence per scorecard: how many claims hold, are consistent, are contradicted."""
    lines = []
    for label, results in _scorecards(docs, SCORECARDS).items():
        counts = verdicts.count(r["verdict"] for r in results)
        lines.append(
            f"- {label}: {counts['holds']} of {len(results)} claims hold, {counts['consistent']} are "
            f"consistent, {counts['contradicted']} are contradicted."
        )
    always = _always_contradicted(_scorecards(docs, READINGS))
    lines.append(f"- Contradicted in every reading, layout and fusion tried: {', '.join(always)}.")
    return "\n".join(lines)


def _always_contradicted(scorecards: dict[str, list]) -> list[str]:
    ids = [r["id"] for r in next(iter(scorecards.values()))]
    return [
        claim
        for claim in ids
        if all(
            next(r["verdict"] for r in results if r["id"] == claim) == verdicts.CONTRADICTED
            for results in scorecards.values()
        )
    ]


@generator("readings")
def readings(docs: Path) -> str:
    """The verdicts under each single reading change (the columns build on one another)."""
    return claims.comparison_markdown(_scorecards(docs, READINGS), claim_text=False)


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
    best = next(c for c in report["candidates"] if c["index"] == report["best"])
    reference = report["candidates"][0]
    moves = [
        float(np.hypot(*(np.array(p) - np.array(q))))
        for key in ("tx_km", "rx_km")
        for p, q in zip(best[key], reference[key], strict=True)
    ]
    judged = sum(1 for c in report["candidates"] if screen in c["scorecards"])
    met = sum(1 for c in report["candidates"] if c["rejected"] is None)
    lines += [
        "",
        f"{report['count']} jittered layouts and the reference (seed {report['seed']}); {met} of "
        f"{report['count'] + 1} meet the text's constraints; {judged} were judged at {screen} trials "
        f"and {sum(1 for c in report['candidates'] if final in c['scorecards'])} at {final}. Layout "
        f"{best['index']} moves every station of the reference, by {min(moves):.1f} to {max(moves):.1f} km.",
    ]
    return "\n".join(lines)


@generator("tracking-targets")
def tracking_targets(docs: Path) -> str:
    """The tracking study's targets, one row per scenario and fusion."""
    text = tracking.targets_markdown(read_json(docs, "tracking/targets.json"))
    return text.split("\n", 2)[2].lstrip("\n")  # without its own title
