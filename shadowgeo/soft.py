"""Soft shadows as geometry: the umbra, the penumbra and graded levels of a
light with a size on a plane.

A light with a size (a sphere light's ``source_radius``, the sun's
``angle``, a :class:`~shadowgeo.lights.RectLight` or
:class:`~shadowgeo.lights.DiskLight`) hides a point of the plane from a
*fraction* of itself. :func:`soft_shadow` gives:

- ``umbra``: the points hidden from the whole light; ``penumbra``: the points
  hidden from some of it (the umbra included), both :class:`~shadowgeo.Shadow`
  values (polygons, mesh, area);
- ``levels``: non-overlapping regions of equal hidden fraction, ``k /
  levels`` for ``k = 1 .. levels`` (the fraction rounded to the nearest
  level), nested from the penumbra's rim to the umbra, so a writer can bake
  them as graded transparency;
- ``fraction(points)``: the hidden fraction at points of the plane.

How, and how exact
------------------
The light is replaced by ``samples`` point (or, for the sun, directional)
lights spread evenly over it: the Hammersley set over a rectangle, mapped
onto a disc by the concentric map (Shirley and Chiu) for a disc, a sphere
(seen as the disc across the line from its centre to the caster's) and the
sun's disc of directions. Each casts its exact hard shadow
(:func:`~shadowgeo.project_shadow`: every hard case of a point light is
handled for every sample: part of the light level with or below the caster's
top, below the receiver plane, touching it, a caster piercing the plane), and
the cover of those shadows is cut into bands of the number of samples hidden
(:func:`~shadowgeo.levels.cover_bands`): ``levels`` and ``fraction`` are the
fraction of *samples* hidden. A grid would let a straight shadow edge hide a
whole row of samples at once (an error of ``1 / sqrt(samples)``); the
Hammersley set has no such rows. Measured at 10,000 points of the plane round
a 2 x 2 x 2 box, against ray tests of 4,096 random points of the light (whose
own noise, about 0.008, is part of these figures), as the largest error and
the mean in the penumbra: under a 1.5 x 1 rectangle 0.11 and 0.022 with 16
samples, 0.035 and 0.0073 with 64 (the default), 0.019 and 0.0038 with 256;
under a disc of radius 0.8, 0.15 and 0.025, 0.065 and 0.010, 0.028 and 0.0057.
A grid of 64 erred by 0.10 and 0.030 under the rectangle (``tests/test_soft.py``
checks the default's bounds).

The umbra and penumbra are **exact for one closed convex caster under a
rectangle**: the points hidden from every point of a convex light are those
hidden from its corners (for a point of the plane, the light points it cannot
see form a convex set), so the umbra is the intersection of the four corners'
shadows, and the penumbra is the convex hull of their union. Under a disc
(sphere, disk, sun) the corners are those of the regular
:data:`DISC_CORNERS`-gon around the disc: the umbra is then conservative
(inside the true one: hidden from a larger light) and the penumbra holds the
true one, the light's outline off by at most ``1 / cos(pi / DISC_CORNERS) - 1``
of its radius (0.12 % for 64 corners). For anything else (several casters,
a concave or open one) the umbra is NOT the intersection of a few corner
shadows: a point can be hidden from every corner and still see the light's
middle (two boxes side by side under a long light, the gap between them).
There the umbra is the region hidden from every sample and the penumbra the
union of the samples' shadows: both from the samples, with the error above at
their edges (``exact`` is False).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from manifold3d import CrossSection
from numpy.typing import ArrayLike, NDArray

from . import plane2d as poly
from .errors import GeometryError
from .levels import cover_bands
from .lights import DirectionalLight, DiskLight, Light, PointLight, RectLight, SpotLight
from .plane import Plane
from .projection import project_shadow
from .shadow import Shadow, ShadowDiagnostics, triangulated
from .tolerance import Tolerance
from .topology import Caster, MeshLike, as_caster, empty_mesh

__all__ = [
    "DEFAULT_SAMPLES",
    "DISC_CORNERS",
    "MAX_CONVEX_CHECK",
    "MAX_SAMPLES",
    "Parts",
    "SizedLight",
    "SoftShadow",
    "band_thresholds",
    "checked_counts",
    "has_size",
    "light_samples",
    "soft_shadow",
]

SizedLight = PointLight | SpotLight | DirectionalLight | RectLight | DiskLight
Parts = list[list[NDArray[np.float64]]]

# Samples of a light with a size when soft_shadow is not told how many.
DEFAULT_SAMPLES = 64
# At most this many samples: the levels cut the arrangement of the samples'
# shadows, whose corners grow with the square of their number (every shadow
# crosses every other), 0.4 s at 330 samples, 4 s at 540.
MAX_SAMPLES = 400
# Corners of the polygon round a disc light for the exact convex case.
DISC_CORNERS = 64
# A caster is checked for convexity only up to this many faces (the check
# pairs every vertex with every face plane, 0.1 s at 20,000 faces); a bigger
# one is taken as not convex, and its umbra and penumbra come from the samples.
MAX_CONVEX_CHECK = 20_000


@dataclass(frozen=True)
class SoftShadow:
    """A light with a size's shadow on a plane (see the module notes).

    Attributes
    ----------
    umbra, penumbra : Shadow
        Hidden from all of the light, and from some of it.
    levels : list of (float, Shadow)
        The regions of equal hidden fraction, lowest fraction first, each
        with its fraction ``k / n`` (``n`` the ``levels`` asked for); they do
        not overlap.
    exact : bool
        Whether ``umbra`` and ``penumbra`` are exact (one convex closed
        caster under a rectangle) or bounds (a disc light, conservative) or
        from the samples.
    samples : tuple of Light
        The point or directional lights the light was replaced by.
    """

    plane: Plane
    light: SizedLight
    umbra: Shadow
    penumbra: Shadow
    levels: list[tuple[float, Shadow]]
    exact: bool
    samples: tuple[Light, ...]
    sample_shadows: list[Shadow] = field(repr=False)

    def fraction(self, points: ArrayLike) -> NDArray[np.float64]:
        """(p,) the fraction of the light's samples hidden from ``points``
        ((p, 3) on the plane, or (p, 2) in ``plane.to_2d`` coordinates)."""
        points = np.asarray(points, dtype=np.float64)
        flat = self.plane.to_2d(points) if points.shape[-1] == 3 else points.reshape(-1, 2)
        hidden = np.zeros(len(flat))
        for shadow in self.sample_shadows:
            hidden += poly.points_in_parts(flat, shadow.polygons)
        return hidden / len(self.sample_shadows)


def light_samples(
    light: SizedLight, count: int = DEFAULT_SAMPLES, towards: ArrayLike | None = None
) -> list[Light]:
    """``count`` point (or directional) lights spread evenly over ``light``
    (one: the light itself, when it has no size). ``towards``: the point a
    sphere light's disc faces (the caster's centre); a spot light's samples
    keep its cone."""
    if count < 1:
        raise GeometryError(f"samples must be >= 1, got {count!r}")
    if isinstance(light, RectLight):
        return _rect_samples(light, count)
    if isinstance(light, DiskLight):
        return [
            PointLight(p)
            for p in _disc_points(light.position, light.direction, light.radius, count)
        ]
    if isinstance(light, DirectionalLight):
        return _directional_samples(light, count)
    return _sphere_samples(light, count, towards)


def _rect_samples(light: RectLight, count: int) -> list[Light]:
    """``count`` point lights over the rectangle: the Hammersley set."""
    across, up = light.axes
    square = _hammersley(count) - 0.5
    points = (
        light.position
        + (square[:, 0] * light.width)[:, None] * across
        + (square[:, 1] * light.height)[:, None] * up
    )
    return [PointLight(point) for point in points]


def _directional_samples(light: DirectionalLight, count: int) -> list[Light]:
    """``count`` directions over the light's cone (itself, with no angle)."""
    if light.angle == 0 or count == 1:
        return [light]
    spread = math.tan(light.angle / 2)
    ends = _disc_points(light.direction, light.direction, spread, count)
    return [DirectionalLight(end) for end in ends]


def _sphere_samples(
    light: PointLight | SpotLight, count: int, towards: ArrayLike | None
) -> list[Light]:
    """``count`` lights over the disc of a sphere light facing ``towards``
    (itself, with no radius); a spot light's keep its cone."""
    if light.source_radius == 0 or count == 1:
        return [light]
    centre = light.position
    facing = centre - np.asarray(towards, dtype=np.float64) if towards is not None else None
    if facing is None or not float(np.linalg.norm(facing)) > 0:
        facing = np.array([0.0, 1.0, 0.0])
    points = _disc_points(centre, facing, light.source_radius, count)
    if isinstance(light, SpotLight):
        return [SpotLight(p, light.direction, light.cut_off_angle, light.radius) for p in points]
    return [PointLight(p, light.radius) for p in points]


def _frame(normal: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    normal = normal / np.linalg.norm(normal)
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    a = np.cross(normal, helper)
    a /= np.linalg.norm(a)
    return a, np.cross(normal, a)


def _hammersley(count: int) -> NDArray[np.float64]:
    """(count, 2) points in the unit square: the Hammersley set, each point in
    the middle of its stratum ((i + 1/2) / count across, the base-2 radical
    inverse of i up). Unlike a grid's, no row of them runs along a straight
    shadow edge, so an edge hides them one by one, not a row at a time."""
    index = np.arange(count, dtype=np.int64)
    up = np.zeros(count)
    bits, weight = index.copy(), 0.5
    while bits.any():
        up += weight * (bits & 1)
        bits >>= 1
        weight *= 0.5
    return np.stack([(index + 0.5) / count, up + 0.5 / count], axis=1)


def _disc_points(
    centre: ArrayLike, normal: ArrayLike, radius: float, count: int
) -> NDArray[np.float64]:
    """``count`` points spread evenly over the disc of ``radius`` round
    ``centre`` across ``normal``: the Hammersley set mapped onto the disc by
    Shirley and Chiu's concentric map (equal areas to equal areas)."""
    x, y = (2 * _hammersley(count) - 1).T
    first = np.abs(x) > np.abs(y)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(first, x, y)
        phi = np.where(first, (math.pi / 4) * (y / x), math.pi / 2 - (math.pi / 4) * (x / y))
    phi = np.nan_to_num(phi)
    a, b = _frame(np.asarray(normal, dtype=np.float64))
    offsets = radius * (r * np.cos(phi))[:, None] * a + radius * (r * np.sin(phi))[:, None] * b
    points: NDArray[np.float64] = np.asarray(centre, dtype=np.float64) + offsets
    return points


def _corners(light: SizedLight, towards: ArrayLike) -> list[Light] | None:
    """The corner lights whose shadows bound a convex caster's umbra and
    penumbra (see the module notes); None for a light with no size."""
    if isinstance(light, RectLight):
        across, up = light.axes
        signs = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
        return [
            PointLight(light.position + 0.5 * (i * light.width * across + j * light.height * up))
            for i, j in signs
        ]
    turn = np.linspace(0, 2 * math.pi, DISC_CORNERS, endpoint=False)
    ring = np.stack([np.cos(turn), np.sin(turn)], axis=1) / math.cos(math.pi / DISC_CORNERS)
    if isinstance(light, DiskLight):
        a, b = _frame(light.direction)
        points = light.position + light.radius * (ring[:, :1] * a + ring[:, 1:] * b)
        return [PointLight(p) for p in points]
    if isinstance(light, DirectionalLight):
        if light.angle == 0:
            return None
        a, b = _frame(light.direction)
        spread = math.tan(light.angle / 2)
        ends = light.direction + spread * (ring[:, :1] * a + ring[:, 1:] * b)
        return [DirectionalLight(end) for end in ends]
    if light.source_radius == 0:
        return None
    a, b = _frame(light.position - np.asarray(towards, dtype=np.float64))
    points = light.position + light.source_radius * (ring[:, :1] * a + ring[:, 1:] * b)
    if isinstance(light, SpotLight):
        return [SpotLight(p, light.direction, light.cut_off_angle, light.radius) for p in points]
    return [PointLight(p, light.radius) for p in points]


def soft_shadow(
    caster: MeshLike,
    light: SizedLight,
    plane: Plane,
    *,
    receiver: ArrayLike | None = None,
    levels: int = 8,
    samples: int | None = None,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
) -> SoftShadow:
    """The soft shadow of ``caster`` from ``light`` (a light with a size) on
    ``plane``: umbra, penumbra, ``levels`` graded regions and the hidden
    fraction (see the module notes for how exact each is).

    ``samples``: how many point lights stand for the light (default
    :data:`DEFAULT_SAMPLES`; a light with no size is one, and its umbra and
    penumbra are then exactly :func:`~shadowgeo.project_shadow`'s shadow).
    ``receiver``, ``offset`` and ``tolerance`` as
    :func:`~shadowgeo.project_shadow` takes them.

    Examples
    --------
    A 2 x 2 x 2 box floating 1 above the ground under a 1 x 1 square light 6
    up: the umbra is the 3 x 3 square, the penumbra the 5 x 5 one.

    >>> import trimesh
    >>> from shadowgeo import Plane
    >>> from shadowgeo.lights import RectLight
    >>> box = trimesh.creation.box([2, 2, 2])
    >>> _ = box.apply_translation([0, 2, 0])
    >>> light = RectLight([0, 6, 0], [0, -1, 0], 1, 1, up=[0, 0, 1])
    >>> soft = soft_shadow(box, light, Plane([0, 1, 0], 0))
    >>> round(soft.umbra.area, 9), round(soft.penumbra.area, 9), soft.exact
    (9.0, 25.0, True)
    """
    levels, count = checked_counts(light, levels, samples)
    body = as_caster(caster)
    lit = _lit_samples(light, body, plane, count, tolerance)
    tolerance = lit.tolerance
    shadows = project_shadow(
        body, list(lit.lights), plane, receiver=receiver, offset=offset, tolerance=tolerance
    )
    if not has_size(light):
        (hard,) = shadows
        return SoftShadow(plane, light, hard, hard, [(1.0, hard)], True, lit.lights, shadows)
    corners = _bounding_corners(light, body, plane, lit)
    cut = _Cut(plane, light, shadows, offset)
    bands = cut.levels(levels)
    if corners is not None:
        sides = project_shadow(
            body, corners, plane, receiver=receiver, offset=offset, tolerance=tolerance
        )
        umbra = cut.common([side.polygons for side in sides])
        penumbra = cut.hull([side.polygons for side in sides])
    else:  # hidden from every sample (the top band), from any
        umbra = bands[-1][1] if bands and bands[-1][0] == 1.0 else CrossSection()
        penumbra = cut.union([s.polygons for s in shadows])
    graded = [(fraction, cut.shadow(region)) for fraction, region in bands]
    exact = corners is not None and isinstance(light, RectLight)
    return SoftShadow(
        plane, light, cut.shadow(umbra), cut.shadow(penumbra), graded, exact, lit.lights, shadows
    )


@dataclass(frozen=True)
class _LitSamples:
    """The samples of a light that light the plane, the point they face
    (the caster's centre) and the tolerance they were checked with."""

    lights: tuple[Light, ...]
    towards: NDArray[np.float64]
    tolerance: Tolerance | None


def _lit_samples(
    light: SizedLight, body: Caster, plane: Plane, count: int, tolerance: Tolerance | None
) -> _LitSamples:
    """``count`` samples of ``light`` less those behind the plane or in it,
    which light none of it, and the tolerance (the caster's and the
    samples' when none is given)."""
    towards = 0.5 * (body.bounds[0] + body.bounds[1]) if body.n_faces else np.zeros(3)
    lights = light_samples(light, count, towards)  # (a light with no size: itself)
    if tolerance is None:
        positions = [s.position[None] for s in lights if not isinstance(s, DirectionalLight)]
        known = [body.bounds] if body.n_faces else []
        tolerance = Tolerance.for_points(*known, *positions) if known or positions else None
    if has_size(light):
        lights = [s for s in lights if _in_front(s, plane, tolerance)]
        if not lights:
            raise GeometryError(f"{light!r} lies wholly behind the plane or in it")
    return _LitSamples(tuple(lights), towards, tolerance)


def _bounding_corners(
    light: SizedLight, body: Caster, plane: Plane, lit: _LitSamples
) -> list[Light] | None:
    """The corner lights whose shadows give a convex caster's umbra and
    penumbra; None for another caster, or a light partly behind the plane
    (both then come from the samples)."""
    if not _convex(body, lit.tolerance):
        return None
    corners = _corners(light, lit.towards)
    if corners is not None and not all(_in_front(c, plane, lit.tolerance) for c in corners):
        return None
    return corners


def _in_front(sample: Light, plane: Plane, tolerance: Tolerance | None) -> bool:
    """Whether a sample of the light lies in front of the plane, off it (by
    more than the tolerance's length; a positional sample always has one)."""
    if isinstance(sample, DirectionalLight):
        return float(plane.normal @ sample.direction) < 0
    reach = tolerance.length if tolerance is not None else 0.0
    return float(plane.signed_distance(sample.position[None])[0]) > reach


def checked_counts(light: SizedLight, levels: int, samples: int | None) -> tuple[int, int]:
    """``levels`` and the number of samples for ``light`` (one for a light
    with no size, else ``samples`` or :data:`DEFAULT_SAMPLES`), checked."""
    if not isinstance(light, SizedLight):
        raise GeometryError(f"light must be a light with or without a size, got {light!r}")
    if int(levels) < 1:
        raise GeometryError(f"levels must be >= 1, got {levels!r}")
    count = 1 if not has_size(light) else int(samples) if samples is not None else DEFAULT_SAMPLES
    if not 1 <= count <= MAX_SAMPLES:
        raise GeometryError(
            f"samples must be in [1, {MAX_SAMPLES}] (shadowgeo.soft.MAX_SAMPLES: the levels' "
            f"cost grows with the square of the samples), got {count!r}"
        )
    return int(levels), count


def band_thresholds(levels: int, total: int) -> tuple[list[int], dict[int, int]]:
    """The thresholds :func:`~shadowgeo.levels.cover_bands` cuts ``total``
    samples' shadows at for ``levels`` bands of the hidden fraction rounded
    to the nearest ``k / levels``, ``k >= 1``, and the band ``k`` each
    threshold starts: band ``k`` holds the points hidden from at least
    ``ceil((k - 1/2) / levels * total)`` samples (a few samples: bands share
    one threshold, the lowest ``k`` kept)."""
    starts: dict[int, int] = {}
    for k in range(1, levels + 1):
        starts[max(1, ((2 * k - 1) * total + 2 * levels - 1) // (2 * levels))] = k
    return sorted(t for t in starts if t <= total), starts


def has_size(light: SizedLight) -> bool:
    """Whether ``light`` has a size (its soft shadow is more than its hard one)."""
    if isinstance(light, RectLight | DiskLight):
        return True
    if isinstance(light, DirectionalLight):
        return light.angle > 0
    return light.source_radius > 0


def _convex(body: object, tolerance: Tolerance | None) -> bool:
    """Whether the caster is one closed convex mesh: every vertex on the
    inner side of every face's plane (within the tolerance's length)."""
    if not isinstance(body, Caster) or not body.n_faces or not body.is_closed:
        return False
    if body.n_faces > MAX_CONVEX_CHECK:
        return False
    triangles = body.triangles
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    keep = lengths > 0
    normals = normals[keep] / lengths[keep, None]
    offsets = np.einsum("ij,ij->i", normals, triangles[keep, 0])
    reach = tolerance.length if tolerance is not None else 0.0
    block = max(1, 4_000_000 // max(len(body.vertices), 1))  # faces per pass: 32 MB
    for start in range(0, len(normals), block):
        heights = body.vertices @ normals[start : start + block].T - offsets[start : start + block]
        if not np.all(heights <= reach):
            return False
    return True


class _Cut:
    """The sample shadows' polygons in one Clipper2 frame (centred, scaled),
    regions made from them there, and those back as :class:`Shadow` values."""

    def __init__(
        self, plane: Plane, light: SizedLight, shadows: list[Shadow], offset: float
    ) -> None:
        self.plane, self.light, self.shadows, self.offset = plane, light, shadows, offset
        points = [loop for s in shadows for part in s.polygons for loop in part]
        if points:
            stacked = np.concatenate(points)
            low, high = stacked.min(axis=0), stacked.max(axis=0)
        else:
            low = high = np.zeros(2)
        self.center = 0.5 * (low + high)
        extent = float(np.abs(high - low).max()) if points else 0.0
        self.scale = poly.local_scale(extent if extent > 0 else 1.0)
        self.low, self.high = (low - self.center) * self.scale, (high - self.center) * self.scale

    def local(self, parts: Parts) -> list[NDArray[np.float64]]:
        return [(loop - self.center) * self.scale for part in parts for loop in part]

    def common(self, each: list[Parts]) -> CrossSection:
        region = CrossSection()
        for index, parts in enumerate(each):
            filled = poly.unite(self.local(parts))
            region = filled if index == 0 else poly.intersect(region, filled)
        return region

    def union(self, each: list[Parts]) -> CrossSection:
        return poly.unite([loop for parts in each for loop in self.local(parts)])

    def hull(self, each: list[Parts]) -> CrossSection:
        return self.union(each).hull()

    def levels(self, count: int) -> list[tuple[float, CrossSection]]:
        """The cover of the sample shadows in ``count`` bands of the hidden
        fraction rounded to the nearest ``k / count``, ``k >= 1``: band ``k``
        holds the points hidden from at least ``ceil((k - 1/2) / count * n)``
        of the ``n`` samples and fewer than band ``k + 1`` asks."""
        regions = [self.local(s.polygons) for s in self.shadows]
        if not any(regions):
            return []
        low, high = self.low, self.high
        window = poly.unite(
            [np.array([low, [high[0], low[1]], high, [low[0], high[1]]], dtype=np.float64)]
        )
        thresholds, starts = band_thresholds(count, len(self.shadows))
        bands = cover_bands(regions, window, thresholds)
        return [
            (starts[t] / count, poly.unite([loop for part in parts for loop in part]))
            for t, parts in zip(thresholds, bands, strict=True)
            if parts
        ]

    def shadow(self, region: CrossSection) -> Shadow:
        info = ShadowDiagnostics()
        local = poly.components(region)
        if not local:
            return Shadow(self.plane, self.light, empty_mesh, [], 0.0, info)  # type: ignore[arg-type]
        parts = [[loop / self.scale + self.center for loop in part] for part in local]
        area = poly.parts_area(local) / self.scale / self.scale
        lift = self.plane.origin + self.offset * self.plane.normal
        u, v = self.plane.basis
        frame = lift + self.center[0] * u + self.center[1] * v
        build = partial(triangulated, local, self.scale, frame, self.plane.basis)
        return Shadow(self.plane, self.light, build, parts, area, info)  # type: ignore[arg-type]
