"""A sun study over a city block: exact sunlight hours, serial and on Dask.

``python benchmarks/bench_sunstudy.py`` (a year of hourly sun positions over
1,000 buildings, several minutes) or ``--days 14`` for a shorter run;
``--summaries`` keeps each day's figures only (``sun_summaries_by_day``, the
level sets' areas without their polygons, as ``shadowgeo sun`` runs many
days), compared between the runs with ``==``. The same
study runs serially in this process and on a Dask ``LocalCluster`` of
single-threaded workers (``--workers 1 2``, 2 by default); the table gives the
wall time, the CPU time of this process and the workers (the machine is
shared: CPU time is what the work cost), the speed-up per worker and whether the
results are identical (every shadow and level polygon, bit for bit).
"""

from __future__ import annotations

import argparse
import datetime as dt
import sys
import time

import numpy as np
import trimesh

from shadowgeo import Plane
from shadowgeo.parallel import client_for
from shadowgeo.sun import hourly
from shadowgeo.sunstudy import SunStudies, sun_study_by_day, sun_summaries_by_day


def city(n_buildings: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray, float]:
    """``n_buildings`` boxes on a square grid of plots (3-40 m tall, 8-16 m
    wide, 20 m apart), as one (vertices, faces) mesh, and the block's half-size."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n_buildings)))
    vertices, faces = [], []
    for index in range(n_buildings):
        row, column = divmod(index, side)
        width, depth = rng.uniform(8, 16, size=2)
        height = rng.uniform(3, 40)
        box = trimesh.creation.box([width, height, depth])
        box.apply_translation([column * 20.0, height / 2, row * 20.0])
        faces.append(box.faces + sum(len(v) for v in vertices))
        vertices.append(box.vertices)
    half = side * 10.0
    mesh_vertices = np.concatenate(vertices) - [half - 10.0, 0.0, half - 10.0]
    return mesh_vertices, np.concatenate(faces), half


def _same_polygons(first: list, second: list) -> bool:
    if [len(part) for part in first] != [len(part) for part in second]:
        return False
    loops = [loop for part in first for loop in part]
    other = [loop for part in second for loop in part]
    return all(np.array_equal(a, b) for a, b in zip(loops, other, strict=True))


def identical(first: SunStudies, second: SunStudies) -> bool:
    """Every day's times, shadows and levels equal, bit for bit."""
    if list(first.days) != list(second.days):
        return False
    for day, study in first.days.items():
        other = second.days[day]
        if study.times != other.times or study.levels.keys() != other.levels.keys():
            return False
        if not all(_same_polygons(a, b) for a, b in zip(study.shadows, other.shadows, strict=True)):
            return False
        if not all(_same_polygons(parts, other.levels[k]) for k, parts in study.levels.items()):
            return False
    return True


def _progress(label: str):
    def show(done: int, total: int) -> None:
        if done == total or done % 30 == 0:
            print(f"  {label}: {done}/{total} days", file=sys.stderr, flush=True)

    return show


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buildings", type=int, default=1000)
    parser.add_argument("--days", type=int, default=365, help="days from 1 January 2026")
    parser.add_argument("--hours", type=float, default=2.0, help="threshold for the table")
    parser.add_argument(
        "--workers", type=int, nargs="+", default=[2], help="Dask LocalCluster sizes to run"
    )
    parser.add_argument(
        "--summaries",
        action="store_true",
        help="each day's figures only (sun_summaries_by_day, as shadowgeo sun runs many days)",
    )
    args = parser.parse_args()
    by_day = sun_summaries_by_day if args.summaries else sun_study_by_day

    vertices, faces, half = city(args.buildings)
    region = np.array([[-half, 0, half], [half, 0, half], [half, 0, -half], [-half, 0, -half]])
    start = dt.datetime(2026, 1, 1, tzinfo=dt.UTC)
    times = hourly(start, start + dt.timedelta(days=args.days))
    site = dict(latitude=51.5, longitude=-0.12)
    ground = Plane([0, 1, 0], 0)
    print(
        f"{args.buildings} buildings ({len(faces):,} triangles), {args.days} days, "
        f"{len(times):,} hourly samples, London"
    )

    begin, cpu = time.perf_counter(), time.process_time()
    serial = by_day((vertices, faces), ground, region, times, **site, progress=_progress("serial"))
    serial_time, serial_cpu = time.perf_counter() - begin, time.process_time() - cpu
    if args.summaries:
        samples = sum(summary.samples for summary in serial.values())
        loops = 0  # no polygons made
    else:
        samples = sum(len(study.times) for study in serial.days.values())
        loops = sum(
            len(part)
            for study in serial.days.values()
            for parts in study.levels.values()
            for part in parts
        )
    print(f"serial: {serial_time:.1f} s wall, {serial_cpu:.1f} s CPU", flush=True)
    rows = [("serial, this process", serial_time, serial_cpu, 1.0, "")]
    for workers in args.workers:
        with client_for("local", workers=workers) as client:
            client.wait_for_workers(workers)
            before = sum(client.run(time.process_time).values())  # the workers' start-up
            begin, cpu = time.perf_counter(), time.process_time()
            parallel = by_day(
                (vertices, faces),
                ground,
                region,
                times,
                **site,
                scheduler=client,
                progress=_progress(f"{workers} worker(s)"),
            )
            elapsed = time.perf_counter() - begin
            spent = time.process_time() - cpu + sum(client.run(time.process_time).values()) - before
        same = serial == parallel if args.summaries else identical(serial, parallel)
        del parallel
        print(f"{workers} worker(s): {elapsed:.1f} s wall, identical: {same}", flush=True)
        rows.append(
            (
                f"Dask LocalCluster, {workers} worker(s)",
                elapsed,
                spent,
                serial_time / elapsed,
                "yes" if same else "NO",
            )
        )

    made = "day summaries, no polygons" if args.summaries else f"{loops:,} level polygons"
    print(f"\n{samples:,} samples with the sun up; {made}\n")
    print(
        "| run | wall time | CPU (this process + workers) | speed-up vs serial | per worker "
        "| identical to serial |"
    )
    print("|---|---:|---:|---:|---:|---|")
    for index, (name, elapsed, spent, speedup, same) in enumerate(rows):
        per_worker = f"{speedup / args.workers[index - 1]:.2f}x" if index else ""
        print(
            f"| {name} | {elapsed:.1f} s | {spent:.1f} s | {speedup:.2f}x | {per_worker} "
            f"| {same or '(reference)'} |"
        )
    if args.summaries:
        fractions = {day: summary.fraction_meeting(args.hours) for day, summary in serial.items()}
    else:
        fractions = serial.fraction_meeting(args.hours)
    march = dt.date(2026, 3, 21)
    if march in fractions:
        print(f"\n21 March: {fractions[march]:.1%} of the block has >= {args.hours:g} h of sun")
    values = np.array(list(fractions.values()))
    print(
        f"days: {len(values)}; fraction with >= {args.hours:g} h of sun: "
        f"min {values.min():.1%}, median {np.median(values):.1%}, max {values.max():.1%}"
    )


if __name__ == "__main__":
    main()
