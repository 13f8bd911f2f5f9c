"""Batch conversion of the shared corpus: serial, and on Dask with 1 and 2 workers.

``PYTHONPATH=$PWD python benchmarks/bench_batch.py [FOLDER ...]`` (default:
every folder of ../shared/corpus; skipped with a note when it is absent).
Every scene file is converted (shadows added, written in its own format) by
:func:`shadowgeo.batch.convert_files`, the engine of ``shadowgeo convert IN...
OUT_DIR``: once in this process, then on a Dask ``LocalCluster`` of each size
of ``--workers``. The table gives the wall time (the cluster's start-up
apart), the speed-up over the serial run and per worker, and whether every
output file and every error message is the same as the serial run's.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import tempfile
import time
from pathlib import Path

# this checkout's shadowgeo and CLI (the workers inherit the path)
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from cli.batch import jobs_for  # noqa: E402  (the CLI's own file walk)
from shadowgeo.batch import ConvertOptions, Outcome, convert_files  # noqa: E402
from shadowgeo.parallel import client_for  # noqa: E402

SHARED = Path(__file__).resolve().parents[2] / "shared"


def fingerprint(out_dir: Path, outcomes: list[Outcome]) -> dict[str, str]:
    """Each output's SHA-256, and each failure's message, by path."""
    prints = {
        str(path.relative_to(out_dir)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(out_dir.rglob("*"))
        if path.is_file()
    }
    prints.update({f"error {o.source}": o.error for o in outcomes if o.error is not None})
    return prints


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="*", type=Path)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    folders = args.folders or sorted(p for p in (SHARED / "corpus").glob("*") if p.is_dir())
    if not folders:
        print(f"no corpus at {SHARED / 'corpus'}: nothing to convert")
        return
    options = ConvertOptions()
    with tempfile.TemporaryDirectory(prefix="bench-batch-") as scratch:
        rows = []
        reference: dict[str, str] | None = None
        serial_time = 0.0
        for workers in [0, *args.workers]:
            out_dir = Path(scratch) / f"out-{workers}"
            jobs: list[tuple[Path, Path]] = []
            for folder in folders:
                found, _ = jobs_for([folder], out_dir / folder.name, None)
                jobs.extend(found)
            if workers == 0:
                begin = time.perf_counter()
                outcomes = convert_files(jobs, options)
                elapsed, startup = time.perf_counter() - begin, 0.0
            else:
                begin = time.perf_counter()
                with client_for("local", workers=workers) as client:
                    client.wait_for_workers(workers)
                    startup = time.perf_counter() - begin
                    begin = time.perf_counter()
                    outcomes = convert_files(jobs, options, scheduler=client)
                    elapsed = time.perf_counter() - begin
            prints = fingerprint(out_dir, outcomes)
            failed = sum(not o.ok for o in outcomes)
            if reference is None:
                reference, serial_time = prints, elapsed
            name = "serial, this process" if workers == 0 else f"Dask LocalCluster, {workers}"
            rows.append((name, len(jobs), failed, elapsed, startup, workers, prints == reference))
            print(f"{name}: {elapsed:.1f} s ({failed} of {len(jobs)} failed)", flush=True)

    print(f"\ncorpus: {', '.join(str(f) for f in folders)}\n")
    print(
        "| run | files | failed | wall time | cluster start | speed-up | per worker "
        "| outputs identical to serial |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    for name, files, failed, elapsed, startup, workers, same in rows:
        speedup = serial_time / elapsed
        per_worker = f"{speedup / workers:.2f}x" if workers else ""
        print(
            f"| {name} | {files} | {failed} | {elapsed:.1f} s | "
            f"{f'{startup:.1f} s' if workers else ''} | {speedup:.2f}x | {per_worker} "
            f"| {'(reference)' if not workers else 'yes' if same else 'NO'} |"
        )


if __name__ == "__main__":
    main()
