"""``shadowgeo convert IN OUT``: read a scene, add its shadows, write it.

A thin layer over :func:`shadowgeo.load`, :func:`shadowgeo.add_shadows` and
:func:`shadowgeo.save`; the formats come from the file extensions. Several
inputs, or a folder, are the batch form (:mod:`cli.batch`, on Dask).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

import shadowgeo
from shadowgeo.batch import save_output, shadowed
from shadowgeo.io.atomic import remove_stale
from shadowgeo.scene.softbake import UnknownLight
from shadowgeo.soft import DEFAULT_SAMPLES, MAX_SAMPLES

from .batch import run_batch
from .common import ProgressBar, add_dask_arguments, options_of, plane_argument, terminal

EPILOG = """\
examples:
  shadowgeo convert examples/scenes/courtyard.x3d out/courtyard.x3d
  shadowgeo convert scene.x3d scene.glb --light sun --receiver floor
  shadowgeo convert model.glb model.usda --plane 0,1,0,0
  shadowgeo convert scene.x3dz scene.x3d --method volume --progress
  shadowgeo convert unlit.x3d unlit.glb --sun 0.3,-1,0.2
  shadowgeo convert scene.x3d soft.x3d --sun-angle 0.53 --light-size lamp=0.1
  shadowgeo convert scenes/ more/a.x3d out/ --format glb       (batch, on Dask)
  shadowgeo convert scenes/ out/ --scheduler tcp://10.0.0.5:8786

Lights with shadows="true" cast (else every light that is on, with a note);
a scene with no light that is on gets a default sun travelling along
(0.3, -1, 0.2), 70 degrees above the horizon (Z up: (0.3, -0.2, -1)), with a
note; --sun gives another directional light, and then only it and --light
cast; neither is written into the scene. Receivers are the large planar
shapes (ground, floor, walls) unless named; when there is none, the ground
plane under the scene's lowest point receives, with a note, and a light-grey
ground is drawn there. A shadow is as dark as the browser would draw it: its
light's shadowIntensity times that light's share of the receiver's lighting.
The lights whose shadows are baked get shadows="false" (a browser drawing its
own over them would darken them twice), unless --keep-runtime-shadows.
Batch: with a folder or more than one input, OUT is a folder; each scene
file under a folder keeps its place below it, each listed file lands in OUT.
The files run on a Dask LocalCluster started here (--workers N, one per core
by default), on a running cluster (--scheduler ADDRESS; its workers must see
the same paths), or one after another here (--serial); the outputs are the
same bytes either way. Outputs keep the input's format unless --format names
one (inputs with no writer, such as .obj, become .glb).
Exit codes: 0 done, 1 bad input or an output that cannot be written (one line
naming the file and what is wrong; in a batch, any file failed), 2 bad usage,
130 interrupted (Ctrl-C, SIGINT), 143 stopped by SIGTERM, 129 by SIGHUP. Every output is
written atomically: whole, or not there (a file it replaces is left as it was).
"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "convert",
        help="add shadows to a scene and write it as X3D, glTF or USD",
        description="Read IN, add the shadows of its lights as geometry, write OUT. "
        "Formats come from the extensions: .x3d .x3dz .x3dj .glb .gltf .usda .usdc "
        "(and .obj .stl .ply .off as input). IN is never modified; OUT is "
        "written atomically. With several inputs or a folder, OUT is a folder and "
        "the files are converted on Dask.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "paths",
        metavar="IN... OUT",
        type=Path,
        nargs="+",
        help="the scene to read and the file to write; or scene files and folders, "
        "then the folder to write into",
    )
    _add_casting(parser)
    _add_quality(parser)
    add_soft_arguments(parser)
    parser.add_argument(
        "--progress", action="store_true", help="show a progress bar even when not on a terminal"
    )
    _add_batch(parser)
    parser.set_defaults(func=run, parser=parser)


def _add_casting(parser: argparse.ArgumentParser) -> None:
    """What casts onto what: --method, --light, --sun, and --receiver or --plane."""
    parser.add_argument(
        "--method",
        choices=("planar", "volume"),
        default="planar",
        help="planar shadows on the receivers (default) or closed shadow volumes",
    )
    parser.add_argument(
        "--light",
        action="append",
        metavar="DEF",
        help="a light that casts (repeat for several); default: lights with shadows=true",
    )
    parser.add_argument(
        "--sun",
        type=direction_argument,
        metavar="DX,DY,DZ",
        help="cast from a directional light travelling along DX,DY,DZ (not added to the "
        "scene) instead of the scene's lights (unless named with --light) or the default "
        "sun",
    )
    receiving = parser.add_mutually_exclusive_group()
    receiving.add_argument(
        "--receiver",
        action="append",
        metavar="DEF",
        help="a planar shape that receives (repeat for several); default: found "
        "automatically, else the ground under the scene",
    )
    receiving.add_argument(
        "--plane",
        type=plane_argument,
        metavar="a,b,c,d",
        help="receive on the plane a x + b y + c z + d = 0 instead of shapes",
    )


def _add_quality(parser: argparse.ArgumentParser) -> None:
    """How finely, how much, and the lights' runtime shadows: --tolerance,
    --max-triangles, --keep-runtime-shadows."""
    parser.add_argument(
        "--tolerance",
        type=tolerance_argument,
        metavar="T",
        help="tessellation tolerance relative to the scene size (default 1e-3)",
    )
    parser.add_argument(
        "--max-triangles",
        type=count_argument,
        metavar="N",
        help="refuse a scene of more than N triangles after tessellation and instancing "
        "(default 5,000,000: shadowgeo.limits.MAX_TRIANGLES); raise it for a trusted file",
    )
    parser.add_argument(
        "--keep-runtime-shadows",
        action="store_true",
        help="let the lights whose shadows are baked draw them at run time too (X3D "
        'shadows="true": a browser then darkens them twice); by default their runtime shadows '
        "are turned off",
    )


def _add_batch(parser: argparse.ArgumentParser) -> None:
    """The options of a batch: --format and Dask's."""
    batch = parser.add_argument_group("batch (several inputs or a folder)")
    batch.add_argument(
        "--format",
        type=output_suffix,
        metavar="EXT",
        help="write every output in this format (glb, x3d, usda, ...); default: the input's",
    )
    add_dask_arguments(batch, "file", "a LocalCluster here")


def add_soft_arguments(parser: argparse.ArgumentParser) -> None:
    """The options that give lights a size, and how finely their soft
    shadows bake (graded layers: shadowgeo.scene.softbake)."""
    soft = parser.add_argument_group(
        "soft shadows (a light with a size bakes graded layers, darkest at the umbra)"
    )
    soft.add_argument(
        "--sun-angle",
        type=angle_argument,
        metavar="DEG",
        help="give the scene's directional lights (and --sun) this angular diameter in "
        "degrees (the real sun: 0.53)",
    )
    soft.add_argument(
        "--light-size",
        action="append",
        type=light_size_argument,
        metavar="NAME=R",
        help="give the point or spot light with DEF NAME a source radius R in scene units "
        "(repeat for several)",
    )
    soft.add_argument(
        "--soft-levels",
        type=count_argument,
        default=8,
        metavar="N",
        help="graded layers per soft shadow (default 8)",
    )
    soft.add_argument(
        "--soft-samples",
        type=samples_argument,
        metavar="N",
        help=f"point lights standing for a light with a size (default {DEFAULT_SAMPLES}, "
        f"at most {MAX_SAMPLES})",
    )


def angle_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 <= value < 180:
        raise argparse.ArgumentTypeError(f"expected degrees in [0, 180), got {text!r}")
    return value


def light_size_argument(text: str) -> tuple[str, float]:
    name, equals, size = text.rpartition("=")
    try:
        radius = float(size) if equals and name else float("nan")
    except ValueError:
        radius = float("nan")
    if not (math.isfinite(radius) and radius >= 0):
        raise argparse.ArgumentTypeError(
            f"expected NAME=R, a light's DEF name and a radius >= 0, got {text!r}"
        )
    return name, radius


def samples_argument(text: str) -> int:
    value = count_argument(text)
    if value > MAX_SAMPLES:
        raise argparse.ArgumentTypeError(f"expected at most {MAX_SAMPLES}, got {text!r}")
    return value


def direction_argument(text: str) -> shadowgeo.DirectionalLight:
    try:
        values = [float(part) for part in text.split(",")]
        if len(values) != 3:
            raise ValueError(f"{len(values)} numbers")
        return shadowgeo.DirectionalLight(values)
    except (ValueError, shadowgeo.GeometryError) as error:
        raise argparse.ArgumentTypeError(
            f"expected three numbers dx,dy,dz, not all zero, got {text!r} ({error})"
        ) from None


def output_suffix(text: str) -> str:
    suffix = text.lower() if text.startswith(".") else "." + text.lower()
    if suffix not in shadowgeo.io.WRITERS:
        raise argparse.ArgumentTypeError(
            f"no writer for {suffix!r}; one of {', '.join(sorted(shadowgeo.io.WRITERS))}"
        )
    return suffix


def tolerance_argument(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"expected a number between 0 and 1, got {text!r}")
    return value


def count_argument(text: str) -> int:
    try:
        value = int(text.replace(",", "").replace("_", ""))
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number of at least 1, got {text!r}")
    return value


# Notes of the reader printed at most (shadowgeo info lists them all).
MAX_READER_NOTES = 20


def print_notes(notes: list[str], n_reader: int, source: Path) -> None:
    """The reader's notes (what it skipped; at most :data:`MAX_READER_NOTES`),
    then every note on the shadows, one ``note:`` line each, on stderr."""
    for note in notes[: min(n_reader, MAX_READER_NOTES)]:
        print(f"note: {terminal(note)}", file=sys.stderr)
    if n_reader > MAX_READER_NOTES:
        print(
            f"note: ... and {n_reader - MAX_READER_NOTES} more notes of the reader "
            f"(shadowgeo info {source} lists them all)",
            file=sys.stderr,
        )
    for note in notes[n_reader:]:
        print(f"note: {terminal(note)}", file=sys.stderr)


def is_batch(paths: list[Path]) -> bool:
    """Several inputs, a folder as input, or an existing folder as OUT."""
    return len(paths) > 2 or paths[0].is_dir() or paths[-1].is_dir()


def run(args: argparse.Namespace) -> int:
    paths = args.paths
    if len(paths) < 2:
        args.parser.error("give IN and OUT (or inputs and an output folder)")
    batch_only = _batch_only(args)
    if is_batch(paths):
        return run_batch(args, paths[:-1], paths[-1])
    if batch_only:
        args.parser.error(f"{', '.join(batch_only)} only apply to several inputs or a folder")
    args.input, args.output = paths
    _check_output(args.input, args.output)
    scene, result = _shadowed(args)
    known = len(scene.warnings)
    try:
        save_output(result, args.output)
    finally:
        remove_stale([args.output])  # what a run killed outright left beside it
    print_notes(result.warnings, known, args.input)
    _report(args, result)
    return 0


def _batch_only(args: argparse.Namespace) -> list[str]:
    """The batch options given, which one IN and OUT do not take."""
    return [
        flag
        for flag, value in (
            ("--format", args.format),
            ("--scheduler", args.scheduler),
            ("--serial", args.serial),
            ("--workers", args.workers),
        )
        if value
    ]


def _check_output(source: Path, target: Path) -> None:
    """OUT is not IN and can be written: found before the long work."""
    if target.exists() and source.exists() and os.path.samefile(source, target):
        raise shadowgeo.SceneError(
            "OUT is the input file; it is never overwritten", path=str(target)
        )
    shadowgeo.io.check_writable(target)  # before the long work


def _shadowed(args: argparse.Namespace) -> tuple[shadowgeo.Scene, shadowgeo.Scene]:
    """The scene read and the scene with its shadows, under a progress bar."""
    show = args.progress or sys.stderr.isatty()
    bar = ProgressBar(f"shadows ({args.method})") if show else None
    try:
        return shadowed(args.input, options_of(args), progress=bar)
    except UnknownLight as error:  # --light-size names no light: a usage error
        parser: argparse.ArgumentParser = args.parser
        parser.error(f"--light-size: {error}")
    finally:
        if bar is not None:
            bar.close()


def _report(args: argparse.Namespace, result: shadowgeo.Scene) -> None:
    """The line saying what was written: the shapes added, their triangles and groups."""
    added = [s for s in result.shapes if s.role in ("shadow", "volume")]  # not the ground
    groups = sorted({s.group for s in added if s.group})
    triangles = sum(s.n_faces for s in added)
    kind = "shadow volume" if args.method == "volume" else "shadow"
    print(
        f"wrote {args.output}: {len(added)} {kind} shape(s), {triangles} triangles, "
        f"in {len(groups)} group(s){': ' + ', '.join(groups) if groups else ''}"
    )
