"""Hours of sunlight on a city's walls and roofs, face by face: what
``shadowgeo sun`` writes beside the ground's levels.

:func:`facade_hours` studies the faces of a scene's buildings at the sun
samples of a sun study with :func:`shadowgeo.sunlight_surfaces.surface_sunlight`
(the engine of :func:`shadowgeo.scene.facades.study_city_surfaces`), the
samples with the sun up a few at a time so that a progress bar can follow,
and sums each face's mean hours of sun over its area
(:meth:`SurfaceSunlight.mean_hours`: exact, from the shadows' areas; no
levels are cut). Translucent casters count by their opacity, as the
converter's rule (:func:`shadowgeo.scene.facades.caster_opacity`).

What is studied: the buildings are the scene's geometry less its ground
cover (:func:`shadowgeo.scene.sunlight.ground_cover`: a city file's roads,
land use and water, the ground of its ground study); they cast on each
other and on themselves, and the faces of the kinds asked for of those
named as ``receivers`` (all of them by default) receive. A terrain (a
shape whose faces are ``TerrainSurface``, :mod:`shadowgeo.io.dem`) is never
ground cover: it casts and receives as a building does, its faces studied
when :data:`TERRAIN` is among the kinds.
A face's kind is its semantic surface in the file (CityJSON's
``RoofSurface``, ``WallSurface``, a footprint's extruded walls and roof);
a face the file gives none (LoD1 blocks, an X3D scene) is sorted by its
facing instead: within ``FLOOR_COSINE`` of straight up a roof, as far from
straight down a floor (``GroundSurface``, not studied), anything steeper a
wall.

:meth:`FacadeHours.polygon_hours` gathers the faces back into the file's
polygons (each polygon's area-weighted mean), what
:func:`shadowgeo.io.cityjson_write.write_surface_hours` puts on the file's
semantic surfaces.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import math
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import SceneError
from ..sun import sun_lights
from ..sunlight_surfaces import surface_sunlight
from .facades import caster_opacity, city_casters
from .model import Scene, Semantics, Shape, located
from .receivers import FLOOR_COSINE
from .sunlight import ground_cover

__all__ = [
    "FacadeHours",
    "PROGRESS_STEPS",
    "ROOFS",
    "SURFACE_KINDS",
    "TERRAIN",
    "WALLS",
    "buildings",
    "facade_hours",
    "is_terrain",
    "oriented_semantics",
]

WALLS, ROOFS, GROUND = "WallSurface", "RoofSurface", "GroundSurface"
# The faces of a terrain (shadowgeo.io.dem, CityGML's name for relief): studied
# and casting like a building's, never taken for ground cover.
TERRAIN = "TerrainSurface"
# The command line's words for the kinds studied.
SURFACE_KINDS = {"walls": WALLS, "roofs": ROOFS}
# At most this many calls of progress (batches of samples) in a study.
PROGRESS_STEPS = 100


@dataclass(frozen=True)
class FacadeHours:
    """Hours of sunlight on the faces of a scene's walls and roofs.

    Attributes
    ----------
    shape : (m,) int64
        Each face's shape, an index into the scene's ``shapes``.
    face : (m,) int64
        The face's index among its shape's faces.
    kind : (m,) int64
        Its kind, an index into ``kinds``.
    kinds : tuple of str
    hours : (m,) float64
        Hours of sun over the samples, the face's mean over its area.
    areas : (m,) float64
    samples : int
        Samples with the sun up.
    most_hours : float
        The hours of sun at every one of them: a face's greatest.
    """

    shape: NDArray[np.int64]
    face: NDArray[np.int64]
    kind: NDArray[np.int64]
    kinds: tuple[str, ...]
    hours: NDArray[np.float64]
    areas: NDArray[np.float64]
    samples: int
    most_hours: float

    def shape_hours(self, scene: Scene) -> dict[int, NDArray[np.float64]]:
        """Shape index -> (f,) hours of each of its faces, NaN on faces not
        studied (floors, faces of other kinds); only shapes with a face studied."""
        found = {}
        for index in np.unique(self.shape):
            chosen = self.shape == index
            values = np.full(scene.shapes[index].n_faces, np.nan)
            values[self.face[chosen]] = self.hours[chosen]
            found[int(index)] = values
        return found

    def corners(self, scene: Scene) -> NDArray[np.float64]:
        """(m, 3, 3) each face's corners in the world (``scene``'s frame)."""
        found = np.zeros((len(self.face), 3, 3))
        for index in np.unique(self.shape):
            chosen = self.shape == index
            shape = scene.shapes[index]
            found[chosen] = shape.world_vertices[shape.faces[self.face[chosen]]]
        return found

    def polygon_hours(self, scene: Scene) -> dict[tuple[str, int], tuple[str, float]]:
        """(object name, polygon number within the object) -> (kind, hours:
        the area-weighted mean of its faces'), for the faces whose kind the
        file gives, of shapes whose semantics number their polygons
        (:attr:`Semantics.polygon`, city files)."""
        found = {}
        for index in np.unique(self.shape):
            shape = scene.shapes[index]
            semantics = shape.semantics
            if semantics is None or semantics.polygon is None:
                continue
            chosen = np.flatnonzero(self.shape == index)
            chosen = chosen[semantics.face_kind[self.face[chosen]] >= 0]  # the file's kinds only
            numbers = semantics.polygon[self.face[chosen]]
            for number in np.unique(numbers):
                rows = chosen[numbers == number]
                area = float(self.areas[rows].sum())
                weights = self.areas[rows] if area > 0 else np.ones(len(rows))
                mean = float(np.average(self.hours[rows], weights=weights))
                found[(shape.name or "", int(number))] = (self.kinds[self.kind[rows[0]]], mean)
        return found


def oriented_semantics(shape: Shape, up_index: int) -> Semantics:
    """Kinds for the faces of a shape the file gives none, from their facing
    (see the module notes): roof, floor (``GroundSurface``) or wall."""
    corners = shape.world_vertices[shape.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    rise = normals[:, up_index]
    kind = np.where(
        rise >= FLOOR_COSINE * lengths, 0, np.where(rise <= -FLOOR_COSINE * lengths, 1, 2)
    )
    # a face of no area faces nowhere: no kind
    return Semantics((ROOFS, GROUND, WALLS), np.where(lengths > 0, kind, -1))


def buildings(scene: Scene) -> tuple[list[Shape], NDArray[np.int64]]:
    """The scene's buildings (see the module notes), each with semantics
    (the file's, or :func:`oriented_semantics`), and their indices in
    ``scene.shapes``."""
    indices = np.array(
        [
            index
            for index, shape in enumerate(scene.shapes)
            if shape.role == "geometry" and shape.n_faces
        ],
        dtype=np.int64,
    )
    shapes = [scene.shapes[index] for index in indices]
    if scene.site is not None and shapes:
        cover = ground_cover(shapes, scene.up_index, scene.meters_per_unit)
        cover &= ~np.array([is_terrain(shape) for shape in shapes])
        if not cover.all():
            indices = indices[~cover]
            shapes = [scene.shapes[index] for index in indices]
    labelled = [
        dataclasses.replace(shape, semantics=_labelled(shape, scene.up_index)) for shape in shapes
    ]
    return labelled, indices


def is_terrain(shape: Shape) -> bool:
    """Whether the shape is a terrain (its semantics name TERRAIN): it casts
    and receives however flat it is."""
    return shape.semantics is not None and TERRAIN in shape.semantics.kinds


def _labelled(shape: Shape, up_index: int) -> Semantics:
    """The shape's semantics, its faces of no kind given one by their facing."""
    facing = oriented_semantics(shape, up_index)
    given = shape.semantics
    if given is None or not np.any(given.face_kind >= 0):
        return facing
    kinds = given.kinds + tuple(kind for kind in facing.kinds if kind not in given.kinds)
    from_facing = np.array([kinds.index(kind) for kind in facing.kinds])
    faced = np.where(facing.face_kind >= 0, from_facing[facing.face_kind], -1)
    return Semantics(kinds, np.where(given.face_kind >= 0, given.face_kind, faced), given.polygon)


@dataclass(frozen=True)
class _Receiver:
    """The faces studied, as one mesh: ``vertices`` (n, 3), ``faces`` (m, 3),
    and each face's building (index into the buildings), face in it and kind."""

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    owner: NDArray[np.int64]
    face: NDArray[np.int64]
    kind: NDArray[np.int64]


def _receiver(
    shapes: list[Shape], kinds: tuple[str, ...], names: Collection[str] | None, scene: Scene
) -> _Receiver:
    """The faces of ``kinds`` of the buildings ``shapes`` (those ``names``
    only, unless None); SceneError when none is."""
    vertices, faces, owner, face, kind = [], [], [], [], []
    base = 0
    for number, shape in enumerate(shapes):
        if names is not None and shape.name not in names:
            continue
        semantics = shape.semantics
        assert semantics is not None  # buildings() labels every shape
        wanted = np.array([kinds.index(name) if name in kinds else -1 for name in semantics.kinds])
        slot = np.where(semantics.face_kind >= 0, wanted[semantics.face_kind], -1)
        chosen = np.flatnonzero(slot >= 0)
        if not len(chosen):
            continue
        world = shape.world_vertices
        vertices.append(world)
        faces.append(shape.faces[chosen].astype(np.int64) + base)
        owner.append(np.full(len(chosen), number, dtype=np.int64))
        face.append(chosen)
        kind.append(slot[chosen])
        base += len(world)
    if not faces:
        raise SceneError(f"no building has a face that is a {' or '.join(kinds)}", path=scene.path)
    return _Receiver(*(np.concatenate(items) for items in (vertices, faces, owner, face, kind)))


def facade_hours(
    scene: Scene,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    kinds: Sequence[str] = (WALLS, ROOFS),
    receivers: Collection[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> FacadeHours:
    """Hours of sun on the walls and roofs (``kinds``) of ``scene``'s
    buildings over ``times`` (see the module notes), each sample standing for
    ``step`` (an hour by default); ``progress(done, total)`` as the samples
    with the sun up are done (after each, or each of :data:`PROGRESS_STEPS`
    batches of them).
    True north is the scene's site's (grid north when it has none).
    ``receivers``: the names of the buildings whose faces are studied (a
    city file's ``Building`` objects, not its trees); the others only cast.

    Raises
    ------
    SceneError
        No building, or no face of ``kinds`` (naming the scene's file).

    Examples
    --------
    A 10 m cube at 52 N on 21 June, every hour: its roof has the sun whenever
    the sun is up (16 samples).

    >>> import datetime as dt
    >>> import trimesh
    >>> from shadowgeo.scene.model import Scene, Shape
    >>> box = trimesh.creation.box([10, 10, 10])
    >>> scene = Scene([Shape(box.vertices + [0, 0, 5], box.faces, name="box")], up_axis="Z")
    >>> day = [dt.datetime(2026, 6, 21, h, 30, tzinfo=dt.UTC) for h in range(24)]
    >>> found = facade_hours(scene, day, latitude=52.0, longitude=0.0)
    >>> found.samples, float(found.hours[found.kind == 1].min())
    (16, 16.0)
    """
    wanted = tuple(kinds)
    shapes, indices = buildings(scene)
    if not shapes:
        raise SceneError("the scene has no building to study", path=scene.path)
    receiver = _receiver(shapes, wanted, receivers, scene)
    own = dataclasses.replace(scene, shapes=shapes)
    casters, opacity = city_casters(own), caster_opacity(own)
    _, _, north = located(scene, latitude, longitude)
    _, lights = sun_lights(latitude, longitude, times, up=scene.up_axis, north=north)
    directions = np.array([light.direction for light in lights]).reshape(-1, 3)
    total = np.zeros(len(receiver.faces))
    # the sun-up samples in at most PROGRESS_STEPS batches: each call sets up its
    # receiver and tolerance again, a tenth of a sample's time on Delft
    size = max(1, math.ceil(len(directions) / PROGRESS_STEPS))
    for first in range(0, len(directions), size):
        sunlight = surface_sunlight(
            casters,
            (receiver.vertices, receiver.faces),
            directions[first : first + size],
            step=step,
            levels=False,
            opacity=opacity,
            shadows=False,  # each face's hours: no outlines kept, the compiled areas
        )
        total += sunlight.mean_hours()
        if progress is not None:
            progress(min(first + size, len(directions)), len(directions))
    samples = len(directions)
    each = (step or _dt.timedelta(hours=1)).total_seconds() / 3600.0
    corners = receiver.vertices[receiver.faces]
    areas = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    return FacadeHours(
        indices[receiver.owner],
        receiver.face,
        receiver.kind,
        wanted,
        total,
        areas,
        samples,
        samples * each,
    )
