"""Sunlight on a city's walls and roofs: the receivers and casters of a scene.

A city scene (:func:`shadowgeo.load` of a CityJSON or footprint file) says
what each face is (:class:`~shadowgeo.scene.model.Semantics`: RoofSurface,
WallSurface, GroundSurface). :func:`city_surfaces` gathers the faces of the
kinds asked for (walls and roofs by default) into one receiving mesh, with
each face's building and kind; every shape that casts is a caster, so the
buildings shade each other and themselves, translucent ones (trees given a
``Material.transparency``) by their opacity, as the converter's rule
(:func:`caster_opacity`). :func:`study_city_surfaces` runs
:func:`shadowgeo.sunlight_surfaces.surface_sun_study` over them at the
scene's site.
"""

from __future__ import annotations

import datetime as _dt
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import SceneError
from ..sunlight_surfaces import SurfaceSunlight, surface_sun_study
from .model import Scene, Shape, located
from .opacity import opacities

__all__ = [
    "CitySurfaces",
    "WALLS_AND_ROOFS",
    "caster_opacity",
    "city_casters",
    "city_surfaces",
    "study_city_surfaces",
]

WALLS_AND_ROOFS = ("WallSurface", "RoofSurface")


@dataclass(frozen=True)
class CitySurfaces:
    """The receiving faces of a city scene, in world coordinates.

    vertices : (n, 3) float64
    faces : (m, 3) int64
    owner : (m,) int64
        Each face's shape (index in ``names``): its building.
    kind : (m,) int64
        Each face's kind (index in ``kinds``).
    names : tuple of str
        The shapes' names (``""`` for an unnamed one).
    kinds : tuple of str
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    owner: NDArray[np.int64]
    kind: NDArray[np.int64]
    names: tuple[str, ...]
    kinds: tuple[str, ...]


def city_surfaces(scene: Scene, kinds: Sequence[str] = WALLS_AND_ROOFS) -> CitySurfaces:
    """The faces of ``kinds`` of every geometry shape of ``scene`` (see the
    module notes). SceneError when no face has any of the kinds (a file
    without semantic surfaces: LoD1 blocks, footprints read without them)."""
    shapes = [shape for shape in scene.shapes if shape.role == "geometry" and shape.n_faces]
    wanted = tuple(kinds)
    vertices: list[NDArray[np.float64]] = []
    faces: list[NDArray[np.int64]] = []
    owner: list[NDArray[np.int64]] = []
    kind: list[NDArray[np.int64]] = []
    base = 0
    for index, shape in enumerate(shapes):
        if shape.semantics is None:
            continue
        for slot, name in enumerate(wanted):
            chosen = shape.semantics.faces(name)
            if not len(chosen):
                continue
            world = shape.world_vertices
            vertices.append(world)
            faces.append(shape.faces[chosen] + base)
            owner.append(np.full(len(chosen), index, dtype=np.int64))
            kind.append(np.full(len(chosen), slot, dtype=np.int64))
            base += len(world)
    if not faces:
        raise SceneError(
            f"no face of the scene is a {' or '.join(wanted)} (the file gives no "
            "semantic surfaces)",
            path=scene.path,
        )
    return CitySurfaces(
        np.concatenate(vertices),
        np.concatenate(faces),
        np.concatenate(owner),
        np.concatenate(kind),
        tuple(shape.name or "" for shape in shapes),
        wanted,
    )


def _casting(scene: Scene) -> list[Shape]:
    """The geometry shapes that cast, in the scene's order."""
    return [
        shape
        for shape in scene.shapes
        if shape.role == "geometry" and shape.n_faces and shape.casts_shadow
    ]


def caster_opacity(scene: Scene) -> NDArray[np.float64] | None:
    """Each face of :func:`city_casters`' mesh's casting opacity
    (:func:`shadowgeo.scene.opacity.casting_opacity` of its shape), for
    :func:`shadowgeo.surface_sunlight`; None when every one is opaque."""
    shapes = _casting(scene)
    counts = [len(shape.faces) for shape in shapes]
    faces: NDArray[np.float64] = np.repeat(opacities(shapes), counts)
    return faces if (faces < 1).any() else None


def city_casters(scene: Scene) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Every geometry shape that casts, as one (vertices, faces) mesh."""
    shapes = _casting(scene)
    if not shapes:
        raise SceneError("nothing in the scene casts a shadow", path=scene.path)
    sizes = np.cumsum([0] + [len(shape.vertices) for shape in shapes[:-1]])
    return (
        np.concatenate([shape.world_vertices for shape in shapes]),
        np.concatenate([shape.faces + base for shape, base in zip(shapes, sizes, strict=True)]),
    )


def study_city_surfaces(
    scene: Scene,
    times: Sequence[_dt.datetime],
    *,
    latitude: float | None = None,
    longitude: float | None = None,
    kinds: Sequence[str] = WALLS_AND_ROOFS,
    step: _dt.timedelta | None = None,
    levels: bool = True,
) -> tuple[CitySurfaces, SurfaceSunlight]:
    """Sunlight on the walls and roofs (``kinds``) of a city scene at
    ``times``; the site and true north from :attr:`Scene.site` unless
    ``latitude`` and ``longitude`` are given (SceneError when neither is)."""
    latitude, longitude, north = located(scene, latitude, longitude)
    surfaces = city_surfaces(scene, kinds)
    sunlight = surface_sun_study(
        city_casters(scene),
        (surfaces.vertices, surfaces.faces),
        times,
        latitude=latitude,
        longitude=longitude,
        step=step,
        up=scene.up_axis,
        north=north,
        levels=levels,
        opacity=caster_opacity(scene),
    )
    return surfaces, sunlight
