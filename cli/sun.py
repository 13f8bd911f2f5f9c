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

import shadowgeo
from shadowgeo.batch import save_output
from shadowgeo.io.atomic import remove_stale
from shadowgeo.scene.sunlight import SceneStudy, study_scene, sunlight_shapes
from shadowgeo.sunstudy import days_table

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
  shadowgeo sun garden.glb --at -33.9,151.2 --date 2026-06-21          (Sydney, midwinter)
  shadowgeo sun city.glb --at 40.7,-74.0 --date 2026-01-01 --days 365 --hours 4
  shadowgeo sun city.glb --at 40.7,-74.0 --days 30 --scheduler tcp://10.0.0.5:8786

The floor is the largest flat surface found that faces up under the scene
(--receiver DEF names one, --plane a,b,c,d gives a plane), else the ground
plane under the scene's lowest point; the region studied is the floor's
outline, or the scene's plan for a plane, or the --region given (corners
in plan, dropped onto the floor's plane). Every other face casts. The sun is
sampled every --every minutes (60), each sample standing for the minutes
around it, over whole days of local mean time (the longitude's hour zone).
It prints, for one day, the area sunlit for each duration and the share of
the region with at least --hours of sun (2); for several days, that share
day by day. OUT (one day) is the scene with the day's map of sunlight hours
added as shapes, dark purple (none) to yellow (sun all day).
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
    parser.add_argument("input", type=Path, metavar="SCENE", help="the scene to study")
    parser.add_argument(
        "output",
        type=Path,
        nargs="?",
        metavar="OUT",
        help="write the scene with the day's map of sunlight hours (one day only)",
    )
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
    parser.add_argument(
        "--hours",
        type=hours_argument,
        default=2.0,
        metavar="H",
        help="the threshold: the share of the region with at least H hours of sun (default 2)",
    )
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
    parser.add_argument(
        "--progress", action="store_true", help="show a progress bar even when not on a terminal"
    )
    add_dask_arguments(parser, "day", "a LocalCluster here for several days")
    parser.set_defaults(func=run, parser=parser)


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


def run(args: argparse.Namespace) -> int:
    if args.output is not None and args.days > 1:
        args.parser.error("OUT takes one day's map: give --days 1, or no OUT for the table")
    if args.workers and (args.serial or args.scheduler):
        args.parser.error("--workers is for the LocalCluster, not --serial or --scheduler")
    if args.output is not None:
        same = args.output.exists() and args.input.exists()
        if same and os.path.samefile(args.input, args.output):
            raise shadowgeo.SceneError(
                "OUT is the input file; it is never overwritten", path=str(args.output)
            )
        shadowgeo.io.check_writable(args.output)  # before the long work
    scene = shadowgeo.load(args.input)
    site = scene.site
    if args.at is None and site is None:  # a usage error (exit 2), as a missing option is
        args.parser.error(
            f"{args.input}: the file does not say where it is (no coordinate reference "
            "system): give the site with --at LAT,LON"
        )
    elif args.at is None and site is not None:
        args.at = (site.latitude, site.longitude)
    latitude, longitude = args.at
    zone = local_zone(longitude)
    first = args.date or dt.date(dt.date.today().year, 3, 21)
    start = dt.datetime(first.year, first.month, first.day, tzinfo=zone)
    step = dt.timedelta(minutes=args.every)
    times = shadowgeo.sun.hourly(start, start + dt.timedelta(days=args.days), step)
    scheduler = None
    if args.days > 1 and not args.serial:
        scheduler = args.scheduler or "local"
    show = args.progress or sys.stderr.isatty()
    bar = ProgressBar(f"{args.days} day(s)") if show else None
    try:
        if scheduler == "local" and args.workers:
            from shadowgeo.parallel import client_for

            with client_for("local", workers=args.workers) as client:
                inputs, studies = _study(args, scene, times, step, zone, client, bar)
        else:
            inputs, studies = _study(args, scene, times, step, zone, scheduler, bar)
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
    for note in [*scene.warnings, *inputs.notes]:
        print(f"note: {terminal(note)}", file=sys.stderr)
    hours = args.hours
    place = f"{latitude:g}, {longitude:g}"
    if args.days == 1:  # a SunStudies of the one day (every sample lies in it)
        ((day, study),) = studies.days.items()
        print(
            f"{args.input}: {len(study.times)} of {len(times)} samples with the sun up on "
            f"{day} at {place} (UTC{_offset(zone)}); region {study.area:.6g} square units\n"
        )
        print("| sunlight (h) | area | share of the region |")
        print("|---:|---:|---:|")
        slivers = 0
        for duration, area in study.level_areas().items():
            if area <= SLIVER * study.area:
                slivers += 1
                continue
            print(f"| {duration:g} | {area:.6g} | {area / study.area:.2%} |")
        if slivers:
            print(
                f"\n({slivers} duration(s) covering under {SLIVER:g} of the region, slivers "
                "where shadow edges meet the region's edges, not listed)"
            )
        print(
            f"\n{study.fraction_meeting(hours):.2%} of the region has at least {hours:g} h of sun"
        )
        if args.output is not None:
            shapes = sunlight_shapes(study, inputs.scale)
            added = dataclasses.replace(scene, shapes=[*scene.shapes, *shapes])
            try:
                save_output(added, args.output)
            finally:
                remove_stale([args.output])  # what a run killed outright left beside it
            triangles = sum(shape.n_faces for shape in shapes)
            print(f"wrote {args.output}: {len(shapes)} sunlight shape(s), {triangles} triangles")
        return 0
    print(
        f"{args.input}: {len(studies)} days from {first} at {place} "
        f"(UTC{_offset(zone)}), every {args.every} min\n"
    )
    print(days_table(studies, hours))
    shares = [summary.fraction_meeting(hours) for summary in studies.values()]
    print(
        f"\nshare of the region with at least {hours:g} h of sun: {min(shares):.2%} to "
        f"{max(shares):.2%} over the days"
    )
    return 0


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
    )


def _offset(zone: dt.timezone) -> str:
    hours = zone.utcoffset(None).total_seconds() / 3600.0
    return f"{hours:+g}" if hours else ""
