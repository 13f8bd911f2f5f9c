"""Every benchmark run on two commits side by side, in one session.

Run from the repository root::

    python benchmarks/side_by_side.py --old b3635ae [--new HEAD] [--rounds 2] [--write]

Each commit is checked out in a temporary worktree. A benchmark that exists at
both commits runs as that commit's own script on that commit's library; one
added since ``--old`` (or whose harness changed since, ``NEW_HARNESS``) runs
its new script on both libraries when the old library has what it calls, and
is reported as new otherwise. The runs
alternate old, new, new, old (``--rounds 2``), so a machine that gets busier
or quieter during the session weighs on both sides alike.

Two figures per benchmark, each the least over the rounds on each side:

* **process CPU**: user and system seconds of the benchmark's process and the
  processes it waited for (peers included, so a change of ours is diluted by
  the peers' share);
* **shadowgeo's rows**: the benchmark's printed Markdown tables, each row
  that names shadowgeo (or every row, in a table that names no method) matched
  by its words between the two commits, and each time-like column compared:
  the geometric mean and the worst of the ratios new / old.

*Noise* is the same comparison between the two runs of one commit (the larger
of the two commits' spreads): a ratio inside it is no change.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from common import write_section

ROOT = Path(__file__).resolve().parent.parent
TITLE = "## Side by side: before and after the one pipeline"

# The quick form of each benchmark: small enough to run twice per commit.
BENCHMARKS: dict[str, list[str]] = {
    "bench_planar.py": ["--repeat", "3"],
    "bench_volume.py": ["--repeat", "3"],
    "bench_surface.py": ["--repeat", "3"],
    "bench_polygons.py": ["--cap", "5"],
    "bench_scale.py": ["--quick"],
    "bench_robustness.py": [],
    "bench_lights.py": ["--lights", "1000", "--repeat", "3"],
    "bench_buildings.py": ["--sizes", "1000", "10000", "--repeat", "3"],
    # the corpus folders both commits read (the old one reads no city data)
    "bench_batch.py": [
        "--workers",
        "1",
        "--",
        "../shared/corpus/castle-demo-models",
        "../shared/corpus/castle-demo-models-classic",
        "../shared/corpus/web3d-json-pairs",
    ],
    "bench_sunstudy.py": ["--buildings", "1000", "--days", "8", "--workers", "1"],
    "bench_compiled.py": ["--repeat", "5"],
    "bench_memory.py": ["--quick", "--no-write"],
    "bench_soft.py": ["--quick", "--no-write"],
    "bench_city_sunlight.py": ["--buildings", "100", "--every", "120", "--workers", "0"],
    "bench_pybdshadow.py": ["--repeat", "3", "--no-report"],
    "bench_viewer.py": ["--only", "pyramid", "--no-write"],
}
# Benchmarks whose new script runs on both libraries although the old commit
# has its own: the script's harness changed, not what it times, and the old
# harness would time something else.
NEW_HARNESS = {
    # each step now starts after gc.collect(): a full collection of the
    # import-time objects (30-40 ms) fell in the old harness's first
    # add_shadows by chance of the allocations before it
    "bench_scale.py",
}
# A run past this is stopped; the memory bombs on a library without budgets
# (before they were added) each run to their 300 s CPU limit, so that
# benchmark is stopped sooner.
TIMEOUT = 1200.0
TIMEOUTS = {"bench_memory.py": 120.0}
# pybdshadow's own side takes minutes and is the same for both commits: it is
# run once, saved, and given to the other runs.
THEIRS = "bench_pybdshadow.py"
TIME_HEADER = re.compile(r"\btime\b|\(m?s\)|\bms\b|\bs$|seconds|\bCPU\b|\bwall\b", re.IGNORECASE)
NUMBER = re.compile(r"^[<>~]?\s*([-+]?[\d,]*\.?\d+(?:e[-+]?\d+)?)\s*(ms|s|x|×|%)?$", re.I)


@dataclass
class Run:
    """One run of one benchmark on one commit."""

    ok: bool
    cpu: float
    wall: float
    rows: dict[tuple, float] = field(default_factory=dict)
    tail: str = ""


def checkout(revision: str, into: Path) -> Path:
    """A detached worktree of ``revision`` under ``into``."""
    subprocess.run(
        ["git", "-C", str(ROOT), "worktree", "add", "--detach", "-f", str(into), revision],
        check=True,
        capture_output=True,
    )
    return into


def timed_rows(output: str) -> dict[tuple, float]:
    """Time-like cells of the Markdown tables in ``output``, keyed by table,
    row (its place and first cell) and column header; only shadowgeo's rows
    or columns where a table names it."""
    tables: list[list[list[str]]] = []
    current: list[list[str]] = []
    for line in output.splitlines() + [""]:
        if line.startswith("|"):
            current.append([c.strip() for c in line.strip().strip("|").split("|")])
        elif current:
            tables.append(current)
            current = []
    rows: dict[tuple, float] = {}
    for number, table in enumerate(tables):
        if len(table) < 3 or not set(table[1][0]) <= set("-: "):
            continue
        header, body = table[0], table[2:]
        # A table that names shadowgeo in a column header or a row: those only.
        ours = [i for i, h in enumerate(header) if "shadowgeo" in h.lower()]
        named = [r for r in body if any("shadowgeo" in c.lower() for c in r)]
        for place, row in enumerate(named or body):
            words = (place, row[0])  # a row's place and its first words (its label)
            for column, cell in enumerate(row):
                match = NUMBER.match(cell.replace(",", ""))
                timed = column < len(header) and TIME_HEADER.search(header[column])
                if match and timed and (not ours or column in ours):
                    if precise(match.group(1)):
                        rows[(number, words, header[column])] = float(match.group(1))
    return rows or plain_rows(output)


def precise(number: str) -> bool:
    """Whether a printed time has two significant digits or more (0.001 s
    printed as 0.001 or 0.000 is below what the benchmark resolves)."""
    digits = number.lower().split("e")[0].replace(".", "").lstrip("+-0")
    return len(digits) >= 2


def plain_rows(output: str) -> dict[tuple, float]:
    """For a benchmark that prints no Markdown table: each line of a label and
    numbers set apart by two or more spaces (a column of times under a header)."""
    rows: dict[tuple, float] = {}
    for line in output.splitlines():
        cells = re.split(r"\s{2,}", line.strip())
        numbers = [NUMBER.match(c.replace(",", "")) for c in cells[1:]]
        if len(cells) > 1 and all(numbers):
            for column, match in enumerate(numbers):
                if match is not None and precise(match.group(1)):
                    rows[(-1, (cells[0],), str(column))] = float(match.group(1))
    return rows


def run(script: Path, library: Path, arguments: list[str], timeout: float) -> Run:
    """``script`` on ``library``'s code, in a copy of its folder (no REPORT.md
    of the repository is written)."""
    folder = library / f"benchmarks-run-{time.monotonic_ns()}"  # beside its examples/
    shutil.copytree(script.parent, folder)
    environment = {**os.environ, "PYTHONPATH": str(library), "MPLBACKEND": "Agg"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    try:
        done = subprocess.run(
            [sys.executable, str(folder / script.name), *arguments],
            cwd=library,
            env=environment,
            capture_output=True,
            text=True,
            check=False,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        shutil.rmtree(folder, ignore_errors=True)
        return Run(False, math.nan, timeout, {}, f"over {timeout:.0f} s (stopped)")
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    shutil.rmtree(folder, ignore_errors=True)
    ok = done.returncode == 0
    return Run(ok, cpu, wall, timed_rows(done.stdout) if ok else {}, done.stderr[-400:])


def least(runs: list[Run]) -> tuple[float, dict[tuple, float]]:
    """The least process CPU and the least of each row's times over ``runs``."""
    rows: dict[tuple, float] = {}
    for one in runs:
        for key, value in one.rows.items():
            rows[key] = min(value, rows.get(key, math.inf))
    return min(r.cpu for r in runs), rows


def ratios(old: dict[tuple, float], new: dict[tuple, float]) -> list[float]:
    """new / old of each row both have, where both are above zero (a time
    printed as 0.000 has no digit to compare)."""
    return [new[k] / old[k] for k in old.keys() & new.keys() if old[k] > 0 and new[k] > 0]


def geometric_mean(values: list[float]) -> float:
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else math.nan


def spread(runs: list[Run]) -> float:
    """How far two runs of one commit differ: the larger of their CPU ratio and
    the geometric mean of their rows' ratios, as a factor above 1."""
    if len(runs) < 2:
        return math.nan
    first, second = runs[0], runs[1]
    cpu = max(first.cpu, second.cpu) / min(first.cpu, second.cpu)
    rows = geometric_mean([max(r, 1 / r) for r in ratios(first.rows, second.rows)])
    return max(cpu, rows) if not math.isnan(rows) else cpu


def compare(name: str, trees: dict[str, Path], rounds: int, scratch: Path) -> str:
    """One benchmark's row of the table."""
    arguments = BENCHMARKS[name]
    saved = scratch / "pybdshadow-side.json"
    own_old = (trees["old"] / "benchmarks" / name).is_file() and name not in NEW_HARNESS
    scripts = {
        "old": trees["old" if own_old else "new"] / "benchmarks" / name,
        "new": trees["new"] / "benchmarks" / name,
    }
    runs: dict[str, list[Run]] = {"old": [], "new": []}
    order = ["old", "new", "new", "old"] * rounds
    for side in order[: 2 * rounds]:
        print(f"  {name} on {side}", file=sys.stderr, flush=True)
        extra = (
            []
            if name != THEIRS
            else ["--theirs" if saved.exists() else "--keep-theirs", str(saved)]
        )
        one = run(scripts[side], trees[side], arguments + extra, TIMEOUTS.get(name, TIMEOUT))
        if not one.ok:
            note = "new since the old commit" if not own_old and side == "old" else "failed"
            if one.tail.startswith("over "):
                note = f"{side}: {one.tail}"
            print(f"    {note}: {one.tail.strip().splitlines()[-1:]}", file=sys.stderr)
            return f"| {name} | {' '.join(arguments)} | {note} | | | | | |"
        runs[side].append(one)
    (old_cpu, old_rows), (new_cpu, new_rows) = least(runs["old"]), least(runs["new"])
    row_ratios = ratios(old_rows, new_rows)
    noise = max(spread(runs["old"]), spread(runs["new"]))
    script = "each its own" if own_old else "new script on both"
    worst = f"{max(row_ratios):.2f}" if row_ratios else "-"
    mean = f"{geometric_mean(row_ratios):.2f}" if row_ratios else "-"
    return (
        f"| {name} | {' '.join(arguments)} | {script} | {old_cpu:.1f} / {new_cpu:.1f} "
        f"| {new_cpu / old_cpu:.2f} | {len(row_ratios)} | {mean} / {worst} | {noise:.2f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--old", required=True, help="the commit before")
    parser.add_argument("--new", default="HEAD", help="the commit after (default HEAD)")
    parser.add_argument("--rounds", type=int, default=2, help="runs per commit (default 2)")
    parser.add_argument("--only", nargs="+", help="benchmarks whose name holds one of these")
    parser.add_argument("--write", action="store_true", help="put the table in REPORT.md")
    args = parser.parse_args()
    revisions = {
        side: subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", rev],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.strip()
        for side, rev in (("old", args.old), ("new", args.new))
    }
    names = [n for n in BENCHMARKS if not args.only or any(o in n for o in args.only)]
    with tempfile.TemporaryDirectory(prefix="side-by-side-") as temporary:
        scratch = Path(temporary)
        shared = ROOT.parent / "shared"
        if shared.is_dir():  # the worktrees find ../shared as the repository does
            (scratch / "shared").symlink_to(shared.resolve())
        trees = {side: checkout(revisions[side], scratch / side) for side in ("old", "new")}
        try:
            lines = []
            for name in names:
                lines.append(compare(name, trees, args.rounds, scratch))
                print(lines[-1], flush=True)  # as each finishes
        finally:
            for tree in trees.values():
                subprocess.run(
                    ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)],
                    check=False,
                    capture_output=True,
                )
    text = (
        f"{TITLE}\n\n`python benchmarks/side_by_side.py --old {args.old} --new {args.new} "
        f"--rounds {args.rounds}`: old {revisions['old']}, new {revisions['new']}, "
        f"{time.strftime('%Y-%m-%d')}, load average at the end "
        f"{os.getloadavg()[0]:.1f}. Process CPU is the least of {args.rounds} runs per commit "
        "(peers included); rows are shadowgeo's timed table cells matched between the "
        "commits (geometric mean / worst of new ÷ old); noise is the larger spread between "
        "two runs of one commit.\n\n"
        "| benchmark | arguments | script | process CPU s (old / new) | CPU ratio "
        "| rows | rows' ratio (mean / worst) | noise |\n|---|---|---|---:|---:|---:|---:|---:|\n"
        + "\n".join(lines)
        + "\n"
    )
    print(text)
    if args.write:
        write_section(TITLE, text)


if __name__ == "__main__":
    main()
