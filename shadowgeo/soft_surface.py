"""Soft shadows on every surface: graded levels of a light with a size on
each face of a triangle mesh.

:func:`soft_shadow_on_surface` is :func:`~shadowgeo.soft_shadow` on a mesh
instead of a plane, face by face as :func:`~shadowgeo.shadow_on_surface`:
the light is replaced by the same point (or directional) samples
(:func:`~shadowgeo.soft.light_samples`), each casts its exact hard shadow on
every face (:func:`~shadowgeo.surface.regions_per_light`: steps 1 to 3 of
:func:`~shadowgeo.shadow_on_surface`, every sample's regions in the same
face frames), and on each face the cover of those regions is cut into bands
of the number of samples hidden (:func:`~shadowgeo.levels.cover_bands`,
with :func:`~shadowgeo.soft.band_thresholds`); the bands of every face are
stitched into one :class:`~shadowgeo.SurfaceShadow` per level.

The hidden fraction of a point of a face is the share of the samples its
face turns its front to that casters hide from it: what the face's own
plane hides is the shading's to draw, as for a hard shadow (a face turned
away from every sample has no level, as :func:`shadow_on_surface` leaves
it; its ``fraction`` is 1). It is the fraction of samples, with the errors
:mod:`shadowgeo.soft` measures on a plane: at 64 samples (the default), at
2,500 points of a floor and a wall by a column under a 1.5 x 1 rectangle,
0.035 at most and 0.0105 on average in the penumbra against ray tests of
1,024 random points of the light (their own noise included;
``tests/test_soft_surface.py``), and the level's rounding to ``k / levels``
on top (half a level at most).

Cost: the samples' steps 1 to 3 (each as one :func:`shadow_on_surface`
call's), one :func:`~shadowgeo.levels.cover_bands` per shadowed face, and a
stitch per level: in that test, 0.41 s at 16 samples, 1.25 s at 64 and 6.4 s
at 256, against 0.02 s for the hard shadow of the light's centre.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import NDArray

from . import plane2d as poly
from .levels import cover_bands
from .lights import Light
from .simplify import loops_of
from .soft import SizedLight, band_thresholds, checked_counts, has_size, light_samples
from .surface import (
    LightRegions,
    SurfaceShadow,
    caster_list,
    regions_per_light,
    shadow_on_surface,
)
from .tolerance import Tolerance
from .topology import MeshLike, as_caster

__all__ = ["SoftSurfaceShadow", "soft_shadow_on_surface"]

# Per face: for each sample turned to it, its shadow region's loops (none: unshadowed).
_FaceCover = list[list[NDArray[np.float64]]]


@dataclass(frozen=True)
class SoftSurfaceShadow:
    """A light with a size's shadow on every face of a mesh.

    Attributes
    ----------
    light : light with or without a size
    levels : list of (float, SurfaceShadow)
        The regions of equal hidden fraction ``k / n`` (``n`` the levels
        asked for), lowest first, each a :class:`~shadowgeo.SurfaceShadow`
        (its ``fraction``: the share of each face in that level); they do not
        overlap, and the last holds the points hidden from every sample.
    samples : tuple of Light
        The point or directional lights the light was replaced by.
    fraction : (m,) float64
        Each face's mean hidden fraction (1.0 on faces turned away from
        every sample).
    """

    light: SizedLight
    levels: list[tuple[float, SurfaceShadow]]
    samples: tuple[Light, ...]
    fraction: NDArray[np.float64]


def soft_shadow_on_surface(
    casters: MeshLike | Sequence[MeshLike],
    light: SizedLight,
    surface: MeshLike,
    *,
    levels: int = 8,
    samples: int | None = None,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
) -> SoftSurfaceShadow:
    """The soft shadow of ``casters`` from ``light`` (a light with a size) on
    every face of ``surface``, in ``levels`` graded layers (module notes).

    Parameters
    ----------
    casters, surface, offset, tolerance
        As :func:`~shadowgeo.shadow_on_surface` takes them.
    light : PointLight, SpotLight, DirectionalLight, RectLight or DiskLight
        A light with no size gives one level, exactly
        :func:`~shadowgeo.shadow_on_surface`'s shadow.
    levels : int
        Bands of the hidden fraction, ``k / levels`` for ``k = 1 .. levels``.
    samples : int, optional
        Point lights standing for the light (default
        :data:`shadowgeo.soft.DEFAULT_SAMPLES`, at most ``MAX_SAMPLES``).

    Returns
    -------
    SoftSurfaceShadow
        Finite; each level's triangles lie in the faces they shade (lifted
        ``offset``), stitched without cracks as a ``SurfaceShadow``'s; the
        levels do not overlap.

    Examples
    --------
    A 1 x 1 roof 1 above a floor under a 1 x 1 light 2 above it: the levels
    cover its 2 x 2 penumbra but the rim hidden from under one eighth of the
    samples, the regions :func:`~shadowgeo.soft_shadow` gives on the plane.

    >>> from shadowgeo import Plane, soft_shadow
    >>> from shadowgeo.lights import RectLight
    >>> roof = ([[-.5, 1, -.5], [.5, 1, -.5], [.5, 1, .5], [-.5, 1, .5]], [[0, 2, 1], [0, 3, 2]])
    >>> floor = ([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], [[0, 2, 1], [0, 3, 2]])
    >>> light = RectLight([0, 3, 0], [0, -1, 0], 1, 1, up=[0, 0, 1])
    >>> soft = soft_shadow_on_surface(roof, light, floor, levels=4)
    >>> [fraction for fraction, _ in soft.levels]
    [0.25, 0.5, 0.75, 1.0]
    >>> round(sum(level.area for _, level in soft.levels), 4)  # (penumbra: 4)
    3.3954
    >>> flat = soft_shadow(roof, light, Plane([0, 1, 0], 0), levels=4)
    >>> [round(level.area, 9) for _, level in flat.levels] == [
    ...     round(level.area, 9) for _, level in soft.levels
    ... ]
    True
    """
    levels, count = checked_counts(light, levels, samples)
    if not has_size(light):
        point = cast(Light, light)  # no size: a point, spot or directional light
        hard = shadow_on_surface(casters, point, surface, offset=offset, tolerance=tolerance)
        return SoftSurfaceShadow(light, [(1.0, hard)], (point,), hard.fraction)
    bodies = [as_caster(caster) for caster in caster_list(casters)]
    boxes = [body.bounds for body in bodies if body.n_faces]
    stacked = np.concatenate(boxes) if boxes else np.zeros((1, 3))
    towards = 0.5 * (stacked.min(axis=0) + stacked.max(axis=0))
    lights = light_samples(light, count, towards)
    found = regions_per_light(bodies, lights, surface, offset=offset, tolerance=tolerance)
    facing = np.stack([each.facing for each in found.found])  # (samples, m)
    covers = _face_covers(found, facing)
    bands = {face: _face_bands(cover, found.outlines[face], levels) for face, cover in covers}
    turned = np.asarray(facing.any(axis=0), dtype=bool)
    graded = []
    for k in range(1, levels + 1):
        faces = np.array([face for face, band in bands.items() if k in band], dtype=np.int64)
        if not len(faces):
            continue
        regions = loops_of([bands[int(face)][k] for face in faces])
        graded.append((k / levels, found.stitched(regions, faces, turned)))
    fraction = np.where(turned, 0.0, 1.0)
    for level_fraction, level in graded:
        fraction[turned] += level_fraction * level.fraction[turned]
    return SoftSurfaceShadow(light, graded, tuple(lights), fraction)


def _face_covers(found: LightRegions, facing: NDArray[np.bool_]) -> list[tuple[int, _FaceCover]]:
    """For each face some sample shadows, each sample's region on it (in
    the face's frame): its loops for the samples turned to the face, none
    from those it turns away from (they are left out of its count)."""
    regions: dict[int, list[list[NDArray[np.float64]] | None]] = {}
    for index, each in enumerate(found.found):
        points, sizes, owner = each.regions
        loops = np.split(points, np.cumsum(sizes)[:-1]) if len(sizes) else []
        for loop, region in zip(loops, owner.tolist(), strict=True):
            face = int(each.faces[region])
            slots = regions.setdefault(face, [None] * len(found.found))
            if slots[index] is None:
                slots[index] = []
            slots[index].append(loop)  # type: ignore[union-attr]
    covers = []
    for face, slots in sorted(regions.items()):
        turned = facing[:, face]
        covers.append((face, [slot or [] for slot, on in zip(slots, turned, strict=True) if on]))
    return covers


def _face_bands(
    cover: _FaceCover, outline: NDArray[np.float64], levels: int
) -> dict[int, list[NDArray[np.float64]]]:
    """One face's cover cut into bands: level ``k`` to its loops, in the face's
    frame (``outline`` (3, 2) its corners there)."""
    total = len(cover)
    if not total:
        return {}
    thresholds, starts = band_thresholds(levels, total)
    scale = poly.local_scale(2.0 * float(np.abs(outline).max()))
    corners = outline if poly.signed_areas([outline])[0] > 0 else outline[::-1]
    window = poly.unite([corners * scale])
    regions = [[loop * scale for loop in _counter_clockwise(loops)] for loops in cover]
    bands = cover_bands(regions, window, thresholds)
    return {
        starts[threshold]: [loop / scale for part in parts for loop in part]
        for threshold, parts in zip(thresholds, bands, strict=True)
        if parts
    }


def _counter_clockwise(loops: list[NDArray[np.float64]]) -> list[NDArray[np.float64]]:
    """A region's loops as cover_bands reads them: outer loops counter-
    clockwise, holes clockwise (regions from Clipper2 already are; a face
    frame that mirrors them turns every loop round)."""
    if not loops:
        return loops
    areas = poly.signed_areas(loops)
    if float(areas.sum()) >= 0:
        return loops
    return [loop[::-1] for loop in loops]
