"""``shadowgeo info IN``: what shadowgeo reads from a scene, as tables.

Shapes (triangles, world bounds, where they come from), lights, viewpoints,
the scene's bounds, and what the reader skipped and why.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np

import shadowgeo

from .common import terminal

EPILOG = """\
examples:
  shadowgeo info examples/scenes/courtyard.x3d
  shadowgeo info model.glb
  shadowgeo info out/scene.x3d --root .   # its urls name files beside out/
"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = subparsers.add_parser(
        "info",
        help="list a scene's shapes, lights, bounds and what was skipped",
        description="Print the shapes (triangle counts, bounds), lights and bounds shadowgeo "
        "reads from IN, and every node it skipped with the reason.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("input", metavar="IN", type=Path, help="the scene to read")
    parser.add_argument(
        "--root",
        metavar="DIR",
        type=Path,
        help="X3D: the folder its Inlines and textures may not leave (default: IN's own); "
        "a folder above IN for a trusted scene converted into another folder",
    )
    parser.set_defaults(func=run)


def table(headers: list[str], rows: list[list[str]]) -> str:
    """Columns padded to their widest cell, two spaces apart; a cell (a name
    or description from the file) is one line fit for a terminal."""
    rows = [[terminal(cell) for cell in row] for row in rows]
    widths = [max(len(str(c)) for c in column) for column in zip(headers, *rows, strict=True)]
    lines = [headers, ["-" * w for w in widths], *rows]
    return "\n".join(
        "  " + "  ".join(str(c).ljust(w) for c, w in zip(line, widths, strict=True)).rstrip()
        for line in lines
    )


def number(value: float) -> str:
    return f"{value:.6g}" if math.isfinite(value) else str(value)


def vector(values: Iterable[float]) -> str:
    return " ".join(number(float(v)) for v in values)


def shadows_column(light: shadowgeo.SceneLight) -> str:
    """Whether a light's shadows are drawn: by the browser at run time, baked
    by shadowgeo (its runtime shadows off), or not at all."""
    intensity = number(light.shadow_intensity)
    if light.baked:
        return f"baked ({intensity})"
    return f"yes ({intensity})" if light.shadows else "no"


def light_where(light: shadowgeo.Light | shadowgeo.RectLight | shadowgeo.DiskLight) -> str:
    """Where a light is and, for one with a size, how big."""
    if isinstance(light, shadowgeo.DirectionalLight):
        size = f", angle {number(math.degrees(light.angle))} deg" if light.angle else ""
        return f"direction {vector(light.direction)}{size}"
    where = f"at {vector(light.position)}"
    if isinstance(light, shadowgeo.RectLight | shadowgeo.DiskLight):
        where += f", direction {vector(light.direction)}, "
        if isinstance(light, shadowgeo.RectLight):
            return where + f"{number(light.width)} x {number(light.height)}"
        return where + f"radius {number(light.radius)}"
    if isinstance(light, shadowgeo.SpotLight):
        where += (
            f", direction {vector(light.direction)}, "
            f"cut-off {number(math.degrees(light.cut_off_angle))} deg"
        )
    if math.isfinite(light.radius):
        where += f", radius {number(light.radius)}"
    if light.source_radius:
        where += f", source radius {number(light.source_radius)}"
    return where


def run(args: argparse.Namespace) -> int:
    scene = shadowgeo.load(args.input, **({"root": args.root} if args.root else {}))
    _print_summary(args.input, scene)
    if scene.shapes:
        _print_shapes(scene)
    if scene.lights:
        _print_lights(scene)
    else:
        print("\nlights: none (convert casts from a default sun, or --sun)")
    if scene.viewpoints:
        _print_viewpoints(scene)
    if scene.warnings:
        print(f"\nskipped or noted ({len(scene.warnings)})")
        for warning in scene.warnings:
            print(f"  - {terminal(warning)}")
    return 0


def _print_summary(source: Path, scene: shadowgeo.Scene) -> None:
    """The counts of shapes, triangles, lights and notes, and the bounds."""
    triangles = sum(s.n_faces for s in scene.shapes)
    print(
        f"{source}: {len(scene.shapes)} shapes, {triangles} triangles, "
        f"{len(scene.lights)} lights, {len(scene.warnings)} notes"
    )
    low, high = scene.bounds
    print(f"bounds: min {vector(low)}  max {vector(high)}  size {vector(high - low)}")


def _print_shapes(scene: shadowgeo.Scene) -> None:
    """The shapes' table: name, triangles, world bounds, role, source."""
    rows = []
    for index, shape in enumerate(scene.shapes):
        points = shape.world_vertices if len(shape.faces) else np.zeros((1, 3))
        rows.append(
            [
                shape.name or f"#{index}",
                str(shape.n_faces),
                vector(points.min(axis=0)),
                vector(points.max(axis=0)),
                shape.role,
                shape.source or "",
            ]
        )
    print("\nshapes")
    print(table(["name", "triangles", "min", "max", "role", "source"], rows))


def _print_lights(scene: shadowgeo.Scene) -> None:
    """The lights' table: name, type, on, shadows, intensity, where."""
    rows = [
        [
            light.name or f"#{index}",
            type(light.emitter).__name__,
            "on" if light.on else "off",
            shadows_column(light),
            number(light.intensity),
            light_where(light.emitter),
        ]
        for index, light in enumerate(scene.lights)
    ]
    print("\nlights")
    print(table(["name", "type", "on", "shadows", "intensity", "where"], rows))


def _print_viewpoints(scene: shadowgeo.Scene) -> None:
    """The viewpoints' table: name, position, direction, field of view, description."""
    rows = [
        [
            view.name or f"#{index}",
            vector(view.position),
            " ".join(f"{v:.3f}" for v in view.direction + 0.0),
            f"{math.degrees(view.field_of_view):.3g} deg",
            view.description,
        ]
        for index, view in enumerate(scene.viewpoints)
    ]
    print("\nviewpoints (the first is shown first; shadowgeo render --viewpoint NAME)")
    print(table(["name", "position", "direction", "field of view", "description"], rows))
