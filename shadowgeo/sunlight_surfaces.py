"""Sunlight on every surface: hours of sun on walls, roofs, terrain, any face.

:func:`shadowgeo.sun_study` measures sunlight on one plane. Here the receiver
is any triangle mesh (a city's walls and roofs, a terrain, a window's pane):
for every sun sample, :func:`shadowgeo.shadow_on_surface` gives the exact
shadow on *all* its faces in one call (the faces batched: the light's frame,
the caster index and the 2-D unions are built once per sample, not once per
face), and each face is then cut into exact polygons of equal sunlight
duration in its own plane.

How the levels stay exact: a sample's shadow on a face is a set of
non-overlapping triangles (a face turned away from the sun, or edge-on, is
dark whole), so the number of samples shadowing a point of the face is its
winding number over all the samples' triangles, and
:func:`shadowgeo.levels.cover_levels` cuts by that number exactly, as for the
ground. Faces go through the cover :data:`CHUNK` at a time: each face's 2-D
frame is laid in its own cell of one plane, cells apart, so one tiled pass of
unions serves a chunk of faces and no Python loop runs over faces times
samples. A sample at which a face is dark, or shadowed whole (its shadow's
area is the face's), only lowers that face's count and sends no loops; and
faces shadowed in part at as many samples share a chunk, since a chunk's
unions, one per level, go up to its deepest face.

Cost: one :func:`shadow_on_surface` call per sample (a receiver whose shadow
passes that call's budgets, a low sun over a city, is cast in halves), and
one cover per chunk whose work follows the shadow triangles' vertices.

Days: :func:`surface_sun_study_by_day` studies each calendar day on its own,
in this process or as one Dask task a day, with the same results.

What a sample means: each of ``times`` stands for ``step`` around it (an hour
by default), as in :func:`shadowgeo.sun_study`; a sunlit sample adds
``step`` to a point's hours.

Translucent casters (``opacity``, one value a caster face) count by their
opacity, as the converter's rule (:mod:`shadowgeo.scene.opacity`): at a sample
a point gets ``(1 - a) * step``, ``a`` the largest opacity among the casters
hiding it. Each sample is cast once per distinct opacity, with the faces at
least that opaque (:mod:`shadowgeo.opacity`); the mean hours weigh each
threshold's shadowed areas, and the levels count each threshold's shadow
triangles a whole number of times in the cover, in steps of ``step / units``.
With every caster opaque the result is the opaque one, bit for bit.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import plane2d as poly
from .compiled import use_compiled
from .errors import BudgetError, GeometryError
from .levels import cover_levels
from .lights import DirectionalLight
from .opacity import Layers, layers
from .parallel import each_day
from .sun import sun_lights
from .surface import shadow_on_surface, shadowed_fractions
from .tolerance import Tolerance
from .topology import Caster, MeshLike, as_caster

__all__ = [
    "CHUNK",
    "Parts",
    "SampleShadows",
    "SurfaceSunlight",
    "surface_sun_study",
    "surface_sun_study_by_day",
    "surface_sunlight",
]

Parts = list[list[NDArray[np.float64]]]


@dataclass(frozen=True)
class SampleShadows:
    """One sun sample's exact shadow on the receiver.

    triangles : (t, 3, 3) float64
        Non-overlapping triangles lying in the receiver's faces.
    face : (t,) int64
        The receiver face of each triangle.
    dark : (m,) bool
        Faces turned away from the sun (or edge-on): dark whole.
    fraction : (m,) float64
        The shadowed share of each face's area (1 on dark faces).
    """

    triangles: NDArray[np.float64]
    face: NDArray[np.int64]
    dark: NDArray[np.bool_]
    fraction: NDArray[np.float64]


@dataclass(frozen=True)
class SurfaceSunlight:
    """Sunlight over the faces of a receiving mesh.

    Attributes
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64
        The receiver; each face's winding gives its front (the side the sun
        must be on to light it).
    directions : (s, 3) float64
        The direction sunlight travels at each sample.
    times : tuple of datetime
        The samples (with the sun up), or () when the lights were given.
    step : timedelta
        The time each sample stands for.
    shadows : tuple of SampleShadows
        The exact shadow on the receiver at each sample (of every caster,
        translucent ones too: see ``layer_shadows``).
    origin, u, v : (m, 3) float64
        Each face's 2-D frame: a point ``p`` of face ``f`` is at
        ``((p - origin[f]) . u[f], (p - origin[f]) . v[f])``; ``u``, ``v``
        and the face normal are right-handed, so a face is counter-clockwise
        in its frame.
    levels : tuple of dict[int, polygons], or None
        For each face, ``k`` sunlit samples -> the part of the face sunlit for
        exactly ``k * step`` (``[outer, hole, ...]`` loops in the face's
        frame; with translucent casters ``k`` units of ``step /
        opacity_units``); levels with no area are left out, and together a
        face's levels tile it. None when not asked for.
    layer_shadows : tuple of tuple of SampleShadows
        With translucent casters, for each opacity threshold above the
        lowest, each sample's shadow of the casters at least that opaque
        (``shadows`` is the lowest's: every caster's); empty when all are
        opaque.
    layer_weights : tuple of int
        How many units of a sample's sun each threshold's shadow takes
        (``shadows``' first), of ``opacity_units``.
    opacity_units : int
        The parts a sample's sunlight is counted in (1 with every caster opaque).
    where : bool
        Whether the samples keep where each shadow lies (their triangles):
        False for a study made with ``shadows=False``, whose samples hold
        each face's shadowed share only (points cannot be asked then).
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    directions: NDArray[np.float64]
    times: tuple[_dt.datetime, ...]
    step: _dt.timedelta
    shadows: tuple[SampleShadows, ...] = field(repr=False)
    origin: NDArray[np.float64] = field(repr=False)
    u: NDArray[np.float64] = field(repr=False)
    v: NDArray[np.float64] = field(repr=False)
    levels: tuple[dict[int, Parts], ...] | None = field(repr=False)
    layer_shadows: tuple[tuple[SampleShadows, ...], ...] = field(default=(), repr=False)
    layer_weights: tuple[int, ...] = (1,)
    opacity_units: int = 1
    where: bool = True

    @property
    def hours_per_sample(self) -> float:
        return self.step.total_seconds() / 3600.0

    @property
    def hours_per_unit(self) -> float:
        """The hours of one level step: a sample's, over ``opacity_units``."""
        return self.hours_per_sample / self.opacity_units

    def _layers(self) -> tuple[tuple[int, tuple[SampleShadows, ...]], ...]:
        """(weight, each sample's shadow) of each opacity threshold, lowest first."""
        every = (self.shadows, *self.layer_shadows)
        return tuple(zip(self.layer_weights, every, strict=True))

    @property
    def face_areas(self) -> NDArray[np.float64]:
        """(m,) each face's area."""
        corners = self.vertices[self.faces]
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        areas: NDArray[np.float64] = 0.5 * np.linalg.norm(cross, axis=1)
        return areas

    def sunlit_fraction(self) -> NDArray[np.float64]:
        """(s, m) the sunlit share of each face's area at each sample."""
        if not self.shadows:
            return np.zeros((0, len(self.faces)))
        if self.opacity_units == 1:  # every caster opaque
            return 1.0 - np.stack([sample.fraction for sample in self.shadows])
        shadowed = sum(
            weight * np.stack([sample.fraction for sample in samples])
            for weight, samples in self._layers()
        )
        dark = np.stack([sample.dark for sample in self.shadows])
        lit: NDArray[np.float64] = np.where(dark, 0.0, 1.0 - shadowed / self.opacity_units)
        return lit

    def mean_hours(self) -> NDArray[np.float64]:
        """(m,) each face's mean hours of sun over its area (the area-weighted
        mean of :meth:`sunlit_hours` over the face): exact from the shadows'
        areas, no levels needed."""
        hours: NDArray[np.float64] = self.sunlit_fraction().sum(axis=0) * self.hours_per_sample
        return hours

    def level_areas(self, face: int) -> dict[float, float]:
        """Hours of sun -> area of ``face`` sunlit that long (needs levels)."""
        levels = self._levels()[face]
        return {
            k * self.hours_per_unit: float(sum(poly.signed_areas(part).sum() for part in parts))
            for k, parts in sorted(levels.items())
        }

    def area_with_at_least(self, hours: float) -> NDArray[np.float64]:
        """(m,) the area of each face sunlit for at least ``hours`` (needs levels)."""
        wanted = self._samples_for(hours)
        return np.array(
            [
                sum(
                    float(poly.signed_areas(part).sum())
                    for k, parts in levels.items()
                    if k >= wanted
                    for part in parts
                )
                for levels in self._levels()
            ]
        )

    def fraction_meeting(self, hours: float) -> NDArray[np.float64]:
        """(m,) the share of each face's area sunlit for at least ``hours``
        (0 for a face of no area; needs levels)."""
        areas = self.face_areas
        meeting = self.area_with_at_least(hours)
        fraction: NDArray[np.float64] = np.divide(
            meeting, areas, out=np.zeros_like(areas), where=areas > 0
        )
        return np.minimum(fraction, 1.0)

    def level_loops(self, face: int) -> dict[float, list[NDArray[np.float64]]]:
        """Hours of sun -> the loops of that level of ``face`` as (k, 3)
        points in the scene (outer loops counter-clockwise seen from the
        face's front, holes clockwise): what a writer colours."""
        origin, u, v = self.origin[face], self.u[face], self.v[face]
        return {
            k * self.hours_per_unit: [
                origin + loop[:, :1] * u + loop[:, 1:] * v for part in parts for loop in part
            ]
            for k, parts in sorted(self._levels()[face].items())
        }

    def sunlit(self, points: ArrayLike, faces: ArrayLike) -> NDArray[np.bool_]:
        """(s, n) whether each of ``points`` (n, 3), lying on ``faces`` (n,)
        of the receiver, is in the sun at each sample: not on a dark face,
        and outside every shadow triangle of its face (a point on a shadow's
        edge counts as shadowed)."""
        uv, face = self._on_faces(points, faces)
        self._where()
        lit = np.ones((len(self.shadows), len(face)), dtype=bool)
        for index, sample in enumerate(self.shadows):
            lit[index] = ~(sample.dark[face] | self._in_triangles(uv, face, sample))
        return lit

    def sunlit_hours(self, points: ArrayLike, faces: ArrayLike) -> NDArray[np.float64]:
        """(n,) hours of sun at ``points`` (n, 3) on ``faces`` (n,): with
        translucent casters each sample's units of sun, less each
        threshold's weight where its shadow holds the point."""
        uv, face = self._on_faces(points, faces)
        self._where()
        units = np.full((len(self.shadows), len(face)), self.opacity_units, dtype=np.int64)
        for weight, samples in self._layers():
            for index, sample in enumerate(samples):
                units[index] -= weight * self._in_triangles(uv, face, sample)
        units[np.stack([sample.dark[face] for sample in self.shadows])] = 0
        hours: NDArray[np.float64] = units.sum(axis=0) * self.hours_per_unit
        return hours

    def _where(self) -> None:
        if not self.where:
            raise GeometryError(
                "this result was made without the shadows' outlines (shadows=False): "
                "it holds each face's hours, not a point's"
            )

    def _levels(self) -> tuple[dict[int, Parts], ...]:
        if self.levels is None:
            raise GeometryError("this result was made without levels (levels=False)")
        return self.levels

    def _samples_for(self, hours: float) -> int:
        """The fewest samples that make at least ``hours`` (a sum of samples
        equal to ``hours`` up to rounding, ``math.isclose``, makes it)."""
        wanted = math.ceil(hours / self.hours_per_unit)
        fewer = wanted - 1
        return fewer if math.isclose(fewer * self.hours_per_unit, hours) else wanted

    def _on_faces(
        self, points: ArrayLike, faces: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """(n, 2) ``points`` in their faces' frames, and the faces."""
        xyz = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        face = np.asarray(faces, dtype=np.int64).reshape(-1)
        if len(face) != len(xyz):
            raise GeometryError(f"{len(xyz)} points but {len(face)} faces given")
        if len(face) and (face.min() < 0 or face.max() >= len(self.faces)):
            raise GeometryError(f"face indices must be in [0, {len(self.faces)})")
        relative = xyz - self.origin[face]
        uv = np.column_stack(
            [
                np.einsum("ij,ij->i", relative, self.u[face]),
                np.einsum("ij,ij->i", relative, self.v[face]),
            ]
        )
        return uv, face

    def _in_triangles(
        self, uv: NDArray[np.float64], face: NDArray[np.int64], sample: SampleShadows
    ) -> NDArray[np.bool_]:
        """(n,) whether each point lies in one of its face's shadow triangles."""
        inside = np.zeros(len(face), dtype=bool)
        if not len(sample.face) or not len(face):
            return inside
        order = np.argsort(sample.face, kind="stable")
        owner = sample.face[order]
        start = np.searchsorted(owner, face, side="left")
        count = np.searchsorted(owner, face, side="right") - start
        point = np.repeat(np.arange(len(face)), count)
        first = np.repeat(start - np.cumsum(count) + count, count)
        triangle = order[np.arange(len(point)) + first]
        flat = _flatten(sample.triangles[triangle], point, face, self)
        inside[point[_holds(flat, uv[point])]] = True
        return inside


def _flatten(
    triangles: NDArray[np.float64],
    point: NDArray[np.int64],
    face: NDArray[np.int64],
    sunlight: SurfaceSunlight,
) -> NDArray[np.float64]:
    """(p, 3, 2) each triangle in the frame of the face of ``point``."""
    owner = face[point]
    relative = triangles - sunlight.origin[owner][:, None, :]
    return np.stack(
        [
            np.einsum("pkd,pd->pk", relative, sunlight.u[owner]),
            np.einsum("pkd,pd->pk", relative, sunlight.v[owner]),
        ],
        axis=2,
    )


def _holds(triangles: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(p,) whether each 2-D triangle holds its point (edges included),
    whatever its winding."""
    sides = []
    for corner in range(3):
        start, end = triangles[:, corner], triangles[:, (corner + 1) % 3]
        edge, to_point = end - start, points - start
        sides.append(edge[:, 0] * to_point[:, 1] - edge[:, 1] * to_point[:, 0])
    stacked = np.stack(sides, axis=1)
    held: NDArray[np.bool_] = np.all(stacked >= 0, axis=1) | np.all(stacked <= 0, axis=1)
    return held


def _frames(
    vertices: NDArray[np.float64], faces: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Each face's (origin, u, v): its centroid, its first edge's direction,
    and the normal crossed with it (zero vectors on a face of no area)."""
    corners = vertices[faces]
    first = corners[:, 1] - corners[:, 0]
    normal = np.cross(first, corners[:, 2] - corners[:, 0])
    normal_length = np.linalg.norm(normal, axis=1, keepdims=True)
    first_length = np.linalg.norm(first, axis=1, keepdims=True)
    proper = (normal_length > 0) & (first_length > 0)
    unit_normal = np.divide(normal, normal_length, out=np.zeros_like(normal), where=proper)
    u = np.divide(first, first_length, out=np.zeros_like(first), where=proper)
    return corners.mean(axis=1), u, np.cross(unit_normal, u)


def _sample(
    casters: MeshLike | Sequence[MeshLike],
    light: DirectionalLight,
    receiver: Caster,
    tolerance: Tolerance,
    where: bool = True,
    compiled: bool = False,
) -> SampleShadows:
    """The exact shadow on every face of ``receiver`` under one sun (without
    ``where``: each face's shadowed share only, by the compiled loops or not)."""
    vertices, faces = receiver.vertices, receiver.faces
    if not where:

        def measure(part: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
            # the whole receiver as the study's one mesh: what is derived from
            # it is kept on it from sample to sample
            mesh = receiver if len(part) == len(faces) else (vertices, faces[part])
            return shadowed_fractions(casters, light, mesh, tolerance=tolerance, compiled=compiled)

        measured = _in_halves(measure, np.arange(len(faces)))
        fraction = np.concatenate([part[0] for part in measured])
        facing = np.concatenate([part[1] for part in measured])
        return SampleShadows(np.zeros((0, 3, 3)), np.zeros(0, np.int64), ~facing, fraction)
    parts = _cast(casters, light, vertices, faces, np.arange(len(faces)), tolerance)
    fraction = np.ones(len(faces))
    for _, _, chosen, part_fraction in parts:
        fraction[chosen] = part_fraction
    triangles = np.concatenate([part[0] for part in parts])
    face = np.concatenate([part[1] for part in parts])
    covered = np.bincount(face, minlength=len(faces)) > 0
    return SampleShadows(triangles, face, (fraction >= 1.0) & ~covered, fraction)


def _cast(
    casters: MeshLike | Sequence[MeshLike],
    light: DirectionalLight,
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    chosen: NDArray[np.int64],
    tolerance: Tolerance,
) -> list[tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]]:
    """:func:`shadow_on_surface` on the faces ``chosen``: (shadow triangles,
    their faces, ``chosen``, the faces' shadowed fractions) of each part of
    :func:`_in_halves`."""

    def cast(
        part: NDArray[np.int64],
    ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
        shadow = shadow_on_surface(casters, light, (vertices, faces[part]), tolerance=tolerance)
        triangles = shadow.vertices[shadow.faces]
        return triangles, part[shadow.face_index], part, shadow.fraction

    return _in_halves(cast, chosen)


_Part = TypeVar("_Part")


def _in_halves(
    work: Callable[[NDArray[np.int64]], _Part], chosen: NDArray[np.int64]
) -> list[_Part]:
    """``work(chosen)`` in one call or, when that call refuses the work (a
    low sun over a city passes a union's or a pair search's budget,
    :mod:`shadowgeo.limits`), on each half in turn, halved again as needed."""
    try:
        return [work(chosen)]
    except BudgetError:
        # only a budget is worth halving for; bad input is not
        if len(chosen) < 2:
            raise
        middle = len(chosen) // 2
        return _in_halves(work, chosen[:middle]) + _in_halves(work, chosen[middle:])


def _tolerance(
    casters: MeshLike | Sequence[MeshLike], vertices: NDArray[np.float64], faces: NDArray[np.int64]
) -> Tolerance:
    """The tolerance :func:`shadow_on_surface` takes by default under a
    directional light (the casters' and the receiver's boxes), fixed once so
    that halves of the receiver get the same."""
    items: list[MeshLike] = _mesh_list(casters)
    boxes = [caster.bounds for caster in map(as_caster, items) if caster.n_faces]
    used = vertices[np.unique(faces)] if len(faces) else np.zeros((0, 3))
    return Tolerance.for_points(*boxes, used)


def _mesh_list(casters: MeshLike | Sequence[MeshLike]) -> list[MeshLike]:
    """One mesh as a list of one; a list of meshes as it is (a list of
    (n, 3) vertices and faces is one mesh, as Dask hands back a scattered
    ``(vertices, faces)``)."""
    if isinstance(casters, list) and not (
        len(casters) == 2 and isinstance(casters[0], np.ndarray) and casters[0].ndim == 2
    ):
        return list(casters)
    return [casters]  # type: ignore[list-item]


def surface_sunlight(
    casters: MeshLike | Sequence[MeshLike],
    surface: MeshLike,
    directions: ArrayLike,
    *,
    step: _dt.timedelta | None = None,
    times: Sequence[_dt.datetime] = (),
    levels: bool = True,
    opacity: ArrayLike | None = None,
    shadows: bool = True,
) -> SurfaceSunlight:
    """Exact sunlight on every face of ``surface`` for given sun directions.

    Parameters
    ----------
    casters : mesh or list of meshes
        As :func:`shadowgeo.shadow_on_surface` takes them; include the
        receiver's own buildings for them to shade themselves.
    surface : trimesh.Trimesh, Caster or (vertices, faces)
        The receiving faces (walls, roofs, terrain, a window's pane).
    directions : (s, 3) array_like
        The direction sunlight travels at each sample (down: the sun is up).
    step : timedelta
        The time each sample stands for (an hour by default).
    times : sequence of datetime
        The samples' times, kept on the result (for :mod:`shadowgeo.metrics`).
    levels : bool
        Also cut each face into polygons of equal sunlight duration (the
        costly part for many samples; hours at points and the faces' mean
        hours need none).
    opacity : (c,) array_like, optional
        Each caster face's opacity (0 to 1, rounded to sixteenths; a list of
        casters' faces in order): a point hidden at a sample gets ``1 - a``
        of its sun, ``a`` the largest opacity of the faces hiding it (see
        the module notes). None, the default: every caster is opaque.
    shadows : bool
        Keep where each sample's shadow lies (its triangles, for hours at
        points). False (with ``levels=False``): each face's shadowed share
        only, measured without building the shadow
        (:func:`shadowgeo.surface.shadowed_fractions`), for a long study of
        each face's hours: the same hours to about 1e-12 of a face's area.

    Returns
    -------
    SurfaceSunlight
        Each sample's shadow as :func:`shadowgeo.shadow_on_surface` gives it
        (finite, non-overlapping, exact up to its tolerance length); the
        levels of each face tile it.

    Examples
    --------
    A 1 m square wall facing south (+y), the sun in front of it for one
    sample and behind it for the other:

    >>> wall = ([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], [[0, 2, 1], [0, 3, 2]])
    >>> post = ([[9, 9, 9], [9, 9, 9.1], [9, 9.1, 9]], [[0, 1, 2]])
    >>> result = surface_sunlight(post, wall, [[0, -1, -1], [0, 1, -1]])
    >>> result.mean_hours().tolist()
    [1.0, 1.0]
    >>> sorted(result.level_areas(0).items())
    [(1.0, 0.5)]
    """
    step = _dt.timedelta(hours=1) if step is None else step
    if step <= _dt.timedelta(0):
        raise GeometryError(f"step must be positive, got {step}")
    receiver = as_caster(surface)
    vertices = np.asarray(receiver.vertices, dtype=np.float64)
    faces = np.asarray(receiver.faces, dtype=np.int64)
    rays = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    if times and len(times) != len(rays):
        raise GeometryError(f"{len(times)} times for {len(rays)} sun directions")
    if levels and not shadows:
        raise GeometryError("levels need the shadows: levels=True with shadows=False")
    tolerance = _tolerance(casters, vertices, faces)
    layered, parts = _layered(casters, opacity)
    # (one choice for the whole study: its size is faces times samples)
    compiled = not shadows and use_compiled("areas", len(faces) * len(rays))
    # the casters made meshes once: what is derived from them is kept from
    # sample to sample
    parts = [[as_caster(mesh) for mesh in _mesh_list(part)] for part in parts]
    every = tuple(
        tuple(
            _sample(part, DirectionalLight(ray), receiver, tolerance, shadows, compiled)
            for ray in rays
        )
        for part in parts
    )
    origin, u, v = _frames(vertices, faces)
    cut = _face_levels(vertices, faces, (origin, u, v), every, layered) if levels else None
    return SurfaceSunlight(
        vertices, faces, rays, tuple(times), step, every[0], origin, u, v, cut,
        every[1:], layered.weights, layered.units, shadows,
    )  # fmt: skip


def _layered(
    casters: MeshLike | Sequence[MeshLike], opacity: ArrayLike | None
) -> tuple[Layers, list[MeshLike | Sequence[MeshLike]]]:
    """The opacity thresholds of the casters' faces and the casters of each
    (the faces at least that opaque, as one mesh); every face opaque: the
    casters as given."""
    if opacity is None:
        return layers(None, 0), [casters]
    meshes = [as_caster(mesh) for mesh in _mesh_list(casters)]
    starts = np.cumsum([0] + [len(mesh.vertices) for mesh in meshes[:-1]])
    vertices = np.concatenate([mesh.vertices for mesh in meshes])
    faces = np.concatenate([mesh.faces + start for mesh, start in zip(meshes, starts, strict=True)])
    layered = layers(opacity, len(faces))
    if layered.opaque:
        return layered, [casters]
    return layered, [(vertices, faces[chosen]) for chosen in layered.faces]


def surface_sun_study(
    casters: MeshLike | Sequence[MeshLike],
    surface: MeshLike,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
    levels: bool = True,
    opacity: ArrayLike | None = None,
    shadows: bool = True,
) -> SurfaceSunlight:
    """:func:`surface_sunlight` at ``times`` for a site: the sun's directions
    from :mod:`shadowgeo.sun`; samples with the sun below the horizon are
    dropped (dark everywhere). ``up`` and ``north`` give the scene's frame
    (a city scene from :func:`shadowgeo.load` is Z up, its site's north);
    ``opacity``: each caster face's, as :func:`surface_sunlight` takes it.

    Examples
    --------
    >>> import datetime as dt
    >>> wall = ([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], [[0, 2, 1], [0, 3, 2]])
    >>> post = ([[9, 9, 9], [9, 9, 9.1], [9, 9.1, 9]], [[0, 1, 2]])
    >>> day = [dt.datetime(2026, 3, 21, h, 30, tzinfo=dt.UTC) for h in range(24)]
    >>> south = surface_sun_study(post, wall, day, latitude=51.5, longitude=0.0, up="Z")
    >>> len(south.times), south.mean_hours().tolist()  # facing north (+y): no sun at the equinox
    (12, [0.0, 0.0])
    """
    kept, lights = sun_lights(latitude, longitude, times, up=up, north=north)
    directions = np.array([light.direction for light in lights]).reshape(-1, 3)
    return surface_sunlight(
        casters,
        surface,
        directions,
        step=step,
        times=kept,
        levels=levels,
        opacity=opacity,
        shadows=shadows,
    )


def surface_sun_study_by_day(
    casters: MeshLike | Sequence[MeshLike],
    surface: MeshLike,
    times: Sequence[_dt.datetime],
    *,
    latitude: float,
    longitude: float,
    step: _dt.timedelta | None = None,
    up: str = "Y",
    north: ArrayLike | None = None,
    levels: bool = True,
    opacity: ArrayLike | None = None,
    shadows: bool = True,
    tz: _dt.tzinfo | None = None,
    scheduler: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict[_dt.date, SurfaceSunlight]:
    """:func:`surface_sun_study` for each calendar day (in ``tz``, UTC by
    default) of ``times``, as :func:`shadowgeo.sun_study_by_day` does for a
    plane. ``opacity``: each caster face's, as for :func:`surface_sun_study`.

    ``scheduler``: None runs the days one after another in this process; a
    ``dask.distributed.Client``, a scheduler address (``"tcp://host:8786"``)
    or ``"local"`` (a ``LocalCluster`` on this machine, started and closed
    here) runs them on Dask, one task a day, the casters and the surface sent
    to the workers once. Results are identical either way (each day is the
    same call on the same input). ``progress(done, total)`` is called as days
    finish.

    Examples
    --------
    >>> import datetime as dt
    >>> wall = ([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], [[0, 1, 2], [0, 2, 3]])
    >>> post = ([[9, 9, 9], [9, 9, 9.1], [9, 9.1, 9]], [[0, 1, 2]])
    >>> days = [dt.datetime(2026, 6, d, h, tzinfo=dt.UTC) for d in (20, 21) for h in range(24)]
    >>> by_day = surface_sun_study_by_day(post, wall, days, latitude=51.5, longitude=0.0, up="Z")
    >>> {day.isoformat(): len(study.times) for day, study in by_day.items()}
    {'2026-06-20': 17, '2026-06-21': 17}
    """
    options: dict[str, Any] = dict(
        latitude=latitude,
        longitude=longitude,
        step=step,
        up=up,
        north=north,
        levels=levels,
        opacity=opacity,
        shadows=shadows,
    )
    return each_day(
        surface_sun_study,
        (casters, surface),
        times,
        tz=tz,
        scheduler=scheduler,
        progress=progress,
        name="surface-sun-study",
        options=options,
    )


def _face_levels(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    frames: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
    thresholds: tuple[tuple[SampleShadows, ...], ...],
    layered: Layers,
) -> tuple[dict[int, Parts], ...]:
    """Each face's exactly-``k``-units-sunlit parts, in its frame:
    :func:`cover_levels` of every sample's shadow (with translucent casters,
    each threshold's, its weight's number of times), :data:`CHUNK` faces at
    a time, each face in its own cell of the chunk's plane."""
    origin, u, v = frames
    n_faces = len(faces)
    flat = _to_frames(vertices[faces], np.arange(n_faces), origin, u, v)
    proper = np.abs(_twice_areas(flat)) > 0
    # a face dark at a sample (turned away) is dark in every unit, whatever
    # casts: it only lowers the face's count (no loops needed)
    dark = np.zeros(n_faces, dtype=np.int64)
    for turned in thresholds[0]:
        dark += turned.dark
    dark *= layered.units
    count = len(thresholds[0])
    shadows = tuple(
        sample
        for at in range(count)
        for weight, samples in zip(layered.weights, thresholds, strict=True)
        for sample in [samples[at]] * weight
    )
    # the units no shadow takes: a sample's beyond the thresholds' weights
    clear = count * (layered.units - sum(layered.weights))
    partial = _PartialShadows.of(shadows, n_faces, frames)
    result: list[dict[int, Parts]] = [{} for _ in range(n_faces)]
    for chunk in partial.chunks(np.flatnonzero(proper)):
        for face, k, part in partial.every.levels(chunk, flat[chunk], len(shadows)):
            level = k + clear - int(dark[face]) - int(partial.whole[face])
            result[face].setdefault(level, []).append(part)
    return tuple(dict(sorted(levels.items())) for levels in result)


@dataclass(frozen=True)
class _PartialShadows:
    """The samples' shadows for cutting levels: ``whole`` (m,) counts the
    samples at which each face, lit (not turned away: those are counted
    apart, in every unit), is shadowed whole (its shadow's area is the
    face's: those lower its count of sunlit samples and need no loops),
    ``depth`` (m,) the samples that shadow it in part, and ``every`` the
    loops of those partial shadows."""

    whole: NDArray[np.int64]
    depth: NDArray[np.int64]
    every: _Chunks

    @classmethod
    def of(
        cls,
        shadows: tuple[SampleShadows, ...],
        n_faces: int,
        frames: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
    ) -> _PartialShadows:
        whole = np.zeros(n_faces, dtype=np.int64)
        depth = np.zeros(n_faces, dtype=np.int64)
        loops, owner, sample = (
            [np.zeros((0, 3, 2))],
            [np.zeros(0, np.int64)],
            [np.zeros(0, np.int64)],
        )
        for index, shadows_at in enumerate(shadows):
            covered = shadows_at.fraction >= 1.0  # dark, or its triangles tile the face
            whole += covered & ~shadows_at.dark
            kept = ~covered[shadows_at.face]
            face = shadows_at.face[kept]
            depth += np.bincount(face, minlength=n_faces) > 0
            loops.append(_to_frames(shadows_at.triangles[kept], face, *frames))
            owner.append(face)
            sample.append(np.full(len(face), index, dtype=np.int64))
        every = _Chunks(np.concatenate(loops), np.concatenate(owner), np.concatenate(sample))
        return cls(whole, depth, every)

    def chunks(self, faces: NDArray[np.int64]) -> Iterator[NDArray[np.int64]]:
        """``faces`` :data:`CHUNK` at a time (each rising), those shadowed at
        as many samples together: a chunk's unions, one per level, stop at
        its deepest face, so shallow faces do not pay for deep ones."""
        ordered = faces[np.argsort(self.depth[faces], kind="stable")]
        for first in range(0, len(ordered), CHUNK):
            yield np.sort(ordered[first : first + CHUNK])


# Faces cut into levels together: one cover of their cells, small enough that
# the cover's cuts of its window (the chunk's faces) stay cheap.
CHUNK = 256


@dataclass(frozen=True)
class _Chunks:
    """Every sample's shadow loops ((t, 3, 2) in their faces' frames), the
    face and the sample of each, for cutting chunks of faces into levels."""

    loops: NDArray[np.float64]
    owner: NDArray[np.int64]
    sample: NDArray[np.int64]

    def levels(
        self, chunk: NDArray[np.int64], flat: NDArray[np.float64], count: int
    ) -> list[tuple[int, int, list[NDArray[np.float64]]]]:
        """(face, sunlit samples, [outer, hole, ...]) of the faces ``chunk``
        (rising; ``flat`` their (f, 3, 2) corners) over ``count`` samples."""
        slot = np.full(int(chunk.max()) + 1, -1, dtype=np.int64)
        slot[chunk] = np.arange(len(chunk))
        mine = np.flatnonzero(np.isin(self.owner, chunk))
        extent = float(np.abs(flat).max())
        pitch = 3.0 * extent  # cells apart: no face reaches its neighbour's cell
        columns = math.ceil(math.sqrt(len(chunk)))
        cells = np.arange(len(chunk))
        shift = np.column_stack([cells % columns, cells // columns]) * pitch
        centre = np.full(2, 0.5 * (columns - 1) * pitch)
        scale = poly.local_scale(2.0 * (float(np.abs(shift - centre).max()) + extent))

        def local(triangles: NDArray[np.float64], at: NDArray[np.int64]) -> NDArray[np.float64]:
            placed: NDArray[np.float64] = (triangles + shift[at][:, None, :] - centre) * scale
            return _counter_clockwise(placed)

        window = poly.unite(list(local(flat, cells)))
        placed = local(self.loops[mine], slot[self.owner[mine]])
        keep = _twice_areas(placed) != 0
        placed, of_sample = placed[keep], self.sample[mine][keep]
        order = np.argsort(of_sample, kind="stable")
        bounds = np.searchsorted(of_sample[order], np.arange(count + 1))
        regions = [list(placed[order[bounds[i] : bounds[i + 1]]]) for i in range(count)]
        found = []
        for covered, parts in cover_levels(regions, window).items():
            for part in parts:
                cell = _cell_of(part[0][0] / scale + centre, pitch, columns)
                back = [loop / scale + centre - shift[cell] for loop in part]
                found.append((int(chunk[cell]), count - covered, back))
        return found


def _to_frames(
    triangles: NDArray[np.float64],
    owner: NDArray[np.int64],
    origin: NDArray[np.float64],
    u: NDArray[np.float64],
    v: NDArray[np.float64],
) -> NDArray[np.float64]:
    """(t, 3, 2) triangles in the frames of their faces ``owner``."""
    relative = triangles - origin[owner][:, None, :]
    return np.stack(
        [
            np.einsum("tkd,td->tk", relative, u[owner]),
            np.einsum("tkd,td->tk", relative, v[owner]),
        ],
        axis=2,
    )


def _twice_areas(triangles: NDArray[np.float64]) -> NDArray[np.float64]:
    """(t,) twice the signed area of each (3, 2) triangle."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    areas: NDArray[np.float64] = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (
        c[:, 0] - a[:, 0]
    )
    return areas


def _counter_clockwise(triangles: NDArray[np.float64]) -> NDArray[np.float64]:
    """The triangles turned counter-clockwise (winding +1 inside)."""
    turned: NDArray[np.float64] = np.where(
        (_twice_areas(triangles) < 0)[:, None, None], triangles[:, ::-1], triangles
    )
    return turned


def _cell_of(point: NDArray[np.float64], pitch: float, columns: int) -> int:
    """The face whose cell holds ``point`` (cells ``pitch`` apart)."""
    column, row = (int(round(float(value) / pitch)) for value in point)
    return row * columns + column
