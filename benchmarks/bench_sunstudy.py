"""A sun study over a city block: exact sunlight hours, serial and on Dask.

``python benchmarks/bench_sunstudy.py`` (a year of hourly sun positions over
1,000 buildings, several minutes) or ``--days 14`` for a shorter run. The same
study runs serially in this process and on a Dask ``LocalCluster`` of 1 and 2
single-threaded workers; the table gives the times, the speed-up per worker and
whether the results are identical (every level polygon, bit for bit).
"""

from __future__ import annotations

import argparse
import datetime as dt
import time

import numpy as np
import trimesh

from shadowgeo import Plane
from shadowgeo.parallel import client_for
from shadowgeo.sun import hourly
from shadowgeo.sunstudy import SunStudies, sun_study_by_day


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


def identical(first: SunStudies, second: SunStudies) -> bool:
    if list(first.days) != list(second.days):
        return False
    for day, study in first.days.items():
        other = second.days[day]
        if study.levels.keys() != other.levels.keys():
            return False
        for k, parts in study.levels.items():
            loops = [loop for part in parts for loop in part]
            other_loops = [loop for part in other.levels[k] for loop in part]
            if len(loops) != len(other_loops):
                return False
            if not all(np.array_equal(a, b) for a, b in zip(loops, other_loops, strict=True)):
                return False
    return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buildings", type=int, default=1000)
    parser.add_argument("--days", type=int, default=365, help="days from 1 January 2026")
    parser.add_argument("--hours", type=float, default=2.0, help="threshold for the table")
    args = parser.parse_args()

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

    begin = time.perf_counter()
    serial = sun_study_by_day((vertices, faces), ground, region, times, **site)
    serial_time = time.perf_counter() - begin
    samples = sum(len(study.times) for study in serial.days.values())
    rows = [("serial, this process", serial_time, 1.0, True)]
    for workers in (1, 2):
        with client_for("local", workers=workers) as client:
            begin = time.perf_counter()
            parallel = sun_study_by_day(
                (vertices, faces), ground, region, times, **site, scheduler=client
            )
            elapsed = time.perf_counter() - begin
        rows.append(
            (
                f"Dask LocalCluster, {workers} worker(s)",
                elapsed,
                serial_time / elapsed,
                identical(serial, parallel),
            )
        )

    print(f"\n{samples:,} samples with the sun up\n")
    print("| run | time | speed-up vs serial | identical to serial |")
    print("|---|---:|---:|---|")
    for name, elapsed, speedup, same in rows:
        print(f"| {name} | {elapsed:.1f} s | {speedup:.2f}x | {'yes' if same else 'NO'} |")
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
