"""Sunlight on ground, walls and roofs of a city block: exact hours, serial and on Dask.

``PYTHONPATH=$PWD python benchmarks/bench_city_sunlight.py`` studies the
1,000-building block of ``bench_sunstudy.py`` (boxes 3-40 m tall, 20 m apart,
London) at hourly sun positions on every ``--every``-th day of 2026 (28 by
default: 13 days, 21 March added) and scales the cost to the year: the ground
with :func:`shadowgeo.sun_summaries_by_day`, every wall and roof with
:func:`shadowgeo.surface_sun_study` (exact shadows on all faces per sun
position, each face cut into polygons of equal sunlight hours). Each day runs
serially in this process, then on a Dask ``LocalCluster`` of single-threaded
workers (``--workers``), one task a day; the results are compared. The error
is measured against rays cast to the sun from random points of the walls,
roofs and ground on 21 March. ``--write`` puts the section in REPORT.md.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import platform
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_sunstudy import city  # noqa: E402
from common import cpu_model, write_section  # noqa: E402

from shadowgeo import Plane, sun_study, sun_summaries_by_day, surface_sun_study  # noqa: E402
from shadowgeo.parallel import client_for  # noqa: E402
from shadowgeo.sun import hourly, sun_lights  # noqa: E402

TITLE = "## Sunlight on ground, walls and roofs"
SITE = dict(latitude=51.5, longitude=-0.12)
MARCH = dt.date(2026, 3, 21)


@dataclass(frozen=True)
class FacadeDay:
    """A day's sunlight on the walls and roofs, without its polygons."""

    samples: int
    mean_hours: np.ndarray  # (m,) per face
    at_least_two: np.ndarray  # (m,) area with >= 2 h per face
    level_parts: int


def facade_day(caster, receiver, times) -> FacadeDay:
    """One day's :func:`surface_sun_study`, kept as its figures."""
    result = surface_sun_study(caster, receiver, times, **SITE)
    parts = sum(len(parts) for levels in result.levels for parts in levels.values())
    return FacadeDay(len(result.times), result.mean_hours(), result.area_with_at_least(2.0), parts)


def study_days(every: int) -> dict[dt.date, list[dt.datetime]]:
    days = {dt.date(2026, 1, 1) + dt.timedelta(days=k) for k in range(0, 365, every)} | {MARCH}
    return {
        day: hourly(
            dt.datetime(day.year, day.month, day.day, tzinfo=dt.UTC),
            dt.datetime(day.year, day.month, day.day, tzinfo=dt.UTC) + dt.timedelta(days=1),
        )
        for day in sorted(days)
    }


def serial_run(caster, receiver, ground, region, days):
    begin, cpu = time.perf_counter(), time.process_time()
    every_time = [t for times in days.values() for t in times]
    grounds = sun_summaries_by_day(caster, ground, region, every_time, **SITE)
    ground_wall, ground_cpu = time.perf_counter() - begin, time.process_time() - cpu
    begin, cpu = time.perf_counter(), time.process_time()
    facades = {}
    for day, times in days.items():
        facades[day] = facade_day(caster, receiver, times)
        print(f"  serial {day}: {time.perf_counter() - begin:.0f} s", file=sys.stderr, flush=True)
    facade_wall, facade_cpu = time.perf_counter() - begin, time.process_time() - cpu
    return grounds, facades, (ground_wall, ground_cpu), (facade_wall, facade_cpu)


def dask_run(caster, receiver, ground, region, days, workers):
    with client_for("local", workers=workers) as client:
        client.wait_for_workers(workers)
        before = sum(client.run(time.process_time).values())
        begin, cpu = time.perf_counter(), time.process_time()
        every_time = [t for times in days.values() for t in times]
        grounds = sun_summaries_by_day(caster, ground, region, every_time, **SITE, scheduler=client)
        # one object each (a scattered tuple would travel as its items)
        shared_caster = client.scatter([caster], broadcast=True)[0]
        shared_receiver = client.scatter([receiver], broadcast=True)[0]
        futures = {
            day: client.submit(
                facade_day, shared_caster, shared_receiver, times, key=f"facades-{day}"
            )
            for day, times in days.items()
        }
        facades = {day: future.result() for day, future in futures.items()}
        elapsed = time.perf_counter() - begin
        spent = time.process_time() - cpu + sum(client.run(time.process_time).values()) - before
        peaks = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    return grounds, facades, elapsed, spent, max(peaks.values()) / 1024


def same(first, second) -> bool:
    grounds_a, facades_a = first
    grounds_b, facades_b = second
    if grounds_a != grounds_b or facades_a.keys() != facades_b.keys():
        return False
    return all(
        a.samples == b.samples
        and a.level_parts == b.level_parts
        and np.array_equal(a.mean_hours, b.mean_hours)
        and np.array_equal(a.at_least_two, b.at_least_two)
        for a, b in ((facades_a[d], facades_b[d]) for d in facades_a)
    )


def _points(vertices, faces, count, rng):
    corners = vertices[faces]
    areas = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    chosen = rng.choice(len(faces), size=count, p=areas / areas.sum())
    a, b = rng.random(count), rng.random(count)
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    triangle = corners[chosen]
    points = triangle[:, 0] + a[:, None] * (triangle[:, 1] - triangle[:, 0])
    return points + b[:, None] * (triangle[:, 2] - triangle[:, 0]), chosen


def ray_errors(vertices, faces, receiver_faces, ground, region, count):
    """Hours of sun on 21 March at ``count`` random facade points and as many
    ground points, exact against rays cast to the sun (trimesh's ray test,
    from each point lifted 1e-6 m off its face). Returns per-kind (points,
    points whose hours differ, largest difference in hours)."""
    times = study_days(365)[MARCH]
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    rays = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    rng = np.random.default_rng(2026)
    result = surface_sun_study((vertices, faces), (vertices, receiver_faces), times, **SITE)
    points, on = _points(vertices, receiver_faces, count, rng)
    normals = mesh.face_normals[np.flatnonzero(mesh.face_normals[:, 1] > -0.5)][on]
    exact = result.sunlit_hours(points, on)
    traced = np.zeros(count)
    for direction in result.directions:
        front = normals @ -direction > 0
        hit = rays.intersects_any(points + 1e-6 * normals, np.tile(-direction, (count, 1)))
        traced += front & ~hit
    found = {"walls and roofs": (count, exact - traced)}
    study = sun_study((vertices, faces), ground, region, times, **SITE)
    flat = rng.uniform(region[:, [0, 2]].min(axis=0), region[:, [0, 2]].max(axis=0), (count, 2))
    on_ground = np.column_stack([flat[:, 0], np.zeros(count), flat[:, 1]])
    outside = ~mesh.contains(on_ground + [0, 1e-3, 0])
    on_ground = on_ground[outside]
    exact_ground = study.sunlit_hours(ground.to_2d(on_ground))
    traced_ground = np.zeros(len(on_ground))
    for light in sun_lights(SITE["latitude"], SITE["longitude"], study.times)[1]:
        direction = light.direction
        hit = rays.intersects_any(
            on_ground + [0, 1e-6, 0], np.tile(-direction, (len(on_ground), 1))
        )
        traced_ground += ~hit
    found["ground"] = (len(on_ground), exact_ground - traced_ground)
    return {
        kind: (n, int(np.sum(diff != 0)), float(np.abs(diff).max()))
        for kind, (n, diff) in found.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buildings", type=int, default=1000)
    parser.add_argument("--every", type=int, default=28, help="study every n-th day of 2026")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--points", type=int, default=2000, help="random points for the ray check")
    parser.add_argument("--write", action="store_true", help="put the section in REPORT.md")
    args = parser.parse_args()

    vertices, faces, half = city(args.buildings)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    walls_and_roofs = faces[mesh.face_normals[:, 1] > -0.5]
    roofs = mesh.face_normals[mesh.face_normals[:, 1] > -0.5][:, 1] > 0.5
    region = np.array([[-half, 0, half], [half, 0, half], [half, 0, -half], [-half, 0, -half]])
    ground = Plane([0, 1, 0], 0)
    days = study_days(args.every)
    caster, receiver = (vertices, faces), (vertices, walls_and_roofs)

    serial = serial_run(caster, receiver, ground, region, days)
    grounds, facades, (ground_wall, ground_cpu), (facade_wall, facade_cpu) = serial
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    samples_up = sum(day.samples for day in facades.values())
    parts = sum(day.level_parts for day in facades.values())
    dask = dask_run(caster, receiver, ground, region, days, args.workers) if args.workers else None
    identical = dask is not None and same((grounds, facades), dask[:2])
    errors = ray_errors(vertices, faces, walls_and_roofs, ground, region, args.points)

    march = facades[MARCH]
    areas = mesh.area_faces[mesh.face_normals[:, 1] > -0.5]
    wall_share = march.at_least_two[~roofs].sum() / areas[~roofs].sum()
    roof_share = march.at_least_two[roofs].sum() / areas[roofs].sum()
    wall_mean = march.mean_hours[~roofs] @ areas[~roofs] / areas[~roofs].sum()
    roof_mean = march.mean_hours[roofs] @ areas[roofs] / areas[roofs].sum()
    ground_share = grounds[MARCH].fraction_meeting(2.0)
    scale = 365 / len(days)
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE
    ).stdout.strip()
    load = os.getloadavg()[0]
    wall_total, cpu_total = ground_wall + facade_wall, ground_cpu + facade_cpu
    if dask is None:
        dask_text = "\nNot run on Dask this time (`--workers 0`).\n"
    else:
        dask_text = (
            f"| both, Dask LocalCluster of {args.workers} | {dask[2]:.1f} s | {dask[3]:.1f} s "
            f"| {dask[3] / samples_up:.3f} s | {dask[3] * scale / 60:.1f} min |\n\n"
            "Serial and Dask results identical (every day's per-face mean hours, areas with at "
            "least 2 h and level counts, and the ground's summaries, compared with `==`): "
            f"**{'yes' if identical else 'NO'}**; speed-up on {args.workers} workers (wall) "
            f"{wall_total / dask[2]:.2f}x; the largest worker peaked at {dask[4]:.0f} MB.\n"
        )
    text = f"""{TITLE}

`PYTHONPATH=$PWD python benchmarks/bench_city_sunlight.py --buildings {args.buildings} --every {args.every} --workers {args.workers}`
(run {dt.date.today()} from commit {commit}; {cpu_model()}, {os.cpu_count()} cores shared with other jobs,
load average {load:.1f} at the end; Python {platform.python_version()}).
{args.buildings:,} boxes ({len(faces):,} triangles, {len(walls_and_roofs):,} of them walls and roofs) on
the block of the sun study above, in London; hourly sun on {len(days)} days of 2026 (every {args.every}th
day from 1 January, and 21 March): {samples_up:,} sun positions above the horizon. The ground: the
block's plane, {"`sun_summaries_by_day`"} (the levels' areas). Walls and roofs: `surface_sun_study`, every
face's exact shadow at each sun position (one `shadow_on_surface` call for all faces) and every
face cut into exact polygons of equal hours ({parts:,} level parts over the days). *Year* scales
the CPU time by 365 / {len(days)}.

| part | wall time | CPU | CPU per sun position | year (scaled CPU) |
|---|---:|---:|---:|---:|
| ground, serial | {ground_wall:.1f} s | {ground_cpu:.1f} s | {ground_cpu / samples_up:.3f} s | {ground_cpu * scale / 60:.1f} min |
| walls and roofs, serial | {facade_wall:.1f} s | {facade_cpu:.1f} s | {facade_cpu / samples_up:.3f} s | {facade_cpu * scale / 60:.1f} min |
| both, serial | {wall_total:.1f} s | {cpu_total:.1f} s | {cpu_total / samples_up:.3f} s | {cpu_total * scale / 60:.1f} min |
{dask_text}
Peak resident memory: {peak:.0f} MB in this process after the serial run (the city, one day's
shadows and levels at a time).

On 21 March: {ground_share:.1%} of the ground has at least 2 h of sun; walls {wall_share:.1%} and roofs
{roof_share:.1%} of their area; mean hours of sun on walls {wall_mean:.2f} h, on roofs {roof_mean:.2f} h.

Error against rays cast to the sun from random points on 21 March (a point counts sunlit where
its face turns to the sun and trimesh's ray test from it, lifted 1e-6 m off the face, meets
nothing; hours compared sample by sample):

| where | points | points whose hours differ | largest difference |
|---|---:|---:|---:|
"""
    for kind, (count, differ, largest) in errors.items():
        text += f"| {kind} | {count:,} | {differ} | {largest:g} h |\n"
    text += """
Reading it. The shadows on walls and roofs cost one `shadow_on_surface` call per sun position
over all faces at once (the light's frame, the caster index and the unions built once); the
levels are one cover of every position's shadow triangles, 256 faces at a time, each face in a
cell of its own plane (`shadowgeo/sunlight_surfaces.py`). Points whose hours differ from the rays'
lie within rounding of a shadow's edge, where either answer is right; the table shows how few.
"""
    print(text)
    if args.write:
        write_section(TITLE, text)


if __name__ == "__main__":
    main()
