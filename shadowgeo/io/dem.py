"""A terrain from a DEM (a GeoTIFF, or any raster GDAL reads, through
rasterio: ``pip install "shadowgeo[dem]"``), as a triangle mesh in a city
scene's frame, to receive and cast sunlight like any surface.

:func:`read_terrain` reads the first band of the raster around the study
region (the scene's plan, ``low`` to ``high``, plus ``margin`` metres), in
the scene's coordinates: the raster's CRS is projected with pyproj to the
CRS of the city data (:attr:`Scene.site`, see :mod:`.city_crs`); a raster
with no CRS is refused when the city data have one, and the other way
round (neither can be placed against the other); with neither, the two are
taken to share their coordinates. Heights are metres above the datum
(turned into the scene's unit), as DEMs give them.

Each cell centre is a vertex; each square of four centres two triangles,
facing up. A nodata cell (or a NaN or infinite one) leaves out the squares
it is a corner of: a hole, never a fall to zero. The window read is
averaged down (GDAL's average resampling, which skips nodata) to at most
:data:`~shadowgeo.limits.DEM_CELLS` cells: exact on a plane, a mean of the
cells it merges elsewhere. A raster whose width x height passes
:data:`~shadowgeo.limits.MAX_DEM_RASTER_CELLS` is refused from its header,
before a pixel is read; a file that is not a raster is a SceneError naming it.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import SceneError
from ..limits import DEM_CELLS, MAX_DEM_RASTER_CELLS
from ..scene.facade_hours import TERRAIN
from ..scene.model import Scene, Semantics, Shape, Site

__all__ = ["Terrain", "read_terrain", "stand_on"]
_INSTALL = 'pip install "shadowgeo[dem]"'
# Points along each side of the study's box projected into the raster's CRS
# to find the window (a projection bends straight sides).
_SIDE_POINTS = 17


def _rasterio(path: str) -> Any:
    try:
        import rasterio
    except ImportError:  # pragma: no cover - the test extra installs it
        raise SceneError(f"reading a DEM needs rasterio ({_INSTALL})", path=path) from None
    return rasterio


@dataclass(frozen=True)
class _Grid:
    """The heights read: (rows, cols) float64, NaN where there is none, and
    the affine (a, b, c, d, e, f) from (col, row) corners to the raster's CRS."""

    heights: NDArray[np.float64]
    affine: tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class Terrain:
    """The terrain of a DEM in a scene's frame.

    Attributes
    ----------
    vertices : (n, 3) float64
        Cell centres in scene coordinates, z up.
    faces : (m, 3) int64
        Triangles facing up; none touches a nodata cell.
    notes : tuple of str
        What the reading decided (averaging, holes, a shared frame assumed).
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    notes: tuple[str, ...]
    grid: _Grid
    to_raster: Any  # pyproj Transformer, scene -> raster CRS; None for the same
    z_scale: float

    def shape(self, name: str = "terrain") -> Shape:
        """The terrain as a geometry :class:`Shape` whose faces are all
        :data:`TERRAIN` (studied by :func:`~shadowgeo.scene.facade_hours.facade_hours`)."""
        kinds = Semantics((TERRAIN,), np.zeros(len(self.faces), dtype=np.int64))
        return Shape(self.vertices, self.faces, name=name, solid=False, semantics=kinds)

    def heights_at(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """(k,) the terrain's height (scene unit) under (k, 2) scene points,
        on its triangles; NaN outside it or over a hole."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        x, y = points[:, 0], points[:, 1]
        if self.to_raster is not None:
            x, y = (np.asarray(v, dtype=np.float64) for v in self.to_raster.transform(x, y))
        a, b, c, d, e, f = self.grid.affine
        det = a * e - b * d
        col = (e * (x - c) - b * (y - f)) / det - 0.5  # from the first cell centre
        row = (a * (y - f) - d * (x - c)) / det - 0.5
        return _on_triangles(self.grid.heights, col, row) * self.z_scale


def _on_triangles(
    heights: NDArray[np.float64], col: NDArray[np.float64], row: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Heights at fractional cell-centre coordinates, on the two triangles
    of each square as :func:`_faces` cuts it (along its (0,0)-(1,1) diagonal)."""
    rows, cols = heights.shape
    inside = (col >= 0) & (row >= 0) & (col <= cols - 1) & (row <= rows - 1)
    found = np.full(len(col), np.nan)
    if not inside.any() or rows < 2 or cols < 2:
        return found
    c0 = np.minimum(np.floor(col[inside]).astype(np.int64), cols - 2)
    r0 = np.minimum(np.floor(row[inside]).astype(np.int64), rows - 2)
    u, v = col[inside] - c0, row[inside] - r0
    z00, z01 = heights[r0, c0], heights[r0, c0 + 1]
    z10, z11 = heights[r0 + 1, c0], heights[r0 + 1, c0 + 1]
    found[inside] = np.where(
        u >= v, z00 + u * (z01 - z00) + v * (z11 - z01), z00 + v * (z10 - z00) + u * (z11 - z10)
    )
    return found


def _faces(valid: NDArray[np.bool_]) -> NDArray[np.int64]:
    """(m, 3) two triangles per square of four valid cell centres (vertex
    ``r * cols + c``), cut along the square's (0,0)-(1,1) diagonal."""
    rows, cols = valid.shape
    index = np.arange(rows * cols, dtype=np.int64).reshape(rows, cols)
    v00, v01 = index[:-1, :-1], index[:-1, 1:]
    v10, v11 = index[1:, :-1], index[1:, 1:]
    whole = valid[:-1, :-1] & valid[:-1, 1:] & valid[1:, :-1] & valid[1:, 1:]
    first = np.stack([v00, v01, v11], axis=-1)[whole]
    second = np.stack([v00, v11, v10], axis=-1)[whole]
    return np.concatenate([first, second]).reshape(-1, 3)


def _facing_up(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """``faces`` each wound counter-clockwise seen from above (the raster's
    rows may run north or south)."""
    corners = vertices[faces]
    rise = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2]
    return np.where((rise < 0)[:, None], faces[:, ::-1], faces)


def _transformers(dataset: Any, site: Site | None, path: str) -> tuple[Any, Any, list[str]]:
    """(raster -> scene, scene -> raster) pyproj transformers (None, None for
    the same coordinates) and notes; SceneError when only one side has a CRS."""
    crs = dataset.crs
    if crs is None and site is None:
        note = (
            f"{Path(path).name}: neither the DEM nor the city data name a CRS: taken as "
            "sharing their coordinates"
        )
        return None, None, [note]
    if crs is None:
        raise SceneError(
            "the DEM has no coordinate reference system, and the city data are in "
            f"{site.source_crs if site else ''}: it cannot be placed under them",
            path=path,
        )
    if site is None:
        raise SceneError(
            f"the DEM is in {crs.to_string()}, and the city data name no coordinate "
            "reference system: it cannot be placed under them",
            path=path,
        )
    import pyproj

    try:
        raster = pyproj.CRS.from_wkt(crs.to_wkt())
    except pyproj.exceptions.CRSError as error:
        raise SceneError(f"the DEM's CRS is not one pyproj knows: {error}", path=path) from None
    scene = pyproj.CRS.from_wkt(site.crs)
    if raster == scene:
        return None, None, []
    forward = pyproj.Transformer.from_crs(raster, scene, always_xy=True)
    backward = pyproj.Transformer.from_crs(scene, raster, always_xy=True)
    return forward, backward, []


def _window(
    dataset: Any, backward: Any, low: NDArray[np.float64], high: NDArray[np.float64], path: str
) -> tuple[int, int, int, int]:
    """(row, col, rows, cols) of the raster covering the scene box ``low`` to
    ``high`` (x, y), a cell more each way; SceneError when it misses the box."""
    steps = np.linspace(0.0, 1.0, _SIDE_POINTS)
    xs = np.concatenate([low[0] + steps * (high[0] - low[0]), np.full(_SIDE_POINTS, high[0])])
    ys = np.concatenate([np.full(_SIDE_POINTS, low[1]), low[1] + steps * (high[1] - low[1])])
    xs = np.concatenate([xs, low[0] + high[0] - xs])
    ys = np.concatenate([ys, low[1] + high[1] - ys])
    if backward is not None:
        xs, ys = (np.asarray(v, dtype=np.float64) for v in backward.transform(xs, ys))
    a, b, c, d, e, f = tuple(dataset.transform)[:6]
    det = a * e - b * d
    cols = (e * (xs - c) - b * (ys - f)) / det
    rows = (a * (ys - f) - d * (xs - c)) / det
    if not (np.all(np.isfinite(cols)) and np.all(np.isfinite(rows))):
        raise SceneError("the study region cannot be projected into the DEM's CRS", path=path)
    first_col = max(int(math.floor(cols.min())) - 1, 0)
    first_row = max(int(math.floor(rows.min())) - 1, 0)
    last_col = min(int(math.ceil(cols.max())) + 1, dataset.width)
    last_row = min(int(math.ceil(rows.max())) + 1, dataset.height)
    if last_col - first_col < 2 or last_row - first_row < 2:
        raise SceneError("the DEM does not cover the study region", path=path)
    return first_row, first_col, last_row - first_row, last_col - first_col


def _grid(
    dataset: Any, window: tuple[int, int, int, int], cells: int, path: str
) -> tuple[_Grid, list[str]]:
    """The window's heights, averaged down to at most ``cells`` cells."""
    from rasterio.enums import Resampling
    from rasterio.errors import RasterioError
    from rasterio.windows import Window

    row, col, rows, cols = window
    factor = max(1, math.ceil(math.sqrt(rows * cols / cells)))
    while math.ceil(rows / factor) * math.ceil(cols / factor) > cells:  # ceil's extra cells
        factor += 1
    # whole blocks of factor x factor cells: each average is then the plane's
    # value at its block's centre on a plane
    rows = _whole_blocks(row, rows, dataset.height, factor)
    cols = _whole_blocks(col, cols, dataset.width, factor)
    shape = (max(2, rows // factor), max(2, cols // factor))
    read = Window(col, row, cols, rows)
    try:
        band = dataset.read(
            1, window=read, out_shape=shape, resampling=Resampling.average, masked=True
        )
    except RasterioError as error:  # a truncated or corrupt block
        raise SceneError(f"cannot read the DEM's heights: {error}", path=path) from None
    heights = np.ma.filled(band.astype(np.float64), np.nan)
    heights[~np.isfinite(heights)] = np.nan
    corner = dataset.window_transform(read)
    scaled = corner @ type(corner).scale(cols / shape[1], rows / shape[0])
    notes = []
    if factor > 1:
        notes.append(
            f"{rows} x {cols} cells around the study averaged to {shape[0]} x {shape[1]} "
            f"(at most {cells:,})"
        )
    return _Grid(heights, tuple(scaled)[:6]), notes


def _whole_blocks(start: int, size: int, limit: int, factor: int) -> int:
    """``size`` cells from ``start`` made a multiple of ``factor``: grown
    while the raster (``limit`` cells) has them, else cut."""
    grown = math.ceil(size / factor) * factor
    if start + grown <= limit:
        return grown
    return max(size // factor, 1) * factor if size >= factor else size


def read_terrain(
    path: str | os.PathLike[str],
    scene: Scene,
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    *,
    margin: float = 100.0,
    cells: int = DEM_CELLS,
) -> Terrain:
    """The terrain of the DEM at ``path`` under ``scene`` (its site and unit)
    over the plan box ``low`` to ``high`` (scene x, y) plus ``margin`` metres.

    Raises
    ------
    SceneError
        Naming the file: not a raster, more cells than
        :data:`~shadowgeo.limits.MAX_DEM_RASTER_CELLS`, a CRS on one side
        only, a window that misses the study or holds no height.
    """
    name = str(path)
    if cells < 4:
        raise SceneError(f"a terrain needs a budget of 4 cells or more, got {cells}", path=name)
    rasterio = _rasterio(name)
    try:
        dataset = rasterio.open(name)
    except rasterio.errors.RasterioIOError as error:
        raise SceneError(f"cannot read as a raster: {error}", path=name) from None
    with dataset:
        return _terrain(dataset, scene, (low, high), margin, cells, name)


def _terrain(
    dataset: Any,
    scene: Scene,
    box: tuple[NDArray[np.float64], NDArray[np.float64]],
    margin: float,
    cells: int,
    path: str,
) -> Terrain:
    """:func:`read_terrain` on the open ``dataset``: checks, window, grid, mesh."""
    width, height = int(dataset.width), int(dataset.height)
    if width * height > MAX_DEM_RASTER_CELLS:
        raise SceneError(
            f"{width:,} x {height:,} cells, more than {MAX_DEM_RASTER_CELLS:,}; refused",
            path=path,
        )
    if dataset.count < 1:
        raise SceneError("the raster has no band", path=path)
    forward, backward, notes = _transformers(dataset, scene.site, path)
    pad = margin / scene.meters_per_unit
    low = np.asarray(box[0], dtype=np.float64)[:2] - pad
    high = np.asarray(box[1], dtype=np.float64)[:2] + pad
    grid, more = _grid(dataset, _window(dataset, backward, low, high, path), cells, path)
    rows, cols = grid.heights.shape
    a, b, c, d, e, f = grid.affine
    col, row = np.meshgrid(np.arange(cols) + 0.5, np.arange(rows) + 0.5)
    xs, ys = (a * col + b * row + c).ravel(), (d * col + e * row + f).ravel()
    if forward is not None:
        xs, ys = (np.asarray(v, dtype=np.float64) for v in forward.transform(xs, ys))
    z_scale = 1.0 / scene.meters_per_unit
    vertices = np.column_stack([xs, ys, grid.heights.ravel() * z_scale])
    valid = np.isfinite(grid.heights)
    faces = _facing_up(vertices, _faces(valid))
    if not len(faces):
        raise SceneError("no height around the study region (all nodata)", path=path)
    holes = int((~valid).sum())
    if holes:
        more.append(f"{holes} cell(s) without a height (nodata) left as holes")
    vertices[~valid.ravel(), 2] = 0.0  # unused points, kept finite for the writers
    label = Path(path).name
    return Terrain(
        vertices,
        faces,
        tuple([*notes, *(f"{label}: {note}" for note in more)]),
        grid,
        backward,
        z_scale,
    )


def stand_on(scene: Scene, terrain: Terrain) -> tuple[Scene, str]:
    """``scene``'s geometry (footprint prisms standing at 0) raised, each
    shape by the terrain's height under the centroid of its plan, and a note;
    a shape over a hole or off the terrain is left where it is."""
    shapes, moved = [], 0
    for shape in scene.shapes:
        if shape.role != "geometry" or not shape.n_faces:
            shapes.append(shape)
            continue
        lift = float(terrain.heights_at(_plan_centroid(shape))[0])
        if not math.isfinite(lift):
            shapes.append(shape)
            continue
        raised = np.eye(4)
        raised[2, 3] = lift
        shapes.append(dataclasses.replace(shape, transform=raised @ shape.transform))
        moved += 1
    note = (
        f"{moved} of {len(scene.shapes)} footprint building(s) stand on the DEM's height "
        "at their footprint's centroid (footprints give heights above a base, here none)"
    )
    return dataclasses.replace(scene, shapes=shapes), note


def _plan_centroid(shape: Shape) -> NDArray[np.float64]:
    """(1, 2) the area-weighted centroid of the shape's faces seen from above."""
    corners = shape.world_vertices[shape.faces][:, :, :2]
    first, second = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    areas = np.abs(first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0])
    centres = corners.mean(axis=1)
    weights = areas if areas.sum() > 0 else None
    centre: NDArray[np.float64] = np.average(centres, axis=0, weights=weights)
    return centre.reshape(1, 2)
