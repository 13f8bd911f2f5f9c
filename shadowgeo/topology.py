"""Caster meshes: validated arrays and the topology every light reuses.

Per-mesh work (edge table, adjacency, closedness) is done once and cached:
on a ``trimesh.Trimesh`` in its own cache (dropped when the mesh changes),
otherwise on the :class:`Caster` object the caller keeps. A second light then
costs only the per-light work.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property
from typing import TYPE_CHECKING, Literal, TypeAlias, TypeVar, Union, cast, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .boxes import bounding_box
from .compiled import use_compiled
from .errors import GeometryError

if TYPE_CHECKING:
    import trimesh

__all__ = [
    "BLOCK",
    "Caster",
    "MeshLike",
    "as_caster",
    "block_normals",
    "closed_by_sort",
    "closed_each",
    "compiled_walk",
    "cycle_walk",
    "empty_mesh",
    "loop_rings",
    "loops_taken",
    "point_ids",
    "row_groups",
    "unique_integers",
]

_CACHE_KEY = "shadowgeo_caster"
# Faces (or vertices) per block where per-face (per-vertex) arrays are
# worked out a block at a time: small temporaries, reused, instead of fresh
# memory the size of a big mesh for every step.
BLOCK = 1 << 16
_T = TypeVar("_T")


def block_normals(columns: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(k, 3) unnormalised normals (twice the area, by the winding) of the
    (k, 3) ``faces`` over the vertex coordinate ``columns`` (3, n): the
    numbers of :attr:`Caster.face_normals` for a block of its faces.

    Component-wise cross products on coordinate columns gathered one at a
    time: several times faster than np.cross on an (m, 3, 3) gather (the
    gathers read contiguous columns), and the same numbers. Callers go a
    block of faces at a time, so the temporaries stay small and are reused
    instead of being fresh memory for every big mesh."""
    first, second, third = faces.T
    x0, y0, z0 = columns[0][first], columns[1][first], columns[2][first]
    ux, uy, uz = columns[0][second] - x0, columns[1][second] - y0, columns[2][second] - z0
    vx, vy, vz = columns[0][third] - x0, columns[1][third] - y0, columns[2][third] - z0
    normals = np.empty((len(first), 3))
    normals[:, 0] = uy * vz - uz * vy
    normals[:, 1] = uz * vx - ux * vz
    normals[:, 2] = ux * vy - uy * vx
    return normals


def _shaped(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A caster's ``vertices`` (n, 3) and ``faces`` (m, 3), empty ones
    reshaped; GeometryError for other shapes."""
    if vertices.size == 0:
        vertices = vertices.reshape(0, 3)
    if faces.size == 0:
        faces = faces.reshape(0, 3)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise GeometryError(f"caster vertices must be (n, 3), got shape {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise GeometryError(f"caster faces must be (m, 3) triangles, got shape {faces.shape}")
    return vertices, faces


def _integer_faces(faces: np.ndarray) -> NDArray[np.int64]:
    """``faces`` as int64 (itself when it is already); GeometryError for
    indices with a fraction."""
    if not np.issubdtype(faces.dtype, np.integer):
        if faces.size and not np.all(np.equal(np.mod(faces, 1), 0)):
            raise GeometryError("caster faces must hold integer vertex indices")
        faces = faces.astype(np.int64)
    return faces.astype(np.int64, copy=False)


def _check_finite(vertices: np.ndarray) -> None:
    """GeometryError naming the first vertex with a NaN or infinite coordinate."""
    if not np.isfinite(vertices).all():
        bad_vertex = ~np.all(np.isfinite(vertices), axis=1)
        index = int(np.flatnonzero(bad_vertex)[0])
        raise GeometryError(
            f"caster vertex {index} is not finite: {vertices[index].tolist()} "
            f"({int(bad_vertex.sum())} such vertices)"
        )


def _check_indices(faces: np.ndarray, n_vertices: int) -> None:
    """GeometryError naming the first face that indexes a missing vertex."""
    if faces.size and (faces.min() < 0 or faces.max() >= n_vertices):
        bad_face = np.any((faces < 0) | (faces >= n_vertices), axis=1)
        if np.any(bad_face):
            index = int(np.flatnonzero(bad_face)[0])
            raise GeometryError(
                f"caster face {index} {faces[index].tolist()} indexes a missing vertex "
                f"(the mesh has {n_vertices} vertices)"
            )


class Caster:
    """A triangle mesh checked for use as a shadow caster.

    Parameters
    ----------
    vertices : (n, 3) float64
    faces : (m, 3) int
        Indices into ``vertices``; the winding gives the outward side.
    closed : bool, optional
        :attr:`is_closed`, when the caller knows it: meshes with no vertex in
        common stacked into one are closed exactly when each of them is, so
        a scene of many copies of one mesh tests its topology once, not the
        whole stack's edges.
    copy : bool
        Copy the arrays (the default), so that later changes to the caller's
        arrays cannot reach the cached topology. ``False`` uses float64 and
        int64 arrays as they are (still checked), for a caller that keeps
        them unchanged while the caster lives: no second copy of a big mesh.

    Raises
    ------
    GeometryError
        NaN or infinite coordinates, faces that are not triangles, or faces
        that index missing vertices.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        *,
        copy: bool = True,
        closed: bool | None = None,
    ) -> None:
        vertices = np.array(vertices, dtype=np.float64, copy=True if copy else None)
        faces = np.array(faces, copy=True if copy else None)
        vertices, faces = _shaped(vertices, faces)
        faces = _integer_faces(faces)
        _check_finite(vertices)
        _check_indices(faces, len(vertices))
        if not copy:  # read-only views: the caller's own arrays stay writable
            vertices, faces = vertices.view(), faces.view()
        vertices.setflags(write=False)
        faces.setflags(write=False)
        self.vertices = vertices
        self.faces = faces
        self._lit_before = False
        if closed is not None:
            self.__dict__["is_closed"] = bool(closed) and len(faces) > 0

    def take_known(
        self,
        *,
        face_normals: np.ndarray | None = None,
        bounds: np.ndarray | None = None,
        closed: bool | None = None,
    ) -> None:
        """Take what a caller has worked out already, the very values the
        caster would (a caster set's stacked face normals, the box of the
        vertices its faces use, whether it is closed by
        :func:`closed_each`): the caster then does not compute them again.
        None leaves one as it is."""
        for name, value in (
            ("face_normals", face_normals),
            ("bounds", bounds),
            ("is_closed", closed),
        ):
            if value is not None:
                self.__dict__[name] = value  # the cached properties' slots

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    @cached_property
    def triangles(self) -> np.ndarray:
        """(m, 3, 3) corner coordinates of every face."""
        return self.vertices[self.faces]

    @cached_property
    def face_normals(self) -> np.ndarray:
        """(m, 3) unnormalised face normals (twice the area, by the winding)."""
        normals = np.empty((len(self.faces), 3))
        for start in range(0, len(self.faces), BLOCK):
            normals[start : start + BLOCK] = self._normals(start, start + BLOCK)
        return normals

    def _normals(self, start: int, stop: int) -> np.ndarray:
        """(k, 3) :attr:`face_normals` of faces ``start:stop``."""
        return block_normals(self._columns, self.faces[start:stop])

    @cached_property
    def _columns(self) -> np.ndarray:
        # a view: gathered by the corners, strided columns are as quick as
        # contiguous ones (CasterSet.columns), and no copy is made
        return self.vertices.T

    @cached_property
    def center(self) -> np.ndarray:
        """(3,) centre of :attr:`bounds`: the origin of :attr:`centered`."""
        low, high = self.bounds
        center: np.ndarray = 0.5 * (low + high)
        return center

    @cached_property
    def centered(self) -> np.ndarray:
        """(n, 4) homogeneous vertices relative to :attr:`center`. Differences
        of nearby coordinates are exact, so a scene far from the origin loses
        nothing when its geometry is computed in this frame."""
        relative = self.vertices - self.center
        return np.column_stack([relative, np.ones(len(relative))])

    def centered_rows(self, indices: np.ndarray) -> np.ndarray:
        """(k, 4) the rows ``indices`` of :attr:`centered`, the same numbers,
        without making the whole array when it is not there yet."""
        if "centered" in self.__dict__:
            rows: np.ndarray = self.centered[indices]
            return rows
        relative = self.vertices[indices] - self.center
        return np.column_stack([relative, np.ones(len(relative))])

    def centered_columns(self) -> list[np.ndarray]:
        """The x, y and z columns of :attr:`centered` as contiguous arrays,
        the same numbers, without making the (n, 4) array when it is not
        there yet."""
        if "centered" in self.__dict__:
            return [np.ascontiguousarray(self.centered[:, axis]) for axis in range(3)]
        return [self.vertices[:, axis] - self.center[axis] for axis in range(3)]

    @cached_property
    def face_offsets(self) -> np.ndarray:
        """(m,) ``face_normals . (first corner - center)``: with
        :attr:`face_normals`, each face's plane in the :attr:`centered` frame."""
        offsets = np.empty(len(self.faces))
        for start in range(0, len(self.faces), BLOCK):
            stop = start + BLOCK
            offsets[start:stop] = self._offsets(self.face_normals[start:stop], start, stop)
        return offsets

    def _offsets(self, normals: np.ndarray, start: int, stop: int) -> np.ndarray:
        """(k,) :attr:`face_offsets` of faces ``start:stop``, their ``normals`` given."""
        corners = self.vertices[self.faces[start:stop, 0]] - self.center  # as in centered
        offsets: np.ndarray = np.einsum("ij,ij->i", normals, corners)
        return offsets

    def facing(self, light_homogeneous: ArrayLike) -> np.ndarray:
        """(m,) positive where a face turns its front to the light given as a
        homogeneous 4-vector in the :attr:`centered` frame (zero edge-on).

        The first light works a block of faces at a time and keeps nothing
        but the result; a second light keeps :attr:`face_normals` (and, if
        positional, :attr:`face_offsets`) for the lights after it. The numbers
        are the same either way.
        """
        light = np.asarray(light_homogeneous, dtype=np.float64)
        positional = light[3] != 0  # a light at infinity does not need the face planes
        # products written out: a BLAS call (@) may wake OpenBLAS's threads,
        # which then spin on the other core for longer than the product takes
        if not self._lit_before and "face_normals" not in self.__dict__:
            self._lit_before = True
            facing: np.ndarray = np.empty(len(self.faces))
            for start in range(0, len(self.faces), BLOCK):
                stop = start + BLOCK
                normals = self._normals(start, stop)
                block = facing[start:stop]
                np.multiply(normals[:, 0], light[0], out=block)
                block += normals[:, 1] * light[1]
                block += normals[:, 2] * light[2]
                if positional:
                    block -= self._offsets(normals, start, stop) * light[3]
            return facing
        normals = self.face_normals
        facing = normals[:, 0] * light[0] + normals[:, 1] * light[1]
        facing += normals[:, 2] * light[2]
        if positional:
            facing -= self.face_offsets * light[3]
        return facing

    @cached_property
    def distinct(self) -> np.ndarray:
        """(m,) bool: False for a face that covers no area (two corners at the
        same point, or all three on a line) or repeats an earlier face's
        corners (in any order or winding), points compared by coordinates.

        The shadow of the faces left is the same region, and a 2-D union
        whose cost grows with overlapping copies never sees them.
        """
        if self.n_faces == 0:
            return np.zeros(0, dtype=bool)
        corners = np.sort(point_ids(self.vertices)[self.faces], axis=1)
        keep = (corners[:, 0] != corners[:, 1]) & (corners[:, 1] != corners[:, 2])
        keep &= np.any(self.face_normals != 0, axis=1)
        unique = np.zeros(self.n_faces, dtype=bool)
        unique[row_groups(corners)[0]] = True
        valid: np.ndarray = keep & unique
        return valid

    @cached_property
    def edge_face_slots(self) -> np.ndarray:
        """(e, 2) for a closed mesh: the two face corners ``3 * face + k`` whose
        edge (corner k to k + 1) is each edge, lower slot first."""
        if not self.is_closed:
            raise ValueError("edge_face_slots needs a closed mesh")
        # The sort leaves an edge's slots in ascending order (the slot rides in
        # the key's low bits, or a stable argsort keeps it), so the pairs are
        # the rows as they are: a view, no copy of 3 m numbers.
        pairs = self.edge_slots.reshape(-1, 2)
        pairs.flags.writeable = False
        return pairs

    @property
    def has_edge_table(self) -> bool:
        """Whether the edge table (:attr:`edges`, :attr:`edge_slots`, ...) is
        built already: code that can do with less then skips building it."""
        return "_edge_sort" in self.__dict__

    @property
    def edge_slots(self) -> np.ndarray:
        """(3 m,) every face corner ``3 * face + k`` grouped by the edge it
        starts (corner k to k + 1): the slots of edge ``i`` are
        ``edge_slots[edge_slot_starts[i]:edge_slot_starts[i + 1]]``."""
        return self._edge_sort[0]

    @property
    def edge_slot_starts(self) -> np.ndarray:
        """(e + 1,) offsets of each edge's group in :attr:`edge_slots`."""
        return self._edge_sort[2]

    @cached_property
    def _edge_sort(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(slots in edge order, (3 m,) bool first slot of its edge, group
        starts, sorted edge keys ``low * n + high``).

        One sort of a single int64 key per face edge gives the edges' groups
        and the slots in them at once (np.unique with return_inverse would
        sort, and edge_face_slots sort again). The slot rides in the key's
        low bits where it fits, so a plain sort (several times faster than
        argsort) yields the order too, ties by slot. What only some callers
        need (unique edges, each face edge's index, its sign) is derived
        from it on demand: a closed caster's silhouette needs none of them.
        """
        starts, ends = self._corner_edges
        n = np.int64(max(len(self.vertices), 1))
        keys = np.minimum(starts, ends) * n + np.maximum(starts, ends)
        slot_bits = max(len(keys).bit_length(), 1)
        if (int(n) * int(n)).bit_length() + slot_bits <= 63:
            packed = (keys << np.int64(slot_bits)) | np.arange(len(keys), dtype=np.int64)
            packed.sort()
            order = packed & np.int64((1 << slot_bits) - 1)
            sorted_keys = packed >> np.int64(slot_bits)
        else:
            order = np.argsort(keys, kind="stable")
            sorted_keys = keys[order]
        first = np.empty(len(sorted_keys), dtype=bool)
        first[:1] = True
        np.not_equal(sorted_keys[1:], sorted_keys[:-1], out=first[1:])
        group_starts = np.append(np.flatnonzero(first), len(keys)).astype(np.int64)
        return order, first, group_starts, sorted_keys

    @cached_property
    def _corner_edges(self) -> tuple[np.ndarray, np.ndarray]:
        """(3 m,) start and end vertex of each face edge (corner k to k + 1)."""
        faces = self.faces
        ends = np.empty_like(faces)  # column copies, no fancy index
        ends[:, :2], ends[:, 2] = faces[:, 1:], faces[:, 0]
        return faces.reshape(-1), ends.reshape(-1)

    @cached_property
    def edges(self) -> np.ndarray:
        """(e, 2) unique undirected edges, lower vertex index first."""
        _, first, _, sorted_keys = self._edge_sort
        n = np.int64(max(len(self.vertices), 1))
        unique_keys = sorted_keys[first]
        return np.column_stack([unique_keys // n, unique_keys % n])

    @cached_property
    def face_edges(self) -> np.ndarray:
        """(m, 3) index into :attr:`edges` of the edge from corner k to corner k+1."""
        order, first, _, _ = self._edge_sort
        inverse = np.empty(len(order), dtype=np.int64)
        inverse[order] = np.cumsum(first) - 1
        return inverse.reshape(-1, 3)

    @cached_property
    def face_edge_signs(self) -> np.ndarray:
        """(m, 3) +1 where that face edge runs from the lower vertex index to
        the higher one, -1 otherwise."""
        starts, ends = self._corner_edges
        return (2 * (starts < ends).astype(np.int64) - 1).reshape(-1, 3)

    @cached_property
    def edge_face_count(self) -> np.ndarray:
        """(e,) number of faces that use each edge."""
        return np.diff(self.edge_slot_starts)

    @cached_property
    def edge_net_direction(self) -> np.ndarray:
        """(e,) sum of the face edge signs: 0 on every edge of a closed,
        consistently wound mesh."""
        if len(self.edge_slots) == 0:
            return np.zeros(0, dtype=np.int64)
        grouped = self.face_edge_signs.reshape(-1)[self.edge_slots]
        return np.add.reduceat(grouped, self.edge_slot_starts[:-1])

    @cached_property
    def is_closed(self) -> bool:
        """True when every edge has exactly two faces that use it in opposite
        directions: a watertight, consistently wound 2-manifold edge set."""
        if self.n_faces == 0:
            return False
        if self.has_edge_table:
            return bool(np.all(self.edge_face_count == 2) and np.all(self.edge_net_direction == 0))
        closed = closed_by_sort(self.faces, len(self.vertices))
        if closed is None:  # too many vertices for one packed key
            return bool(np.all(self.edge_face_count == 2) and np.all(self.edge_net_direction == 0))
        return closed

    @property
    def closedness_known(self) -> bool:
        """Whether :attr:`is_closed` is settled already (given, taken or
        worked out), so that asking costs nothing."""
        return "is_closed" in self.__dict__

    def derived(self, key: str, compute: Callable[[Caster], _T]) -> _T:
        """``compute(self)``, computed once per mesh and ``key`` and kept, as
        the cached properties are (the arrays are read-only): for derived data
        that other modules define, such as a receiving surface's face frames."""
        store: dict[str, object] = self.__dict__.setdefault("_derived", {})
        if key not in store:
            store[key] = compute(self)
        return cast(_T, store[key])

    @cached_property
    def bounds(self) -> np.ndarray:
        """(2, 3) lower and upper corner of the used vertices' bounding box."""
        if self.n_faces == 0:
            return np.zeros((2, 3))
        used = np.zeros(len(self.vertices), dtype=bool)
        used[self.faces.reshape(-1)] = True
        points = self.vertices if used.all() else self.vertices[used]
        return bounding_box(points)

    def winding_number(self, point: ArrayLike) -> float:
        """Generalised winding number of the mesh around ``point`` (1 inside a
        closed outward-wound mesh, 0 outside), by the solid angle of every face
        (Van Oosterom and Strackee)."""
        return float(self.winding_numbers(np.asarray(point, dtype=np.float64)[None])[0])

    def winding_numbers(self, points: ArrayLike) -> np.ndarray:
        """(p,) :meth:`winding_number` at each of ``points`` (p, 3), in blocks
        of about a million point-face pairs."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        triangles = self.triangles
        result = np.empty(len(points))
        block = max(1, _WINDING_PAIRS // max(len(triangles), 1))
        for start in range(0, len(points), block):
            rel = triangles[None] - points[start : start + block, None, None]
            a, b, c = rel[:, :, 0], rel[:, :, 1], rel[:, :, 2]
            la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
            numerator = np.einsum("pij,pij->pi", a, np.cross(b, c))
            denominator = (
                la * lb * lc
                + np.einsum("pij,pij->pi", a, b) * lc
                + np.einsum("pij,pij->pi", b, c) * la
                + np.einsum("pij,pij->pi", c, a) * lb
            )
            angles = 2.0 * np.arctan2(numerator, denominator)
            result[start : start + block] = np.sum(angles, axis=1) / (4.0 * np.pi)
        return result


# Point-face pairs per pass of Caster.winding_numbers (about 72 MB of corners).
_WINDING_PAIRS = 1_000_000


def closed_by_sort(faces: np.ndarray, n_vertices: int) -> bool | None:
    """Whether the (m, 3) ``faces`` use every edge exactly twice, in opposite
    directions (:attr:`Caster.is_closed`), by one in-place sort of one int64
    key per face edge; None when ``n_vertices`` is too large for the key.

    The key of the edge from ``a`` to ``b`` is its undirected key
    ``min * n + max`` with one more bit, set when ``a > b``. The faces are
    closed exactly when the sorted keys come in pairs ``2 k, 2 k + 1``: each
    edge once each way (sorted, the next pair's key is then larger, so no
    edge has a third use). An edge from a vertex to itself has no set bit and
    never pairs. Only the keys are made: no argsort, no edge table.

    Examples
    --------
    >>> tetrahedron = np.array([[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]])
    >>> closed_by_sort(tetrahedron, 4), closed_by_sort(tetrahedron[:3], 4)
    (True, False)
    """
    faces = np.asarray(faces)
    count = len(faces)
    n = max(int(n_vertices), 1)
    if (2 * n * n).bit_length() > 63:
        return None
    if count == 0 or count % 2:  # an odd number of face edges cannot pair
        return False
    keys = _edge_keys(faces, n)
    flat = keys.reshape(-1)
    # numpy's default sort, not its stable one: only the keys are sorted, so
    # order among equals is moot, and on x86 with AVX2/AVX-512 the default is
    # a vectorised quicksort. The 3.9M edge keys of a 1.3M-triangle icosphere
    # sort in 56 ms against 247 ms by timsort in the mesh's face order, and
    # 531 ms with the faces shuffled (the sphere of benchmarks/bench_scale.py).
    flat.sort()
    pairs = flat.reshape(-1, 2)
    for first in range(0, len(pairs), BLOCK):
        block = pairs[first : first + BLOCK]
        if not np.all((block[:, 0] ^ block[:, 1]) == 1):
            return False
    return True


def _edge_keys(faces: np.ndarray, n: int) -> np.ndarray:
    """(3, m) int64 :func:`closed_by_sort`'s key of each face edge, row k
    for the edges from corner k to k + 1, worked out a block at a time
    (small temporaries, reused); ``n``: at least the vertex count."""
    count = len(faces)
    # 2 (min n + max) + (start > end)
    keys = np.empty((3, count), dtype=np.int64)
    larger = np.empty(min(count, BLOCK), dtype=np.int64)
    for first in range(0, count, BLOCK):
        block = faces[first : first + BLOCK]
        high = larger[: len(block)]
        for corner in range(3):
            start, end = block[:, corner], block[:, (corner + 1) % 3]
            key = keys[corner, first : first + len(block)]
            np.minimum(start, end, out=key)
            key *= np.int64(2 * n)
            np.maximum(start, end, out=high)
            high <<= np.int64(1)
            key += high
            key += start > end
    return keys


def closed_each(meshes: list[tuple[np.ndarray, int]]) -> np.ndarray | None:
    """(k,) bool: :func:`closed_by_sort` of each of ``meshes`` ((m, 3)
    faces indexing their own vertices, vertex count), by one sort of all
    their edge keys; None when their vertices together are too many for
    the key.

    With the meshes' vertices numbered one mesh after another, each mesh's
    keys sort into one run of the sorted keys, in the meshes' order (a key
    orders first by its edge's lower vertex), so each mesh's pairs are
    checked within its own run, as :func:`closed_by_sort` checks them.

    Examples
    --------
    >>> tetrahedron = np.array([[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]])
    >>> closed_each([(tetrahedron, 4), (tetrahedron[:3], 4), (tetrahedron, 4)]).tolist()
    [True, False, True]
    """
    counts = np.array([len(faces) for faces, _ in meshes], dtype=np.int64)
    n_vertices = np.array([max(int(n), 0) for _, n in meshes], dtype=np.int64)
    n = max(int(n_vertices.sum()), 1)
    if (2 * n * n).bit_length() > 63:
        return None
    result = np.zeros(len(meshes), dtype=bool)
    tried = np.flatnonzero((counts > 0) & (counts % 2 == 0))  # odd: cannot pair
    if not len(tried):
        return result
    first_vertex = np.cumsum(n_vertices) - n_vertices
    faces = np.concatenate(
        [np.asarray(meshes[k][0], dtype=np.int64) + first_vertex[k] for k in tried.tolist()]
    )
    flat = _edge_keys(faces, n).reshape(-1)
    flat.sort()  # numpy's default sort, as in closed_by_sort
    # each tried mesh's run of 3 m keys, checked in pairs from its start
    pairs = 3 * counts[tried] // 2
    run_start = 3 * (np.cumsum(counts[tried]) - counts[tried])
    first = np.repeat(run_start - 2 * (np.cumsum(pairs) - pairs), pairs) + 2 * np.arange(
        int(pairs.sum())
    )
    paired = (flat[first] ^ flat[first + 1]) == 1
    result[tried] = np.logical_and.reduceat(paired, np.cumsum(pairs) - pairs)
    return result


def loop_rings(sizes: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """For loops laid one after another, ``sizes[i]`` points each: each
    loop's first point, and each point's next one on its loop (the last
    point's is its loop's first; an empty loop holds no point).

    Examples
    --------
    >>> starts, following = loop_rings([3, 0, 2])
    >>> starts.tolist(), following.tolist()
    ([0, 3, 3], [1, 2, 0, 4, 3])
    """
    sizes = np.asarray(sizes, dtype=np.int64)
    starts = np.cumsum(sizes) - sizes
    following = np.arange(1, int(sizes.sum()) + 1)
    nonempty = sizes > 0
    following[(starts + sizes - 1)[nonempty]] = starts[nonempty]
    return starts, following


def loops_taken(sizes: np.ndarray, order: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For loops laid one after another, ``sizes[i]`` points each: the
    index that takes their points loop by loop in ``order`` (some or all
    of the loops), and the loops' sizes in that order.

    Examples
    --------
    >>> index, sizes = loops_taken(np.array([2, 3, 1]), np.array([2, 0]))
    >>> index.tolist(), sizes.tolist()
    ([5, 0, 1], [1, 2])
    """
    sizes = np.asarray(sizes, dtype=np.int64)
    starts = np.cumsum(sizes) - sizes
    taken = sizes[order]
    index = np.repeat(starts[order] - (np.cumsum(taken) - taken), taken)
    index += np.arange(int(taken.sum()))
    return index, taken


def point_ids(points: ArrayLike) -> np.ndarray:
    """(n,) int64 ids of ``points`` (n, k): equal for points with equal
    coordinates (compared as numbers: -0.0 is 0.0), numbered in sorted order.

    Each column is ranked by one sort and the ranks are packed into a single
    int64 key where they fit, which is many times faster than
    ``np.unique(points, axis=0)``.

    Examples
    --------
    >>> point_ids([[0, 1, 0], [2, 0, 0], [0, 1, -0.0]]).tolist()
    [0, 1, 0]
    """
    values = np.asarray(points, dtype=np.float64)
    values = values.reshape(len(values), -1)
    if len(values) == 0:
        return np.zeros(0, dtype=np.int64)
    ranks = [
        np.unique(values[:, k], return_inverse=True)[1].reshape(-1) for k in range(values.shape[1])
    ]
    return row_groups(np.column_stack(ranks))[1]


def row_groups(rows: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Equal rows of the (m, k) non-negative integer array ``rows``.

    Returns ``(first, inverse, counts)``: for each distinct row, in sorted
    order, the index of its first copy; for every row, the index of its
    distinct row; and how many copies each distinct row has.

    Examples
    --------
    >>> first, inverse, counts = row_groups([[2, 1], [0, 5], [2, 1]])
    >>> first.tolist(), inverse.tolist(), counts.tolist()
    ([1, 0], [1, 0, 1], [1, 2])
    """
    table = np.asarray(rows, dtype=np.int64)
    table = table.reshape(len(table), -1)
    if len(table) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    sizes = [int(column.max()) + 1 for column in table.T]
    if sum(size.bit_length() for size in sizes) + len(table).bit_length() <= 62:
        # Pack the row, then the row's index, into one key: a plain sort gives
        # the groups, each in row order.
        key = np.zeros(len(table), dtype=np.int64)
        for column, size in zip(table.T, sizes, strict=True):
            key = key * np.int64(size) + column
        index_bits = len(table).bit_length()
        packed = np.sort((key << np.int64(index_bits)) | np.arange(len(table), dtype=np.int64))
        order = packed & np.int64((1 << index_bits) - 1)
        ordered_keys = packed >> np.int64(index_bits)
        starts = np.append(True, ordered_keys[1:] != ordered_keys[:-1])
    else:
        order = np.lexsort(table.T[::-1])  # stable: each group in row order
        ordered = table[order]
        starts = np.append(True, np.any(ordered[1:] != ordered[:-1], axis=1))
    group_of_sorted = np.cumsum(starts) - 1
    inverse = np.empty(len(table), dtype=np.int64)
    inverse[order] = group_of_sorted
    first = order[starts]
    counts = np.diff(np.append(np.flatnonzero(starts), len(table)))
    return first, inverse, counts


@overload
def unique_integers(values: ArrayLike, return_inverse: Literal[False] = False) -> np.ndarray: ...


@overload
def unique_integers(
    values: ArrayLike, return_inverse: Literal[True]
) -> tuple[np.ndarray, np.ndarray]: ...


def unique_integers(
    values: ArrayLike, return_inverse: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """``np.unique`` of integers, by :func:`row_groups`' one sort (numpy
    2.4's hash-based ``np.unique`` is many times slower on large arrays).

    Examples
    --------
    >>> unique_integers([5, -2, 5, 0]).tolist()
    [-2, 0, 5]
    """
    flat = np.asarray(values, dtype=np.int64).reshape(-1)
    if len(flat) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return (empty, empty) if return_inverse else empty
    first, inverse, _ = row_groups(flat - flat.min())
    return (flat[first], inverse) if return_inverse else flat[first]


# What every geometry function takes as its caster.
MeshLike: TypeAlias = Union["trimesh.Trimesh", tuple[ArrayLike, ArrayLike], Caster]  # noqa: UP007


def compiled_walk(count: int) -> bool:
    """Whether a walk of ``count`` items (here, and the outline matching of
    ``silhouette._successors``) takes the compiled loops of
    :mod:`shadowgeo.kernels` (numba): the rule and its override are
    :mod:`shadowgeo.compiled`'s (the walks give the same arrays either way)."""
    return use_compiled("walk", count)


def cycle_walk(successor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cycles of a permutation, walked.

    Parameters
    ----------
    successor : (k,) int
        A permutation: item ``i`` is followed by ``successor[i]``.

    Returns
    -------
    walk : (k,) int64
        The items in cycle order, each cycle from its lowest item, cycles
        by that item.
    cuts : (c - 1,) int64
        The positions in ``walk`` where a new cycle begins.

    Examples
    --------
    >>> walk, cuts = cycle_walk(np.array([2, 0, 1, 4, 3]))
    >>> walk.tolist(), cuts.tolist()
    ([0, 2, 1, 3, 4], [3])
    """
    count = len(successor)
    if compiled_walk(count):  # the same result
        from .kernels import cycle_walk as compiled

        walk: np.ndarray
        cuts: np.ndarray
        walk, cuts = compiled(np.asarray(successor, dtype=np.int64))
        return walk, cuts
    # Each item's cycle label: the smallest item on its cycle. After s
    # doublings a label is the least of 2^s successors; it is final once
    # every item agrees with its successor (then each cycle holds one value,
    # which must be its least item), checked every second doubling.
    label, jump = np.arange(count), successor.copy()
    for step in range(max(1, int(count).bit_length())):
        label = np.minimum(label, label[jump])
        jump = jump[jump]
        if step % 2 and np.array_equal(label[successor], label):
            break
    # Cut each cycle before its labelled item and rank items by their
    # distance to the cut: the labelled item comes first, then its
    # successors in order.
    indices = np.arange(count)
    last = successor == label
    # The last item of each cycle points at a sentinel (index count) that
    # has nothing remaining and points at itself.
    after = np.append(np.where(last, count, successor), count)
    remaining = np.append((~last).astype(np.int64), 0)
    longest = int(np.bincount(label).max())
    for _ in range(max(1, longest.bit_length())):  # distances double each step
        remaining += remaining[after]
        after = after[after]
    remaining = remaining[:count]
    # Place each item directly (no sort): cycles in label order, each from
    # its labelled item, which has the most items remaining.
    sizes = np.bincount(label, minlength=count)
    offsets = np.cumsum(sizes) - sizes
    walk = np.empty(count, dtype=np.int64)
    walk[offsets[label] + sizes[label] - 1 - remaining] = indices
    cuts = offsets[sizes > 0][1:]
    return walk, cuts


def as_caster(caster: MeshLike) -> Caster:
    """A :class:`Caster` from a ``Caster``, a ``trimesh.Trimesh`` (cached on the
    mesh) or a ``(vertices, faces)`` pair."""
    if isinstance(caster, Caster):
        return caster
    if isinstance(caster, tuple | list):
        if len(caster) == 2:
            return Caster(caster[0], caster[1])
        raise _not_a_caster(caster)
    cache = getattr(caster, "_cache", None)
    if cache is not None and hasattr(caster, "vertices") and hasattr(caster, "faces"):
        try:
            cached = cache[_CACHE_KEY]
        except (KeyError, TypeError):
            cached = None
        if isinstance(cached, Caster):
            return cached
        result = Caster(caster.vertices, caster.faces)
        try:
            cache[_CACHE_KEY] = result
        except (KeyError, TypeError):
            pass
        return result
    raise _not_a_caster(caster)


def _not_a_caster(caster: object) -> GeometryError:
    return GeometryError(
        "caster must be a trimesh.Trimesh, a shadowgeo Caster or a (vertices, faces) pair, "
        f"got {type(caster).__name__}"
        + (f" of {len(caster)} items" if isinstance(caster, tuple | list) else "")
    )


def empty_mesh() -> trimesh.Trimesh:
    """A ``trimesh.Trimesh`` without vertices or faces: the shadow or shadow
    volume where there is none."""
    import trimesh

    return trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), process=False)
