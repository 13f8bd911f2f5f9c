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

from dataclasses import dataclass

import numpy as np

from .lights import DirectionalLight, Light, PointLight
from .limits import LARGEST_COORDINATE
from .polygons import MAX_COORDINATE
from .silhouette import Outlines
from .tolerance import Tolerance, resolution, scene_scales
from .topology import Caster

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
    # Tolerances: the caster's box with each positional light in it.
    if tolerance is not None:
        scene_scale = np.full(count, tolerance.scale)
        magnitude = np.full(count, tolerance.magnitude)
        length = np.full(count, tolerance.length)
        coplanar = np.full(count, tolerance.coplanar_length)
        bound = np.full(count, tolerance.bound_length)
        angle = tolerance.angle
    else:
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
        angle = default.angle
    verdict = np.full(count, CASTS, dtype=np.int8)
    verdict[positional & (height < 0)] = BEHIND
    verdict[positional & (np.abs(height) <= length)] = ON_PLANE
    verdict[~positional & (cosine < 0)] = BACK
    verdict[~positional & (np.abs(cosine) <= angle)] = PARALLEL
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
        scene_scale,
        magnitude,
        length,
        coplanar,
        inside,
        near,
        np.all(np.abs(vectors) <= LARGEST_COORDINATE, axis=1),
    )


def _scales(bound: np.ndarray) -> np.ndarray:
    """:func:`shadowgeo.polygons.local_scale` of each bound (the window
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
        for column in range(3):
            H[:, row, column] = scale * (s * axis[column] - reach * plane[column])
        H[:, row, 3] = scale * (s * shift - reach * plane[3])
    for column in range(4):
        H[:, 2, column] = s * (column == 3) - w * plane[column]
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
    normals, offsets = caster.face_normals, caster.face_offsets
    facing = np.empty(caster.n_faces)
    for light in range(count):
        np.matmul(normals, light_h[light, :3], out=facing)
        if light_h[light, 3] != 0.0:
            facing -= offsets * light_h[light, 3]
        np.greater(facing, 0.0, out=flags[light])
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


def project_outlines(centered: np.ndarray, outlines: Outlines, H: np.ndarray) -> ProjectedOutlines:
    """The corners of ``outlines`` (k lights) projected by each light's
    ``H`` (k, 3, 4), ``centered`` the caster's (n, 4) homogeneous vertices.

    Each image is the sum ``x H[i, 0] + y H[i, 1] + z H[i, 2] + H[i, 3]``,
    left to right, then divided by W: the same bits for one light or many.
    """
    count = len(H)
    # Coefficient by coefficient and column by column: gathers from short
    # contiguous tables, no (c, 12) matrix per corner.
    coefficients = np.ascontiguousarray(H.reshape(count, 12).T)
    columns = [np.ascontiguousarray(centered[:, axis]) for axis in range(3)]
    corner_light = np.repeat(outlines.loop_light, outlines.loop_lengths)

    def image(i: int, vertices: np.ndarray, light: np.ndarray) -> np.ndarray:
        total: np.ndarray = columns[0][vertices] * coefficients[4 * i][light]
        total += columns[1][vertices] * coefficients[4 * i + 1][light]
        total += columns[2][vertices] * coefficients[4 * i + 2][light]
        total += coefficients[4 * i + 3][light]
        return total

    corners = outlines.corners
    with np.errstate(divide="ignore", invalid="ignore"):
        w = image(2, corners, corner_light)
        projected = np.column_stack(
            [image(0, corners, corner_light) / w, image(1, corners, corner_light) / w]
        )
    # W of every vertex a silhouette edge starts at (a dropped two-edge loop's too)
    touching = np.zeros(count, dtype=bool)
    w_all = image(2, outlines.edge_starts, outlines.edge_light)
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
