"""Where a viewer's smooth shading lights a curved surface: the terminator.

An X3D browser shades a curved shape (a Sphere, a Cylinder's side, an
IndexedFaceSet with a ``creaseAngle``) with normals interpolated across its
faces, not with the faces' own normals. The line where its shading turns from
lit to unlit, the *smooth terminator* (interpolated normal perpendicular to
the light), therefore crosses the facets, while the faces' own normals switch
from lit to unlit at facet edges: a staircase one facet wide around the
smooth curve (the *faceted terminator*). A cast shadow that reaches the
terminator (a hat's on the head, a sphere's on the next) ends at the faceted
one on the exact geometry, and drawn over the smooth shading that end shows as
stair steps a whole facet wide: on one side the shadow stops a facet short of
where the shading goes dark, on the other it blacks out a facet the shading
already leaves unlit (the "shadow terminator" problem of renderers).

The scene converter therefore draws a cast shadow only where the viewer's
shading lights the surface, ``n_s . l > 0``, with ``n_s`` the interpolated
normal and ``l`` the direction to the light (:func:`clip_to_lit`); beyond it
the viewer adds no light from that light, shadowed or not. The value is
linear across a face (interpolated from its corners), so the cut is a straight
segment in each face, continuous from face to face: a smooth curve, no steps.
The faces beyond the faceted terminator whose shading is still lit get the
shadow of every other shape (:mod:`.surfaces`): like the offset renderers
use, a shape does not shadow itself there, as the smooth surface it stands for
would not.

:func:`corner_normals` gives the interpolated normals as X3D defines them
for generated normals: at each corner, the mean of the normals of the faces
around that vertex that meet the face at less than the shape's crease angle.
"""

from __future__ import annotations

import numpy as np

from ..lights import Light, is_positional
from ..limits import PRODUCT_ROUNDING, TINY

__all__ = ["clip_to_lit", "corner_normals", "lit_values"]

# Past this many (corner, face around its vertex) pairs, faces keep their own
# normals: a vertex shared by thousands of faces is a fan no one smooths.
_MAX_PAIRS = 4_000_000


def corner_normals(
    vertices: np.ndarray, faces: np.ndarray, groups: np.ndarray, crease: np.ndarray
) -> np.ndarray:
    """(m, 3, 3) unit normals at each face's corners, smoothed as X3D's
    ``creaseAngle`` says.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int64
    groups : (m,) int64
        The shape of each face: normals are smoothed within a shape only.
        Corners at one position share a vertex (positions are matched exactly).
    crease : (m,) float64
        The crease angle of each face's shape (radians); 0 keeps the face's
        own normal at every corner.

    Returns
    -------
    (m, 3, 3) float64
        At corner ``k`` of face ``f``: the area-weighted mean of the normals
        of the faces of ``f``'s shape around that corner's position whose
        normal is less than ``crease[f]`` from ``f``'s, normalised (``f``'s
        own normal for a degenerate face).

    Examples
    --------
    Two faces of a roof meeting at 90 degrees, smoothed and not:

    >>> import numpy as np
    >>> vertices = np.array([[0, 0, 0], [0, 0, 1], [1, 1, 0], [-1, 1, 0]], float)
    >>> faces = np.array([[0, 2, 1], [0, 1, 3]])
    >>> smooth = corner_normals(vertices, faces, np.zeros(2, int), np.full(2, 2.0))
    >>> np.round(smooth[0, 0], 3).tolist()
    [0.0, -1.0, 0.0]
    >>> flat = corner_normals(vertices, faces, np.zeros(2, int), np.full(2, 1.0))
    >>> np.round(flat[0, 0], 3).tolist()
    [0.707, -0.707, 0.0]
    """
    corners = vertices[faces]
    weighted = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(weighted, axis=1, keepdims=True)
    unit = np.divide(weighted, length, out=np.zeros_like(weighted), where=length > 0)
    result = np.repeat(unit[:, None, :], 3, axis=1)
    smooth = crease[np.arange(len(faces))] > 0
    if not smooth.any():
        return result
    # one key per (shape, position): corners of a shape at one point meet there
    # (only the smooth faces' corners: a flat city around one sphere costs nothing)
    corner_face = np.repeat(np.flatnonzero(smooth), 3)
    _, position = np.unique(vertices[faces[smooth].reshape(-1)], axis=0, return_inverse=True)
    position = position.reshape(-1)
    key = groups[corner_face] * (int(position.max()) + 1) + position
    order = np.argsort(key, kind="stable")
    key_sorted = key[order]
    starts = np.flatnonzero(np.r_[True, key_sorted[1:] != key_sorted[:-1]])
    sizes = np.diff(np.r_[starts, len(key_sorted)])
    if int((sizes.astype(np.int64) ** 2).sum()) > _MAX_PAIRS:
        return result
    # every (corner, other corner at its vertex) pair, by group
    group_of = np.repeat(np.arange(len(starts)), sizes)
    each = np.repeat(np.arange(len(key_sorted)), sizes[group_of])
    offset = np.arange(len(each)) - np.repeat(
        np.cumsum(sizes[group_of]) - sizes[group_of], sizes[group_of]
    )
    other = starts[group_of[each]] + offset
    face, neighbour = corner_face[order[each]], corner_face[order[other]]
    near = (
        np.einsum("ij,ij->i", unit[face], unit[neighbour])
        >= np.cos(crease[face]) - PRODUCT_ROUNDING
    )
    sums = np.zeros((len(key_sorted), 3))
    np.add.at(sums, each[near], weighted[neighbour[near]])
    norm = np.linalg.norm(sums, axis=1, keepdims=True)
    sums = np.divide(sums, norm, out=unit[corner_face[order]], where=norm > 0)
    smoothed = np.empty_like(sums)
    smoothed[order] = sums
    result[smooth] = smoothed.reshape(-1, 3, 3)
    return result


def lit_values(corners: np.ndarray, normals: np.ndarray, light: Light) -> np.ndarray:
    """(m, 3) ``n . l`` at each corner: its normal ``normals`` (m, 3, 3) against
    the unit direction from the corner ``corners`` (m, 3, 3) to the light."""
    if is_positional(light):
        towards = light.position - corners
        towards /= np.maximum(np.linalg.norm(towards, axis=2, keepdims=True), TINY)
    else:
        towards = np.broadcast_to(-light.direction, corners.shape)
    values: np.ndarray = np.einsum("mkd,mkd->mk", normals, towards)
    return values


def clip_to_lit(
    vertices: np.ndarray,
    faces: np.ndarray,
    face_index: np.ndarray,
    surface_corners: np.ndarray,
    values: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shadow triangles cut to where the interpolated ``values`` are > 0.

    Parameters
    ----------
    vertices : (k, 3) float64
    faces : (t, 3) int64
        Shadow triangles, each lying in (or lifted just off) the surface
        face ``face_index[i]``.
    face_index : (t,) int64
    surface_corners : (m, 3, 3) float64
        The surface's faces.
    values : (m, 3) float64
        A value at each corner of each surface face, interpolated linearly
        (barycentrically) across the face.

    Returns
    -------
    vertices, faces, face_index
        The parts of the triangles where the interpolated value is > 0,
        as triangles (a corner cut off leaves a quad: two triangles), wound
        as before. Points where an edge is cut depend on that edge's ends
        only, so triangles that shared an edge still meet along it.

    Examples
    --------
    >>> import numpy as np
    >>> face = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    >>> cut = clip_to_lit(face[0], np.array([[0, 1, 2]]), np.array([0]), face,
    ...                   np.array([[-1.0, 1.0, 1.0]]))
    >>> len(cut[1]), round(float(cut[0][cut[1]][:, :, 0].min()), 3)
    (2, 0.0)
    """
    if not len(faces):
        return vertices, faces, face_index
    triangles = vertices[faces]  # (t, 3, 3)
    own = surface_corners[face_index]  # (t, 3, 3)
    origin = own[:, 0]
    edges = np.stack([own[:, 1] - origin, own[:, 2] - origin], axis=1)  # (t, 2, 3)
    # in units of each face's size, so that its Gram determinant neither
    # underflows nor overflows, whatever the scene's scale
    size = np.linalg.norm(edges, axis=2).max(axis=1)
    size = np.where(size > 0, size, 1.0)[:, None, None]
    edges = edges / size
    gram = np.einsum("tid,tjd->tij", edges, edges)
    rhs = np.einsum("tid,tkd->tki", edges, (triangles - origin[:, None]) / size)  # (t, 3, 2)
    determinant = gram[:, 0, 0] * gram[:, 1, 1] - gram[:, 0, 1] ** 2
    safe = np.where(np.abs(determinant) > 0, determinant, 1.0)
    beta = (gram[:, None, 1, 1] * rhs[..., 0] - gram[:, None, 0, 1] * rhs[..., 1]) / safe[:, None]
    gamma = (gram[:, None, 0, 0] * rhs[..., 1] - gram[:, None, 0, 1] * rhs[..., 0]) / safe[:, None]
    face_values = values[face_index]
    value = (
        (1 - beta - gamma) * face_values[:, None, 0]
        + beta * face_values[:, None, 1]
        + gamma * face_values[:, None, 2]
    )  # (t, 3): at each shadow corner
    inside = value > 0
    count = inside.sum(axis=1)
    whole = count == 3
    pieces = [triangles[whole]]
    owners = [face_index[whole]]
    # one corner in: it and the two cut points; two in: a quad, two triangles
    for kept in (1, 2):
        chosen = np.flatnonzero(count == kept)
        if not len(chosen):
            continue
        flags = inside[chosen] if kept == 1 else ~inside[chosen]
        lone = np.argmax(flags, axis=1)  # the corner on its own side
        rows = np.arange(len(chosen))
        a = lone
        b, c = (lone + 1) % 3, (lone + 2) % 3
        points, vals = triangles[chosen], value[chosen]
        pa, pb, pc = points[rows, a], points[rows, b], points[rows, c]
        va, vb, vc = vals[rows, a], vals[rows, b], vals[rows, c]
        ab = _crossing(pa, pb, va, vb)
        ac = _crossing(pa, pc, va, vc)
        if kept == 1:
            pieces.append(np.stack([pa, ab, ac], axis=1))
            owners.append(face_index[chosen])
        else:
            pieces += [np.stack([ab, pb, pc], axis=1), np.stack([ab, pc, ac], axis=1)]
            owners += [face_index[chosen]] * 2
    kept_triangles = np.concatenate(pieces)
    points, inverse = np.unique(kept_triangles.reshape(-1, 3), axis=0, return_inverse=True)
    return points, inverse.reshape(-1, 3).astype(np.int64), np.concatenate(owners)


def _crossing(
    start: np.ndarray, end: np.ndarray, at_start: np.ndarray, at_end: np.ndarray
) -> np.ndarray:
    """Where the value, linear from ``at_start`` to ``at_end`` (opposite
    signs), is 0 on each segment; computed from the end with the smaller
    key first, so a segment gives the same point from either triangle."""
    flip = _after(start, end)
    first = np.where(flip[:, None], end, start)
    second = np.where(flip[:, None], start, end)
    value_first = np.where(flip, at_end, at_start)
    value_second = np.where(flip, at_start, at_end)
    share = value_first / (value_first - value_second)
    crossing: np.ndarray = first + share[:, None] * (second - first)
    return crossing


def _after(start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(s,) bool: ``start`` comes after ``end`` in (x, y, z) order."""
    differ = start != end
    first = np.argmax(differ, axis=1)
    rows = np.arange(len(start))
    after: np.ndarray = differ.any(axis=1) & (start[rows, first] > end[rows, first])
    return after
