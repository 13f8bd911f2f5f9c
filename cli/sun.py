"""``shadowgeo sun SCENE [OUT] [--at LAT,LON]``: a sun study of a scene's floor.

A thin layer over :func:`shadowgeo.scene.sunlight.study_scene` (the floor and
casters found as ``convert`` finds receivers) and, for OUT, over
:func:`shadowgeo.scene.sunlight.sunlight_shapes` and :func:`shadowgeo.save`.
Several days run on Dask, one task a day, as ``convert``'s batches do.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np
import shapely

import shadowgeo
from shadowgeo.batch import save_output
from shadowgeo.io.atomic import remove_stale
from shadowgeo.io.cityjson_write import (
    ATTRIBUTE,
    SurfacePolygon,
    object_types,
    polygon_values,
    surface_polygons,
    write_surface_hours,
)
from shadowgeo.io.gis_write import (
    Layer,
    axis_names,
    is_gis_path,
    output_crs,
    to_output,
    write_layers,
)
from shadowgeo.io.sunlight_glb import write_hours_glb
from shadowgeo.scene.facade_hours import (
    ROOFS,
    SURFACE_KINDS,
    TERRAIN,
    WALLS,
    FacadeHours,
    facade_hours,
    is_terrain,
)
from shadowgeo.scene.sunlight import (
    SceneStudy,
    hours_faces,
    level_regions,
    roof_triangles,
    shadows_at,
    study_scene,
    sunlight_shapes,
)
from shadowgeo.sunstudy import SUN_DISC_SAMPLES, days_table

from .common import (
    ProgressBar,
    add_dask_arguments,
    dask_failure,
    plane_argument,
    positive_int,
    terminal,
)

EPILOG = """\
examples:
  shadowgeo sun courtyard.x3d --at 51.5,-0.12                  (21 March: BRE's 2-hour test)
  shadowgeo sun courtyard.x3d map.x3d --at 51.5,-0.12 --date 2026-06-21
  shadowgeo sun courtyard.x3d --at 51.5,-0.12 --region -3,-3,3,-3,3,3,-3,3
  shadowgeo sun courtyard.x3d --at 51.5,-0.12 --sun-angle 0.53         (the sun's disc)
  shadowgeo sun garden.glb --at -33.9,151.2 --date 2026-06-21          (Sydney, midwinter)
  shadowgeo sun city.glb --at 40.7,-74.0 --date 2026-01-01 --days 365 --hours 4
  shadowgeo sun city.glb --at 40.7,-74.0 --days 30 --scheduler tcp://10.0.0.5:8786
  shadowgeo sun delft.city.json levels.gpkg --date 2026-03-21 --shadows-at 09:00,12:00,15:00
  shadowgeo sun suzhou.geojson levels.geojson --date 2026-03-21 --plot map.png
  shadowgeo sun delft.city.json --date 2026-03-21 --mesh hours.glb   (ground, walls, roofs)
  shadowgeo sun rotterdam.city.json --at 51.92,4.48 --cityjson hours.city.json
  shadowgeo sun delft.city.json --dem ahn.tif --mesh hours.glb      (terrain: hours, casts)

The floor is the largest flat surface found that faces up under the scene
(--receiver DEF names one, --plane a,b,c,d gives a plane), else the ground
plane under the scene's lowest point; the region studied is the floor's
outline, or the scene's plan for a plane, or the --region given (corners
in plan, dropped onto the floor's plane). Every other face casts. The sun is
sampled every --every minutes (60), each sample standing for the minutes
around it, over whole days of local mean time (the longitude's hour zone).
--sun-angle 0.53 takes the sun as the disc it is: a point near a shadow
edge that sees part of it counts that part of the sample (durations become
fractional there, in steps of the sample's time over --sun-samples).
It prints, for one day, the area sunlit for each duration and the share of
the region with at least --hours of sun (2); for several days, that share
day by day. OUT (one day) is the scene with the day's map of sunlight hours
added as shapes, dark purple (none) to yellow (sun all day); OUT as .gpkg or
.geojson gets the day's levels as polygons (layer 'sunlight': hours, date,
threshold_h, meets) in the input's CRS: a GeoPackage in the file's own CRS,
GeoJSON in longitude and latitude (CRS84, as RFC 7946 asks); --shadows-at
adds the shadows at those local times (layer 'shadows', attribute 'time').
--plot draws the day's map with the buildings and a legend of hours, in the
input's CRS. City data (a file naming its CRS) with flat objects (roads,
land, water: no wall, or lower than 1 m) is studied on their ground: the
plane at their median height over the file's plan, the rest casting.
Walls and roofs: for city data (CityJSON, footprints), --mesh and --cityjson
also get the hours of sun on every wall and roof of the buildings (a
CityJSON's Building and BuildingPart objects; trees and the rest only
cast), which shade each other, at the same samples:
each face's mean over its area, exact (--surfaces walls, roofs or none
chooses; given for any scene, it also prints their summary). A face's kind
is its semantic surface in the file, else its facing (LoD1 blocks: steeper
than 30 degrees a wall, facing up a roof). --mesh colours them by the map's
legend; --cityjson writes the input CityJSON with, on each RoofSurface and
WallSurface, an attribute 'sunlight_hours': the polygon's mean hours of sun
over all the days studied (any --days). Footprints have no CityJSON to carry
them: use --mesh. A GIS OUT gets, when walls and roofs are studied (ask with
--surfaces), a layer 'surfaces': each face a 3-D triangle (object, kind,
hours, date). Walls and roofs take the sun as a point (--sun-angle is for
the ground).
--dem TIF (a GeoTIFF DEM, read with rasterio) adds the terrain under the
city: the raster around the buildings (plus --dem-margin metres, 100),
projected into the city data's CRS, averaged down to at most 40,000 cells,
nodata cells left as holes. It receives (its faces' hours, kind
TerrainSurface, in --mesh and the GIS 'surfaces' layer) and casts on the
buildings and on itself. CityJSON heights are absolute and stay as given;
footprints give heights above a base, so each footprint building is stood
on the DEM's height at its footprint's centroid (with a note). The ground
plane study and its table are as without --dem.
Several days run on a Dask LocalCluster started here (--workers N), on a
running cluster (--scheduler ADDRESS) or here (--serial); the results are the
same either way. Exit codes: 0 done, 1 bad input or OUT cannot be written,
2 bad usage, 130 interrupted (Ctrl-C, SIGINT), 143 stopped by SIGTERM, 129 by SIGHUP; OUT is
written atomically: whole, or not there.
"""


# Durations whose area is under this share of the region are not listed: the
# slivers (about 1e-15 of it) left where shadow edges run along the region's.
SLIVER = 1e-9


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "sun",
        help="sun study: hours of sunlight on a scene's floor, as a table and a map",
        description="Study the sunlight on SCENE's floor at a place, over whole days: the "
        "area sunlit for each duration, exactly, and the share meeting a threshold; OUT "
        "gets the scene with the day's map of sunlight hours.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_files(parser)
    _add_days(parser)
    _add_sun(parser)
    _add_floor(parser)
    _add_extra_outputs(parser)
    _add_terrain(parser)
    add_dask_arguments(parser, "day", "a LocalCluster here for several days")
    parser.set_defaults(func=run, parser=parser)


def _add_files(parser: argparse.ArgumentParser) -> None:
    """SCENE and OUT."""
    parser.add_argument("input", type=Path, metavar="SCENE", help="the scene to study")
    parser.add_argument(
        "output",
        type=Path,
        nargs="?",
        metavar="OUT",
        help="write the scene with the day's map of sunlight hours (one day only)",
    )


def _add_days(parser: argparse.ArgumentParser) -> None:
    """Where and when: --at, --date, --days, --every."""
    parser.add_argument(
        "--at",
        type=place_argument,
        metavar="LAT,LON",
        help="the site, in degrees (north and east positive); needed only when the file "
        "does not say where it is (city data with a CRS does)",
    )
    parser.add_argument(
        "--date",
        type=date_argument,
        metavar="YYYY-MM-DD",
        help="the first day (default: 21 March of this year)",
    )
    parser.add_argument(
        "--days", type=positive_int, default=1, metavar="N", help="days studied (default 1)"
    )
    parser.add_argument(
        "--every",
        type=positive_int,
        default=60,
        metavar="MINUTES",
        help="minutes between sun samples (default 60)",
    )


def _add_sun(parser: argparse.ArgumentParser) -> None:
    """The sun and the threshold: --sun-angle, --sun-samples, --hours."""
    parser.add_argument(
        "--sun-angle",
        type=sun_angle_argument,
        default=0.0,
        metavar="DEG",
        help="the sun's angular diameter in degrees: 0.53 is the real sun's, whose disc "
        "half hidden near a shadow edge counts half (fractional hours there); 0, the "
        "default, is a point sun",
    )
    parser.add_argument(
        "--sun-samples",
        type=positive_int,
        default=None,
        metavar="N",
        help=f"directions each sample's sun disc is spread over (default {SUN_DISC_SAMPLES}; "
        "the time grows with about the cube of N times the samples)",
    )
    parser.add_argument(
        "--hours",
        type=hours_argument,
        default=2.0,
        metavar="H",
        help="the threshold: the share of the region with at least H hours of sun (default 2)",
    )


def _add_floor(parser: argparse.ArgumentParser) -> None:
    """What is studied: --receiver or --plane, and --region."""
    receiving = parser.add_mutually_exclusive_group()
    receiving.add_argument(
        "--receiver",
        action="append",
        metavar="DEF",
        help="the floor to study (the first that faces up, if repeated)",
    )
    receiving.add_argument(
        "--plane",
        type=plane_argument,
        metavar="a,b,c,d",
        help="study the plane a x + b y + c z + d = 0 over the scene's plan",
    )
    parser.add_argument(
        "--region",
        type=region_argument,
        metavar="X,Z,X,Z,...",
        help="study only this polygon, corners in plan (x,z for a Y-up scene, x,y for Z up)",
    )


def _add_extra_outputs(parser: argparse.ArgumentParser) -> None:
    """What else is written or shown: --shadows-at, --plot, --mesh, --progress."""
    parser.add_argument(
        "--shadows-at",
        type=clock_times_argument,
        metavar="HH:MM[,HH:MM...]",
        help="with a .gpkg or .geojson OUT: add the shadows at these local times of the "
        "day, one feature a time with a 'time' attribute, in a layer 'shadows'",
    )
    parser.add_argument(
        "--plot",
        type=Path,
        metavar="PNG",
        help="draw the day's map of sunlight hours, buildings over it, in the input's CRS",
    )
    parser.add_argument(
        "--mesh",
        type=Path,
        metavar="GLB",
        help="write the day's ground levels and the buildings as a .glb with hours of "
        "sunlight per face (attribute _SUNLIGHT_HOURS, -1 where not studied) and colours",
    )
    parser.add_argument(
        "--cityjson",
        type=Path,
        metavar="CITY.json",
        help="write the input CityJSON with the hours of sun over the days studied on each "
        "RoofSurface and WallSurface polygon (attribute 'sunlight_hours')",
    )
    parser.add_argument(
        "--surfaces",
        type=surfaces_argument,
        metavar="KINDS",
        help="the building faces given hours: walls,roofs (the default for city data "
        "when --mesh or --cityjson is asked), walls, roofs, or none (the ground only); "
        "with a .gpkg or .geojson OUT, their faces in a layer 'surfaces'",
    )
    parser.add_argument(
        "--progress", action="store_true", help="show a progress bar even when not on a terminal"
    )


def _add_terrain(parser: argparse.ArgumentParser) -> None:
    """The terrain: --dem and --dem-margin."""
    parser.add_argument(
        "--dem",
        type=Path,
        metavar="TIF",
        help="a DEM (GeoTIFF) giving the terrain under city data, which receives (hours "
        "per face in --mesh and the GIS 'surfaces' layer) and casts",
    )
    parser.add_argument(
        "--dem-margin",
        type=margin_argument,
        default=100.0,
        metavar="METRES",
        help="how far round the buildings the DEM is read (default 100 m)",
    )


def margin_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a distance in metres >= 0, got {text!r}")
    return value


def place_argument(text: str) -> tuple[float, float]:
    try:
        latitude, longitude = (float(part) for part in text.split(","))
    except ValueError:
        latitude = longitude = float("nan")
    if not (-90 <= latitude <= 90 and -180 <= longitude <= 180):
        raise argparse.ArgumentTypeError(
            f"expected LAT,LON in degrees (-90..90, -180..180), got {text!r}"
        )
    return latitude, longitude


def region_argument(text: str) -> list[tuple[float, float]]:
    try:
        values = [float(part) for part in text.split(",")]
    except ValueError:
        values = []
    if len(values) < 6 or len(values) % 2 or not all(map(math.isfinite, values)):
        raise argparse.ArgumentTypeError(
            f"expected three or more plan corners X,Z,X,Z,X,Z,..., got {text!r}"
        )
    return list(zip(values[0::2], values[1::2], strict=True))


def date_argument(text: str) -> dt.date:
    try:
        return dt.date.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a date YYYY-MM-DD, got {text!r}") from None


def clock_times_argument(text: str) -> list[dt.time]:
    try:
        return [dt.time.fromisoformat(part.strip()) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected local times HH:MM[,HH:MM...], got {text!r}"
        ) from None


def surfaces_argument(text: str) -> tuple[str, ...]:
    """``walls,roofs`` -> the semantic kinds; ``none`` -> ()."""
    words = [part.strip() for part in text.split(",")]
    if words == ["none"]:
        return ()
    if not all(word in SURFACE_KINDS for word in words):
        raise argparse.ArgumentTypeError(
            f"expected walls, roofs, walls,roofs or none, got {text!r}"
        )
    return tuple(dict.fromkeys(SURFACE_KINDS[word] for word in words))


def sun_angle_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 <= value < 90:
        raise argparse.ArgumentTypeError(
            f"expected the sun's angular diameter in degrees, 0 to under 90 (the sun's is "
            f"0.53), got {text!r}"
        )
    return value


def hours_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 <= value <= 24:
        raise argparse.ArgumentTypeError(f"expected hours between 0 and 24, got {text!r}")
    return value


def local_zone(longitude: float) -> dt.timezone:
    """The hour zone of local mean time at ``longitude`` (15 degrees an hour)."""
    return dt.timezone(dt.timedelta(hours=round(longitude / 15.0)))


@dataclasses.dataclass(frozen=True)
class _Days:
    """The days studied: their hour zone, first day, sample step and sample times."""

    zone: dt.timezone
    first: dt.date
    step: dt.timedelta
    times: list[dt.datetime]


def run(args: argparse.Namespace) -> int:
    _check_usage(args)
    _check_output(args)
    scene = shadowgeo.load(args.input)
    if args.output is not None and is_gis_path(args.output):
        output_crs(scene.site, args.output)  # GeoJSON of a file with no CRS: refused now
    _settle_site(args, scene)
    kinds = _surface_kinds(args, scene)
    polygons = _cityjson_polygons(args, kinds)  # before the long work
    scene, terrain = _terrain(args, scene)
    kinds = kinds if terrain is None else (*kinds, TERRAIN)
    days = _days(args)
    studied = _run_study(args, scene, days)
    if isinstance(studied, int):
        return studied
    inputs, studies = studied
    for note in [*scene.warnings, *inputs.notes]:
        print(f"note: {terminal(note)}", file=sys.stderr)
    if args.days == 1:  # a SunStudies of the one day (every sample lies in it)
        ((day, study),) = studies.days.items()
        _report_day(args, days, day, study)
    else:
        _report_days(args, days, studies)
    if terrain is not None:  # receives and casts from here on; not in the ground study
        scene = dataclasses.replace(scene, shapes=[*scene.shapes, terrain])
    facades = _facades(args, scene, days, kinds)
    if args.days == 1:
        _write_outputs(args, scene, inputs, study, day, days.zone, facades)
    if facades is not None and args.cityjson is not None:
        _write_cityjson(args, scene, facades, polygons)
    return 0


def _check_output(args: argparse.Namespace) -> None:
    """OUT is not the input and, unless GIS, can be written, and --mesh's
    folder can be written in: found before the long work."""
    if args.mesh is not None:
        shadowgeo.io.check_folder(args.mesh)
    if args.output is None:
        return
    same = args.output.exists() and args.input.exists()
    if same and os.path.samefile(args.input, args.output):
        raise shadowgeo.SceneError(
            "OUT is the input file; it is never overwritten", path=str(args.output)
        )
    if not is_gis_path(args.output):
        shadowgeo.io.check_writable(args.output)  # before the long work


def _terrain(
    args: argparse.Namespace, scene: shadowgeo.Scene
) -> tuple[shadowgeo.Scene, shadowgeo.Shape | None]:
    """--dem: the terrain under the scene's geometry as a shape, and the
    scene with footprint buildings stood on it (notes printed)."""
    if args.dem is None:
        return scene, None
    if scene.up_index != 2:
        args.parser.error("--dem puts a terrain under city data (z up), not a Y-up scene")
    from shadowgeo.io.dem import read_terrain, stand_on

    points = [
        shape.world_vertices for shape in scene.shapes if shape.role == "geometry" and shape.n_faces
    ]
    if not points:
        raise shadowgeo.SceneError("no geometry to put a terrain under", path=scene.path)
    plan = np.concatenate(points)[:, :2]
    terrain = read_terrain(
        args.dem, scene, plan.min(axis=0), plan.max(axis=0), margin=args.dem_margin
    )
    notes = list(terrain.notes)
    if shadowgeo.io.reader_name(args.input) == "footprints":
        scene, note = stand_on(scene, terrain)
        notes.append(note)
    for note in notes:
        print(f"note: {terminal(note)}", file=sys.stderr)
    return scene, terrain.shape()


def _surface_kinds(args: argparse.Namespace, scene: shadowgeo.Scene) -> tuple[str, ...]:
    """The building faces given hours: --surfaces, else walls and roofs for
    city data (a site, or semantic surfaces) when --mesh or --cityjson asks."""
    if args.surfaces is not None:
        kinds: tuple[str, ...] = args.surfaces
    elif args.mesh is None and args.cityjson is None:
        kinds = ()
    else:
        city = scene.site is not None or any(shape.semantics for shape in scene.shapes)
        kinds = (WALLS, ROOFS) if city else ()
    if args.cityjson is not None and not kinds:
        args.parser.error(
            "--cityjson writes the hours of walls and roofs: not with --surfaces none"
        )
    return kinds


def _cityjson_polygons(args: argparse.Namespace, kinds: tuple[str, ...]) -> list[SurfacePolygon]:
    """--cityjson's polygons of the input: usage errors (exit 2) for an input
    that is not CityJSON or has no semantic surface of ``kinds``."""
    if args.cityjson is None:
        return []
    if args.cityjson.suffix.lower() != ".json":
        args.parser.error(f"--cityjson writes CityJSON (.city.json), not {args.cityjson.name!r}")
    try:
        polygons = surface_polygons(args.input)
    except shadowgeo.SceneError as error:
        args.parser.error(
            f"--cityjson adds hours to the input's own CityJSON, and {error} (footprints "
            "have no CityJSON file to carry them: give walls and roofs their hours with "
            "--mesh, as a .glb)"
        )
    if not any(polygon.kind in kinds for polygon in polygons):
        args.parser.error(
            f"--cityjson: no polygon of {args.input} has a {' or '.join(kinds)} semantic "
            "surface to carry hours (LoD1 blocks often have none): --mesh gives their "
            "faces hours, by their facing"
        )
    if args.cityjson.exists() and os.path.samefile(args.input, args.cityjson):
        raise shadowgeo.SceneError(
            "--cityjson is the input file; it is never overwritten", path=str(args.cityjson)
        )
    shadowgeo.io.check_folder(args.cityjson)
    return polygons


def _settle_site(args: argparse.Namespace, scene: shadowgeo.Scene) -> None:
    """``args.at`` from the file's site when not given; neither is a usage error."""
    site = scene.site
    if args.at is None and site is None:  # a usage error (exit 2), as a missing option is
        args.parser.error(
            f"{args.input}: the file does not say where it is (no coordinate reference "
            "system): give the site with --at LAT,LON"
        )
    elif args.at is None and site is not None:
        args.at = (site.latitude, site.longitude)


def _days(args: argparse.Namespace) -> _Days:
    """The sample times over the days asked for, in local mean time."""
    _, longitude = args.at
    zone = local_zone(longitude)
    first = args.date or dt.date(dt.date.today().year, 3, 21)
    start = dt.datetime(first.year, first.month, first.day, tzinfo=zone)
    step = dt.timedelta(minutes=args.every)
    times = shadowgeo.sun.hourly(start, start + dt.timedelta(days=args.days), step)
    return _Days(zone, first, step, times)


def _run_study(
    args: argparse.Namespace, scene: shadowgeo.Scene, days: _Days
) -> tuple[SceneStudy, Any] | int:
    """The study, here or on Dask, with a progress bar; an exit code if Dask fails."""
    scheduler = None
    if args.days > 1 and not args.serial:
        scheduler = args.scheduler or "local"
    show = args.progress or sys.stderr.isatty()
    bar = ProgressBar(f"{args.days} day(s)") if show else None
    try:
        if scheduler == "local" and args.workers:
            from shadowgeo.parallel import client_for

            with client_for("local", workers=args.workers) as client:
                return _study(args, scene, days.times, days.step, days.zone, client, bar)
        return _study(args, scene, days.times, days.step, days.zone, scheduler, bar)
    except (ImportError, OSError) as error:
        return dask_failure("sun", error)
    except Exception as error:
        if type(error).__name__ != "KilledWorker":
            raise
        # Dask ran the day again on other workers (allowed-failures) and gave up
        day = str(getattr(error, "task", "")).removeprefix("sun-summary-")
        print(
            f"shadowgeo sun: the Dask worker studying {day or 'a day'} died on each try "
            "(KilledWorker: killed, or out of memory); nothing was written",
            file=sys.stderr,
        )
        return 1
    finally:
        if bar is not None:
            bar.close()


def _place(args: argparse.Namespace) -> str:
    latitude, longitude = args.at
    return f"{latitude:g}, {longitude:g}"


def _report_day(
    args: argparse.Namespace, days: _Days, day: dt.date, study: shadowgeo.SunStudy
) -> None:
    """One day: the header, the area sunlit for each duration, the share meeting --hours."""
    hours = args.hours
    print(
        f"{args.input}: {len(study.times)} of {len(days.times)} samples with the sun up on "
        f"{day} at {_place(args)} (UTC{_offset(days.zone)}){_disc(args, study.disc_samples)}; "
        f"region {study.area:.6g} square units\n"
    )
    print("| sunlight (h) | area | share of the region |")
    print("|---:|---:|---:|")
    slivers = 0
    for duration, area in _duration_rows(study):
        if area <= SLIVER * study.area:
            slivers += 1
            continue
        print(f"| {duration} | {area:.6g} | {area / study.area:.2%} |")
    if slivers:
        print(
            f"\n({slivers} duration(s) covering under {SLIVER:g} of the region, slivers "
            "where shadow edges meet the region's edges, not listed)"
        )
    print(f"\n{study.fraction_meeting(hours):.2%} of the region has at least {hours:g} h of sun")


def _report_days(args: argparse.Namespace, days: _Days, studies: Any) -> None:
    """Several days: the share meeting --hours day by day, and its range."""
    hours = args.hours
    print(
        f"{args.input}: {len(studies)} days from {days.first} at {_place(args)} "
        f"(UTC{_offset(days.zone)}), every {args.every} min"
        f"{_disc(args, args.sun_samples)}\n"
    )
    print(days_table(studies, hours))
    shares = [summary.fraction_meeting(hours) for summary in studies.values()]
    print(
        f"\nshare of the region with at least {hours:g} h of sun: {min(shares):.2%} to "
        f"{max(shares):.2%} over the days"
    )


def _check_usage(args: argparse.Namespace) -> None:
    """The options that do not go together (exit 2)."""
    if any(item is not None for item in (args.output, args.plot, args.mesh)) and args.days > 1:
        args.parser.error("OUT, --plot and --mesh take one day's map: give --days 1")
    if args.mesh is not None and args.mesh.suffix.lower() != ".glb":
        args.parser.error(f"--mesh writes a .glb, not {args.mesh.name!r}")
    if args.workers and (args.serial or args.scheduler):
        args.parser.error("--workers is for the LocalCluster, not --serial or --scheduler")
    if args.shadows_at and (args.output is None or not is_gis_path(args.output)):
        args.parser.error("--shadows-at adds layers to a GIS OUT: give OUT as .gpkg or .geojson")


def _study(
    args: argparse.Namespace,
    scene: shadowgeo.Scene,
    times: list[dt.datetime],
    step: dt.timedelta,
    zone: dt.timezone,
    scheduler: Any,
    bar: ProgressBar | None,
) -> tuple[SceneStudy, Any]:
    latitude, longitude = args.at
    return study_scene(
        scene,
        times,
        latitude=latitude,
        longitude=longitude,
        step=step,
        receivers=args.receiver,
        plane=args.plane,
        region=args.region,
        tz=zone,
        scheduler=scheduler,
        progress=bar,
        summaries=args.days > 1,  # a table only: no day's polygons kept
        sun_angle=math.radians(args.sun_angle),
        sun_samples=args.sun_samples,
    )


def _facades(
    args: argparse.Namespace, scene: shadowgeo.Scene, days: _Days, kinds: tuple[str, ...]
) -> FacadeHours | None:
    """Hours of sun on the buildings' ``kinds`` of face at the ground study's
    samples, with a progress bar, and their summary; None for no kinds."""
    if not kinds:
        return None
    if args.sun_angle:
        print(
            "note: walls and roofs take the sun as a point (--sun-angle is for the ground)",
            file=sys.stderr,
        )
    latitude, longitude = args.at
    receivers = _buildings_named(args.input)
    if receivers is not None and TERRAIN in kinds:
        receivers |= {shape.name or "" for shape in scene.shapes if is_terrain(shape)}
    show = args.progress or sys.stderr.isatty()
    bar = ProgressBar("walls and roofs") if show else None
    try:
        found = facade_hours(
            scene,
            days.times,
            latitude=latitude,
            longitude=longitude,
            step=days.step,
            kinds=kinds,
            receivers=receivers,
            progress=bar,
        )
    finally:
        if bar is not None:
            bar.close()
    _report_facades(found)
    return found


def _report_facades(found: FacadeHours) -> None:
    """Each kind's faces, area and mean hours of sun."""
    print()
    for slot, kind in enumerate(found.kinds):
        chosen = found.kind == slot
        if not chosen.any():
            continue
        hours, areas = found.hours[chosen], found.areas[chosen]
        mean = float(np.average(hours, weights=areas)) if areas.sum() > 0 else 0.0
        print(
            f"{_WORDS[kind]}: {int(chosen.sum())} faces, {areas.sum():.6g} square units, "
            f"{mean:.3g} h of sun on average (a face {hours.min():.3g} to {hours.max():.3g} h), "
            f"of {found.most_hours:g} h with the sun up"
        )


_WORDS = {WALLS: "walls", ROOFS: "roofs", TERRAIN: "terrain"}
# The CityJSON object types whose walls and roofs are studied; the others
# (trees, bridges, land use with steps, city furniture) only cast.
_BUILDINGS = {"Building", "BuildingPart"}


def _buildings_named(path: Path) -> set[str] | None:
    """The ids of a CityJSON file's buildings, with a note; None (every
    standing object) for other input (footprints are all buildings) or a
    file with none."""
    if not path.name.lower().endswith(".json"):
        return None
    try:
        types = object_types(path)
    except shadowgeo.SceneError:
        return None
    found = {name for name, kind in types.items() if kind in _BUILDINGS}
    if not found:
        return None
    print(
        f"note: walls and roofs of the {len(found)} Building and BuildingPart object(s) are "
        "studied; other standing objects (trees, bridges, ...) only cast",
        file=sys.stderr,
    )
    return found


def _write_cityjson(
    args: argparse.Namespace,
    scene: shadowgeo.Scene,
    facades: FacadeHours,
    polygons: list[SurfacePolygon],
) -> None:
    """--cityjson: the input with each studied polygon's hours on its semantic surface."""
    hours, mismatched = polygon_values(polygons, facades.polygon_hours(scene))
    write_surface_hours(args.input, args.cityjson, hours)
    given = sum(value is not None for value in hours)
    if mismatched:
        print(
            f"note: {mismatched} polygon(s) read with another kind than their semantic "
            "surface's were given no hours",
            file=sys.stderr,
        )
    print(
        f"wrote {args.cityjson}: {given} semantic surface(s) with '{ATTRIBUTE}', the hours "
        f"of sun over the {args.days} day(s) studied"
    )


def _write_outputs(
    args: argparse.Namespace,
    scene: shadowgeo.Scene,
    inputs: SceneStudy,
    study: shadowgeo.SunStudy,
    day: dt.date,
    zone: dt.timezone,
    facades: FacadeHours | None = None,
) -> None:
    """The day's --plot and OUT: GIS polygons, or the scene with the map as shapes."""
    gis = args.output is not None and is_gis_path(args.output)
    # the levels in plan, made once for the plot and the GIS layers
    levels = level_regions(study, inputs.up) if args.plot is not None or gis else []
    if args.plot is not None:
        _plot(args, scene, inputs, study, day, levels)
    if args.mesh is not None:
        given = None if facades is None else facades.shape_hours(scene)
        vertices, faces, hours, groups, names = hours_faces(
            scene, study, inputs.scale, shape_hours=given
        )
        write_hours_glb(
            args.mesh,
            vertices,
            faces,
            hours,
            most_hours=study.hours(study.full_level),
            groups=groups,
            names=names,
            up="Z" if scene.up_index == 2 else "Y",
        )
        studied = int(np.count_nonzero(~np.isnan(hours)))
        print(f"wrote {args.mesh}: {len(faces)} faces, {studied} with hours of sunlight")
    if args.output is None:
        return
    if gis:
        _write_gis(args, scene, inputs, (day, zone), levels, facades)
        return
    shapes = sunlight_shapes(study, inputs.scale)
    added = dataclasses.replace(scene, shapes=[*scene.shapes, *shapes])
    try:
        save_output(added, args.output)
    finally:
        remove_stale([args.output])  # what a run killed outright left beside it
    triangles = sum(shape.n_faces for shape in shapes)
    print(f"wrote {args.output}: {len(shapes)} sunlight shape(s), {triangles} triangles")


def _write_gis(
    args: argparse.Namespace,
    scene: shadowgeo.Scene,
    inputs: SceneStudy,
    when: tuple[dt.date, dt.timezone],
    levels: list[tuple[float, Any]],
    facades: FacadeHours | None,
) -> None:
    """OUT as GeoPackage or GeoJSON: the day's ``levels`` of sunlight (layer
    'sunlight': hours, date, threshold_h, meets), with --shadows-at the
    shadows at those times (layer 'shadows': time, date), and with walls and
    roofs studied their faces in 3-D (layer 'surfaces': object, kind, hours,
    date)."""
    day, zone = when
    layers = {
        "sunlight": Layer(
            [region for _, region in levels],
            {
                "hours": [hours for hours, _ in levels],
                "date": [day.isoformat()] * len(levels),
                "threshold_h": [args.hours] * len(levels),
                "meets": [hours >= args.hours for hours, _ in levels],
            },
        )
    }
    if args.shadows_at:
        latitude, longitude = args.at
        times = [dt.datetime.combine(day, clock, tzinfo=zone) for clock in args.shadows_at]
        site = scene.site
        found = shadows_at(
            inputs,
            times,
            latitude=latitude,
            longitude=longitude,
            north=None if site is None else site.north,
        )
        for time in sorted(set(times) - {time for time, _ in found}):
            print(f"note: the sun is down at {time.isoformat()}: no shadow", file=sys.stderr)
        layers["shadows"] = Layer(
            [region for _, region in found],
            {
                "time": [time.isoformat() for time, _ in found],
                "date": [day.isoformat()] * len(found),
            },
        )
    if facades is not None:
        layers["surfaces"] = _surfaces_layer(scene, facades, day)
    crs = write_layers(args.output, layers, scene.site)
    counts = ", ".join(f"{len(layer.polygons)} {name}" for name, layer in layers.items())
    print(f"wrote {args.output}: {counts} feature(s), CRS {crs or 'none (the input has none)'}")


def _surfaces_layer(scene: shadowgeo.Scene, facades: FacadeHours, day: dt.date) -> Layer:
    """Each studied face of the walls and roofs as a 3-D triangle with its
    building's name, its kind and its hours."""
    names = [scene.shapes[index].name or "" for index in facades.shape]
    return Layer(
        list(shapely.polygons(facades.corners(scene))),
        {
            "object": names,
            "kind": [facades.kinds[slot] for slot in facades.kind],
            "hours": [float(value) for value in facades.hours],
            "date": [day.isoformat()] * len(names),
        },
    )


def _plot(
    args: argparse.Namespace,
    scene: shadowgeo.Scene,
    inputs: SceneStudy,
    study: shadowgeo.SunStudy,
    day: dt.date,
    levels: list[tuple[float, Any]],
) -> None:
    """--plot: the day's ``levels`` and the buildings' roofs, in the input's CRS."""
    from shadowgeo.sunmap import plot_sunlight

    site = scene.site
    crs = None if site is None else site.source_crs
    roofs = roof_triangles(inputs)
    moved_levels = to_output([region for _, region in levels], site, crs)
    moved_roofs = to_output(roofs, site, crs)
    names, degrees = axis_names(crs, scene.meters_per_unit)
    plot_sunlight(
        args.plot,
        [(hours, region) for (hours, _), region in zip(levels, moved_levels, strict=True)],
        moved_roofs,
        most_hours=study.hours(study.full_level),
        title=f"{args.input.name}: hours of sunlight on {day}",
        axis_names=names,
        degrees=degrees,
    )
    print(f"wrote {args.plot}: the map of sunlight hours")


def _duration_rows(study: shadowgeo.SunStudy) -> list[tuple[str, float]]:
    """The day's table rows, (duration, area): one per duration for a point
    sun; for a sun disc or translucent casters, whose partly covered samples
    make a duration of every fraction of a step, one per step ("2 to 3": at
    least 2 h, under 3), so a day is a dozen rows, not hundreds."""
    areas = study.level_areas()
    per = study.disc_samples * study.opacity_units  # the levels in a sample
    if per == 1:
        return [(f"{duration:g}", area) for duration, area in areas.items()]
    step = study.hours(per)  # one whole sample's hours
    rows: dict[int, float] = {}
    for duration, area in areas.items():
        whole = round(duration / step * per) // per  # the whole samples it holds
        rows[whole] = rows.get(whole, 0.0) + area
    last = len(study.times)
    return [
        (
            f"{study.hours(whole * per):g}"
            if whole == last
            else f"{study.hours(whole * per):g} to {study.hours((whole + 1) * per):g}",
            area,
        )
        for whole, area in sorted(rows.items())
    ]


def _disc(args: argparse.Namespace, samples: int | None) -> str:
    """How the sun was taken, for the header: nothing for a point sun."""
    if not args.sun_angle:
        return ""
    count = SUN_DISC_SAMPLES if samples is None else samples
    return f", the sun a {args.sun_angle:g} degree disc of {count} directions"


def _offset(zone: dt.timezone) -> str:
    hours = zone.utcoffset(None).total_seconds() / 3600.0
    return f"{hours:+g}" if hours else ""
