"""The campaign's section of ``benchmarks/REPORT.md``: runs and failures per
encoding and for geometry, from the campaign's ``results.jsonl``, with the
commit, seed, command and time, and what a full campaign would take here."""

from __future__ import annotations

import json
import subprocess
from collections import Counter, defaultdict
from pathlib import Path

from .inputs import ROOT

TITLE = "## Fuzz campaign"
FULL = {"per_encoding": 10_000, "geometry": 20_000}


def commit() -> str:
    """The checkout's commit, with ``+changes`` when files differ from it."""

    def git(*args: str) -> str:
        done = subprocess.run(["git", *args], capture_output=True, text=True, cwd=ROOT)
        return done.stdout.strip()

    head = git("rev-parse", "--short", "HEAD") or "unknown"
    return head + ("+changes" if git("status", "--porcelain", "--untracked-files=no") else "")


def tally(results: Path) -> tuple[dict[str, Counter], dict[str, float]]:
    """Per group (encoding, or ``geometry``): runs, failures and each failing
    signature's count; and the seconds its runs took."""
    counts: dict[str, Counter] = defaultdict(Counter)
    seconds: dict[str, float] = defaultdict(float)
    for line in results.read_text().splitlines():
        entry = json.loads(line)
        group = entry.get("encoding", "geometry")
        counts[group]["runs"] += 1
        seconds[group] += float(entry.get("seconds") or 0.0)
        if not entry["ok"]:
            counts[group]["failures"] += 1
            counts[group][f"sig:{entry['signature']}"] += 1
    return counts, seconds


def section(results: Path, *, seed: int, jobs: int, command: str, wall: float, at: str) -> str:
    """The Markdown section, headed :data:`TITLE`, of a campaign run at commit ``at``."""
    counts, seconds = tally(results)
    total_runs = sum(c["runs"] for c in counts.values())
    total_failures = sum(c["failures"] for c in counts.values())
    rows = []
    for group in sorted(counts, key=lambda g: (g == "geometry", g)):
        c = counts[group]
        signatures = ", ".join(
            f"{key[4:]} ({n})" for key, n in c.most_common() if key.startswith("sig:")
        )
        mean = seconds[group] / max(c["runs"], 1)
        rows.append(
            f"| {group} | {c['runs']:,} | {c['failures']:,} | {mean:.2f} | {signatures or '-'} |"
        )
    # A full campaign here: each group's mean seconds a run times its runs, on `jobs` workers.
    estimate = sum(
        seconds[g]
        / max(counts[g]["runs"], 1)
        * (FULL["geometry"] if g == "geometry" else FULL["per_encoding"])
        for g in counts
    ) / max(jobs, 1)
    return "\n".join(
        [
            TITLE,
            "",
            f"`{command}` at commit {at}, seed {seed}, {jobs} workers: {total_runs:,} runs "
            f"in {wall / 60:.1f} min ({total_runs / max(wall, 1e-9):.2f} runs/s), "
            f"{total_failures:,} failures. A run fails when it raises anything but a clean "
            "exit 1/2, leaves a file after failing, writes NaN or inf, changes its input, "
            "passes its CPU or memory budget, or (with --sun and --plane) draws a shadow whose "
            "area differs from the textbook union's (`tools/fuzz.py`'s docstring).",
            "",
            "| encoding | runs | failures | s / run | failing signatures (runs) |",
            "|---|---|---|---|---|",
            *rows,
            "",
            f"At these rates the full campaign (`--per-encoding {FULL['per_encoding']:,} "
            f"--geometry {FULL['geometry']:,}`, {len(counts) - ('geometry' in counts)} "
            f"encodings) would take about {estimate / 3600:.1f} hours on {jobs} workers here "
            "(each group's mean seconds a run times its runs, over the workers; shrinking the "
            "failures comes on top).",
            "",
        ]
    )


def write_section(report: Path, text: str) -> None:
    """Put ``text`` in ``report`` in place of its :data:`TITLE` section (up to
    the next level-2 heading), or at the end."""
    document = report.read_text() if report.is_file() else ""
    start = document.find(TITLE + "\n")
    if start < 0:
        document = document.rstrip("\n") + "\n\n" + text
    else:
        end = document.find("\n## ", start + len(TITLE))
        document = document[:start] + text + ("" if end < 0 else document[end:])
    report.write_text(document)
