"""``shadowgeo view IN``: an interactive window with the scene and its shadows.

Needs a display; where there is none it says so and exits 1 (use
``shadowgeo render`` there).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import shadowgeo as sg
from shadowgeo import viz

from .render import add_picture_options, camera, scene_to_draw


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "view",
        help="open a scene and its shadows in an interactive window",
        description=__doc__.splitlines()[0].replace("``", ""),
    )
    parser.add_argument("input", type=Path, help="scene file (.x3d, .glb, .gltf, .obj, ...)")
    add_picture_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    reason = viz.no_display_reason()
    if reason is not None:
        print(
            f"shadowgeo view: no display to open a window on ({reason}); "
            f"render a picture instead: shadowgeo render {args.input} picture.png",
            file=sys.stderr,
        )
        return 1
    scene = scene_to_draw(args)
    sg.plot(scene, view=camera(args, scene), pbr=args.pbr)
    return 0
