"""Fuzzing campaign for shadowgeo: mutated real scenes through the converter, and
random geometry through the core API.

Converter mode mutates real scenes (``../shared/corpus/**``, ``examples/scenes``;
glTF, glb, USD and x3dz seeds are made from the X3D ones with shadowgeo's own
writers) at three levels:

* bytes: bit flips, truncation, splices of two seeds, repeated or deleted
  chunks, inserted bytes;
* structure: elements, attributes, JSON keys or brace blocks dropped,
  duplicated, reordered or renamed to another node type;
* meaning: numbers turned into 0, -0, 1e308, 1e-320, nan, inf, huge counts or
  negative indices, fields emptied, deep nesting, DEF/USE cycles.

Each mutant runs through ``cli.main.main(argv)`` in a forked worker with a time
budget (a CPU-time alarm, so that other work on a shared machine does not
count; then a kill by wall clock at four times the budget) and an
address-space limit, so a hang or a blow-up is recorded, not fatal. A run
fails when it raises anything but ``SystemExit`` 1/2, returns a code outside
{0, 1, 2}, leaves an output (or a temporary file) after failing, writes no
output after succeeding, modifies its input, writes NaN or inf, or exceeds
the time or memory budget; with ``--sun`` and ``--plane`` the shadow area
must also match the textbook one (shapely union of the projected
triangles). Geometry mode (``--geometry N``) sends random casters, planes
and lights through ``project_shadow``, ``silhouette`` and ``shadow_volume``.

Failures are grouped by signature (exception type and innermost shadowgeo
frame, or the check that failed), each group's first input is shrunk by delta
debugging, and everything goes to ``--out``: ``summary.md``, ``results.jsonl``
and one folder per signature with the original and the smallest input.

The parts live in the package ``tools/fuzz/`` (see its ``__init__``); this
script parses the options and runs the campaign.

Usage::

    python tools/fuzz.py --inputs 2000 --seed 1 --out /tmp/fuzz --jobs 2
    python tools/fuzz.py --inputs 0 --geometry 5000 --seed 1 --out /tmp/fuzz-geo

Exit status 1 when any run failed. ``kill -USR1`` the campaign to stop starting
runs early and go on to shrinking and the summary.

Each run is appended to ``--out``'s ``results.jsonl`` as it ends. Stopped by
SIGINT or SIGTERM (exit 130 or 143) or killed, the campaign goes on where it
stopped when run again with the same ``--out`` (or ``campaign --resume OUT``):
the runs recorded are not run again, and the summary counts them all. It is
refused (exit 2) when the commit, its uncommitted changes, the seed, the
sizes, the budgets or the seed files differ from those in ``campaign.json``.

The whole campaign on one commit, every encoding (X3D XML, x3dz, ClassicVRML,
VRML 97, X3D JSON, glTF, glb, USD text and crate, OBJ, STL, PLY, OFF,
CityJSON, GeoJSON footprints) and the geometry cases, its table written into
``benchmarks/REPORT.md``'s "Fuzz campaign" section::

    python tools/fuzz.py campaign --per-encoding 10000 --geometry 20000 --seed 7 --jobs 2
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
from pathlib import Path

# One BLAS thread a worker: the campaign runs --jobs workers side by side.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

# tools/ for the package fuzz/, and this repository's shadowgeo and cli, not
# another checkout's installed in the environment
sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

from fuzz.campaign import campaign  # noqa: E402
from fuzz.inputs import ENCODINGS  # noqa: E402
from fuzz.pool import Pool  # noqa: E402
from fuzz.report import TITLE, commit, section, write_section  # noqa: E402
from fuzz.resume import PLAN  # noqa: E402
from fuzz.seeds import collect_seeds  # noqa: E402

REPORT = Path(__file__).resolve().parents[1] / "benchmarks" / "REPORT.md"


def whole_campaign(argv: list[str]) -> int:
    """``campaign``: every encoding and the geometry cases on this commit, then
    the table in REPORT.md (``fuzz.report``)."""
    parser = argparse.ArgumentParser(
        prog="fuzz.py campaign", description="the whole campaign on one commit, reported"
    )
    parser.add_argument("--per-encoding", type=int, default=10_000)
    parser.add_argument("--geometry", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, help="default /tmp/shadowgeo-campaign-SEED")
    parser.add_argument(
        "--resume",
        type=Path,
        metavar="OUT",
        help="go on with the campaign in OUT (the same as --out OUT, which resumes too when OUT "
        "holds runs; refused unless they are of this commit, seed and sizes)",
    )
    parser.add_argument("--report", type=Path, default=REPORT, help="default %(default)s")
    parser.add_argument("--no-report", action="store_true", help="write no REPORT.md section")
    parser.add_argument("--encodings", default=",".join(ENCODINGS), help="default: all")
    args = parser.parse_args(argv)
    out = args.resume or args.out or Path(f"/tmp/shadowgeo-campaign-{args.seed}")
    at = commit()  # the code the runs use (before anything changes meanwhile)
    code = main(
        [
            f"--inputs={args.per_encoding}",
            f"--geometry={args.geometry}",
            f"--seed={args.seed}",
            f"--jobs={args.jobs}",
            f"--out={out}",
            f"--encodings={args.encodings}",
            *(["--resume"] if args.resume else []),
        ]
    )
    if code not in (0, 1):  # refused, or stopped by a signal: no table yet
        return code
    # every session's wall clock, when the campaign was stopped and resumed
    wall = json.loads((out / PLAN).read_text())["wall_seconds"]
    command = f"python tools/fuzz.py campaign {' '.join(argv)}"
    text = section(
        out / "results.jsonl", seed=args.seed, jobs=args.jobs, command=command, wall=wall, at=at
    )
    print(text)
    if not args.no_report:
        write_section(args.report, text)
        print(f"wrote the section {TITLE[3:]!r} of {args.report}", file=sys.stderr)
    return code


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["campaign"]:
        return whole_campaign(argv[1:])
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--inputs", type=int, default=200, help="mutants per encoding")
    parser.add_argument("--geometry", type=int, default=0, help="random geometry cases")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--first-index", type=int, default=0, help="index of the first mutant (to run in chunks)"
    )
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--encodings", default=",".join(ENCODINGS))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--time-budget", type=float, default=20.0, help="CPU seconds per input")
    parser.add_argument("--memory-budget", type=float, default=1.5, help="GiB per worker")
    parser.add_argument("--shrink-tries", type=int, default=300)
    parser.add_argument("--max-seed-bytes", type=int, default=64 << 10)
    parser.add_argument(
        "--max-minutes", type=float, default=0, help="stop starting runs after this (0: never)"
    )
    parser.add_argument(
        "--replay",
        type=Path,
        metavar="RESULTS",
        help="no new runs: re-create the first failing run of each signature in a results.jsonl "
        "made with the same --seed, and shrink those",
    )
    parser.add_argument("--no-known", action="store_true", help="skip matching known findings")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="go on with the campaign recorded in --out (any --out holding runs is resumed; "
        "with this flag, one holding none is refused)",
    )
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    encodings = [e.strip() for e in args.encodings.split(",") if e.strip()]
    unknown = [e for e in encodings if e not in ENCODINGS]
    if unknown:
        parser.error(f"unknown encodings {unknown}; known: {', '.join(ENCODINGS)}")
    args.out.mkdir(parents=True, exist_ok=True)
    pool = Pool(args.jobs, args.time_budget, int(args.memory_budget * (1 << 30)))
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(143))  # so the pool closes
    try:
        seeds = collect_seeds(pool, args.max_seed_bytes, encodings) if args.inputs else {}
        return campaign(args, encodings, seeds, pool)
    finally:
        pool.close()


if __name__ == "__main__":
    sys.exit(main())
