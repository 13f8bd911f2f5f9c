"""A year of sunlight hours on the ground and on every wall and roof of a city block.

``PYTHONPATH=$PWD python benchmarks/bench_year.py`` studies the 1,000-building
block of ``bench_sunstudy.py`` (boxes 3-40 m tall, 20 m apart, London) at
hourly sun positions on every day of 2026, as a planner would ask for it:

- **The year, on Dask** (``--workers`` single-threaded workers of a
  ``LocalCluster``, one task a day): the ground with
  :func:`shadowgeo.sun_summaries_by_day` (the exact levels of equal hours and
  their areas), the walls and roofs with
  :func:`shadowgeo.surface_sun_study_by_day` and ``shadows=False`` (each
  face's exact hours, from the shadowed share of each face at each sun
  position: convex bodies as one ring a face, the union of a face's pieces
  measured by compiled loops). Wall time, CPU (the workers' included) and
  peak memory.
- **Side by side on every ``--sample``-th day**, in this process, the walls'
  and roofs' hours three ways: ``shadows=False`` as above; the exact shadows
  of :func:`shadowgeo.shadow_on_surface` (``shadows=True``, the 2-D union of
  each face's pieces, and where each shadow lies); and the method of the
  daylighting tools (Ladybug's "direct sun hours", Radiance): rays to the sun
  from points on each face, here ``--points`` squared points a face on a
  regular grid of the triangle (trimesh's ray test), each face's hours the
  mean of its points', on ``--ray-faces`` random faces (its time scaled to
  all). CPU per sun position, as a ratio to ``shadows=False``, and each
  method's largest difference in a face's hours on a day from the exact
  shadows'.

``--write`` puts the section in REPORT.md.
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
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_city_sunlight import SITE, study_days  # noqa: E402
from bench_sunstudy import city  # noqa: E402
from common import cpu_model, write_section  # noqa: E402

from shadowgeo import (  # noqa: E402
    Plane,
    sun_summaries_by_day,
    surface_sun_study,
    surface_sun_study_by_day,
)
from shadowgeo.parallel import client_for  # noqa: E402

TITLE = "## A year of sunlight on every wall, roof and the ground"


def _peaks(client) -> float:
    """The largest worker's peak memory, MB."""
    found = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    return max(found.values()) / 1024


def year_on_dask(caster, receiver, ground, region, times, workers):
    """The year's ground and facade studies on one LocalCluster: per part
    (wall s, CPU s, peak MB) and the results (ground summaries, per-face
    hours over the year, sun positions)."""
    figures = {}
    with client_for("local", workers=workers) as client:
        client.wait_for_workers(workers)

        def measured(name, work):
            before = sum(client.run(time.process_time).values())
            begin, cpu = time.perf_counter(), time.process_time()
            result = work()
            wall = time.perf_counter() - begin
            spent = time.process_time() - cpu + sum(client.run(time.process_time).values()) - before
            figures[name] = (wall, spent, _peaks(client))
            print(f"  {name}: {wall:.0f} s wall, {spent:.0f} CPU-s", file=sys.stderr, flush=True)
            return result

        def progress(done, total):
            print(f"\r  {done}/{total} days", end="", file=sys.stderr, flush=True)

        grounds = measured(
            "ground",
            lambda: sun_summaries_by_day(
                caster, ground, region, times, **SITE, scheduler=client, progress=progress
            ),
        )
        facades = measured(
            "walls and roofs",
            lambda: surface_sun_study_by_day(
                caster, receiver, times, **SITE, levels=False, shadows=False,
                scheduler=client, progress=progress,
            ),
        )  # fmt: skip
    hours = sum(day.mean_hours() for day in facades.values())
    positions = sum(len(day.times) for day in facades.values())
    return figures, grounds, hours, positions


def grid_points(triangles: np.ndarray, per_side: int) -> tuple[np.ndarray, np.ndarray]:
    """Points on a regular grid inside each triangle (the centres of its
    ``per_side``² congruent sub-triangles): (f * per_side², 3) and the face
    of each."""
    k = per_side
    weights = []
    for i in range(k):
        for j in range(k - i):
            weights.append(((i + 1 / 3) / k, (j + 1 / 3) / k))  # upright sub-triangles
            if i + j < k - 1:
                weights.append(((i + 2 / 3) / k, (j + 2 / 3) / k))  # and the turned ones
    w = np.array(weights)
    a, b = triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    points = triangles[:, None, 0] + w[None, :, :1] * a[:, None] + w[None, :, 1:] * b[:, None]
    return points.reshape(-1, 3), np.repeat(np.arange(len(triangles)), len(w))


def ray_hours(mesh, receiver_faces, directions, per_side) -> tuple[np.ndarray, float]:
    """Each receiving face's hours (one per sun position) as the mean over
    its grid points of the positions whose ray to the sun meets nothing
    (from the point lifted 1e-6 m off its face), and the CPU seconds."""
    cpu = time.process_time()
    rays = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    triangles = mesh.vertices[receiver_faces]
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    points, face = grid_points(triangles, per_side)
    lifted = points + 1e-6 * normal[face]
    sunlit = np.zeros(len(points))
    for direction in directions:
        front = normal[face] @ -direction > 0
        hit = np.ones(len(points), dtype=bool)
        if front.any():
            hit[front] = rays.intersects_any(
                lifted[front], np.tile(-direction, (int(front.sum()), 1))
            )
        sunlit += ~hit
    hours = np.bincount(face, weights=sunlit, minlength=len(triangles)) / (
        len(points) / len(triangles)
    )
    return hours, time.process_time() - cpu


def side_by_side(caster, receiver, days, per_side, ray_faces):
    """Per method: CPU seconds over the days (the rays' scaled from
    ``ray_faces`` random faces to all) and the largest difference in a face's
    hours on a day from the exact shadows'; and the sun positions."""
    mesh = trimesh.Trimesh(*caster, process=False)
    chosen = np.random.default_rng(2026).choice(len(receiver[1]), ray_faces, replace=False)
    cpu = {"quick": 0.0, "shadows": 0.0, "rays": 0.0}
    worst = {"quick": 0.0, "rays": 0.0}
    positions = 0
    for day, times in days.items():
        start = time.process_time()
        quick = surface_sun_study(caster, receiver, times, **SITE, levels=False, shadows=False)
        cpu["quick"] += time.process_time() - start
        start = time.process_time()
        exact = surface_sun_study(caster, receiver, times, **SITE, levels=False)
        cpu["shadows"] += time.process_time() - start
        traced, spent = ray_hours(mesh, receiver[1][chosen], exact.directions, per_side)
        cpu["rays"] += spent * len(receiver[1]) / ray_faces
        hours = exact.mean_hours()
        worst["quick"] = max(worst["quick"], float(np.abs(quick.mean_hours() - hours).max()))
        worst["rays"] = max(worst["rays"], float(np.abs(traced - hours[chosen]).max()))
        positions += len(exact.times)
        print(f"  side by side {day}: {cpu}", file=sys.stderr, flush=True)
    return cpu, worst, positions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buildings", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--sample", type=int, default=61, help="side by side on every n-th day")
    parser.add_argument(
        "--points", type=int, default=3, help="grid points a face side for the rays"
    )
    parser.add_argument("--ray-faces", type=int, default=1000, help="faces the rays test")
    parser.add_argument(
        "--days", type=int, default=365, help="the year's first n days (a quick run)"
    )
    parser.add_argument("--write", action="store_true", help="put the section in REPORT.md")
    args = parser.parse_args()

    vertices, faces, half = city(args.buildings)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    chosen = mesh.face_normals[:, 1] > -0.5
    receiver = (vertices, faces[chosen])
    region = np.array([[-half, 0, half], [half, 0, half], [half, 0, -half], [-half, 0, -half]])
    ground = Plane([0, 1, 0], 0)
    caster = (vertices, faces)
    every_day = study_days(1)
    year = [t for day in sorted(every_day)[: args.days] for t in every_day[day]]

    figures, grounds, hours, positions = year_on_dask(
        caster, receiver, ground, region, year, args.workers
    )
    sampled = {day: every_day[day] for day in sorted(every_day)[: args.days : args.sample]}
    cpu, worst, sampled_positions = side_by_side(
        caster, receiver, sampled, args.points, min(args.ray_faces, len(receiver[1]))
    )

    areas = mesh.area_faces[chosen]
    roofs = mesh.face_normals[chosen][:, 1] > 0.5
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE
    ).stdout.strip()
    ground_mean = sum(
        sum(h * a for h, a in summary.level_areas.items()) / summary.area
        for summary in grounds.values()
    )
    rows = []
    for name, (wall, spent, peak) in figures.items():
        rows.append(
            f"| {name} | {wall / 60:.1f} min | {spent / 60:.1f} min | {spent / positions:.3f} s "
            f"| {peak:.0f} MB |"
        )
    total_wall = sum(f[0] for f in figures.values())
    total_cpu = sum(f[1] for f in figures.values())
    rows.append(
        f"| **ground + walls and roofs** | **{total_wall / 60:.1f} min** | {total_cpu / 60:.1f} min "
        f"| {total_cpu / positions:.3f} s | |"
    )
    per = {name: spent / sampled_positions for name, spent in cpu.items()}
    grid = args.points * args.points
    text = f"""{TITLE}

`PYTHONPATH=$PWD python benchmarks/bench_year.py --buildings {args.buildings} --workers {args.workers} --sample {args.sample} --points {args.points} --ray-faces {args.ray_faces}`
(run {dt.date.today()} from commit {commit}; {cpu_model()}, {os.cpu_count()} cores;
Python {platform.python_version()}; load average {os.getloadavg()[0]:.1f} at the end).
{args.buildings:,} boxes ({len(faces):,} triangles, {int(chosen.sum()):,} of them walls and roofs) in
London, hourly sun on {min(args.days, 365)} days of 2026: {positions:,} sun positions above the
horizon. The ground: the block's plane, `sun_summaries_by_day` (the exact levels of equal hours and
their areas); walls and roofs: `surface_sun_study_by_day(..., levels=False, shadows=False)`, each
face's exact hours. Both on a Dask `LocalCluster` of {args.workers} single-threaded workers, one task
a day; CPU counts the workers'. Peak memory is the largest worker's.

| the year | wall time | CPU | CPU per sun position | peak memory |
|---|---:|---:|---:|---:|
{chr(10).join(rows)}

Mean hours of sun over the year (area-weighted): ground {ground_mean:,.0f} h, walls
{hours[~roofs] @ areas[~roofs] / areas[~roofs].sum():,.0f} h, roofs {hours[roofs] @ areas[roofs] / areas[roofs].sum():,.0f} h.

Side by side on one day in {args.sample} ({len(sampled)} days, {sampled_positions} sun positions), walls and
roofs, one process: each method's CPU per sun position and its largest difference in one face's
hours on one day from the exact shadows' (`shadow_on_surface`, the 2-D union of each face's pieces).
Rays: the daylighting tools' way (Ladybug's direct sun hours), {grid} points a face on a regular
grid, a ray to the sun from each (trimesh's ray test), a face's hours the mean of its points'; on
{args.ray_faces:,} random faces, its time scaled to all.

| method | CPU per sun position | time / `shadows=False` | largest difference in a face's hours on a day |
|---|---:|---:|---:|
| `shadows=False` (convex pieces, compiled union) | {per["quick"]:.3f} s | 1.00x | {worst["quick"]:.1e} h |
| `shadows=True` (exact shadows, 2-D union) | {per["shadows"]:.3f} s | {per["shadows"] / per["quick"]:.2f}x | 0 (the reference) |
| rays, {grid} points a face | {per["rays"]:.3f} s | {per["rays"] / per["quick"]:.2f}x | {worst["rays"]:.2f} h |
"""
    text += READING
    print(text)
    if args.write:
        write_section(TITLE, text)


READING = """
Reading it. A face's hours need only its shadowed share at each sun position, not where on it the
shadow lies. `shadows=False` measures that share from convex pieces: each box is one piece a face,
the hull of its corners' images cut to the face (cut first to its part ahead of the face's plane),
a face that one hull holds is shadowed whole, and the area of the union of a face's pieces comes
from compiled loops (`shadowgeo.kernels`); the 2-D union, the stitching and the triangles of the
exact shadows are skipped. The differences from the exact shadows are rounding. The Dask figures
include what a study pays beyond the geometry: each worker's import of numba and its cached loops,
sending the meshes once, and each day's result back to the client. The rays are trimesh's own ray
test (numpy and an R-tree, no Embree): a compiled ray tracer (Radiance, Embree) is far faster per
ray, but a point sample still misses the share of a face between its points, hence their error
of up to most of an hour on one face in one day with 9 points a face.
"""


if __name__ == "__main__":
    main()
