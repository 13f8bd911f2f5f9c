"""Silhouettes: which faces a light sees, and the outline between them.

Every face gets one bit, *front* (``facing > 0``: it turns its front to the
light) or not. A face exactly edge-on to the light (``facing == 0``) is not
front. Because each face has exactly one bit, the edges where the bit changes
always form closed loops on a closed mesh, whatever the rounding: there is no
per-edge decision that two neighbouring faces could make differently, so a
shadow volume built from these edges cannot crack.

The same outline code serves :func:`shadowgeo.project_shadow` (its fast path
projects the loops alone) and :func:`shadowgeo.shadow_volume` (it extrudes
them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .deprecation import renamed_keyword
from .errors import GeometryError
from .lights import DirectionalLight, Light, require_light
from .limits import check_geometry
from .tolerance import Tolerance
from .topology import BLOCK, Caster, MeshLike, as_caster, compiled_walk, cycle_walk

__all__ = [
    "Outlines",
    "Silhouette",
    "boundary_loops",
    "chain",
    "chain_flat",
    "check_light_outside",
    "front_boundary",
    "light_homogeneous",
    "point_triangle_distance",
    "silhouette",
    "silhouette_loops",
    "silhouette_loops_many",
    "silhouette_outlines",
    "vertex_components",
]


@dataclass(frozen=True, eq=False)
class Silhouette:
    """The outline of a mesh as seen from a light.

    Attributes
    ----------
    front : (m,) bool
        One bit per face: True where the face turns its front (the side its
        winding makes outward) to the light. Edge-on faces are False.
    edges : (k, 2) int64
        Silhouette edges: edges between a front face and a face that is not,
        directed as they run in the front face. Mesh border edges are not
        included (see ``border``).
    loops : list of (n_i,) int64
        The boundary of the front region chained into closed loops of vertex
        indices, each running as its front faces do (counter-clockwise seen
        from the light). For a closed mesh these are the silhouette edges;
        for an open mesh they also use the border edges of front faces.
    border : (b, 2) int64
        Edges used by one face only (empty for a closed mesh), directed as
        they run in that face.
    non_manifold : (q, 2) int64
        Edges used by more than two faces (lower vertex index first).
    is_closed : bool
        The mesh is closed, 2-manifold and consistently wound
        (:attr:`Caster.is_closed`).
    """

    front: np.ndarray
    edges: np.ndarray
    loops: list[np.ndarray]
    border: np.ndarray
    non_manifold: np.ndarray
    is_closed: bool


@renamed_keyword("mesh", "caster")
def silhouette(caster: MeshLike, light: Light) -> Silhouette:
    """Front faces, silhouette edges, their loops and the border of ``caster``
    seen from ``light``.

    Parameters
    ----------
    caster : trimesh.Trimesh, Caster or (vertices, faces)
        The topology is cached on the mesh (see :func:`shadowgeo.as_caster`),
        so a second light costs only the per-light work.
    light : PointLight, SpotLight or DirectionalLight
        A spot light counts as a point light at its position (its cone does
        not change which faces turn to it).

    Returns
    -------
    Silhouette
        ``loops`` are closed: every loop vertex has as many outline edges in
        as out.

    Raises
    ------
    GeometryError
        A coordinate or light radius outside the supported range
        (:mod:`shadowgeo.limits`).

    Examples
    --------
    A cube lit from straight above: the top face (two triangles) is front,
    the side faces are edge-on, and the silhouette is the top square.

    >>> import trimesh
    >>> cube = trimesh.creation.box()
    >>> from shadowgeo import DirectionalLight
    >>> outline = silhouette(cube, DirectionalLight([0, 0, -1]))
    >>> int(outline.front.sum()), len(outline.edges), [len(loop) for loop in outline.loops]
    (2, 4, [4])
    """
    caster = as_caster(caster)
    check_geometry(caster, require_light(light))
    front = caster.facing(light_homogeneous(caster, light)) > 0
    counts = caster.edge_face_count
    border = _directed_edges(caster, caster.edge_slots[caster.edge_slot_starts[:-1][counts == 1]])
    non_manifold = caster.edges[counts > 2]
    starts, ends = front_boundary(caster, front)
    loops = chain(starts, ends)
    if caster.is_closed:
        edges = np.column_stack([starts, ends])
    else:
        # Drop the front faces' own border edges: those are in ``border``.
        low, high = np.minimum(starts, ends), np.maximum(starts, ends)
        keys = low * np.int64(len(caster.vertices)) + high
        border_edges = caster.edges[counts == 1]
        border_keys = border_edges[:, 0] * np.int64(len(caster.vertices)) + border_edges[:, 1]
        keep = ~np.isin(keys, border_keys)
        edges = np.column_stack([starts[keep], ends[keep]])
    return Silhouette(
        front=front,
        edges=edges.reshape(-1, 2),
        loops=loops,
        border=border.reshape(-1, 2),
        non_manifold=non_manifold.reshape(-1, 2),
        is_closed=caster.is_closed,
    )


def light_homogeneous(caster: Caster, light: Light) -> np.ndarray:
    """(4,) the light as a homogeneous vector in the caster's centred frame
    (:attr:`Caster.centered`)."""
    light = require_light(light)
    if isinstance(light, DirectionalLight):
        return np.append(-light.direction, 0.0)
    return np.append(light.position - caster.center, 1.0)


def front_boundary(caster: Caster, front: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k,) starts and (k,) ends of the directed edges that bound the
    ``front`` faces, as they run in those faces.

    On a closed mesh each silhouette edge has exactly one front face, found
    from :attr:`Caster.edge_face_slots`; otherwise an edge appears once for
    each front face use it does not cancel (see :func:`boundary_loops`).
    """
    if not caster.is_closed:
        return _net_boundary(caster, front, np.ones(caster.n_faces, dtype=np.int64))
    if caster.has_edge_table:
        slots = caster.edge_face_slots
        slot_front = front[slots // 3]
        outline = np.flatnonzero(slot_front[:, 0] != slot_front[:, 1])
        front_slot = np.where(slot_front[outline, 0], slots[outline, 0], slots[outline, 1])
    else:
        front_slot = _mixed_outline_slots(caster, front)
    directed = _directed_edges(caster, front_slot)
    return directed[:, 0], directed[:, 1]


def _mixed_outline_slots(caster: Caster, front: np.ndarray) -> np.ndarray:
    """The front face slot of each silhouette edge of a closed caster, in the
    order of the edges' keys (as :attr:`Caster.edge_face_slots` gives them),
    from the edges of the few faces near the silhouette instead of the
    mesh's whole edge table.

    Both ends of a silhouette edge are *mixed* vertices (they have a front
    and a back face: the edge's own two), and both faces of the edge contain
    both ends; so the faces with at least two mixed corners hold both slots
    of every silhouette edge. On a closed caster each directed edge is in
    one face and its reverse in another: a front face's edge a -> b between
    mixed vertices is on the silhouette exactly when b -> a is in no front
    face, and the face of b -> a, holding two mixed corners, is near.
    """
    faces = caster.faces
    n_vertices = len(caster.vertices)
    # a block of faces at a time: a few small temporaries, reused
    has_front = np.zeros(n_vertices, dtype=bool)
    has_back = np.zeros(n_vertices, dtype=bool)
    for start in range(0, len(faces), BLOCK):
        block, lit = faces[start : start + BLOCK], front[start : start + BLOCK]
        # corner by corner: a column gathered by face numbers, not rows
        # picked by a mask (twice as quick)
        lit_faces, unlit_faces = np.flatnonzero(lit), np.flatnonzero(~lit)
        for corner in range(3):
            column = block[:, corner]
            has_front[column[lit_faces]] = True
            has_back[column[unlit_faces]] = True
    mixed = has_front & has_back
    near_parts = []
    for start in range(0, len(faces), BLOCK):
        first, second, third = mixed[faces[start : start + BLOCK]].T
        near_parts.append(
            start + np.flatnonzero((first & second) | (second & third) | (third & first))
        )
    near = np.concatenate(near_parts) if near_parts else np.zeros(0, dtype=np.int64)
    near = near[front[near]]
    corners = faces[near]
    starts, ends = corners.reshape(-1), corners[:, [1, 2, 0]].reshape(-1)
    between = np.flatnonzero(mixed[starts] & mixed[ends])
    starts, ends = starts[between], ends[between]
    slots = 3 * near[between // 3] + between % 3
    width = np.int64(max(n_vertices, 1))
    ahead = np.sort(starts * width + ends, kind="stable")  # runs: see _successors
    back = ends * width + starts
    found = np.minimum(np.searchsorted(ahead, back), max(len(ahead) - 1, 0))
    outline = np.flatnonzero(ahead[found] != back) if len(ahead) else between[:0]
    # in the order of the undirected edges' keys, as the edge table lists them
    starts, ends, slots = starts[outline], ends[outline], slots[outline]
    order = np.argsort(np.minimum(starts, ends) * width + np.maximum(starts, ends), kind="stable")
    result: np.ndarray = slots[order]
    return result


def boundary_loops(
    caster: Caster, selected: np.ndarray, orientation: np.ndarray
) -> tuple[list[np.ndarray], np.ndarray]:
    """Loops of vertex indices whose winding number is the number of
    ``selected`` triangles that cover a point, once projected.

    ``orientation`` (m,) is the sign of each face's projected area. Each
    triangle counts +1 whatever its orientation: negative ones are reversed.
    Edges shared by two triangles of the same orientation cancel, so for a
    closed caster only the silhouette remains. Also returns the vertices used.
    """
    return _loops_and_vertices(*_net_boundary(caster, selected, orientation))


def silhouette_loops(caster: Caster, front: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Loops of a closed caster's silhouette (see :func:`front_boundary`),
    and the vertices they use."""
    return _loops_and_vertices(*front_boundary(caster, front))


def _loops_and_vertices(
    starts: np.ndarray, ends: np.ndarray
) -> tuple[list[np.ndarray], np.ndarray]:
    if len(starts) == 0:
        return [], np.zeros(0, dtype=np.int64)
    used = np.zeros(max(int(starts.max()), int(ends.max())) + 1, dtype=bool)
    used[starts] = True
    used[ends] = True
    return chain(starts, ends), np.flatnonzero(used)  # sorted, as np.unique, without a sort


def _net_boundary(
    caster: Caster, selected: np.ndarray, orientation: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    weights = (caster.face_edge_signs[selected] * orientation[selected, None]).reshape(-1)
    net = np.bincount(
        caster.face_edges[selected].reshape(-1), weights=weights, minlength=len(caster.edges)
    )
    boundary = np.flatnonzero(np.rint(net))
    net = np.rint(net[boundary]).astype(np.int64)
    edges = caster.edges[boundary]
    count = np.abs(net)
    forward = net > 0
    starts = np.where(forward, edges[:, 0], edges[:, 1]).repeat(count)
    ends = np.where(forward, edges[:, 1], edges[:, 0]).repeat(count)
    return starts, ends


def _directed_edges(caster: Caster, slots: np.ndarray) -> np.ndarray:
    """(k, 2) the edge of each face slot ``3 * face + corner``, from that
    corner to the next, as the face runs."""
    faces = caster.faces.reshape(-1)
    next_corner = slots - slots % 3 + (slots % 3 + 1) % 3
    return np.column_stack([faces[slots], faces[next_corner]]).reshape(-1, 2)


def chain(starts: np.ndarray, ends: np.ndarray) -> list[np.ndarray]:
    """Split directed edges with in-degree = out-degree at every vertex into
    closed loops of vertex indices.

    At a vertex with several edges in and out, the k-th edge in (by index)
    goes on to the k-th edge out: every edge then has one successor, and the
    loops are the cycles of that permutation, found by pointer jumping in
    O(k log k) numpy steps. A loop may pass a vertex twice (two outlines
    touching there); loops of fewer than three edges enclose nothing and are
    dropped.
    """
    corners, lengths = chain_flat(starts, ends)
    return _cut(corners, np.cumsum(lengths)[:-1]) if len(lengths) else []


def chain_flat(starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`chain`'s loops as one array of their vertices, one loop after
    another, and (l,) the loops' lengths (no array per loop)."""
    if len(starts) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    walk, cuts = cycle_walk(_successors(starts, ends))
    lengths = np.diff(np.concatenate([[0], cuts, [len(walk)]]))
    kept = lengths >= 3
    corners = starts[walk]
    if not kept.all():
        corners = corners[np.repeat(kept, lengths)]
    return corners, lengths[kept]


def _cut(values: np.ndarray, cuts: np.ndarray) -> list[np.ndarray]:
    """``values`` cut before each index of ``cuts`` (np.split, without its
    per-piece overhead)."""
    bounds = [0, *cuts.tolist(), len(values)]
    return [values[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _successors(starts: np.ndarray, ends: np.ndarray, span: int | None = None) -> np.ndarray:
    """(k,) the edge each edge goes on to: the k-th edge ending at a vertex
    to the k-th edge starting there, both by edge index.

    ``span``: the keys come in blocks of that many (``light * span +
    vertex``, the blocks rising with the edge index); many edges are then
    matched by a compiled pass a block (:func:`shadowgeo.kernels.successors`,
    the same result) instead of two sorts."""
    if compiled_walk(len(starts)):
        size = span if span is not None else int(max(starts.max(), ends.max())) + 1
        if size <= 16 * len(starts):  # (the lists' heads are ``size`` long)
            from .kernels import successors

            successor, matched = successors(
                np.asarray(starts, dtype=np.int64), np.asarray(ends, dtype=np.int64), size
            )
            if matched:
                return np.asarray(successor)
    # numpy's timsort finds the runs a mesh's face order leaves in these keys
    # (6,000 outline corners of a city: 0.012 ms, against 0.18 ms for its
    # default sort, which on a machine without its SIMD sort ignores runs)
    out_order = np.argsort(starts, kind="stable")
    in_order = np.argsort(ends, kind="stable")
    mismatch = starts[out_order] != ends[in_order]
    if np.any(mismatch):
        vertex = int(ends[in_order][np.flatnonzero(mismatch)[0]])
        raise GeometryError(f"internal error: the outline is not closed at vertex {vertex}")
    successor = np.empty(len(starts), dtype=np.int64)
    successor[in_order] = out_order
    return successor


def silhouette_loops_many(
    caster: Caster, fronts: list[np.ndarray]
) -> list[tuple[list[np.ndarray], np.ndarray]]:
    """:func:`silhouette_loops` of a closed caster for many lights at once.

    Parameters
    ----------
    caster : Caster
        A closed caster (:attr:`Caster.is_closed`).
    fronts : list of (m,) bool
        The front faces of each light.

    Returns
    -------
    list of (loops, vertices)
        One pair per light, equal array for array to what
        :func:`silhouette_loops` gives for that light alone.

    Notes
    -----
    The loops come from :func:`silhouette_outlines`, cut light by light.
    """
    outlines = silhouette_outlines(caster, fronts)
    loops = _cut(outlines.corners, np.cumsum(outlines.loop_lengths)[:-1])
    loop_bounds = np.searchsorted(outlines.loop_light, np.arange(len(fronts) + 1)).tolist()
    vertices = outlines.vertices(len(fronts), len(caster.vertices))
    return [
        (loops[loop_bounds[light] : loop_bounds[light + 1]], vertices[light])
        for light in range(len(fronts))
    ]


@dataclass(frozen=True)
class Outlines:
    """The silhouettes of many lights, flat: every light's loops one after
    the other, light by light, each light's as :func:`silhouette_loops`
    gives them.

    Attributes
    ----------
    corners : (c,) int64
        Vertex indices of every loop corner, loop after loop.
    loop_lengths : (l,) int64
        Corners in each loop (>= 3).
    loop_light : (l,) int64
        The light of each loop, ascending.
    edge_starts : (e,) int64
        The first vertex of every silhouette edge (also of loops dropped for
        having fewer than three edges): each vertex of a light's silhouette
        at least once, as every vertex has as many edges out as in.
    edge_light : (e,) int64
        The light of each edge, ascending.
    """

    corners: np.ndarray
    loop_lengths: np.ndarray
    loop_light: np.ndarray
    edge_starts: np.ndarray
    edge_light: np.ndarray

    def vertices(self, n_lights: int, n_vertices: int) -> list[np.ndarray]:
        """Each light's silhouette vertices, ascending (as
        :func:`silhouette_loops` gives them)."""
        used = np.zeros(n_lights * n_vertices, dtype=bool)
        used[self.edge_starts + self.edge_light * np.int64(n_vertices)] = True
        keys = np.flatnonzero(used)
        bounds = np.searchsorted(keys, np.arange(n_lights + 1) * np.int64(n_vertices)).tolist()
        return [
            keys[bounds[light] : bounds[light + 1]] - light * n_vertices
            for light in range(n_lights)
        ]


def silhouette_outlines(caster: Caster, fronts: list[np.ndarray] | np.ndarray) -> Outlines:
    """The silhouettes of a closed caster for many lights (``fronts``: each
    light's (m,) bool front faces, or a (k, m) uint8 array of 0 and 1 whose
    k is a multiple of 8), as one flat :class:`Outlines`.

    Notes
    -----
    The front bits of 64 lights are packed into one 64-bit word per face, so
    one XOR per edge finds the edges where the bit changes for all 64; only
    those edges are unpacked, and the outlines of all the lights are chained
    together (each light's vertices numbered apart).
    """
    if len(fronts) == 1:
        # One light: its own boundary, no word of 64 to pack and unpack.
        starts, ends = front_boundary(caster, np.asarray(fronts[0]).astype(bool, copy=False))
        corners, lengths = chain_flat(starts, ends)
        zeros = np.zeros(len(lengths), dtype=np.int64)
        return Outlines(corners, lengths, zeros, starts, np.zeros(len(starts), dtype=np.int64))
    words = [
        _outlines_of_word(caster, fronts[first : first + _WORD])
        for first in range(0, len(fronts), _WORD)
    ]
    if len(words) == 1:
        return words[0]
    firsts = range(0, len(fronts), _WORD)
    return Outlines(
        np.concatenate([word.corners for word in words]),
        np.concatenate([word.loop_lengths for word in words]),
        np.concatenate([w.loop_light + f for w, f in zip(words, firsts, strict=True)]),
        np.concatenate([word.edge_starts for word in words]),
        np.concatenate([w.edge_light + f for w, f in zip(words, firsts, strict=True)]),
    )


# Lights whose front bits share one machine word in silhouette_outlines.
_WORD = 64


def _pack_bits(fronts: list[np.ndarray] | np.ndarray) -> np.ndarray:
    """(m,) uint64 words from up to 64 (m,) bool arrays: bit k of word f is
    ``fronts[k][f]``. Eight lights at a time make one byte of each word.
    A (8 j, m) uint8 array of 0 and 1 is used as it is."""
    n_bytes = -(-len(fronts) // 8)  # the bytes that hold any light's bit
    if isinstance(fronts, np.ndarray) and fronts.dtype == np.uint8 and len(fronts) % 8 == 0:
        rows = fronts
    else:
        rows = np.zeros((8 * n_bytes, len(fronts[0])), dtype=np.uint8)
        rows[: len(fronts)] = fronts
    packed = np.zeros((len(fronts[0]), _WORD // 8), dtype=np.uint8)
    for byte in range(n_bytes):
        group = rows[8 * byte : 8 * byte + 8]
        value = group[0].copy()
        for bit in range(1, 8):
            value |= group[bit] << bit
        packed[:, byte] = value
    words: np.ndarray = packed.view(np.uint64).reshape(-1)
    return words


def _outlines_of_word(caster: Caster, fronts: list[np.ndarray] | np.ndarray) -> Outlines:
    words = _pack_bits(fronts)
    slots = caster.edge_face_slots
    faces_of = slots // 3
    changes = words[faces_of[:, 0]] ^ words[faces_of[:, 1]]
    changed = np.flatnonzero(changes)
    # (64, k) flags, light-major: each light's edges in index order, as
    # front_boundary has them
    flags = np.unpackbits(
        np.ascontiguousarray(changes[changed].view(np.uint8).reshape(-1, 8).T),
        axis=0,
        bitorder="little",
    )
    hits = np.flatnonzero(flags.view(bool))  # a flat bool scan: far faster than 2-D nonzero
    bounds = np.searchsorted(hits, np.arange(_WORD + 1) * len(changed))
    light_of = np.repeat(np.arange(_WORD, dtype=np.int64), np.diff(bounds))
    outline = changed[hits - light_of * len(changed)]
    first_front = (words[faces_of[outline, 0]] >> light_of.astype(np.uint64)) & np.uint64(1)
    front_slot = np.where(first_front.astype(bool), slots[outline, 0], slots[outline, 1])
    directed = _directed_edges(caster, front_slot)
    n_vertices = np.int64(len(caster.vertices))
    apart = light_of * n_vertices  # each light's vertices apart
    starts = directed[:, 0] + apart
    ends = directed[:, 1] + apart
    if len(starts) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return Outlines(empty, empty, empty, empty, empty)
    walk, cuts = cycle_walk(_successors(starts, ends, int(n_vertices)))
    loop_starts = np.concatenate([[0], cuts])
    lengths = np.diff(np.append(loop_starts, len(walk)))
    kept = lengths >= 3
    loop_light = light_of[walk[loop_starts]]
    if kept.all():
        corners = directed[walk, 0]
    else:
        corners = directed[walk[np.repeat(kept, lengths)], 0]
    return Outlines(corners, lengths[kept], loop_light[kept], directed[:, 0], light_of)


def check_light_outside(caster: Caster, position: np.ndarray, tolerance: Tolerance) -> None:
    """Raise :class:`GeometryError` if a light at ``position`` touches the
    caster (within ``tolerance.length``) or lies inside a closed caster."""
    lower, upper = caster.bounds
    reach = tolerance.length
    if np.any(position < lower - reach) or np.any(position > upper + reach):
        return
    triangles = caster.triangles
    near = np.all(triangles.min(axis=1) <= position + reach, axis=1) & np.all(
        triangles.max(axis=1) >= position - reach, axis=1
    )
    if np.any(near):
        distances = point_triangle_distance(position, triangles[near])
        if distances.min() <= reach:
            face = int(np.flatnonzero(near)[int(np.argmin(distances))])
            raise GeometryError(
                f"the light at {position.tolist()} touches the caster (face {face}, "
                f"distance {distances.min():.3g}, tolerance {reach:.3g})"
            )
    if caster.is_closed and abs(caster.winding_number(position)) > 0.5:
        raise GeometryError(
            f"the light at {position.tolist()} is inside the closed caster: "
            "everything around it is in shadow"
        )


def point_triangle_distance(point: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(m,) distance from ``point`` (3,) to each of (m, 3, 3) triangles,
    degenerate ones included: the nearer of the three edges and, where the
    point projects inside, the face."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    nearest = np.minimum.reduce(
        [_point_segment_distance(point, p, q) for p, q in ((a, b), (b, c), (c, a))]
    )
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=1)
    proper = length > 0
    if np.any(proper):
        unit = normal[proper] / length[proper, None]
        inside = np.ones(int(proper.sum()), dtype=bool)
        for p, q in ((a, b), (b, c), (c, a)):
            edge_normal = np.cross(unit, q[proper] - p[proper])
            inside &= np.einsum("ij,ij->i", edge_normal, point - p[proper]) >= 0
        plane_distance = np.abs(np.einsum("ij,ij->i", unit, point - a[proper]))
        face = np.where(inside, plane_distance, np.inf)
        nearest[proper] = np.minimum(nearest[proper], face)
    distances: np.ndarray = nearest
    return distances


def _point_segment_distance(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    direction = end - start
    length2 = np.einsum("ij,ij->i", direction, direction)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(length2 > 0, np.einsum("ij,ij->i", point - start, direction) / length2, 0.0)
    t = np.clip(t, 0.0, 1.0)
    distances: np.ndarray = np.linalg.norm(start + t[:, None] * direction - point, axis=1)
    return distances


def vertex_components(caster: Caster) -> np.ndarray:
    """(n,) int64 label of each vertex's connected part of the mesh (joined by
    faces): the least vertex index of that part.

    Hook and compress: every edge hooks the larger label under the smaller,
    then pointers jump to their roots; a few rounds for a mesh of many small
    parts, O(log n) rounds in general. The labels only fall, each to another
    vertex of the same part, until no edge joins two labels: each part then
    holds its least vertex's. The edges are taken a block of faces at a time
    and the jumps written into one buffer: a whole mesh's edge arrays at once
    were fresh memory each round (most of the time of the first call on a
    million faces).
    """
    label = np.arange(len(caster.vertices))
    jumped = np.empty_like(label)
    faces = caster.faces
    while True:
        joined = False
        for start in range(0, len(faces), BLOCK):
            block = faces[start : start + BLOCK]
            for one, other in ((0, 1), (1, 2)):
                a, b = label[block[:, one]], label[block[:, other]]
                differ = a != b
                if differ.any():
                    joined = True
                    a, b = a[differ], b[differ]
                    np.minimum.at(label, np.maximum(a, b), np.minimum(a, b))
        if not joined:
            return label
        while True:
            np.take(label, label, out=jumped)
            if np.array_equal(jumped, label):
                break
            label, jumped = jumped, label
