"""Sunlight on ground, walls and roofs of a city block: exact hours, serial and on Dask.

``PYTHONPATH=$PWD python benchmarks/bench_city_sunlight.py`` studies the
1,000-building block of ``bench_sunstudy.py`` (boxes 3-40 m tall, 20 m apart,
London) at hourly sun positions on every ``--every``-th day of 2026 (28 by
default: 13 days, 21 March added) and scales the cost to the year: the ground
with :func:`shadowgeo.sun_summaries_by_day`, every wall and roof with
:func:`shadowgeo.surface_sun_study` (exact shadows on all faces per sun
position, each face cut into polygons of equal sunlight hours). Each part runs
serially, then on a Dask ``LocalCluster`` of single-threaded workers
(``--workers``), one task a day; the results are compared. The walls and roofs
run in child processes, each a fresh interpreter: with ``--before DIR`` (the
source of an earlier commit, e.g. ``git archive 358660c | tar -x -C DIR``)
the earlier code runs too, alternately with this one (before serial, after
serial, before Dask, after Dask), so that both meet the same load on a shared
machine; CPU time is the measure. The error is measured against rays cast to
the sun from random points of the walls, roofs and ground on 21 March.
``--write`` puts the section in REPORT.md.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import pickle
import platform
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_sunstudy import city  # noqa: E402
from common import cpu_model, write_section  # noqa: E402

import shadowgeo  # noqa: E402
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


@dataclass(frozen=True)
class Run:
    """One run of a part: wall and CPU seconds (the workers' CPU included),
    the largest process's peak memory in MB, and the per-day results."""

    wall: float
    cpu: float
    peak: float
    results: dict


def ground_serial(caster, ground, region, days) -> Run:
    begin, cpu = time.perf_counter(), time.process_time()
    every_time = [t for times in days.values() for t in times]
    grounds = sun_summaries_by_day(caster, ground, region, every_time, **SITE)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return Run(time.perf_counter() - begin, time.process_time() - cpu, peak, grounds)


def ground_dask(caster, ground, region, days, workers) -> Run:
    with client_for("local", workers=workers) as client:
        client.wait_for_workers(workers)
        before = sum(client.run(time.process_time).values())
        begin, cpu = time.perf_counter(), time.process_time()
        every_time = [t for times in days.values() for t in times]
        grounds = sun_summaries_by_day(caster, ground, region, every_time, **SITE, scheduler=client)
        elapsed = time.perf_counter() - begin
        spent = time.process_time() - cpu + sum(client.run(time.process_time).values()) - before
        peaks = client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    return Run(elapsed, spent, max(peaks.values()) / 1024, grounds)


def facades_serial(caster, receiver, days) -> Run:
    """Each day's :func:`facade_day` in this process, one after another."""
    begin, cpu = time.perf_counter(), time.process_time()
    facades = {}
    for day, times in days.items():
        facades[day] = facade_day(caster, receiver, times)
        print(f"  serial {day}: {time.perf_counter() - begin:.0f} s", file=sys.stderr, flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return Run(time.perf_counter() - begin, time.process_time() - cpu, peak, facades)


def facades_dask(caster, receiver, days, workers) -> Run:
    """Each day's :func:`facade_day` as a task on a LocalCluster (the split
    :func:`shadowgeo.surface_sun_study_by_day` makes, kept here so that the
    earlier code, which lacks it, runs the same way; only the figures travel
    back)."""
    with client_for("local", workers=workers) as client:
        client.wait_for_workers(workers)
        before = sum(client.run(time.process_time).values())
        begin, cpu = time.perf_counter(), time.process_time()
        # one object each (a scattered tuple would travel as its items)
        shared_caster = client.scatter([caster], broadcast=True, hash=False)[0]
        shared_receiver = client.scatter([receiver], broadcast=True, hash=False)[0]
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
    return Run(elapsed, spent, max(peaks.values()) / 1024, facades)


def facades_child(args) -> None:
    """``--child serial|dask``: one facade run in this fresh process (whose
    ``shadowgeo`` is whatever PYTHONPATH gives), pickled to ``--out``."""
    vertices, faces, _ = city(args.buildings)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    receiver = (vertices, faces[mesh.face_normals[:, 1] > -0.5])
    days = study_days(args.every)
    if args.child == "serial":
        run = facades_serial((vertices, faces), receiver, days)
    else:
        run = facades_dask((vertices, faces), receiver, days, args.workers)
    with open(args.out, "wb") as out:
        pickle.dump((shadowgeo.__file__, run), out)


def facades_in_child(source: Path, mode: str, args) -> Run:
    """A facade run (``mode``: serial or dask) in a child process whose
    ``shadowgeo`` comes from ``source``."""
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "run.pickle"
        command = [sys.executable, __file__, "--child", mode, "--out", str(out)]
        command += ["--buildings", str(args.buildings), "--every", str(args.every)]
        command += ["--workers", str(args.workers)]
        env = dict(os.environ, PYTHONPATH=str(source))
        subprocess.run(command, check=True, env=env)
        with open(out, "rb") as found:
            module, run = pickle.load(found)
    if not Path(module).resolve().is_relative_to(source.resolve()):
        raise SystemExit(f"the child ran {module}, not the code in {source}")
    print(f"  {source.name} {mode}: {run.cpu:.1f} CPU-s", file=sys.stderr, flush=True)
    return run


def same_facades(first: dict, second: dict) -> bool:
    """Every day's figures equal with ``==``."""
    return first.keys() == second.keys() and all(
        a.samples == b.samples
        and a.level_parts == b.level_parts
        and np.array_equal(a.mean_hours, b.mean_hours)
        and np.array_equal(a.at_least_two, b.at_least_two)
        for a, b in ((first[d], second[d]) for d in first)
    )


def facade_runs(args) -> dict[tuple[str, str], Run]:
    """(code, mode) -> run, before and after alternately when ``--before``."""
    codes = {"after": HERE.parent}
    if args.before:
        codes = {"before": Path(args.before), "after": HERE.parent}
    modes = ["serial"] + (["dask"] if args.workers else [])
    return {
        (code, mode): facades_in_child(source, mode, args)
        for mode in modes
        for code, source in codes.items()
    }


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


def _row(part: str, run: Run, samples: int, scale: float) -> str:
    return (
        f"| {part} | {run.wall:.1f} s | {run.cpu:.1f} s | {run.cpu / samples:.3f} s "
        f"| {run.cpu * scale / 60:.1f} min | {run.peak:.0f} MB |"
    )


def _ratios(runs: dict[tuple[str, str], Run]) -> str:
    """The before / after lines of the table, where both ran."""
    lines = []
    for mode in ("serial", "dask"):
        if ("before", mode) in runs and ("after", mode) in runs:
            before, after = runs["before", mode], runs["after", mode]
            lines.append(
                f"| walls and roofs, {mode}: before / after | {before.wall / after.wall:.2f}x "
                f"| {before.cpu / after.cpu:.2f}x | | | |"
            )
    return "\n".join(lines)


def _agreement(runs: dict[tuple[str, str], Run]) -> str:
    """How the runs' figures compare: serial with Dask, and before with after."""
    text = ""
    if ("after", "dask") in runs:
        same = same_facades(runs["after", "serial"].results, runs["after", "dask"].results)
        text += (
            "Serial and Dask walls and roofs identical (every day's per-face mean hours, "
            f"areas with at least 2 h and level counts, with `==`): **{'yes' if same else 'NO'}**. "
        )
    if ("before", "serial") in runs:
        before, after = runs["before", "serial"].results, runs["after", "serial"].results
        mean_same = all(np.array_equal(before[d].mean_hours, after[d].mean_hours) for d in after)
        largest = max(
            float(np.abs(before[d].at_least_two - after[d].at_least_two).max()) for d in after
        )
        text += (
            f"Before and after: per-face mean hours identical **{'yes' if mean_same else 'NO'}** "
            f"(the shadows are the same bits); per-face area with at least 2 h differs by at "
            f"most {largest:.1e} m² (the levels' rounding); level parts "
            f"{sum(d.level_parts for d in before.values()):,} before, "
            f"{sum(d.level_parts for d in after.values()):,} after (slivers at rounding "
            "no longer cut from faces a sample shadows whole).\n"
        )
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--buildings", type=int, default=1000)
    parser.add_argument("--every", type=int, default=28, help="study every n-th day of 2026")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--points", type=int, default=2000, help="random points for the ray check")
    parser.add_argument("--before", help="source folder of the earlier commit to compare with")
    parser.add_argument("--write", action="store_true", help="put the section in REPORT.md")
    parser.add_argument("--child", choices=["serial", "dask"], help=argparse.SUPPRESS)
    parser.add_argument("--out", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        facades_child(args)
        return

    vertices, faces, half = city(args.buildings)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    walls_and_roofs = faces[mesh.face_normals[:, 1] > -0.5]
    roofs = mesh.face_normals[mesh.face_normals[:, 1] > -0.5][:, 1] > 0.5
    region = np.array([[-half, 0, half], [half, 0, half], [half, 0, -half], [-half, 0, -half]])
    ground = Plane([0, 1, 0], 0)
    days = study_days(args.every)
    caster = (vertices, faces)

    runs = facade_runs(args)
    grounds = ground_serial(caster, ground, region, days)
    on_dask = ground_dask(caster, ground, region, days, args.workers) if args.workers else None
    errors = ray_errors(vertices, faces, walls_and_roofs, ground, region, args.points)

    facades = runs["after", "serial"].results
    samples_up = sum(day.samples for day in facades.values())
    march = facades[MARCH]
    areas = mesh.area_faces[mesh.face_normals[:, 1] > -0.5]
    wall_share = march.at_least_two[~roofs].sum() / areas[~roofs].sum()
    roof_share = march.at_least_two[roofs].sum() / areas[roofs].sum()
    wall_mean = march.mean_hours[~roofs] @ areas[~roofs] / areas[~roofs].sum()
    roof_mean = march.mean_hours[roofs] @ areas[roofs] / areas[roofs].sum()
    ground_share = grounds.results[MARCH].fraction_meeting(2.0)
    scale = 365 / len(days)
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=HERE
    ).stdout.strip()
    load = os.getloadavg()[0]
    rows = [_row("ground, serial", grounds, samples_up, scale)]
    if on_dask is not None:
        rows.append(_row(f"ground, Dask ({args.workers} workers)", on_dask, samples_up, scale))
    for (code, mode), run in runs.items():
        how = "serial" if mode == "serial" else f"Dask ({args.workers} workers)"
        rows.append(_row(f"walls and roofs, {how}, {code}", run, samples_up, scale))
    after = runs["after", "serial"]
    rows.append(
        _row(
            "ground + walls and roofs, serial, after",
            Run(
                grounds.wall + after.wall,
                grounds.cpu + after.cpu,
                max(grounds.peak, after.peak),
                {},
            ),
            samples_up,
            scale,
        )
    )
    ratios = _ratios(runs)
    before_text = f" --before {args.before}" if args.before else ""
    ground_same = on_dask is not None and on_dask.results == grounds.results
    text = f"""{TITLE}

`PYTHONPATH=$PWD python benchmarks/bench_city_sunlight.py --buildings {args.buildings} --every {args.every} --workers {args.workers}{before_text}`
(run {dt.date.today()} from commit {commit}; {cpu_model()}, {os.cpu_count()} cores shared with other jobs,
load average {load:.1f} at the end; Python {platform.python_version()}).
{args.buildings:,} boxes ({len(faces):,} triangles, {len(walls_and_roofs):,} of them walls and roofs) on
the block of the sun study above, in London; hourly sun on {len(days)} days of 2026 (every {args.every}th
day from 1 January, and 21 March): {samples_up:,} sun positions above the horizon. The ground: the
block's plane, {"`sun_summaries_by_day`"} (the levels' areas). Walls and roofs: `surface_sun_study`, every
face's exact shadow at each sun position (one `shadow_on_surface` call for all faces) and every
face cut into exact polygons of equal hours, one day a task on Dask (as
`surface_sun_study_by_day` splits them). *Before* is the code of the earlier commit given
(`--before`, 358660c for issue 33 item 5), *after* this commit's; each walls-and-roofs run is a
fresh process, before and after alternately, and CPU time (the Dask workers' included) is the
measure on this shared machine. *Year* scales the CPU time by 365 / {len(days)}.

| part | wall time | CPU | CPU per sun position | year (scaled CPU) | peak memory |
|---|---:|---:|---:|---:|---:|
{chr(10).join(rows)}
{ratios}

{_agreement(runs)}Ground serial and on Dask identical (`==` on every day's summary): **{"yes" if ground_same else "not run" if on_dask is None else "NO"}**.
Peak memory is the largest process's (a Dask worker's on Dask).

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
    text += READING
    print(text)
    if args.write:
        write_section(TITLE, text)


READING = """
Reading it. Where the time went before (cProfile of 21 March, 12 sun positions, 17 s): half in
the shadows, one `shadow_on_surface` call per sun position over all faces at once (of that,
Clipper2's unions of each face's pieces with their budget checks 45%, clipping and projecting the
caster triangles onto each face 28%, the pair search 17%), and half in the levels: one cover of
every position's shadow triangles, 256 faces at a time, each face in a cell of its own plane
(`shadowgeo/sunlight_surfaces.py`), whose Clipper2 unions, one per level, took 55% of it and the
level polygons' extraction 18%. What changed: a sun position that shadows a face whole (its
shadow's area is the face's: 28% of the shadowed face-positions on 21 March) now lowers that
face's count like a face turned away, instead of sending its triangles through every union; and
faces go to the cover in chunks of faces shadowed in part at as many positions, so a chunk of
faces shadowed once or twice stops after two or three unions instead of paying for a neighbour
shadowed all day (the unions on 21 March: 3,884 before, 1,800 after). The shadows are unchanged
(same bits), and are now most of the time. Points whose hours differ from the rays' lie within
rounding of a shadow's edge, where either answer is right; the table shows how few.
"""


if __name__ == "__main__":
    main()
