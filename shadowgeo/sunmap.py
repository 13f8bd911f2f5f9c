"""A map of a day's sunlight hours as a picture (matplotlib): what a planner
pins to a report.

Each level of sunlight is filled with :func:`shadowgeo.scene.sunlight.ramp_colour`
(dark purple, no sun, to yellow, sun at every sample), the buildings drawn
over it in grey, with a legend of hours; the axes are in the map's CRS units
(metres for a projected CRS, degrees for longitude and latitude, where the
aspect is set so a degree of longitude is as long as it is on the ground).
Inputs are plain shapely polygons already in the map's CRS, so the picture
and the GIS file (:mod:`shadowgeo.io.gis_write`) show the same coordinates.
matplotlib is imported when a map is drawn, never with the package.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from .errors import SceneError
from .io.atomic import atomic_path
from .scene.sunlight import ramp_colour

__all__ = ["plot_sunlight"]

_BUILDING = (0.55, 0.55, 0.55)
_EDGE = (0.25, 0.25, 0.25)


def plot_sunlight(
    path: str | os.PathLike[str],
    levels: Sequence[tuple[float, Any]],
    buildings: Sequence[Any],
    *,
    most_hours: float,
    title: str,
    axis_names: tuple[str, str] = ("x", "y"),
    degrees: bool = False,
) -> None:
    """Draw the map to ``path`` (PNG, or any format matplotlib writes by its
    extension), atomically.

    Parameters
    ----------
    levels : sequence of (hours, shapely (Multi)Polygon)
        The day's levels of sunlight, in the map's CRS.
    buildings : sequence of shapely geometry
        Footprints (or roof triangles) drawn over the levels, same CRS.
    most_hours : float
        The hours of sun at every sample: the ramp's yellow end.
    title : str
    axis_names : (str, str)
        The axes' labels (with their unit).
    degrees : bool
        The map is in longitude and latitude: the aspect is
        ``1 / cos(latitude)`` so lengths east and north agree.

    Raises
    ------
    SceneError
        matplotlib missing, or the file cannot be written (naming it).
    """
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only, no window
        import matplotlib.pyplot as plt
        from matplotlib.collections import PathCollection, PolyCollection
        from matplotlib.patches import Patch
    except ImportError:
        raise SceneError(
            'a plot needs matplotlib (pip install "shadowgeo[plot]")', path=str(path)
        ) from None
    figure, axes = plt.subplots(figsize=(9, 8), dpi=120)
    try:
        handles = []
        for hours, region in levels:
            colour = ramp_colour(hours / most_hours if most_hours > 0 else 1.0)
            paths = _paths(region)
            # no anti-aliasing: a level cut along tile edges shows no seams
            axes.add_collection(
                PathCollection(paths, facecolors=[colour], edgecolors="none", antialiaseds=False)
            )
            handles.append(Patch(facecolor=colour, label=f"{hours:g} h"))
        triangles = [np.asarray(polygon.exterior.coords) for polygon in _polygons(buildings)]
        axes.add_collection(
            PolyCollection(triangles, facecolors=[_BUILDING], edgecolors="face", linewidths=0.3)
        )
        handles.append(Patch(facecolor=_BUILDING, edgecolor=_EDGE, label="buildings"))
        _frame(axes, handles, title, axis_names, degrees)
        figure.tight_layout()
        target = Path(path)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            with atomic_path(target) as temporary:
                figure.savefig(temporary, format=target.suffix.lstrip(".") or "png")
        except OSError as error:
            raise SceneError(f"cannot write: {error.strerror or error}", path=str(path)) from None
    finally:
        plt.close(figure)


def _frame(
    axes: Any, handles: list[Any], title: str, axis_names: tuple[str, str], degrees: bool
) -> None:
    """The map's extent, aspect, labels, title and legend (beside it)."""
    axes.autoscale_view()
    low, high = axes.get_ylim()
    if degrees:  # a degree of longitude as long as on the ground at the map's latitude
        axes.set_aspect(1.0 / math.cos(math.radians((low + high) / 2)))
    else:
        axes.set_aspect("equal")
    axes.set_xlabel(axis_names[0])
    axes.set_ylabel(axis_names[1])
    axes.set_title(title)
    axes.ticklabel_format(useOffset=False, style="plain")
    axes.legend(handles=handles, title="sunlight", loc="upper left", bbox_to_anchor=(1.01, 1.0))


def _polygons(geometries: Sequence[Any]) -> list[Any]:
    """Every polygon of ``geometries`` (multi-parts taken apart)."""
    parts = shapely.get_parts(np.asarray(list(geometries), dtype=object))
    return [part for part in parts if isinstance(part, shapely.Polygon) and not part.is_empty]


def _paths(region: Any) -> list[Any]:
    """matplotlib paths of a (Multi)Polygon's parts, holes cut out (each
    ring a closed sub-path: the even-odd rule matplotlib fills by leaves the
    holes empty)."""
    from matplotlib.path import Path as Outline

    outlines = []
    # outer rings counter-clockwise, holes clockwise: holes stay empty under
    # the non-zero rule matplotlib fills by
    for polygon in _polygons([shapely.orient_polygons(region)]):
        rings = [polygon.exterior, *polygon.interiors]
        vertices = np.concatenate([np.asarray(ring.coords)[:, :2] for ring in rings])
        codes = np.concatenate(
            [
                [Outline.MOVETO, *[Outline.LINETO] * (len(ring.coords) - 2), Outline.CLOSEPOLY]
                for ring in rings
            ]
        )
        outlines.append(Outline(vertices, codes))
    return outlines
