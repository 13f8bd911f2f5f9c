"""Convex closed bodies of a caster, each casting one convex shadow a face.

A closed caster is often many bodies: a city block's buildings in one mesh.
Where a body is convex (no corner of it ahead of the plane of one of its
faces), its shadow on a plane it lies wholly ahead of, under a directional
light, is one convex polygon: the convex hull of its corners' images. That
polygon stands for the images of the body's three to six light-facing
triangles (a box's), which tile it edge to edge: one convex piece per
receiving face and body for the compiled union of
:func:`shadowgeo.surface.shadowed_fractions`, in place of several that meet
along shared edges. A body that crosses the face's plane is first cut to its
part ahead of it (its corners there and where its edges cross the plane),
still convex; a face whose whole lies inside one hull is wholly shadowed,
and its other pairs are not measured.

:func:`convex_bodies` finds the bodies once per caster (kept on it, as
:meth:`Caster.derived` keeps derived data); :func:`light_bodies` gathers
them for one light, and :func:`ring_pieces` makes the shadow of each
(body, face) pair by compiled loops (:func:`shadowgeo.kernels.ring_pieces`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .limits import MAX_BODY_FACES
from .silhouette import vertex_components
from .topology import BLOCK, Caster

__all__ = ["Bodies", "LightBodies", "convex_bodies", "light_bodies", "ring_pieces"]


class _Counted:
    """Bodies numbered by where their vertices start (``vertex_starts``,
    one more than there are bodies)."""

    vertex_starts: np.ndarray

    @property
    def count(self) -> int:
        """The number of bodies."""
        return len(self.vertex_starts) - 1


@dataclass(frozen=True)
class Bodies(_Counted):
    """The convex closed bodies of a caster, body by body.

    Attributes
    ----------
    vertices : (n,) int64
        The caster's vertex indices of each body in turn.
    vertex_starts : (b + 1,) int64
        Where each body's vertices start in ``vertices`` (and the end).
    faces : (f,) int64
        The caster's face indices of each body in turn.
    face_starts : (b + 1,) int64
        Where each body's faces start in ``faces`` (and the end).
    normals : (f, 3) float64
        The unit normal of each of ``faces`` (zero for a face without area).
    edges : (e, 2) int64
        Each body's edges in turn, as pairs of the caster's vertex indices.
    edge_starts : (b + 1,) int64
        Where each body's edges start in ``edges`` (and the end).
    rest : (r,) int64
        The caster's faces in no convex body (those of a body that is not
        convex, or too large to test, or of a caster that is not closed).
    """

    vertices: np.ndarray
    vertex_starts: np.ndarray
    faces: np.ndarray
    face_starts: np.ndarray
    normals: np.ndarray
    edges: np.ndarray
    edge_starts: np.ndarray
    rest: np.ndarray


def convex_bodies(caster: Caster, length: float) -> Bodies:
    """The convex closed bodies of ``caster``: its connected parts (joined by
    shared vertices) that are closed (every edge used by two of the part's
    faces, once each way) and whose every vertex lies within ``length`` (the
    scene's tolerance length) in front of no face plane of the part, of at
    least four faces and at most :data:`shadowgeo.limits.MAX_BODY_FACES`. An
    open part's shadow is its faces'. A body whose vertices are another's, the
    same points (a building repeated in the data), casts nothing more and is
    left out, its faces in neither the bodies nor the rest. Kept on the caster
    per ``length``."""
    return caster.derived(f"convex_bodies:{length!r}", lambda mesh: _bodies(mesh, length))


def _bodies(caster: Caster, length: float) -> Bodies:
    faces = caster.faces
    none = np.zeros(0, np.int64)
    if caster.n_faces == 0:
        start = np.zeros(1, np.int64)
        return Bodies(none, start, none, start, np.zeros((0, 3)), np.zeros((0, 2), np.int64),
                      start, np.arange(caster.n_faces))  # fmt: skip
    label = vertex_components(caster)
    face_label = label[faces[:, 0]]
    face_order = np.argsort(face_label, kind="stable")
    parts, face_counts = np.unique(face_label, return_counts=True)
    used = np.unique(faces)
    vertex_order = used[np.argsort(label[used], kind="stable")]
    vertex_counts = np.bincount(np.searchsorted(parts, label[vertex_order]), minlength=len(parts))
    edge_part = np.searchsorted(parts, label[caster.edges[:, 0]])
    tested = (face_counts >= 4) & (face_counts <= MAX_BODY_FACES)
    # closed parts only: each edge used by two faces, once each way
    unpaired = (caster.edge_face_count != 2) | (caster.edge_net_direction != 0)
    tested[edge_part[unpaired]] = False
    normals = _unit_normals(caster.vertices, faces[face_order])
    convex = tested & _convex(caster.vertices, faces[face_order], normals, vertex_order,
                              face_counts, vertex_counts, tested, length)  # fmt: skip
    repeated = _repeated(caster.vertices, vertex_order, vertex_counts, convex)
    kept = convex & ~repeated
    face_body = np.repeat(kept, face_counts)
    left_out = np.repeat(repeated, face_counts)
    # the caster's edges of each body, body by body
    edge_order = np.argsort(edge_part, kind="stable")
    edge_counts = np.bincount(edge_part, minlength=len(parts))
    return Bodies(
        vertex_order[np.repeat(kept, vertex_counts)],
        _starts(vertex_counts[kept]),
        face_order[face_body],
        _starts(face_counts[kept]),
        normals[face_body],
        caster.edges[edge_order[np.repeat(kept, edge_counts)]],
        _starts(edge_counts[kept]),
        np.sort(face_order[~face_body & ~left_out]),
    )


def _starts(sizes: np.ndarray) -> np.ndarray:
    """(n + 1,) where each of consecutive groups of ``sizes`` starts (and the end)."""
    return np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)


def _repeated(
    vertices: np.ndarray, vertex_order: np.ndarray, vertex_counts: np.ndarray, chosen: np.ndarray
) -> np.ndarray:
    """(p,) whether each part among ``chosen`` has the same points as an
    earlier chosen part (its vertices consecutive in ``vertex_order``)."""
    repeated = np.zeros(len(vertex_counts), dtype=bool)
    starts = np.concatenate([[0], np.cumsum(vertex_counts)[:-1]])
    for size in np.unique(vertex_counts[chosen]):
        group = np.flatnonzero(chosen & (vertex_counts == size))
        if len(group) < 2:
            continue
        points = vertices[vertex_order[starts[group][:, None] + np.arange(size)]]  # (g, size, 3)
        order = np.lexsort(points.transpose(2, 0, 1)[::-1], axis=-1)  # each part's points sorted
        points = np.take_along_axis(points, order[:, :, None], axis=1)
        rows = np.ascontiguousarray(points.reshape(len(group), -1)).view(
            np.dtype((np.void, points.itemsize * size * 3))
        )
        _, first = np.unique(rows.ravel(), return_index=True)
        repeated[group] = True
        repeated[group[first]] = False
    return repeated


def _unit_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(f, 3) unit normals of ``faces`` (zero where a face has no area)."""
    corners = vertices[faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    size = np.linalg.norm(normal, axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(size > 0, normal / size, 0.0)


def _convex(
    vertices: np.ndarray,
    faces: np.ndarray,
    normals: np.ndarray,
    vertex_order: np.ndarray,
    face_counts: np.ndarray,
    vertex_counts: np.ndarray,
    tested: np.ndarray,
    length: float,
) -> np.ndarray:
    """(p,) whether each part (its faces and vertices consecutive in
    ``faces`` and ``vertex_order``) has no vertex more than ``length`` in
    front of one of its face planes; parts not ``tested`` are not measured."""
    part_of_face = np.repeat(np.arange(len(face_counts)), face_counts)
    vertex_start = np.concatenate([[0], np.cumsum(vertex_counts)[:-1]])
    chosen = np.flatnonzero(tested[part_of_face])
    outside = np.zeros(len(face_counts), dtype=bool)
    # one row per (face, vertex of its part), a block of faces at a time
    step = max(1, BLOCK // max(1, MAX_BODY_FACES))
    for start in range(0, len(chosen), step):
        block = chosen[start : start + step]
        part = part_of_face[block]
        rows = vertex_counts[part]
        face_row = np.repeat(block, rows)
        first = np.repeat(vertex_start[part] - np.cumsum(rows) + rows, rows)
        vertex_row = vertex_order[first + np.arange(len(face_row))]
        height = np.einsum(
            "ij,ij->i", normals[face_row], vertices[vertex_row] - vertices[faces[face_row, 0]]
        )
        outside[part_of_face[face_row[height > length]]] = True
    return ~outside


@dataclass(frozen=True)
class LightBodies(_Counted):
    """The convex bodies of several casters under one directional light, in
    one frame.

    Attributes
    ----------
    points : (p, 3) float64
        The casters' vertices, one caster after another, in the frame.
    triangles : (t, 3) int64
        Each body's light-facing faces, as indices into ``points``.
    triangle_body : (t,) int64
        The body of each of ``triangles``.
    vertices : (n,) int64
        Each body's vertices in turn, as indices into ``points``.
    vertex_starts : (b + 1,) int64
        Where each body's vertices start in ``vertices`` (and the end).
    edges : (e, 2) int64
        Each body's edges in turn, as pairs of indices into ``points``.
    edge_starts : (b + 1,) int64
        Where each body's edges start in ``edges`` (and the end).
    """

    points: np.ndarray
    triangles: np.ndarray
    triangle_body: np.ndarray
    vertices: np.ndarray
    vertex_starts: np.ndarray
    edges: np.ndarray
    edge_starts: np.ndarray


def light_bodies(
    casters: list[Caster], found: list[Bodies], center: np.ndarray, direction: np.ndarray
) -> LightBodies:
    """The convex bodies ``found`` of ``casters`` (:func:`convex_bodies` of
    each) under a directional light travelling along ``direction`` (unit), in
    the frame centred on ``center``."""
    chosen = [
        (caster, bodies) for caster, bodies in zip(casters, found, strict=True) if bodies.count
    ]
    starts = np.cumsum([0] + [len(caster.vertices) for caster, _ in chosen])
    firsts = np.cumsum([0] + [bodies.count for _, bodies in chosen])
    triangles, owners, vertices, edges = [], [], [], []
    for (caster, bodies), start, first in zip(chosen, starts, firsts, strict=False):
        front = bodies.normals @ direction < 0.0
        per_body = np.repeat(np.arange(bodies.count), np.diff(bodies.face_starts))
        triangles.append(caster.faces[bodies.faces[front]] + start)
        owners.append(per_body[front] + first)
        vertices.append(bodies.vertices + start)
        edges.append(bodies.edges + start)
    return LightBodies(
        np.concatenate([caster.vertices - center for caster, _ in chosen]),
        np.concatenate(triangles),
        np.concatenate(owners),
        np.concatenate(vertices),
        _starts(np.concatenate([np.diff(bodies.vertex_starts) for _, bodies in chosen])),
        np.concatenate(edges),
        _starts(np.concatenate([np.diff(bodies.edge_starts) for _, bodies in chosen])),
    )


def ring_pieces(
    bodies: LightBodies,
    body: np.ndarray,
    face: np.ndarray,
    frames: np.ndarray,
    direction: np.ndarray,
    length: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each pair ``i`` (sorted by face): the shadow of body ``body[i]``
    on face ``face[i]`` under a light travelling along ``direction``: the body
    cut to the part ahead of the face's plane (the whole body where no corner
    lies more than ``length`` behind it), its image on that plane and their
    convex hull cut to the face (:func:`shadowgeo.kernels.ring_pieces`;
    ``frames`` (f, 7, 3): each face's corners, its unit normal, in-plane axes
    u and v and its frame's origin). Returns (m, k, 2) convex
    counter-clockwise polygons in the faces' frames, padded by repeating the
    last corner; (m,) their
    counts (0 where the body lies no more than ``length`` ahead of the plane,
    its shadow there has no area, or an earlier pair's hull holds the face);
    and (m,) whether the hull holds the whole face (it is wholly shadowed)."""
    from .kernels import ring_pieces as compiled_ring_pieces

    if len(body) == 0:
        return np.zeros((0, 3, 2)), np.zeros(0, np.int64), np.zeros(0, dtype=bool)
    # room for each pair's corners: its body's vertices and edge crossings, and
    # three more from the cut to the face
    offsets = _starts(np.diff(bodies.vertex_starts)[body] + np.diff(bodies.edge_starts)[body] + 3)
    flat, counts, covers = compiled_ring_pieces(
        bodies.points, bodies.vertices, bodies.vertex_starts, bodies.edges, bodies.edge_starts,
        body, face, frames, direction, length, offsets,
    )  # fmt: skip
    width = max(3, int(counts.max()))
    slots = np.minimum(np.arange(width)[None, :], np.maximum(counts, 1)[:, None] - 1)
    return flat[offsets[:-1, None] + slots], counts, covers
