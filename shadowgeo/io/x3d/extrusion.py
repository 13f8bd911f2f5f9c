"""X3D Extrusion: a cross-section swept along a spine, as triangles.

Follows ISO/IEC 19775-1, 13.3.5 (Extrusion): at each spine point the
cross-section ``(x, z)`` is scaled by ``scale``, turned by ``orientation``
and placed in the spine-aligned cross-section plane (SCP), whose Y axis runs
along the spine and whose Z axis is the spine's local bend normal (kept from
the previous point where the spine is straight, flipped when it would reverse,
and for a wholly straight spine the turn taking +Y onto the spine). Sides are
quads between consecutive cross-sections; the caps are the first and last
cross-sections (skipped when the spine is closed), triangulated like
IndexedFaceSet polygons.
"""

from __future__ import annotations

import numpy as np

from ...limits import MAX_EXTRUSION_POINTS as MAX_POINTS
from ...limits import PRODUCT_ROUNDING, SHORTEST_DIRECTION
from ...plane2d import polygon_triangles
from .fields import Context, Element, rotation_matrix

__all__ = ["extrusion", "frames"]

# MAX_POINTS: vertices one Extrusion may make (spine x section): a few
# kilobytes of text could otherwise ask for billions.


def _unit(vector: np.ndarray) -> np.ndarray | None:
    length = float(np.linalg.norm(vector))
    return vector / length if length > SHORTEST_DIRECTION else None


def _turn(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotation (3x3) taking unit ``source`` onto unit ``target``."""
    axis = np.cross(source, target)
    sine, cosine = float(np.linalg.norm(axis)), float(np.dot(source, target))
    if sine < PRODUCT_ROUNDING:
        return np.eye(3) if cosine > 0 else np.diag([1.0, -1.0, -1.0])  # half turn about x
    return rotation_matrix(np.append(axis, np.arctan2(sine, cosine)))


def _is_closed(spine: np.ndarray) -> bool:
    """A spine of more than two points that ends where it starts."""
    return len(spine) > 2 and bool(np.allclose(spine[0], spine[-1]))


def _units(vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) unit vectors and (n,) whether each was long enough to have a
    direction (rows that were not are left as they are)."""
    lengths = np.linalg.norm(vectors, axis=1)
    ok = lengths > SHORTEST_DIRECTION
    units = vectors.copy()
    units[ok] /= lengths[ok, None]
    return units, ok


def frames(spine: np.ndarray) -> np.ndarray:
    """(n, 3, 3) SCP axes per spine point: columns X, Y, Z (world).

    Vectorised over the spine (a spine of 20,000 points took seconds point by
    point); the Z axes' sign flips, which depend on the previous point, are a
    running product of signs.
    """
    spine = np.asarray(spine, dtype=np.float64).reshape(-1, 3)
    n = len(spine)
    closed = _is_closed(spine)
    index = np.arange(n)
    y = spine[np.minimum(index + 1, n - 1)] - spine[np.maximum(index - 1, 0)]
    if n > 2:
        inner = np.clip(index, 1, n - 2)
        z = np.cross(spine[inner + 1] - spine[inner], spine[inner - 1] - spine[inner])
    else:
        z = np.zeros((n, 3))
    if closed:
        y[[0, -1]] = spine[1] - spine[n - 2]
        z[[0, -1]] = np.cross(spine[1] - spine[0], spine[n - 2] - spine[0])
    ys, has_y = _units(y)
    zs, has_z = _units(z)
    # a spine with repeated points: borrow the nearest defined direction
    ys[~has_y] = ys[has_y][0] if has_y.any() else np.array([0.0, 1.0, 0.0])
    if not has_z.any():  # a straight spine: turn +Y onto it
        turn = _turn(np.array([0.0, 1.0, 0.0]), ys[0])
        return np.repeat(turn[None], n, axis=0)
    # undefined Z axes keep the previous one (the first defined one before it)
    source = np.maximum.accumulate(np.where(has_z, index, -1))
    source[source < 0] = int(np.argmax(has_z))
    zs = zs[source]
    # Z flips when it would reverse: sign_i = +1 if sign_{i-1} * dot_i >= 0 else -1,
    # a running product of the dots' signs restarting at +1 where a dot is 0.
    dots = np.einsum("ij,ij->i", zs, np.concatenate([zs[:1], zs[:-1]]))
    steps = np.where(dots < 0, -1.0, 1.0)
    running = np.cumprod(steps)
    restart = np.maximum.accumulate(np.where(dots == 0, index, 0))
    signs = running * running[restart]
    signs[restart == index] = 1.0
    zs = zs * signs[:, None]
    previous = np.concatenate([zs[:1], zs[:-1]])
    xs, has_x = _units(np.cross(ys, zs))
    xs[~has_x] = np.cross(ys[~has_x], previous[~has_x])
    return np.stack([xs, ys, zs], axis=2)


def _per_point(
    context: Context, element: Element, name: str, default: list[float], n: int
) -> np.ndarray:
    """Field ``name`` with one value per spine point. X3D: one value applies
    everywhere; a short list repeats its last; an empty one (the spec gives
    no meaning to it) is the field's default, with a note."""
    values = context.field(element, name).reshape(-1, len(default))
    if len(values) == 0:
        context.warn(element, f"field {name} is empty; its default {default} is used")
        values = np.array([default], dtype=np.float64)
    if len(values) >= n:
        first_n: np.ndarray = values[:n]
        return first_n
    return np.concatenate([values, np.repeat(values[-1:], n - len(values), axis=0)])


def extrusion(context: Context, element: Element) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) float64 and faces (m, 3) int64 of an Extrusion element
    (a concave cap is triangulated in its plane)."""
    spine = context.field(element, "spine").reshape(-1, 3)
    section = context.field(element, "crossSection").reshape(-1, 2)
    if len(spine) < 2 or len(section) < 2:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    if len(spine) * len(section) > MAX_POINTS:
        raise context.error(
            element,
            f"{len(spine):,} spine points x {len(section):,} section points is more than "
            f"{MAX_POINTS:,} vertices (shadowgeo.limits.MAX_EXTRUSION_POINTS); refused",
        )
    scale = _per_point(context, element, "scale", [1.0, 1.0], len(spine))
    turns = _per_point(context, element, "orientation", [0.0, 0.0, 1.0, 0.0], len(spine))
    axes = frames(spine)
    flat = np.column_stack([section[:, 0], np.zeros(len(section)), section[:, 1]])
    rings = []
    for point, frame, size, turn in zip(spine, axes, scale, turns, strict=True):
        local = (flat * [size[0], 1.0, size[1]]) @ rotation_matrix(turn).T
        rings.append(local @ frame.T + point)
    vertices = np.concatenate(rings)
    m = len(section)
    i, j = np.meshgrid(np.arange(len(spine) - 1), np.arange(m - 1), indexing="ij")
    a = (i * m + j).ravel()
    # (i, j), (i, j+1), (i+1, j+1), (i+1, j): outward for the default box
    faces = [np.column_stack([a, a + 1, a + m + 1]), np.column_stack([a, a + m + 1, a + m])]
    closed_spine = _is_closed(spine)
    ring = np.arange(m - 1 if np.allclose(section[0], section[-1]) else m)
    repeated = len(np.unique(section[ring], axis=0)) < len(ring)
    if repeated and len(ring) >= 3 and not closed_spine:
        # A section that visits a point twice is no simple polygon: its cap has
        # no meaning, and triangulating it can take minutes (a section written
        # 10,000 times over).
        context.warn(element, "crossSection repeats a point: not a simple polygon, no caps")
    elif len(ring) >= 3 and not closed_spine:
        if context.field(element, "convex"):
            cap = np.column_stack([np.zeros(len(ring) - 2, int), ring[1:-1], ring[2:]])
        else:
            cap = ring[polygon_triangles(flat[ring])]
        # the section as written faces +Y of its SCP: the end cap as is, the begin cap turned
        if context.field(element, "endCap"):
            faces.append(cap + (len(spine) - 1) * m)
        if context.field(element, "beginCap"):
            faces.append(cap[:, ::-1])
    return vertices, np.concatenate(faces).astype(np.int64)
