"""The soft-shadow benchmark's references, written apart from shadowgeo.

- :func:`light_points`: stratified random points of a rectangle light, or
  directions of the sun's disc (uniform over the spherical cap), ``n x n``
  strata with one random point each;
- :func:`hidden_fraction`: for each receiver point, the share of such light
  samples whose ray from the point is blocked by a *convex* caster, by a cone
  test: the blocked samples are those inside the caster's central projection
  from the point onto the light (the convex hull of its vertices' images),
  the same answer as a ray test per sample at a fraction of the cost;
- :func:`ray_blocked`: that ray test itself (Moller-Trumbore, open segment),
  to check the cone test on a subset;
- :func:`pcf_fraction`: percentage-closer filtering of a depth map
  (``shadowmap.depth_map``), the renderers' soft shadow, with its blocker
  depth fixed (PCF) or searched per point (PCSS).

Nothing here imports shadowgeo.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from matplotlib.path import Path as PolygonPath
from scipy.spatial import ConvexHull


@dataclass(frozen=True)
class Rect:
    """A one-sided rectangle light: centre, unit normal (the way it shines),
    unit axes along its width and height, and its size."""

    centre: np.ndarray
    normal: np.ndarray
    across: np.ndarray
    up: np.ndarray
    width: float
    height: float


@dataclass(frozen=True)
class Sun:
    """The sun's disc: ``direction`` the way its central ray travels (unit),
    ``angle`` its angular diameter in radians."""

    direction: np.ndarray
    angle: float


def frame(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors across ``normal``, and across each other."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    first = np.cross(normal, helper)
    first /= np.linalg.norm(first)
    return first, np.cross(normal, first)


def _stratified(side: int, rng: np.random.Generator) -> np.ndarray:
    """(side * side, 2) points of the unit square, one uniform in each cell."""
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2)
    return (cells + rng.uniform(size=cells.shape)) / side


def light_points(light: Rect | Sun, side: int, rng: np.random.Generator) -> np.ndarray:
    """(side * side, 2) light samples in the light's own 2-D frame: offsets
    along ``across`` and ``up`` from a rectangle's centre, or, for the sun,
    the tangent offsets (along :func:`frame`) of unit directions towards the
    sun divided by their component towards the disc's centre."""
    square = _stratified(side, rng)
    if isinstance(light, Rect):
        return (square - 0.5) * [light.width, light.height]
    # Shirley and Chiu's concentric map takes equal areas of the square to
    # equal areas of the disc; r^2 uniform then gives cos(theta) uniform on the cap.
    x, y = square[:, 0] * 2 - 1, square[:, 1] * 2 - 1
    first = np.abs(x) > np.abs(y)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(first, x, y)
        phi = np.where(first, (math.pi / 4) * (y / x), math.pi / 2 - (math.pi / 4) * (x / y))
    phi = np.nan_to_num(phi)
    cos_theta = 1 - r**2 * (1 - math.cos(light.angle / 2))
    # r < 0 is the other side of the disc (phi spans half a turn)
    tan_theta = np.sign(r) * np.sqrt(np.maximum(1 - cos_theta**2, 0)) / cos_theta
    return np.column_stack([tan_theta * np.cos(phi), tan_theta * np.sin(phi)])


def light_positions(light: Rect | Sun, offsets: np.ndarray) -> np.ndarray:
    """(s, 3) world points of a rectangle's samples, or unit directions
    towards the sun's."""
    if isinstance(light, Rect):
        return light.centre + offsets[:, :1] * light.across + offsets[:, 1:] * light.up
    first, second = frame(-light.direction)
    towards = -light.direction + offsets[:, :1] * first + offsets[:, 1:] * second
    return towards / np.linalg.norm(towards, axis=1, keepdims=True)


def cone_images(light: Rect | Sun, point: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """(v, 2) the caster's vertices seen from ``point``, in the light's 2-D
    frame: where the rays from the point through them meet the rectangle's
    plane, or their directions' tangent offsets (as :func:`light_points`)."""
    rel = vertices - point
    if isinstance(light, Rect):
        reach = (light.centre - point) @ light.normal  # < 0: the light shines towards -normal side
        along = rel @ light.normal
        if not np.all(along / reach > 0) or not np.all(along / reach < 1):
            raise ValueError("the caster must lie between the receiver point and the light")
        hits = point + rel * (reach / along)[:, None] - light.centre
        return np.column_stack([hits @ light.across, hits @ light.up])
    towards = -light.direction
    first, second = frame(towards)
    along = rel @ towards
    if not np.all(along > 0):
        raise ValueError("the caster must lie towards the sun from the receiver point")
    return np.column_stack([rel @ first, rel @ second]) / along[:, None]


def hidden_fraction(
    light: Rect | Sun,
    vertices: np.ndarray,
    points: np.ndarray,
    side: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """(p,) the share of ``side * side`` stratified random light samples
    (fresh for each point) that a convex caster with ``vertices`` hides from
    each of ``points`` (p, 3)."""
    fraction = np.empty(len(points))
    for index, point in enumerate(points):
        samples = light_points(light, side, rng)
        images = cone_images(light, point, vertices)
        hull = images[ConvexHull(images).vertices]
        fraction[index] = PolygonPath(hull).contains_points(samples).mean()
    return fraction


def ray_blocked(origins: np.ndarray, targets: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(p, s) bool: whether the open segment from each origin (p, 3) to each
    target (p, s, 3) crosses one of ``triangles`` (t, 3, 3) (Moller-Trumbore)."""
    origins = np.broadcast_to(origins[:, None, :], targets.shape)
    direction = targets - origins
    blocked = np.zeros(direction.shape[:2], dtype=bool)
    for a, b, c in triangles:
        e1, e2 = b - a, c - a
        p = np.cross(direction, e2)
        det = p @ e1
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            t_vec = origins - a
            u = np.einsum("psk,psk->ps", t_vec, p) * inv
            q = np.cross(t_vec, e1)
            v = np.einsum("psk,psk->ps", direction, q) * inv
            t = (q @ e2) * inv
        blocked |= (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0) & (t < 1)
    return blocked


def ray_fraction(
    light: Rect | Sun, triangles: np.ndarray, points: np.ndarray, offsets
) -> np.ndarray:
    """(p, s) bool by :func:`ray_blocked`: the same light samples for every
    point, the sun's rays 1,000 units long (past any caster here)."""
    positions = light_positions(light, offsets)
    if isinstance(light, Rect):
        targets = np.broadcast_to(positions, (len(points), *positions.shape))
    else:
        targets = points[:, None, :] + 1000.0 * positions[None, :, :]
    return ray_blocked(points, np.ascontiguousarray(targets), triangles)


def cone_blocked(
    light: Rect | Sun, vertices: np.ndarray, points: np.ndarray, offsets
) -> np.ndarray:
    """(p, s) bool by the cone test, for the same samples as :func:`ray_fraction`."""
    rows = []
    for point in points:
        images = cone_images(light, point, vertices)
        rows.append(PolygonPath(images[ConvexHull(images).vertices]).contains_points(offsets))
    return np.array(rows)


def pcf_fraction(camera, buffer, points, light_taps, blocker_depth=None, search=None):
    """(p,) the share of a light's taps whose depth-map texel is nearer than
    each receiver point: percentage-closer filtering.

    ``light_taps`` (k, 2): light samples in the light's frame, already as
    shifts of the map per unit of ``(receiver - blocker) / (receiver *
    blocker)`` depth (a rectangle light, perspective map) or of ``receiver -
    blocker`` (the sun, orthographic map), in pixels: where the ray from a
    point to that part of the light crosses a flat blocker at
    ``blocker_depth``. PCF takes one ``blocker_depth`` for every point; PCSS
    (``blocker_depth`` None) first averages the depths nearer than the point
    among ``search`` (k, 2) pixel offsets round it (its blocker search), and
    points with no blocker there are lit.
    """
    pixels, depth = camera.view(points)
    size = camera.resolution
    perspective = not getattr(camera, "orthographic", False)

    def fetch(offsets):
        cols = np.clip(np.floor(pixels[:, None, 0] + offsets[None, :, 0]).astype(int), 0, size - 1)
        rows = np.clip(np.floor(pixels[:, None, 1] + offsets[None, :, 1]).astype(int), 0, size - 1)
        return buffer[rows, cols]

    if blocker_depth is None:
        found = fetch(search)
        nearer = found < depth[:, None]
        count = nearer.sum(axis=1)
        blocker = np.where(nearer, found, 0).sum(axis=1) / np.maximum(count, 1)
        blocker = np.where(count > 0, blocker, depth)
    else:
        blocker = np.full(len(points), float(blocker_depth))
    with np.errstate(divide="ignore", invalid="ignore"):
        spread = (depth - blocker) / (depth * blocker) if perspective else depth - blocker
    spread = np.nan_to_num(np.maximum(spread, 0))
    cols = np.floor(pixels[:, None, 0] + spread[:, None] * light_taps[None, :, 0]).astype(int)
    rows = np.floor(pixels[:, None, 1] + spread[:, None] * light_taps[None, :, 1]).astype(int)
    inside = (cols >= 0) & (cols < size) & (rows >= 0) & (rows < size)
    stored = buffer[np.clip(rows, 0, size - 1), np.clip(cols, 0, size - 1)]
    return np.mean(inside & (stored < depth[:, None]), axis=1)
