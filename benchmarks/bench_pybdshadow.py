"""Sunlight beside pybdshadow, on its own demo data (issue 33, Done-when 3).

Run from the repository root, with pybdshadow installed in its own venv::

    python3 -m venv /work/pbvenv && /work/pbvenv/bin/pip install pybdshadow
    PYTHONPATH=$PWD python benchmarks/bench_pybdshadow.py            # writes REPORT.md's section
    PYTHONPATH=$PWD python benchmarks/bench_pybdshadow.py --no-report

pybdshadow (Yu et al. 2023; 0.3.5 here) pulls in geopandas, transbigdata,
suncalc and keplergl; it lives in its own venv, and this script runs its side
there (``--pybdshadow-python``; the same file, ``--their-side``), which
writes what it computed and timed to a JSON file this side reads. The data:
``suzhou_buildings.geojson`` of the shared corpus, pybdshadow's
``example/data/bd_demo_2.json`` (2,000-odd footprints with heights, CRS84),
through its ``bd_preprocess``.

1. **One sun**: at 10:00 China Standard Time (02:00 UTC) on the day,
   pybdshadow's ``bdshadow_sunlight`` (one shadow polygon per building, in
   longitude and latitude: each wall's quadrilateral in an azimuthal
   equidistant frame at the walls' mean, the footprint added, merged by
   ``buffer(0)``), then the union of those (GEOS ``union_all``, timed apart);
   beside it ``shadowgeo.project_shadow`` of the footprint prisms read by
   ``shadowgeo.load`` (metres in a transverse Mercator at the data's centre)
   onto the ground, under *pybdshadow's* sun (suncalc's azimuth and
   altitude, turned into a direction in our frame with its true north).
   Areas compared in our metric frame (pybdshadow's polygons projected by
   pyproj); the symmetric difference measures where they differ.
2. **A day**: pybdshadow's ``cal_sunshine`` (ground, grid of ``--cell`` m
   cells by transbigdata, one sample every hour from sunrise + 30 min)
   against ``shadowgeo.sun_study`` of the same instants over a rectangle
   holding its grid, our sun (the same instants; the two sun models differ
   by hundredths of a degree). A cell's shadow time in pybdshadow is the
   samples whose shadow *touches* the cell (a spatial join), cells touching
   a building left out; ours per cell is exact: the area-weighted mean of the
   exact levels over the cell, and the same touching rule applied to our
   exact shadows reproduces its figure: the difference is its grid's.

Times are medians of ``--repeat`` calls after one warm call (``cal_sunshine``
and the study: one call each, minutes), in the same run; the machine is
shared (two cores, other jobs), so the ratio is what to read.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import shapely

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "corpus" / "gis" / "suzhou_buildings.geojson"
TITLE = "## Sunlight beside pybdshadow"
PB_PYTHON = "/work/pbvenv/bin/python"


def _timed(function, repeat):
    """Medians of ``repeat`` calls after a warm one: wall seconds and this
    process's CPU seconds (steadier on a shared machine), and the last result."""
    result = function()
    walls, cpus = [], []
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        result = function()
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus), result


def _once(function):
    """Wall and CPU seconds of one call, and its result."""
    start, cpu = time.perf_counter(), time.process_time()
    result = function()
    return time.perf_counter() - start, time.process_time() - cpu, result


# -- pybdshadow's side (run in its venv) ------------------------------------------------


def their_side(args: argparse.Namespace) -> None:
    import warnings

    # pybdshadow's own, about pandas, pyproj and CRS on concatenation
    warnings.simplefilter("ignore", FutureWarning)
    warnings.simplefilter("ignore", UserWarning)
    import geopandas as gpd
    import pandas as pd
    import pybdshadow
    from suncalc import get_position

    buildings = pybdshadow.bd_preprocess(gpd.read_file(args.data))
    moment = pd.Timestamp(args.moment)  # UTC
    low_lon, low_lat, high_lon, high_lat = list(buildings.bounds.mean())
    centre = ((low_lon + high_lon) / 2, (low_lat + high_lat) / 2)  # as bdshadow_sunlight
    sun = get_position(moment, *centre)
    wall, cpu, shadows = _timed(
        lambda: pybdshadow.bdshadow_sunlight(buildings, moment), args.repeat
    )
    union_wall, union_cpu, union = _once(lambda: shapely.union_all(np.asarray(shadows.geometry)))
    day_wall, day_cpu, grids = _once(
        lambda: pybdshadow.cal_sunshine(
            buildings.copy(), day=args.day, roof=False, accuracy=args.cell, precision=3600
        )
    )
    lon, lat = buildings["geometry"].iloc[0].bounds[:2]  # as cal_sunshadows
    table = pybdshadow.get_timetable(lon, lat, [args.day], 3600, 1800)
    suns = [get_position(stamp, *centre) for stamp in table["datetime"]]
    result = {
        "version": pybdshadow.__version__,
        "buildings": len(buildings),
        "sun": {"azimuth": float(sun["azimuth"]), "altitude": float(sun["altitude"])},
        "centre": centre,
        "shadow_seconds": [wall, cpu],
        "union_seconds": [union_wall, union_cpu],
        "shadow": shapely.to_wkb(union, hex=True),
        "per_building": len(shadows),
        "day_seconds": [day_wall, day_cpu],
        "times": [str(stamp) for stamp in table["datetime"]],
        "suns": [[float(sun["azimuth"]), float(sun["altitude"])] for sun in suns],
        "cells": shapely.to_wkb(np.asarray(grids.geometry), hex=True).tolist(),
        "cell_time": [float(value) for value in grids["time"]],
        "cell_hour": [float(value) for value in grids["Hour"]],
        "footprints": shapely.to_wkb(np.asarray(buildings.geometry), hex=True).tolist(),
    }
    Path(args.their_side).write_text(json.dumps(result))


# -- our side ----------------------------------------------------------------------------


def run_theirs(args: argparse.Namespace) -> dict:
    if args.theirs:
        return json.loads(Path(args.theirs).read_text())
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "theirs.json"
        command = [
            args.pybdshadow_python, __file__, "--their-side", str(out), "--data", str(args.data),
            "--moment", args.moment, "--day", args.day, "--cell", str(args.cell),
            "--repeat", str(args.repeat),
        ]  # fmt: skip
        subprocess.run(command, check=True)
        if args.keep_theirs:
            Path(args.keep_theirs).write_text(out.read_text())
        return json.loads(out.read_text())


def sun_light(site, azimuth: float, altitude: float):
    """suncalc's sun (azimuth from south, towards west; radians) as a
    DirectionalLight in the scene's frame (x east, y north at the grid,
    true north ``site.north``)."""
    from shadowgeo import DirectionalLight

    north = np.asarray(site.north, dtype=np.float64)
    east = np.array([north[1], -north[0], 0.0])
    towards = (
        -math.sin(azimuth) * math.cos(altitude) * east
        - math.cos(azimuth) * math.cos(altitude) * north
        + math.sin(altitude) * np.array([0.0, 0.0, 1.0])
    )
    return DirectionalLight(-towards)


def to_scene(site, geometries):
    """Longitude-latitude geometries in the scene's metric frame."""
    import pyproj

    move = pyproj.Transformer.from_crs("OGC:CRS84", site.crs, always_xy=True)
    return shapely.transform(
        geometries, lambda points: np.column_stack(move.transform(points[:, 0], points[:, 1]))
    )


def one_sun(args, scene, theirs) -> dict:
    from shadowgeo import Plane, project_shadow
    from shadowgeo.scene.sunlight import scene_study

    inputs = scene_study(scene, plane=Plane([0, 0, 1], 0))
    light = sun_light(scene.site, theirs["sun"]["azimuth"], theirs["sun"]["altitude"])
    ground = Plane([0, 0, 1], 0)
    wall, cpu, shadow = _timed(lambda: project_shadow(inputs.caster, light, ground), args.repeat)
    ours = shapely.MultiPolygon(
        [shapely.Polygon(ground.to_3d(p[0])[:, :2], [ground.to_3d(h)[:, :2] for h in p[1:]])
         for p in shadow.polygons]
    )  # fmt: skip
    ours = shapely.make_valid(ours)
    theirs_shadow = to_scene(scene.site, shapely.from_wkb(theirs["shadow"]))
    return {
        "ours": float(shadow.area),
        "theirs": float(theirs_shadow.area),
        "difference": float(shapely.symmetric_difference(ours, theirs_shadow).area),
        "seconds": [wall, cpu],
        "triangles": len(inputs.caster.faces),
    }


def one_day(args, scene, theirs) -> dict:
    from shadowgeo import Plane
    from shadowgeo.scene.sunlight import level_regions, study_scene

    times = [dt.datetime.fromisoformat(text).replace(tzinfo=dt.UTC) for text in theirs["times"]]
    cells = to_scene(scene.site, shapely.from_wkb(theirs["cells"]))
    low = np.min(shapely.bounds(cells)[:, :2], axis=0) - 1.0
    high = np.max(shapely.bounds(cells)[:, 2:], axis=0) + 1.0
    region = [[low[0], low[1]], [high[0], low[1]], [high[0], high[1]], [low[0], high[1]]]
    wall, cpu, (_, studies) = _once(
        lambda: study_scene(
            scene,
            times,
            step=dt.timedelta(hours=1),
            plane=Plane([0, 0, 1], 0),
            region=region,
            tz=dt.timezone(dt.timedelta(hours=8)),  # China Standard Time: the day, whole
        )
    )
    (study,) = studies.days.values()
    shadowed_hours = len(study.times) - np.asarray(
        [hours for hours, _ in level_regions(study, "Z")]
    )
    exact = _area_weighted(cells, level_regions(study, "Z"), shadowed_hours)
    touched = _touching(cells, scene, theirs)
    theirs_hours = np.asarray(theirs["cell_time"]) / 3600.0
    return {
        "seconds": [wall, cpu],
        "samples": len(study.times),
        "their_samples": len(times),
        "cells": len(cells),
        "exact": exact,
        "touched": touched,
        "theirs": theirs_hours,
        "levels": sum(len(parts) for parts in study.levels.values()),
    }


def _area_weighted(cells, levels, shadowed_hours) -> np.ndarray:
    """Per cell, the area-weighted mean shadowed hours of the exact levels."""
    total = np.zeros(len(cells))
    tree = shapely.STRtree(cells)
    for (_, region), hours in zip(levels, shadowed_hours, strict=True):
        # a ring that touches itself at a corner (as Clipper2 leaves them) made
        # two, for GEOS; the area is the same
        parts = shapely.get_parts(shapely.make_valid(shapely.get_parts(region)))
        part, cell = tree.query(parts, predicate="intersects")
        areas = shapely.area(shapely.intersection(parts[part], cells[cell]))
        np.add.at(total, cell, areas * hours)
    return total / shapely.area(cells)


def _touching(cells, scene, theirs) -> np.ndarray:
    """Per cell, the samples whose exact shadow under pybdshadow's sun at
    that instant touches it, in hours: its rule applied to our shadows."""
    from shadowgeo import Plane, project_shadow
    from shadowgeo.scene.sunlight import scene_study

    ground = Plane([0, 0, 1], 0)
    caster = scene_study(scene, plane=ground).caster
    lights = [sun_light(scene.site, azimuth, altitude) for azimuth, altitude in theirs["suns"]]
    count = np.zeros(len(cells))
    tree = shapely.STRtree(cells)
    for shadow in project_shadow(caster, lights, ground):
        parts = np.asarray(
            [
                shapely.Polygon(ground.to_3d(p[0])[:, :2], [ground.to_3d(h)[:, :2] for h in p[1:]])
                for p in shadow.polygons
            ],
            dtype=object,
        )
        _, cell = tree.query(parts, predicate="intersects")
        count[np.unique(cell)] += 1
    return count


def section(args, theirs, sun, day, commit) -> str:
    (their_wall, their_cpu), (union_wall, union_cpu) = (
        theirs["shadow_seconds"],
        theirs["union_seconds"],
    )
    our_wall, our_cpu = sun["seconds"]
    relative = (sun["ours"] - sun["theirs"]) / sun["theirs"]
    exact, touched, them = day["exact"], day["touched"], day["theirs"]
    same = float(np.mean(np.isclose(touched, them)))
    altitude = math.degrees(theirs["sun"]["altitude"])
    azimuth = math.degrees(theirs["sun"]["azimuth"]) + 180.0
    (day_wall, day_cpu), (study_wall, study_cpu) = theirs["day_seconds"], day["seconds"]
    lines = [
        TITLE,
        "",
        f"`PYTHONPATH=$PWD python benchmarks/bench_pybdshadow.py` (run {dt.date.today()} from "
        f"commit {commit}; pybdshadow {theirs['version']} in its own venv, same machine, same "
        "run, its side first; the 2 cores shared with other jobs, so CPU time, this process's "
        "own, is the figure to compare). pybdshadow's demo data, `suzhou_buildings.geojson` "
        f"(its `bd_demo_2.json`): {theirs['buildings']} footprints with heights, CRS84; ours "
        f"reads them as {sun['triangles']:,} triangles in a transverse Mercator at the data's "
        "centre.",
        "",
        f"**One sun**, {args.moment} UTC: suncalc's sun (pybdshadow's) at {altitude:.3f} "
        f"degrees up, azimuth {azimuth:.3f} degrees from north, used by both. Times: median of "
        f"{args.repeat} calls after a warm one.",
        "",
        "| | shadow area (m²) | wall | CPU | CPU ratio |",
        "|---|---:|---:|---:|---:|",
        f"| pybdshadow `bdshadow_sunlight` ({theirs['per_building']} shadows, one a building) "
        f"| | {their_wall:.3f} s | {their_cpu:.3f} s | 1 |",
        f"| its shadows united (GEOS `union_all`, one call) | {sun['theirs']:.3f} | "
        f"{union_wall:.3f} s | {union_cpu:.3f} s | |",
        f"| shadowgeo `project_shadow` (the union, exact) | {sun['ours']:.3f} | "
        f"{our_wall:.4f} s | {our_cpu:.4f} s | {our_cpu / their_cpu:.3f} "
        f"({our_cpu / (their_cpu + union_cpu):.3f} of both) |",
        "",
        f"Areas (in our metric frame): ours {relative:+.2e} relative to pybdshadow's; their "
        f"symmetric difference {sun['difference']:.3g} m², {sun['difference'] / sun['ours']:.1e} "
        "of the area.",
        "",
        f"**A day**, {args.day}: pybdshadow's `cal_sunshine` (ground, a {args.cell:g} m grid: "
        f"{day['cells']:,} cells not touching a building) against `shadowgeo.sun_study` at its "
        f"{day['their_samples']} instants ({day['samples']} with our sun up) over a rectangle "
        f"holding its grid: {day['levels']:,} exact level polygons. One call each.",
        "",
        "| | wall | CPU | CPU ratio |",
        "|---|---:|---:|---:|",
        f"| pybdshadow `cal_sunshine` | {day_wall:.1f} s | {day_cpu:.1f} s | 1 |",
        f"| shadowgeo `sun_study` (exact levels) | {study_wall:.1f} s | {study_cpu:.1f} s | "
        f"{study_cpu / day_cpu:.3f} |",
        "",
        "| shadowed hours per ground cell | mean | largest |",
        "|---|---:|---:|",
        f"| pybdshadow − ours exact (area-weighted mean over the cell) | "
        f"{float(np.mean(them - exact)):+.3f} h | {float(np.max(them - exact)):+.3f} h |",
        f"| smallest pybdshadow − ours exact | | {float(np.min(them - exact)):+.3f} h |",
        f"| pybdshadow − its rule on our exact shadows under its sun | "
        f"{float(np.mean(them - touched)):+.4f} h | "
        f"{float(np.max(np.abs(them - touched))):.3f} h |",
        "",
        f"Cells where pybdshadow's figure equals its rule (a cell is shadowed at an instant when "
        f"a shadow touches it) applied to our exact shadows under its sun: {same:.2%}.",
        "",
        READING,
    ]
    return "\n".join(lines) + "\n"


READING = """Reading it. **Shadows**: pybdshadow's shadow of a footprint prism is each
wall's quadrilateral swept along the sun plus the footprint, which on flat ground is exact,
so the two agree to its longitude-latitude round trip (an azimuthal equidistant frame at the
walls' mean and back, then pyproj to our transverse Mercator): the areas agree inside
1e-6, and the symmetric difference is a band along the shadows' edges (about 300 km of them)
some hundredths of a millimetre wide. Its time is Python over pandas rows
(a row a wall, a `groupby` and `buffer(0)` a building) and leaves the shadows overlapping;
ours is one vectorised pass over all triangles, the union included. **Hours**: pybdshadow
counts a cell as shadowed at an instant when any shadow touches it, so its shadowed hours
are never below the cell's true mean and are biased upwards wherever a shadow edge crosses
a cell; the exact levels give the true mean, the area-weighted one. Its own rule applied to
our exact shadows under its sun gives back its figure cell for cell (the last table row):
the whole difference from the exact levels is its grid's rule, not its shadows (the few
cells a little below the exact mean are the two sun models': the exact levels are cast under
our sun, its rule here under its own). It reports
sunlight as the day's length minus the shadowed samples, where we count sunlit samples;
shadowed hours mean the same in both, so they are what is compared."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--moment", default="2026-03-21 02:00:00", help="UTC")
    parser.add_argument("--day", default="2026-03-21")
    parser.add_argument("--cell", type=float, default=10.0, help="grid cell (m), pybdshadow's")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--pybdshadow-python", default=PB_PYTHON)
    parser.add_argument("--their-side", help=argparse.SUPPRESS)
    parser.add_argument("--keep-theirs", metavar="JSON", help="save pybdshadow's side here")
    parser.add_argument("--theirs", metavar="JSON", help="reuse a saved pybdshadow side")
    parser.add_argument("--no-report", action="store_true")
    args = parser.parse_args()
    if args.their_side:
        their_side(args)
        return
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from common import write_section

    import shadowgeo

    theirs = run_theirs(args)
    scene = shadowgeo.load(args.data)
    sun = one_sun(args, scene, theirs)
    day = one_day(args, scene, theirs)
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    text = section(args, theirs, sun, day, commit)
    print(text)
    if not args.no_report:
        write_section(TITLE, text)


if __name__ == "__main__":
    main()
