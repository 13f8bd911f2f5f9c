"""The casters of a scene, all in one pair of arrays, and what each can shadow.

A scene of ten thousand small shapes must cost little more than one shape of
the same triangles. :class:`CasterSet` therefore computes every shape's world
vertices once and stacks them, with every shape's faces, into one vertex and
one face array; the tests that drop a caster (wholly behind the receiver,
beyond a positional light, out of its radius or cone, its shadow missing the
receiver's box, the light touching it or inside it) and the removal of
triangles lying in the receiver's plane are then a few numpy operations over
all shapes at once (the light's touch exactly only for the few casters whose
box holds it), and the casters a receiver keeps go to
:func:`shadowgeo.project_shadow` as one mesh. The topology of that mesh is
cached by the faces it holds, so a second light whose casters are the same
reuses it.
"""

from __future__ import annotations

import functools
import hashlib

import numpy as np

from ..errors import GeometryError
from ..lights import Light, SpotLight, is_positional
from ..plane import Plane
from ..silhouette import check_light_outside
from ..tolerance import Tolerance
from ..topology import BLOCK, Caster, block_normals, closed_by_sort
from .model import Shape, transformed
from .opacity import casting_opacity

__all__ = ["CasterSet", "SceneCaster", "distinct"]

# Stacked caster meshes kept for later lights (each holds its topology: a few
# times the size of its arrays).
_MESHES_KEPT = 2
# Up to this many distinct shape transforms, world vertices are computed per
# transform over all its shapes at once.
_TRANSFORMS_BATCHED = 16
_IDENTITY = np.eye(4).reshape(16)
# Closedness is tested per shape: once per distinct face array for shapes of
# at most this many faces, while there are at most this many distinct ones
# (see _closed_by_topology); a bigger shape by its own sort.
_SMALL_TOPOLOGY = 4096
_TOPOLOGIES_TESTED = 64


def distinct(shapes: list[Shape]) -> list[Shape]:
    """``shapes`` without those that repeat an earlier one's geometry exactly
    (vertices, faces, transform and sidedness), casting opacity
    (:func:`~.opacity.casting_opacity`) and scopes (:attr:`Shape.scopes`): a
    node copied ten thousand times over casts, and receives, one shadow.

    Shapes are first told apart by a cheap probe (array shapes, transform,
    sidedness, first and last vertex); only shapes whose probes agree are
    hashed whole, so ten thousand different meshes cost no hashing at all.
    """
    if len(shapes) < 2:
        return list(shapes)
    probes: dict[tuple[object, ...], Shape | dict[bytes, Shape]] = {}
    kept = []
    for shape in shapes:
        vertices = shape.vertices
        probe = (
            vertices.shape,
            shape.faces.shape,
            shape.transform.tobytes(),
            shape.solid,
            vertices[:1].tobytes(),
            vertices[-1:].tobytes(),
            casting_opacity(shape),
            shape.scopes,  # copies lit by different lights cast and receive for their own
        )
        earlier = probes.get(probe)
        if earlier is None:
            probes[probe] = shape
            kept.append(shape)
            continue
        if not isinstance(earlier, dict):
            earlier = probes[probe] = {_digest(earlier): earlier}
        key = _digest(shape)
        if key not in earlier:
            earlier[key] = shape
            kept.append(shape)
    return kept


def _digest(shape: Shape) -> bytes:
    """A hash of a shape's vertices, faces, transform and sidedness."""
    digest = hashlib.blake2b(digest_size=16)
    for array in (shape.vertices, shape.faces, shape.transform):
        digest.update(str(array.shape).encode())
        digest.update(np.ascontiguousarray(array).data)  # no copy of a contiguous array
    digest.update(b"s" if shape.solid else b"d")
    return digest.digest()


class SceneCaster:
    """One caster shape in world coordinates (its vertices shared with the
    set's arrays), its topology made when first needed and kept for every
    light."""

    def __init__(self, shape: Shape, vertices: np.ndarray) -> None:
        self.shape = shape
        self.vertices = vertices
        self.name = shape.name or shape.source or "unnamed shape"
        # whether its faces are closed, when the set knows it before the
        # caster is made (CasterSet.caster): the caster then does not test it
        self.closed: bool | None = None

    @functools.cached_property
    def caster(self) -> Caster:
        return Caster(self.vertices, self.shape.faces, closed=self.closed)


class CasterSet:
    """Every caster shape's world vertices and faces stacked into one mesh.

    Parameters
    ----------
    shapes : list of Shape
        Shapes with at least one face each.
    """

    def __init__(self, shapes: list[Shape]) -> None:
        self.vertex_counts = np.array([len(shape.vertices) for shape in shapes], dtype=np.int64)
        self.face_counts = np.array([len(shape.faces) for shape in shapes], dtype=np.int64)
        counts = self.vertex_counts
        self.vertex_starts = np.cumsum(counts) - counts
        self.face_starts = np.cumsum(self.face_counts) - self.face_counts
        self.vertices = _world_vertices(shapes, counts)
        if len(shapes) == 1:  # one shape: its own faces, not a copy
            self.faces = shapes[0].faces
        elif shapes:
            self.faces = np.concatenate([shape.faces for shape in shapes])
            self.faces += np.repeat(self.vertex_starts, self.face_counts)[:, None]
        else:
            self.faces = np.zeros((0, 3), np.int64)
        self.casters = [
            SceneCaster(shape, self.vertices[start : start + count])
            for shape, start, count in zip(shapes, self.vertex_starts, counts, strict=True)
        ]
        if shapes:
            self.low = np.minimum.reduceat(self.vertices, self.vertex_starts, axis=0)
            self.high = np.maximum.reduceat(self.vertices, self.vertex_starts, axis=0)
        else:
            self.low = self.high = np.zeros((0, 3))
        self._meshes: dict[bytes, Caster] = {}
        # the shapes whose face normals the receiver search wrote, with the
        # box of their faces' corners (see normals_known)
        self._used_boxes: dict[int, np.ndarray] = {}
        self._shapes = shapes

    @functools.cached_property
    def _shape_closed(self) -> np.ndarray | None:
        """(k,) each shape's closedness, shape by shape (None: too many
        distinct small topologies, the stack's edge table decides)."""
        return _closed_by_topology(self._shapes)

    @functools.cached_property
    def vertex_owner(self) -> np.ndarray:
        """(n,) the index of the caster of each stacked vertex."""
        return np.repeat(np.arange(len(self)), self.vertex_counts)

    @functools.cached_property
    def face_owner(self) -> np.ndarray:
        """(m,) the index of the caster of each stacked face."""
        return np.repeat(np.arange(len(self)), self.face_counts)

    def faces_of(self, chosen: np.ndarray) -> np.ndarray:
        """(m,) bool over the stacked faces: the faces of the ``chosen`` (k,)
        casters (``chosen[face_owner]`` without the owner array)."""
        return np.repeat(chosen, self.face_counts)

    def owners(self, faces: np.ndarray) -> np.ndarray:
        """The indices of the casters with a face in the (m,) bool mask
        ``faces``, in order."""
        if not len(self):
            return np.zeros(0, dtype=np.int64)
        return np.flatnonzero(np.logical_or.reduceat(faces, self.face_starts))

    def __len__(self) -> int:
        return len(self.casters)

    @functools.cached_property
    def bounds(self) -> np.ndarray:
        """(2, 3) the bounding box of every caster's vertices: the box of
        the casters' boxes (the same numbers, without another pass)."""
        if len(self.vertices) == 0:
            return np.zeros((2, 3))
        return np.array([self.low.min(axis=0), self.high.max(axis=0)])

    def per_caster(self, values: np.ndarray, reduce: np.ufunc) -> np.ndarray:
        """``reduce`` (np.minimum or np.maximum) of per-vertex ``values`` over
        each caster's vertices."""
        result: np.ndarray = reduce.reduceat(values, self.vertex_starts, axis=0)
        return result

    def lit(self, light: Light) -> np.ndarray:
        """(k,) bool: False for a caster with no part within the light's
        radius or, for a spot light, its cone (bounding box and sphere)."""
        keep = np.ones(len(self), dtype=bool)
        if not is_positional(light) or not len(self):
            return keep
        position = light.position
        nearest = np.clip(position, self.low, self.high)
        keep &= np.linalg.norm(nearest - position, axis=1) <= light.radius
        if isinstance(light, SpotLight):
            center = 0.5 * (self.low + self.high)
            radius = 0.5 * np.linalg.norm(self.high - self.low, axis=1)
            to_center = center - position
            reach = np.linalg.norm(to_center, axis=1)
            far = reach > radius
            with np.errstate(divide="ignore", invalid="ignore"):
                cosine = np.clip((to_center @ light.direction) / reach, -1.0, 1.0)
                spread = np.arcsin(np.clip(radius / reach, 0.0, 1.0))
            keep &= ~(far & (np.arccos(cosine) - spread > light.cut_off_angle))
        return keep

    def holding(
        self, light: Light, tolerance: Tolerance, among: np.ndarray | None = None
    ) -> dict[int, str]:
        """The casters (of ``among``, (k,) bool, when given) that a positional
        ``light`` touches (within ``tolerance.length``) or lies inside (a
        closed one: a lamp's bulb, a room around it), each index with the
        reason :func:`~shadowgeo.silhouette.check_light_outside` gives: such a
        caster cannot cast for that light (every shadow function raises
        :class:`~shadowgeo.errors.GeometryError` for it). One numpy test of
        every caster's box first; the exact test only for the few whose box
        holds the light."""
        if not is_positional(light) or not len(self):
            return {}
        position = light.position
        reach = tolerance.length
        boxed = np.all((self.low - reach <= position) & (position <= self.high + reach), axis=1)
        if among is not None:
            boxed &= among
        held = {}
        for index in np.flatnonzero(boxed).tolist():
            try:
                check_light_outside(self.caster(index), position, tolerance)
            except GeometryError as error:
                held[index] = str(error)
        return held

    def may_shadow(
        self,
        light: Light,
        plane: Plane,
        box2d: tuple[np.ndarray, np.ndarray] | None,
        tolerance: Tolerance,
    ) -> np.ndarray:
        """(k,) bool: False for a caster that certainly casts nothing on the
        receiver's box in ``plane``."""
        if not len(self):
            return np.zeros(0, dtype=bool)
        distance = plane.signed_distance(self.vertices)
        lowest = self.per_caster(distance, np.minimum)
        keep = self.per_caster(distance, np.maximum) > tolerance.length  # not wholly behind
        if is_positional(light):
            position = light.position
            height = float(plane.signed_distance(position[None])[0])
            keep &= lowest < height - tolerance.length  # not wholly at or beyond the light
            keep &= self.lit(light)
        if box2d is None:
            return keep
        # Casters with every vertex strictly between the plane and the light:
        # the shadow is inside the hull of the vertices' images. (A caster
        # reaching the light's height casts a shadow without bound.)
        boxed = keep & (lowest > tolerance.length)
        if is_positional(light):
            boxed &= self.per_caster(distance, np.maximum) < height - tolerance.length
        else:
            cosine = -float(plane.normal @ light.direction)
            if not cosine > 0:  # a sun along the plane (or from behind): no images
                return keep
        if not boxed.any():
            return keep
        inside = np.repeat(boxed, self.vertex_counts)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if is_positional(light):
                scale = np.where(inside, height / (height - distance), 1.0)
                images = position + (self.vertices - position) * scale[:, None]
            else:
                images = self.vertices + np.outer(
                    np.where(inside, distance, 0.0) / cosine, light.direction
                )
            image2d = plane.to_2d(images)
        low, high = box2d
        reach_low = self.per_caster(image2d, np.minimum)
        reach_high = self.per_caster(image2d, np.maximum)
        meets = np.all(reach_high >= low, axis=1) & np.all(reach_low <= high, axis=1)
        # images past float64's range (a caster a hair from the light's
        # height): not ruled out
        meets |= ~(np.isfinite(reach_low).all(axis=1) & np.isfinite(reach_high).all(axis=1))
        result: np.ndarray = keep & (~boxed | meets)
        return result

    def off_plane(self, plane: Plane, tolerance: Tolerance) -> np.ndarray:
        """(m,) bool over the stacked faces: False for a face lying in the lit
        ``plane`` (its normal towards the light's side) that does not rest on
        it: a patch does not shadow itself, nor a rug the floor, nor the hood
        of a car (a closed shape's face turned to the light) the hood. A
        closed caster keeps the faces it rests on the plane with (turned away
        from the light's side): they shadow its footprint, as it would anyway,
        and it stays closed, so its outline comes from its silhouette."""
        near = np.empty(len(self.vertices), dtype=bool)
        for start in range(0, len(self.vertices), BLOCK):
            block = self.vertices[start : start + BLOCK]
            distance = np.abs(plane.signed_distance(block))
            np.less_equal(distance, tolerance.coplanar_length, out=near[start : start + len(block)])
        if not near.any():
            return np.ones(len(self.faces), dtype=bool)
        # a face lies in the plane when its three corners do: the first
        # corner's test rules out all but a few faces in one pass
        lying = np.flatnonzero(near[self.faces[:, 0]])
        lying = lying[near[self.faces[lying, 1]] & near[self.faces[lying, 2]]]
        off: np.ndarray = np.ones(len(self.faces), dtype=bool)
        if not len(lying):
            return off
        off[lying] = False
        corners = self.vertices[self.faces[lying]]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        resting = normals @ plane.normal < 0  # turned away from the light's side
        # the stack's topology, for closedness, only when it matters
        off[lying[resting & self.closed[self.face_owner[lying]]]] = True
        return off

    @functools.cached_property
    def box_corners(self) -> np.ndarray:
        """(k, 8, 3) the corners of every caster's bounding box."""
        return np.stack(
            [
                np.column_stack([xs[:, 0], ys[:, 1], zs[:, 2]])
                for xs in (self.low, self.high)
                for ys in (self.low, self.high)
                for zs in (self.low, self.high)
            ],
            axis=1,
        )

    @functools.cached_property
    def closed(self) -> np.ndarray:
        """(k,) bool: True for a caster whose faces form a closed, consistently
        wound mesh (from the edge table of the whole stack, which the first
        light reuses: shapes share no stacked vertex), or from each distinct
        small topology once."""
        if self._shape_closed is not None:
            return self._shape_closed
        whole = self.mesh(np.ones(len(self.faces), dtype=bool))
        if not len(self.faces):
            return np.zeros(len(self), dtype=bool)
        bad_edge = (whole.edge_face_count != 2) | (whole.edge_net_direction != 0)
        bad_face = bad_edge[whole.face_edges].any(axis=1)
        closed = np.ones(len(self), dtype=bool)
        closed[self.face_owner[bad_face]] = False
        return closed

    @functools.cached_property
    def columns(self) -> np.ndarray:
        """(3, n) the stacked vertices' x, y and z: a view (the transpose),
        not a copy. Gathering a column of a million-vertex mesh by the
        faces' corners takes as long strided as contiguous (19 ms either way
        for the 3.9M corners of bench_scale's sphere), and a copy is 16 MB of
        fresh memory to fault in."""
        return self.vertices.T

    @functools.cached_property
    def _normal_rows(self) -> np.ndarray:
        return np.empty((len(self.faces), 3))

    def caster(self, index: int) -> Caster:
        """Caster ``index`` alone, as a :class:`Caster` of its world vertices
        (made once, kept for every light), its closedness the set's
        (:attr:`closed`: one test per distinct topology, not one a shape)."""
        scene_caster = self.casters[index]
        if scene_caster.closed is None:
            scene_caster.closed = bool(self.closed[index])
        return scene_caster.caster

    def normal_rows(self, index: int) -> np.ndarray:
        """(k, 3) the rows of :attr:`face_normals` for caster ``index``'s
        faces, to be written by a caller (the receiver search) with
        :func:`~shadowgeo.topology.block_normals`' arithmetic and then
        declared known (:meth:`normals_known`): :attr:`face_normals` takes
        them as they are."""
        start, count = int(self.face_starts[index]), int(self.face_counts[index])
        rows: np.ndarray = self._normal_rows[start : start + count]
        return rows

    def normals_known(self, index: int, used_box: np.ndarray) -> None:
        """Caster ``index``'s :meth:`normal_rows` are written; ``used_box``
        (2, 3): the box of its faces' corners, which the casters' mesh of
        every face takes for :attr:`Caster.bounds` once every caster's is
        known (the same numbers: the box of the vertices its faces use)."""
        self._used_boxes[index] = used_box

    @functools.cached_property
    def face_normals(self) -> np.ndarray:
        """(m, 3) every stacked face's unnormalised normal, the numbers of
        :attr:`Caster.face_normals`: those the receiver search kept, the
        others computed here; the casters' mesh takes them (or its faces'
        rows) once they are made."""
        normals = self._normal_rows
        known = np.zeros(len(self), dtype=bool)
        known[list(self._used_boxes)] = True
        missing = np.repeat(~known, self.face_counts)
        for start in range(0, len(self.faces), BLOCK):
            stop = start + BLOCK
            wanted = missing[start:stop]
            if wanted.all():
                normals[start:stop] = block_normals(self.columns, self.faces[start:stop])
            elif wanted.any():
                rows = start + np.flatnonzero(wanted)
                normals[rows] = block_normals(self.columns, self.faces[rows])
        return normals

    def mesh(self, faces: np.ndarray) -> Caster:
        """The stacked vertices with the face mask ``faces`` as one caster, its
        topology cached for the next light with the same faces."""
        key = hashlib.blake2b(np.packbits(faces).tobytes(), digest_size=16).digest()
        if key not in self._meshes:
            if len(self._meshes) >= _MESHES_KEPT:
                del self._meshes[next(iter(self._meshes))]  # the oldest
            everything = bool(faces.all())
            chosen = self.faces if everything else self.faces[faces]
            closed = None
            if len(self):
                # whole casters only (each all in or all out): closed when each is
                whole = np.logical_and.reduceat(faces, self.face_starts)
                if (
                    everything
                    or np.array_equal(whole, np.logical_or.reduceat(faces, self.face_starts))
                ) and self._shape_closed is not None:
                    closed = bool(self._shape_closed[whole].all())
            caster = Caster(self.vertices, chosen, copy=False, closed=closed)
            normals = bounds = None
            if "face_normals" in self.__dict__ or self._used_boxes:
                # (some) computed already: the same numbers
                normals = self.face_normals if everything else self.face_normals[faces]
            if everything and len(self._used_boxes) == len(self) and len(self):
                boxes = np.array(list(self._used_boxes.values()))
                bounds = np.array([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])
            caster.take_known(face_normals=normals, bounds=bounds)
            self._meshes[key] = caster
        return self._meshes[key]


def _closed_by_topology(shapes: list[Shape]) -> np.ndarray | None:
    """(k,) bool: whether each shape's faces are closed (:func:`closed_by_sort`),
    tested once per distinct small face array: 10,000 copies of a cylinder
    are one sort of 312 keys, not one of 3.1 million. A big shape is tested
    on its own: one sort of its edge keys, several times quicker than the
    stack's edge table. None when the shapes have more than
    ``_TOPOLOGIES_TESTED`` distinct small face arrays: then the stack's own
    test is as quick."""
    keys: list[tuple[int, int | bytes]] = []
    found: dict[tuple[int, int | bytes], bool | None] = {}
    small = 0
    for shape in shapes:
        if len(shape.faces) > _SMALL_TOPOLOGY:
            # tested alone, its bytes not hashed; shapes sharing one face
            # array (DEF/USE, instancing) once
            key: tuple[int, int | bytes] = (len(shape.vertices), id(shape.faces))
        else:
            key = (len(shape.vertices), shape.faces.tobytes())
        if key not in found:
            if isinstance(key[1], bytes):
                if small >= _TOPOLOGIES_TESTED:
                    return None
                small += 1
            found[key] = closed_by_sort(shape.faces, len(shape.vertices))
        keys.append(key)
    if any(closed is None for closed in found.values()):
        return None
    return np.array([bool(found[key]) for key in keys], dtype=bool)


def _world_vertices(shapes: list[Shape], counts: np.ndarray) -> np.ndarray:
    """Every shape's world vertices, stacked: one matrix product per distinct
    transform when there are few (scenes of many shapes mostly share one),
    else one per shape; a shape alone under no transform keeps its array."""
    if not shapes:
        return np.zeros((0, 3))
    transforms = np.stack([shape.transform for shape in shapes]).reshape(len(shapes), 16)
    if np.array_equal(transforms, np.broadcast_to(transforms[0], transforms.shape)):
        # one transform for all (the usual scene of many shapes): no sort of
        # rows as void records (np.unique(axis=0): 31 ms for 10,000 shapes)
        distinct, group = transforms[:1], np.zeros(len(shapes), dtype=np.int64)
    else:
        distinct, group = np.unique(transforms, axis=0, return_inverse=True)
    if len(distinct) > _TRANSFORMS_BATCHED:
        return np.concatenate([shape.world_vertices for shape in shapes])
    if len(distinct) == 1 and np.array_equal(distinct[0], _IDENTITY):
        # x * 1 + y * 0 + z * 0 + 0 is x: no product to compute (nor copy, for one shape)
        return (
            shapes[0].vertices
            if len(shapes) == 1
            else np.concatenate([shape.vertices for shape in shapes])
        )
    if len(shapes) == 1:
        return shapes[0].world_vertices
    raw = np.concatenate([shape.vertices for shape in shapes])
    if len(distinct) == 1:
        return transformed(raw, distinct[0].reshape(4, 4))
    owner = np.repeat(group.reshape(-1), counts)
    world = np.empty_like(raw)
    for index, transform in enumerate(distinct.reshape(-1, 4, 4)):
        rows = owner == index
        world[rows] = transformed(raw[rows], transform)
    return world
