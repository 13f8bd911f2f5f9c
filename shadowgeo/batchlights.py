"""Many lights on one closed caster: the common case of a planar shadow, as arrays.

:func:`shadowgeo.project_shadow` spends most of a light's time, on a mesh of
thousands of faces lit by a point or directional light with no receiver, on
small fixed steps: the light's tolerance, its frame on the plane, the window
the shadow can reach, the test that the caster lies inside that window, the
projection of its silhouette. Here each step is done for every light at once,
on (k, ...) arrays, in element-wise sums whose bits do not depend on how many
lights share the arrays: a call with one light (which goes through the same
functions) gives the same numbers as a call with a thousand.

The per-light remainder (the 2-D union of each light's outline and the result
objects) stays in :mod:`shadowgeo.projection`.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import partial
from itertools import pairwise
from typing import TYPE_CHECKING, cast

import numpy as np

from . import plane2d as poly
from .compiled import use_compiled
from .errors import GeometryError
from .lights import DirectionalLight, Light, PointLight
from .limits import LARGEST_COORDINATE, PRODUCT_SLACK, check_light
from .orientation import MAX_COORDINATE, POINT_SLACK
from .plane import Plane
from .shadow import Shadow, ShadowDiagnostics, triangulated
from .silhouette import Outlines, check_light_outside, silhouette_outlines, vertex_components
from .tolerance import Tolerance, resolution, scene_scales
from .topology import BLOCK, Caster, empty_mesh

if TYPE_CHECKING:
    import trimesh

__all__ = [
    "BACK",
    "BEHIND",
    "CASTS",
    "HELD_CORNERS",
    "HELD_LOOPS",
    "LightFrames",
    "ON_PLANE",
    "PARALLEL",
    "ProjectedOutlines",
    "array_shadows",
    "front_rows",
    "light_frames",
    "pieces",
    "project_outlines",
    "projected_many",
    "settle",
    "takes_arrays",
    "whole_outlines",
]

# What the frame alone decides about a light.
CASTS = 0  # the light reaches the plane's front: a shadow to compute
ON_PLANE = 1  # a positional light on the plane: an error
BEHIND = 2  # a positional light behind the plane: empty
PARALLEL = 3  # a directional light parallel to the plane: empty
BACK = 4  # a directional light shining on the plane's back: empty


def takes_arrays(light: Light) -> bool:
    """Whether :func:`light_frames` handles ``light``: a point light of
    unlimited range or a directional light (spot cones and finite ranges
    are 2-D limits, left to the general path)."""
    if type(light) is DirectionalLight:
        return True
    return type(light) is PointLight and light.radius == np.inf


@dataclass(frozen=True)
class LightFrames:
    """The frames of k lights on one plane, in the caster's centred frame.

    Attributes
    ----------
    positional : (k,) bool
    verdict : (k,) int8
        :data:`CASTS`, or why the light casts nothing (:data:`BEHIND`, ...)
        or is refused (:data:`ON_PLANE`).
    height : (k,) float64
        A positional light's signed distance to the plane (0 for the others).
    light_h : (k, 4) float64
        The light as a homogeneous vector.
    origin : (k, 3) float64
        The plane point where each light's 2-D frame starts: a positional
        light's foot, or the caster centre's shadow.
    H : (k, 3, 4) float64
        Centred homogeneous point -> (U, V, W) in local units (divide by W).
    scale : (k,) float64
        Local units per scene unit.
    bound : (k,) float64
        Half-width of the default bound square, scene units.
    scene_scale, magnitude : (k,) float64
        Each light's :class:`Tolerance` (``scale`` and ``magnitude``; the
        call's own tolerance when it gave one).
    length, coplanar : (k,) float64
        ``Tolerance.length`` and ``coplanar_length``.
    inside : (k,) bool
        The caster's box lies strictly inside the five half-spaces of the
        window (the plane, lowered by ``coplanar``, and the planes joining
        the light to the bound square): every face projects whole.
    near : (k,) bool
        A positional light within ``length`` of the caster's box: it must be
        checked against the faces (touching, inside).
    in_range : (k,) bool
        The light's coordinates are within the supported range
        (:func:`shadowgeo.limits.check_light` need not be asked).
    """

    positional: np.ndarray
    verdict: np.ndarray
    height: np.ndarray
    light_h: np.ndarray
    origin: np.ndarray
    H: np.ndarray
    scale: np.ndarray
    bound: np.ndarray
    scene_scale: np.ndarray
    magnitude: np.ndarray
    length: np.ndarray
    coplanar: np.ndarray
    inside: np.ndarray
    near: np.ndarray
    in_range: np.ndarray

    def tolerance(self, index: int, given: Tolerance | None) -> Tolerance:
        """Light ``index``'s tolerance as an object (``given`` when the call
        had one)."""
        if given is not None:
            return given
        return Tolerance(
            scale=float(self.scene_scale[index]), magnitude=float(self.magnitude[index])
        )


def light_frames(
    caster: Caster,
    normal: np.ndarray,
    plane_offset: float,
    basis: tuple[np.ndarray, np.ndarray],
    lights: list[Light],
    tolerance: Tolerance | None,
) -> LightFrames:
    """The frames of ``lights`` (each one :func:`takes_arrays` accepts) on
    the plane ``normal . x + plane_offset = 0`` with 2-D ``basis`` (u, v),
    for ``caster`` (closed, with faces).

    The tolerance of each light is ``tolerance``, else that of the caster's
    box and the light's position (a directional light: the box alone).
    """
    count = len(lights)
    positional = np.array([type(light) is PointLight for light in lights], dtype=bool)
    vectors = np.array(
        [
            light.direction if isinstance(light, DirectionalLight) else light.position
            for light in lights
        ],
        dtype=np.float64,
    ).reshape(count, 3)
    center = caster.center
    low_box, high_box = caster.bounds
    # The light and plane in the centred frame (as _Projector sets them up).
    d = plane_offset + float(normal @ center)
    relative = vectors - center
    toward = np.where(positional[:, None], relative, vectors)
    along = toward[:, 0] * normal[0] + toward[:, 1] * normal[1] + toward[:, 2] * normal[2]
    height = np.where(positional, along + d, 0.0)
    cosine = np.where(positional, 0.0, -along)
    tol = _tolerances(caster, vectors, positional, tolerance)
    length, coplanar, bound = tol.length, tol.coplanar, tol.bound
    verdict = _verdicts(positional, height, cosine, length, tol.angle)
    light_h = np.empty((count, 4))
    light_h[:, :3] = np.where(positional[:, None], relative, -vectors)
    light_h[:, 3] = np.where(positional, 1.0, 0.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # a positional light's foot; the caster centre's shadow along a direction
        origin = np.where(
            positional[:, None],
            relative - height[:, None] * normal,
            (d / cosine)[:, None] * vectors,
        )
        scale = _scales(bound)
        H = _projections(light_h, origin, normal, d, basis, scale)
        inside = _inside_window(caster, H, scale * bound, normal, d + coplanar)
    near = positional & np.all(
        (vectors >= low_box - length[:, None]) & (vectors <= high_box + length[:, None]), axis=1
    )
    return LightFrames(
        positional,
        verdict,
        height,
        light_h,
        origin,
        H,
        scale,
        bound,
        tol.scene_scale,
        tol.magnitude,
        length,
        coplanar,
        inside,
        near,
        np.all(np.abs(vectors) <= LARGEST_COORDINATE, axis=1),
    )


@dataclass(frozen=True)
class _Tolerances:
    """Each light's tolerances (n,): its scene's scale and magnitude, the
    length, coplanar length and bound; one angle for all."""

    scene_scale: np.ndarray
    magnitude: np.ndarray
    length: np.ndarray
    coplanar: np.ndarray
    bound: np.ndarray
    angle: float


def _tolerances(
    caster: Caster, vectors: np.ndarray, positional: np.ndarray, tolerance: Tolerance | None
) -> _Tolerances:
    """``tolerance`` for every light, else each light's own: the caster's box
    with the light's position in it (a directional light: the box alone)."""
    count = len(vectors)
    if tolerance is not None:
        return _Tolerances(
            np.full(count, tolerance.scale),
            np.full(count, tolerance.magnitude),
            np.full(count, tolerance.length),
            np.full(count, tolerance.coplanar_length),
            np.full(count, tolerance.bound_length),
            tolerance.angle,
        )
    low_box, high_box = caster.bounds
    default = Tolerance()
    inside_box = np.where(positional[:, None], vectors, low_box)
    lower = np.minimum(low_box, inside_box)
    upper = np.maximum(high_box, np.where(positional[:, None], vectors, high_box))
    box_magnitude = float(np.abs(caster.bounds).max())
    reach = np.abs(np.where(positional[:, None], vectors, 0.0))
    magnitude = np.maximum(
        np.maximum(np.maximum(reach[:, 0], reach[:, 1]), reach[:, 2]), box_magnitude
    )
    scene_scale = scene_scales(lower, upper, magnitude)
    length = np.maximum(default.relative * scene_scale, resolution(magnitude))
    coplanar = np.maximum(default.coplanar * scene_scale, length)
    bound = default.bound * scene_scale
    return _Tolerances(scene_scale, magnitude, length, coplanar, bound, default.angle)


def _verdicts(
    positional: np.ndarray,
    height: np.ndarray,
    cosine: np.ndarray,
    length: np.ndarray,
    angle: float,
) -> np.ndarray:
    """(n,) int8: whether each light casts on the plane's front, or why not."""
    verdict = np.full(len(positional), CASTS, dtype=np.int8)
    verdict[positional & (height < 0)] = BEHIND
    verdict[positional & (np.abs(height) <= length)] = ON_PLANE
    verdict[~positional & (cosine < 0)] = BACK
    verdict[~positional & (np.abs(cosine) <= angle)] = PARALLEL
    return verdict


def _scales(bound: np.ndarray) -> np.ndarray:
    """:func:`shadowgeo.plane2d.local_scale` of each bound (the window
    [-bound, bound]^2 reaches ``bound`` at most)."""
    scales: np.ndarray = MAX_COORDINATE / bound  # local_scale, for every bound at once
    return scales


def _projections(
    light_h: np.ndarray,
    origin: np.ndarray,
    normal: np.ndarray,
    d: float,
    basis: tuple[np.ndarray, np.ndarray],
    scale: np.ndarray,
) -> np.ndarray:
    """(k, 3, 4) ``diag(scale, scale, 1) @ to_plane2d @ M``: the planar shadow
    matrix ``M = (P . L) I - L P^T`` of each light followed by the plane's
    2-D frame around ``origin``, row by row in closed form.

    Row ``r`` of ``to_plane2d`` (``(u, -u . origin)``, ``(v, -v . origin)``,
    ``(0, 0, 0, 1)``) times ``M`` is ``(P . L) r - (r . L) P``.
    """
    u, v = basis
    plane = np.append(normal, d)
    w = light_h[:, 3]
    s = (
        light_h[:, 0] * plane[0]
        + light_h[:, 1] * plane[1]
        + light_h[:, 2] * plane[2]
        + light_h[:, 3] * plane[3]
    )
    H = np.empty((len(light_h), 3, 4))
    for row, axis in enumerate((u, v)):
        shift = -(origin[:, 0] * axis[0] + origin[:, 1] * axis[1] + origin[:, 2] * axis[2])
        reach = light_h[:, 0] * axis[0] + light_h[:, 1] * axis[1] + light_h[:, 2] * axis[2]
        reach = reach + shift * w
        # the row (axis, shift), all four columns at once
        frame = np.empty((len(light_h), 4))
        frame[:, :3] = axis
        frame[:, 3] = shift
        H[:, row] = scale[:, None] * (s[:, None] * frame - reach[:, None] * plane)
    H[:, 2] = -w[:, None] * plane
    H[:, 2, 3] += s
    return H


def _inside_window(
    caster: Caster, H: np.ndarray, half: np.ndarray, normal: np.ndarray, lowered: np.ndarray
) -> np.ndarray:
    """(k,) whether all eight corners of the caster's box (centred frame)
    lie strictly inside the plane ``normal . x + lowered >= 0`` and the
    four planes joining each light to its window [-half, half]^2 (local
    units): ``U + half W >= 0``, ``half W - U >= 0``, and the same in V."""
    low, high = caster.bounds - caster.center
    corners = np.array(
        [[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])]
    )
    x, y, z = corners[:, 0], corners[:, 1], corners[:, 2]

    def images(row: int) -> np.ndarray:
        m = H[:, row, :]
        image: np.ndarray = (
            m[:, 0, None] * x[None, :]
            + m[:, 1, None] * y[None, :]
            + m[:, 2, None] * z[None, :]
            + m[:, 3, None]
        )
        return image

    U, V, W = images(0), images(1), images(2)
    reach = half[:, None] * W
    above = (x * normal[0] + y * normal[1] + z * normal[2])[None, :] + lowered[:, None]
    inside = (above > 0) & (U + reach > 0) & (reach - U > 0) & (V + reach > 0) & (reach - V > 0)
    result: np.ndarray = inside.all(axis=1)
    return result


def front_rows(caster: Caster, light_h: np.ndarray) -> np.ndarray:
    """(8 j, m) uint8, row k 1 where a face turns its front to light k
    (``caster.facing(light_h[k]) > 0``), rows past the lights' count 0: the
    front bits as :func:`shadowgeo.silhouette.silhouette_outlines` packs
    them, written in place."""
    count = len(light_h)
    rows = np.zeros((-(-count // 8) * 8, caster.n_faces), dtype=np.uint8)
    flags = rows.view(bool)
    # Caster.facing's arithmetic, into one buffer: ``normals @ l_xyz -
    # offsets l_w``; with l_w = 0 the subtraction changes no sign.
    normals = caster.face_normals
    # (suns alone need no face planes: one product per face less to make)
    positional = bool(np.any(light_h[:, 3] != 0.0))
    offsets = caster.face_offsets if positional else None
    # a block of faces at a time: one small buffer, reused, not a fresh
    # array the size of a big mesh's faces
    buffer = np.empty(min(caster.n_faces, BLOCK))
    for light in range(count):
        for start in range(0, caster.n_faces, BLOCK):
            stop = min(start + BLOCK, caster.n_faces)
            facing = buffer[: stop - start]
            np.matmul(normals[start:stop], light_h[light, :3], out=facing)
            if offsets is not None and light_h[light, 3] != 0.0:
                facing -= offsets[start:stop] * light_h[light, 3]
            np.greater(facing, 0.0, out=flags[light, start:stop])
    return rows


@dataclass(frozen=True)
class ProjectedOutlines:
    """Every light's silhouette loops in its 2-D frame.

    Attributes
    ----------
    points : (c, 2) float64
        The corners of :attr:`Outlines.corners`, projected (local units).
    touching : (k,) bool
        Some vertex of the light's silhouette projects to infinity (W <= 0):
        the light touches the caster.
    low, high : (k, 2) float64
        The box of each light's loop corners (zeros when it has none).
    """

    points: np.ndarray
    touching: np.ndarray
    low: np.ndarray
    high: np.ndarray


def project_outlines(caster: Caster, outlines: Outlines, H: np.ndarray) -> ProjectedOutlines:
    """The corners of ``outlines`` (k lights) projected by each light's
    ``H`` (k, 3, 4), in the frame of ``caster``'s :attr:`~Caster.centered`
    vertices.

    Each image is the sum ``x H[i, 0] + y H[i, 1] + z H[i, 2] + H[i, 3]``,
    left to right, then divided by W: the same bits for one light or many.
    Where the outlines have fewer corners than the mesh has vertices, only
    theirs are centred (the same numbers as :attr:`~Caster.centered`'s
    rows): a mesh of a million faces has a few thousand, and the whole
    centred copy with its columns was memory touched for the first time in
    every process.
    """
    count = len(H)
    # Coefficient by coefficient and column by column: gathers from short
    # contiguous tables, no (c, 12) matrix per corner.
    coefficients = np.ascontiguousarray(H.reshape(count, 12).T)
    corner_light = np.repeat(outlines.loop_light, outlines.loop_lengths)

    if len(outlines.corners) + len(outlines.edge_starts) > len(caster.vertices):
        # (many lights on a small mesh: the centred columns once, then gathers)
        columns = caster.centered_columns()

        def coordinates(vertices: np.ndarray) -> list[np.ndarray]:
            return [column[vertices] for column in columns]
    else:

        def coordinates(vertices: np.ndarray) -> list[np.ndarray]:
            rows = caster.centered_rows(vertices)
            return [rows[:, 0], rows[:, 1], rows[:, 2]]

    def image(i: int, xyz: list[np.ndarray], light: np.ndarray) -> np.ndarray:
        total: np.ndarray = xyz[0] * coefficients[4 * i][light]
        total += xyz[1] * coefficients[4 * i + 1][light]
        total += xyz[2] * coefficients[4 * i + 2][light]
        total += coefficients[4 * i + 3][light]
        return total

    corners = coordinates(outlines.corners)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = image(2, corners, corner_light)
        projected = np.column_stack(
            [image(0, corners, corner_light) / w, image(1, corners, corner_light) / w]
        )
    # W of every vertex a silhouette edge starts at (a dropped two-edge loop's too)
    touching = np.zeros(count, dtype=bool)
    w_all = image(2, coordinates(outlines.edge_starts), outlines.edge_light)
    touching[outlines.edge_light[w_all <= 0]] = True
    low = np.zeros((count, 2))
    high = np.zeros((count, 2))
    if len(projected):
        corner_counts = np.bincount(corner_light, minlength=count)
        has = corner_counts > 0
        starts = (np.cumsum(corner_counts) - corner_counts)[has]
        low[has] = np.minimum.reduceat(projected, starts, axis=0)
        high[has] = np.maximum.reduceat(projected, starts, axis=0)
    return ProjectedOutlines(projected, touching, low, high)


def settle(
    caster: Caster,
    plane: Plane,
    frames: LightFrames,
    row: int,
    light: Light,
    tolerance: Tolerance | None,
) -> Shadow | None:
    """What the frame decides for light ``row`` of ``frames`` (``tolerance``:
    the call's own, if any): its (empty) shadow, or None when it goes on
    (on the array path if ``frames.inside[row]``, else the general path).

    Raises
    ------
    GeometryError
        The light lies on the plane, touches the caster or is inside it, or
        its coordinates are out of range.
    """
    if not frames.in_range[row]:
        check_light(light)
    verdict = int(frames.verdict[row])
    if verdict == ON_PLANE:
        light = cast("PointLight", light)
        raise GeometryError(
            f"the light at {light.position.tolist()} lies on the receiving plane "
            f"(distance {float(frames.height[row]):.3g}, "
            f"tolerance {float(frames.length[row]):.3g})"
        )
    if verdict != CASTS:
        info = ShadowDiagnostics(n_triangles=caster.n_faces, empty_reason=_EMPTY[verdict])
        return Shadow(plane, light, empty_mesh, [], 0.0, info)
    if frames.near[row]:
        position = cast("PointLight", light).position
        check_light_outside(caster, position, frames.tolerance(row, tolerance))
    return None


_EMPTY = {
    BEHIND: "the light is behind the plane (its normal points away)",
    PARALLEL: "the light travels parallel to the plane",
    BACK: "the light shines on the back of the plane",
}


def array_shadows(
    caster: Caster,
    plane: Plane,
    basis: tuple[np.ndarray, np.ndarray],
    offset: float,
    frames: LightFrames,
    lights: Sequence[Light],
    chunk: list[tuple[int, int]],
) -> Iterator[Shadow | None]:
    """The shadow of each light of ``chunk`` ((index into ``lights``, row of
    ``frames``) pairs, every corner of the caster's box inside each one's
    window), in order, as the general path of
    :func:`shadowgeo.project_shadow` makes it (``basis``: the plane's 2-D
    frame, ``offset``: the lift); None for a light the general path must
    take (its outline leaves the window after all, or touches the light).

    The silhouettes are found and projected together, then each light's
    loops are united on their own (a GeometryError there comes out at that
    light's turn).
    """
    rows = np.array([row for _, row in chunk], dtype=np.int64)
    fronts = front_rows(caster, frames.light_h[rows])
    outlines = silhouette_outlines(caster, fronts if len(chunk) > 1 else fronts[:1])
    projected = project_outlines(caster, outlines, frames.H[rows])
    scale, bound = frames.scale[rows], frames.bound[rows]
    half = scale * bound
    general = (
        projected.touching
        | np.any(projected.low < -half[:, None], axis=1)
        | np.any(projected.high > half[:, None], axis=1)
    ).tolist()
    whole = whole_outlines(
        projected.points, outlines.loop_lengths, outlines.loop_light, len(chunk)
    ).tolist()
    corner_bounds = np.append(0, np.cumsum(outlines.loop_lengths)).tolist()
    firsts = outlines.corners[corner_bounds[:-1]]
    loop_bounds = np.searchsorted(outlines.loop_light, np.arange(len(chunk) + 1)).tolist()
    # The union's corners are the loops' corners and crossings, rounded to
    # Clipper2's grid (1e-8 local units): loops a unit inside the limit
    # cannot reach it.
    limit = (bound - frames.length[rows]) * scale
    reach = np.maximum(np.abs(projected.low), np.abs(projected.high)).max(axis=1)
    unbounded = (reach + 1.0 < limit).tolist()
    u, v = basis
    # element-wise sums: a matrix product's bits may depend on the rows' count
    relative = (frames.origin[rows] + caster.center) - plane.origin
    origins = np.column_stack(
        [
            relative[:, 0] * axis[0] + relative[:, 1] * axis[1] + relative[:, 2] * axis[2]
            for axis in (u, v)
        ]
    )
    lifts = (frames.origin[rows] + offset * plane.normal) + caster.center
    positional = frames.positional[rows].tolist()
    scales, bounds, limits = scale.tolist(), bound.tolist(), limit.tolist()
    for k, (index, _) in enumerate(chunk):
        if general[k]:
            yield None
            continue
        first, last = loop_bounds[k], loop_bounds[k + 1]
        parts: list[list[np.ndarray]] | poly.FlatParts
        if whole[k] >= 0:  # one loop is the whole: no union to do (a copy: not a view of the chunk)
            begin, end = corner_bounds[whole[k]], corner_bounds[whole[k] + 1]
            parts = [[projected.points[begin:end].copy()]]
        else:  # the light's loops, as views of the chunk's points; many convex
            # ones (a city) stay one array from the union to the result
            own = [projected.points[a:b] for a, b in pairwise(corner_bounds[first : last + 1])]
            labels = partial(_part_labels, caster, firsts[first:last])
            parts = poly.unite(own, groups=labels, form="flat")
        bounded = not unbounded[k] and _reaches(parts, limits[k])
        info = ShadowDiagnostics(
            n_triangles=caster.n_faces,
            clipped=dict(_NONE_CLIPPED if positional[k] else _NONE_CLIPPED_DIRECTIONAL),
            bounded_artificially=bounded,
            bound=bounds[k],
            n_loops=last - first,
        )
        yield _array_result(
            plane, basis, lights[index], parts, scales[k], origins[k], lifts[k], info
        )


# The per-reason counts of a shadow no face of which was clipped (copied
# into each result: the diagnostics' dict is the caller's to keep).
_NONE_CLIPPED = {"below_plane": 0, "at_or_above_light": 0, "outside_bound": 0}
_NONE_CLIPPED_DIRECTIONAL = {"below_plane": 0, "outside_bound": 0}


def _part_labels(caster: Caster, firsts: np.ndarray) -> np.ndarray:
    """The connected part of the caster that each outline loop (starting
    at vertex ``firsts``) runs on: the groups of :func:`poly.unite`."""
    labels: np.ndarray = vertex_components(caster)[firsts]
    return labels


def _reaches(parts: list[list[np.ndarray]] | poly.FlatParts, limit: float) -> bool:
    """Whether an outer loop of ``parts`` reaches ``limit`` (local units):
    the default bound cut the shadow."""
    if isinstance(parts, poly.FlatParts):
        return parts.reach() >= limit
    if not parts:
        return False
    outer = np.abs(np.concatenate([part[0] for part in parts])).max()
    return max(float(outer), 0.0) >= limit


def _array_result(
    plane: Plane,
    basis: tuple[np.ndarray, np.ndarray],
    light: Light,
    parts: list[list[np.ndarray]] | poly.FlatParts,
    scale: float,
    origin2d: np.ndarray,
    lift: np.ndarray,
    info: ShadowDiagnostics,
) -> Shadow:
    """The shadow of one light of the array path from its united ``parts``
    (local units), as the general path makes it."""
    if isinstance(parts, poly.FlatParts):  # scaled and moved as one array
        if not parts.groups:
            return Shadow(plane, light, empty_mesh, [], 0.0, info)
        area = parts.area / scale / scale
        polygons = parts.parts(parts.cut(parts.points / scale + origin2d))
        flat = parts  # (cut into loops when the mesh is asked for: most callers never do)

        def build() -> trimesh.Trimesh:
            return triangulated(flat.parts(), scale, lift, basis)

        return Shadow(plane, light, build, polygons, area, info)
    if not parts:
        return Shadow(plane, light, empty_mesh, [], 0.0, info)
    area = _parts_area(parts) / scale / scale  # no square to over/underflow
    polygons = [[loop / scale + origin2d for loop in loops] for loops in parts]
    build = partial(triangulated, parts, scale, lift, basis)
    return Shadow(plane, light, build, polygons, area, info)


def _parts_area(parts: list[list[np.ndarray]]) -> float:
    """:func:`poly.parts_area` by two dot products a loop (the shoelace
    sum ``x_i y_i+1 - x_i+1 y_i``): a shadow is mostly one loop, and a
    handful of numpy calls on it is most of the cost."""
    total = 0.0
    for loops in parts:
        for loop in loops:
            x, y = loop[:, 0], loop[:, 1]
            total += float(x[:-1] @ y[1:] - x[1:] @ y[:-1] + (x[-1] * y[0] - x[0] * y[-1]))
    return 0.5 * total


def _images_many(
    homogeneous: np.ndarray, vertices: list[np.ndarray], matrices: list[np.ndarray]
) -> list[np.ndarray]:
    """:func:`_images` of ``homogeneous[vertices[i]]`` under ``matrices[i]``
    for every i, in one pass."""
    counts = [len(each) for each in vertices]
    points = homogeneous[np.concatenate(vertices)] if sum(counts) else np.zeros((0, 4))
    H = np.repeat(np.array(matrices), counts, axis=0)  # (k, 3, 4): each point's matrix
    rows = [
        points[:, 0] * H[:, i, 0]
        + points[:, 1] * H[:, i, 1]
        + points[:, 2] * H[:, i, 2]
        + H[:, i, 3]
        for i in range(3)
    ]
    return pieces(np.column_stack(rows), counts)


def projected_many(
    homogeneous: np.ndarray,
    outlines: list[tuple[list[np.ndarray], np.ndarray]],
    matrices: list[np.ndarray],
) -> list[tuple[list[np.ndarray] | None, np.ndarray]]:
    """The general path's projection of every light's silhouette (``outlines`` from
    :func:`silhouette_loops_many`, ``matrices`` each light's ``H``) in one
    pass, and the box of each light's 2-D points. The points are the same
    numbers one light's call gives: the same explicit sums, the same
    division. ``None`` loops for a light with a vertex at infinity."""
    n_lights = len(outlines)
    counts = [len(vertices) for _, vertices in outlines]
    images = _images_many(homogeneous, [vertices for _, vertices in outlines], matrices)
    if sum(counts) == 0:
        return [([], np.zeros((2, 2))) for _ in range(n_lights)]
    image = np.concatenate(images)
    light_of = np.repeat(np.arange(n_lights), counts)
    n_vertices = np.int64(len(homogeneous))
    keys = np.concatenate([v + k * n_vertices for k, (_, v) in enumerate(outlines)])
    with np.errstate(divide="ignore", invalid="ignore"):  # such a light raises, below
        points = image[:, :2] / image[:, 2:3]
    touching = np.zeros(n_lights, dtype=bool)
    touching[light_of[image[:, 2] <= 0]] = True
    loops = [loop + k * n_vertices for k, (own, _) in enumerate(outlines) for loop in own]
    lengths = [len(loop) for loop in loops]
    corners = points[np.searchsorted(keys, np.concatenate(loops))] if loops else points[:0]
    cut = pieces(corners, lengths)
    # the box of each light's loop corners (not of all its vertices: a loop
    # of two edges is dropped, and its vertices with it)
    corner_counts = np.array([sum(len(loop) for loop in own) for own, _ in outlines])
    starts = np.concatenate([[0], np.cumsum(corner_counts)[:-1]])
    has_points = corner_counts > 0
    low = np.zeros((n_lights, 2))
    high = np.zeros((n_lights, 2))
    if has_points.any():
        low[has_points] = np.minimum.reduceat(corners, starts[has_points], axis=0)
        high[has_points] = np.maximum.reduceat(corners, starts[has_points], axis=0)
    result: list[tuple[list[np.ndarray] | None, np.ndarray]] = []
    first = 0
    for k, (own, _) in enumerate(outlines):
        mine = cut[first : first + len(own)]
        first += len(own)
        result.append((None if touching[k] else mine, np.array([low[k], high[k]])))
    return result


def pieces(rows: np.ndarray, counts: list[int]) -> list[np.ndarray]:
    """``rows`` cut into consecutive pieces of ``counts`` rows (np.split,
    without its per-piece overhead)."""
    ends = np.cumsum(counts).tolist()
    return [rows[end - count : end] for count, end in zip(counts, ends, strict=True)]


# Lights of at most this many outline loops are tried for one loop holding
# the others (a dented caster's folds); a light of more (a city, many shapes
# as one caster) is not: its largest loop would not hold them.
HELD_LOOPS = 64
# ... and of at least this many corners in all: the union of a few small
# loops takes Clipper2 microseconds, not worth loading compiled code for (a
# sphere and a box in a small scene; a dented 20k-face mesh has 200-440).
HELD_CORNERS = 128


def whole_outlines(
    points: np.ndarray, loop_lengths: np.ndarray, loop_light: np.ndarray, count: int
) -> np.ndarray:
    """(count,) for each light, the index of the one loop whose inside is
    certainly the light's whole region of positive winding, else -1: that
    region is then the loop as it is, with no 2-D union to find it.

    Two certificates, each for lights of one kind, so that a light gets the
    same answer alone or among others:

    - **One loop** (numpy, :func:`_star_shaped_alone`): star-shaped around
      the mean of its corners and counter-clockwise. That is every light on
      a convex caster, and most on a smooth one.
    - **Two to** :data:`HELD_LOOPS` **loops**, :data:`HELD_CORNERS` or more
      corners in all, one loop's box holding the others' (compiled:
      :func:`shadowgeo.kernels.whole_loops`, which imports numba the first
      time; not under ``SHADOWGEO_COMPILED=never``, :mod:`shadowgeo.compiled`):
      the light's loop of largest area, the holder, is star-shaped
      round the mean of its corners; every other loop is simple and
      counter-clockwise, being monotone along an axis (its principal axis,
      which suits a crescent, else one of 16 directions), so it winds at
      least zero times round any point; and inside the holder, each corner
      strictly inside a wedge (the triangle from the mean to an edge), each
      edge crossing every spoke between its ends' wedges short of the
      holder's corner. The holder winds once round each point inside it and
      the others at least zero times, and none round a point outside it:
      a dented caster, whose folds project inside its outline.

    ``points`` (c, 2) are the loops' corners one loop after another,
    ``loop_lengths`` (l,) their counts and ``loop_light`` (l,) (ascending)
    their lights, as :func:`project_outlines` and
    :class:`~shadowgeo.silhouette.Outlines` give them.
    """
    result = _star_shaped_alone(points, loop_lengths, loop_light, count)
    light_loops = np.bincount(loop_light, minlength=count)
    tried = (light_loops >= 2) & (light_loops <= HELD_LOOPS)
    tried &= np.bincount(loop_light, weights=loop_lengths, minlength=count) >= HELD_CORNERS
    if tried.any():
        tried &= _one_box_holds_all(points, loop_lengths, loop_light, count)
    # (none tried: a scene of separate shapes, and numba is not loaded; the
    # rule and its override: shadowgeo.compiled)
    if not use_compiled("certificate", int(tried.sum())):
        return result
    from .kernels import whole_loops  # numba: imported on first use

    loops = np.flatnonzero(tried[loop_light])
    corners = np.repeat(tried[loop_light], loop_lengths)
    held = whole_loops(
        np.ascontiguousarray(points[corners, 0]),
        np.ascontiguousarray(points[corners, 1]),
        np.asarray(loop_lengths[loops], dtype=np.int64),
        np.asarray(loop_light[loops], dtype=np.int64),
        count,
        POINT_SLACK,
        PRODUCT_SLACK,
        float(np.finfo(np.float64).eps),
    )
    found = held >= 0
    result[found] = loops[held[found]]  # (held counts the tried loops only)
    return result


def _one_box_holds_all(
    points: np.ndarray, loop_lengths: np.ndarray, loop_light: np.ndarray, count: int
) -> np.ndarray:
    """(count,) bool: whether one of the light's loops has a box (of its
    corners) holding every other loop's box. The second certificate of
    :func:`whole_outlines` needs it (the others' corners inside the holder
    lie inside the holder's box; comparisons of the same floats, exact), so a
    light without it, separate shapes side by side, is not sent to the
    compiled test at all."""
    starts = np.cumsum(loop_lengths) - loop_lengths
    low = np.minimum.reduceat(points, starts, axis=0)
    high = np.maximum.reduceat(points, starts, axis=0)
    firsts = np.searchsorted(loop_light, np.arange(count))  # loop_light ascends
    present = np.bincount(loop_light, minlength=count) > 0
    light_low = np.full((count, 2), np.inf)
    light_high = np.full((count, 2), -np.inf)
    light_low[present] = np.minimum.reduceat(low, firsts[present], axis=0)
    light_high[present] = np.maximum.reduceat(high, firsts[present], axis=0)
    whole = np.all(low == light_low[loop_light], axis=1) & np.all(
        high == light_high[loop_light], axis=1
    )
    return np.bincount(loop_light[whole], minlength=count) > 0


def _star_shaped_alone(
    points: np.ndarray, loop_lengths: np.ndarray, loop_light: np.ndarray, count: int
) -> np.ndarray:
    """(count,) for each light, the index of its one loop when the light has
    one loop only and that loop is certainly simple and counter-clockwise,
    else -1 (the first certificate of :func:`whole_outlines`).

    The loop is star-shaped around the mean of its corners
    (:func:`shadowgeo.plane2d.star_shaped_flat`).
    """
    result = np.full(count, -1, dtype=np.int64)
    light_loops = np.bincount(loop_light, minlength=count)
    alone = np.flatnonzero(light_loops[loop_light] == 1)  # loops that are their light's only one
    if len(alone) == 0:
        return result
    lengths = loop_lengths[alone]
    firsts = (np.cumsum(loop_lengths) - loop_lengths)[alone]
    starts = np.cumsum(lengths) - lengths  # in the loops taken out
    corner = np.repeat(firsts - starts, lengths) + np.arange(int(lengths.sum()))
    star = poly.star_shaped_flat(points[corner], starts, lengths)
    result[loop_light[alone[star]]] = alone[star]
    return result
