"""``shadowgeo render IN OUT.png``: a picture of a scene and its shadows, off-screen.

Needs no display: VTK renders through EGL (Mesa's software renderer on a
machine without a GPU). Shadows are computed with :func:`shadowgeo.add_shadows`
unless the scene already has some or ``--no-shadows`` is given.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import shadowgeo as sg

from .common import terminal

VIEWS = ("iso", "top", "front")
# What --view gives: one of VIEWS, or a direction (x, y, z).
View = str | tuple[float, ...]


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "render",
        help="render a scene and its shadows to PNG, off-screen",
        description=__doc__.splitlines()[0].replace("``", ""),
    )
    parser.add_argument("input", type=Path, help="scene file (.x3d, .glb, .gltf, .obj, ...)")
    parser.add_argument("output", type=Path, help="PNG file to write")
    add_picture_options(parser)
    parser.add_argument(
        "--size", type=parse_size, default=(1024, 768), metavar="WxH", help="default 1024x768"
    )
    parser.set_defaults(func=run)


def add_picture_options(parser: argparse.ArgumentParser) -> None:
    """Options ``render`` and ``view`` share."""
    parser.add_argument(
        "--view",
        type=parse_view,
        metavar="iso|top|front|X,Y,Z",
        help="camera direction from the scene's centre, framing the scene and its shadows "
        "(default: the scene's first Viewpoint, else iso); "
        "write --view=-1,1,0 when X starts with a minus",
    )
    parser.add_argument(
        "--viewpoint",
        metavar="NAME",
        help="the scene's Viewpoint with this DEF name or description as the camera",
    )
    parser.add_argument("--no-shadows", action="store_true", help="do not compute shadows")
    parser.add_argument("--pbr", action="store_true", help="physically based shading")


def parse_size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WxH, e.g. 800x600, got {text!r}") from None
    if not (16 <= width <= 8192 and 16 <= height <= 8192):
        raise argparse.ArgumentTypeError(f"size must be 16..8192 pixels each way, got {text!r}")
    return width, height


def parse_view(text: str) -> View:
    if text in VIEWS:
        return text
    try:
        direction = tuple(float(part) for part in text.split(","))
    except ValueError:
        direction = ()
    if len(direction) != 3 or not any(direction):
        raise argparse.ArgumentTypeError(
            f"expected one of {', '.join(VIEWS)} or a direction X,Y,Z, got {text!r}"
        )
    return direction


def camera(args: argparse.Namespace, scene: sg.Scene) -> View | sg.Viewpoint | None:
    """What ``view=`` of :func:`shadowgeo.plot` gets: ``--view``, else the
    Viewpoint ``--viewpoint`` names, else None (the scene's first Viewpoint,
    else the automatic view)."""
    view: View | None = args.view
    if view is not None:
        return view
    if args.viewpoint is None:
        return None
    for viewpoint in scene.viewpoints:
        if args.viewpoint in (viewpoint.name, viewpoint.description):
            return viewpoint
    known = ", ".join(v.name or repr(v.description) for v in scene.viewpoints) or "none"
    raise sg.SceneError(
        f"no Viewpoint named or described '{args.viewpoint}' (viewpoints: {known})",
        path=str(args.input),
    )


def scene_to_draw(args: argparse.Namespace) -> sg.Scene:
    """Load the scene and add its shadows, as the options ask."""
    scene = sg.load(args.input)
    if args.no_shadows or scene.shapes_with_role("shadow"):
        return scene
    try:
        return sg.add_shadows(scene)
    except sg.SceneError as error:  # no light on or no receiver: still worth a picture
        print(
            f"shadowgeo {args.command}: no shadows drawn: {terminal(error.message)}",
            file=sys.stderr,
        )
        return scene


def run(args: argparse.Namespace) -> int:
    if args.output.suffix.lower() != ".png":
        print(
            f"shadowgeo render: the output must be a .png file, got {args.output}", file=sys.stderr
        )
        return 2
    scene = scene_to_draw(args)
    view = camera(args, scene)
    sg.plot(scene, screenshot=args.output, window_size=args.size, view=view, pbr=args.pbr)
    n_shadows = len(scene.shapes_with_role("shadow"))
    width, height = args.size
    print(
        f"wrote {args.output} ({width}x{height}, {len(scene.shapes)} shapes, {n_shadows} shadows)"
    )
    return 0
