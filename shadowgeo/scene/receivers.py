"""Which surfaces receive shadows: flat patches of a scene's shapes, or a plane.

A *patch* is the set of a shape's triangles that lie within
``Tolerance.coplanar_length`` of one plane (the top of a ground slab, a floor,
a wall). Real scenes rarely model a ground as a lone quad: it is a box, a
plane with a kerb, a room with walls. So receivers are patches, not whole
shapes:

* found automatically: every patch whose bounding-box diagonal is at least a
  quarter of the scene's and whose area is at least a quarter of the largest
  such patch's (a ground, a floor, a large wall; not a box's face, a sign or a
  step), and with some geometry in front of it (a lone box's faces do not
  receive: nothing can shadow them); the ``MAX_FOUND`` largest of them, with
  a note when more qualify. Shapes are ruled out before any per-patch work
  when a histogram of their face normals shows no flat part that large
  (:func:`~.patchbound.may_hold_patch`);
* named (``--receiver DEF``): the named shape's patches of at least a quarter
  of its largest patch's area; its largest patch must cover at least a tenth
  of the shape's area, else it is not planar;
* a plane ``a x + b y + c z + d = 0``: unbounded, lit from either side;
* when none is found: the ground plane under the scene's lowest point (along
  its up axis), unbounded, lit from above, with a note (``add_shadows`` draws
  a visible ground there: :mod:`.ground`). The ground plane also
  receives, besides those found, when none of them is a floor under the scene
  (:func:`is_floor`): a car's flat hood or a facade's wall is found, but the
  shadow a reader looks for is the one on the ground.

A patch of a ``solid`` shape receives only on its front (the side its
triangles face, as a renderer culls the back); a patch of a ``solid="false"``
shape receives on whichever side a light is on.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..boxes import bounding_box
from ..errors import GeometryError, SceneError
from ..lights import Light, is_positional
from ..plane import Plane
from ..tolerance import Tolerance
from ..topology import point_ids, row_groups, unique_integers
from .casters import CasterSet
from .ground import MATERIAL as GROUND_MATERIAL
from .model import Material, Scene, Shape, safe_name
from .patchbound import may_hold_patch

__all__ = [
    "AREA_FRACTION",
    "BOUNDING_FRACTION",
    "FLOOR_COSINE",
    "FLOOR_COVER",
    "FLOOR_FRACTION",
    "MAX_FOUND",
    "NAMED_FRACTION",
    "Receiver",
    "SIZE_FRACTION",
    "bounds_the_scene",
    "found",
    "given_plane",
    "ground",
    "is_floor",
    "named",
    "patches",
    "repeated_faces",
    "select",
]

# A found receiver: at least these fractions of the largest patch's area and of
# the scene's bounding-box diagonal.
AREA_FRACTION = 0.25
SIZE_FRACTION = 0.25
# A named receiver's largest patch covers at least this fraction of its area.
NAMED_FRACTION = 0.1
# Receivers found automatically, at most (the largest): each unites every
# caster's shadow in its own plane.
MAX_FOUND = 8
# A found receiver is a floor under the scene when it faces up within this
# angle's cosine (30 degrees) and its highest point lies within this fraction
# of the scene's height above the scene's lowest point, or it lies in the
# scene's lower half and covers this fraction of its plan or its lowest vertex
# (see is_floor); without one, the ground plane receives too.
FLOOR_COSINE = 0.866
FLOOR_FRACTION = 0.1
FLOOR_COVER = 0.5
# A found receiver is also a floor when it is a side of the scene's box turned
# inwards, within this fraction of the box's extent, whichever axis is up.
BOUNDING_FRACTION = 0.2
# Patches looked for per shape (largest triangles first).
_MAX_PATCHES = 64


@dataclasses.dataclass
class Receiver:
    """A receiving plane and, for a patch, the triangles that bound it.

    Attributes
    ----------
    plane : Plane
        Its normal points to the patch's front.
    name : str
        DEF-safe, for the added shape's name.
    triangles : (m, 3, 3) float64 or None
        The patch in world coordinates; None for an unbounded plane.
    two_sided : bool
        Receives on either side (else only in front of ``plane``).
    material : Material, optional
        The look of the shape it is a patch of (how dark its shadows are
        drawn depends on it); None for a plane.
    scopes : frozenset of int or None
        The scopes of the shape it is a patch of (:attr:`Shape.scopes`): a
        non-global light shadows it only within its scope. The ground plane
        lies at the top of the scene (no scope); a given plane (None) takes
        every light's shadows.
    """

    plane: Plane
    name: str
    triangles: np.ndarray | None = None
    two_sided: bool = True
    area: float = float("inf")
    material: Material | None = None
    scopes: frozenset[int] | None = None

    def facing(self, light: Light, tolerance: Tolerance) -> Plane | None:
        """The plane turned towards ``light``; None when the light lies in it,
        or behind a one-sided patch."""
        plane = self.plane
        if is_positional(light):
            side = float(plane.signed_distance(light.position[None])[0])
            if abs(side) <= tolerance.length:
                return None
        else:
            side = -float(plane.normal @ light.direction)
            if abs(side) <= tolerance.angle:
                return None
        if side > 0:
            return plane
        return plane.flipped() if self.two_sided else None


def repeated_faces(
    vertices: np.ndarray, faces: np.ndarray, groups: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct faces of (m, 3) ``faces`` over ``vertices``: corners
    compared by coordinates, and a face and its turns (``(a, b, c)``,
    ``(b, c, a)``, ``(c, a, b)``) being one; with ``groups`` (m,) non-negative
    ints, only faces of the same group are compared (the shapes of a stack).

    Returns ``(first, inverse, counts)``: the index of each distinct face's
    first copy, the (m,) index mapping every face to its distinct one, and
    how many copies each has.
    """
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if not len(faces):
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    corners = point_ids(vertices)[faces]
    turn = np.argmin(corners, axis=1)
    turned = corners[np.arange(len(corners))[:, None], (turn[:, None] + np.arange(3)) % 3]
    if groups is not None:
        turned = np.column_stack([np.asarray(groups, dtype=np.int64), turned])
    return row_groups(turned)


def patches(
    shape: Shape, tolerance: Tolerance, world_vertices: np.ndarray | None = None
) -> list[tuple[Plane, np.ndarray, float]]:
    """The flat patches of a shape: ``(plane, faces mask (m,) bool, area)``,
    largest first. Triangles facing either way join a patch; its plane faces
    the way most of its area does. ``world_vertices``, when the caller has
    them, saves computing them again."""
    if world_vertices is None:
        world_vertices = shape.world_vertices
    # Repeated faces (a coordIndex written 10,000 times over) are found once,
    # weighted by how often they repeat: each patch scans every face.
    first, inverse, counts = repeated_faces(world_vertices, shape.faces)
    triangles = world_vertices[shape.faces[first]]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    doubled = np.linalg.norm(normals, axis=1)
    valid = doubled / tolerance.length > 2 * tolerance.length  # no square to overflow
    unit = np.zeros_like(normals)
    unit[valid] = normals[valid] / doubled[valid, None]
    assigned = ~valid
    found: list[tuple[Plane, np.ndarray, float]] = []
    limit = tolerance.coplanar_length
    for seed in np.argsort(-doubled, kind="stable"):
        if len(found) >= _MAX_PATCHES or assigned.all():
            break
        if assigned[seed]:
            continue
        normal = unit[seed]
        offset = -float(normal @ triangles[seed, 0])
        distance = triangles @ normal + offset
        member = ~assigned & np.all(np.abs(distance) <= limit, axis=1)
        member[seed] = True
        assigned |= member
        if (normals[member] * counts[member, None]).sum(axis=0) @ normal < 0:
            normal, offset = -normal, -offset
        area = 0.5 * float((doubled[member] * counts[member]).sum())
        found.append((Plane(normal, offset), member[inverse], area))
    found.sort(key=lambda item: -item[2])
    return found


def ground(
    scene: Scene,
    geometry: list[Shape],
    bounds: np.ndarray | None = None,
    besides: Sequence[Receiver] = (),
) -> tuple[Receiver, str]:
    """The unbounded ground plane through the lowest point of the geometry
    (height along the scene's up axis), facing up, and the note that says
    so: the receiver when none is found, or when those found (``besides``)
    hold no floor under the scene. ``bounds``: the geometry's world box, when
    known."""
    axis = scene.up_index
    if bounds is None and geometry:
        bounds = bounding_box(np.concatenate([shape.world_vertices for shape in geometry]))
    lowest = float(bounds[0, axis]) if bounds is not None else 0.0
    normal = np.zeros(3)
    normal[axis] = 1.0
    name = "xyz"[axis]
    plane = f"the ground plane {name} = {lowest:.6g} under the scene's lowest point receives"
    if besides:
        note = (
            f"shadows: none of the receivers found is a floor under the scene; {plane} too "
            "(--receiver DEF or --plane a,b,c,d chooses others)"
        )
    else:
        note = (
            "shadows: no receiver found (no large flat surface with something in front of "
            f"it); {plane} (--receiver DEF or --plane a,b,c,d chooses another)"
        )
    receiver = Receiver(
        Plane(normal, -lowest),
        "ground",
        two_sided=False,
        material=GROUND_MATERIAL,
        scopes=frozenset(),  # the ground is added at the top of the scene
    )
    return receiver, note


def bounds_the_scene(receiver: Receiver, bounds: np.ndarray) -> bool:
    """Whether a found ``receiver`` is a side of the scene's world box
    ``bounds``, turned inwards: its plane is within :data:`FLOOR_COSINE` of
    an axis, it lies within :data:`BOUNDING_FRACTION` of the box's extent of
    one of the box's faces across that axis, faces into the box (either way
    for a two-sided patch) and covers :data:`FLOOR_COVER` of that face. Such a
    patch is the scene's floor whichever axis is up: many VRML files exported
    from Z-up tools are read as Y-up.

    >>> tile = np.array([[[0, 0, 0], [2, 0, 0], [0, 0, 2]]], dtype=float)
    >>> wall = Receiver(Plane([0, 0, 1], 0.0), "wall", tile[..., [0, 2, 1]], area=2.0)
    >>> box = np.array([[0.0, 0.0, 0.0], [2.0, 2.0, 3.0]])
    >>> bounds_the_scene(wall, box), bounds_the_scene(wall, box - [0, 0, 1.5])
    (True, False)
    >>> wall.two_sided = False
    >>> bounds_the_scene(wall, box), bounds_the_scene(wall, box - [0, 0, 3])
    (True, False)
    """
    if receiver.triangles is None:
        return True
    normal = receiver.plane.normal
    k = int(np.argmax(np.abs(normal)))
    if abs(float(normal[k])) < FLOOR_COSINE:
        return False
    extent = bounds[1] - bounds[0]
    across = [j for j in range(3) if j != k]
    face = float(np.prod(extent[across]))
    if not receiver.area * abs(float(normal[k])) >= FLOOR_COVER * face:
        return False
    heights = receiver.triangles[..., k]
    near = BOUNDING_FRACTION * float(extent[k])
    inward_up = receiver.two_sided or normal[k] > 0
    inward_down = receiver.two_sided or normal[k] < 0
    return bool(
        (inward_up and float(heights.max() - bounds[0, k]) <= near)
        or (inward_down and float(bounds[1, k] - heights.min()) <= near)
    )


def is_floor(receiver: Receiver, bounds: np.ndarray, lowest: np.ndarray, axis: int) -> bool:
    """Whether a found ``receiver`` is a floor under the scene whose world box
    is ``bounds`` and whose lowest vertex is ``lowest``: it faces up (within
    :data:`FLOOR_COSINE`; either way for a two-sided patch) and either its
    highest point is within :data:`FLOOR_FRACTION` of the scene's height above
    the scene's lowest point, or it lies in the lower half of the scene and
    covers :data:`FLOOR_COVER` of the scene's plan or the lowest vertex in
    plan (a ground slab that a foundation, a basement or a sunken object
    reaches under: what lies below it is hidden by it).

    >>> tile = np.array([[[0, 0, 0], [2, 0, 0], [0, 0, 2]]], dtype=float)
    >>> floor = Receiver(Plane([0, 1, 0], 0.0), "floor", tile, two_sided=False, area=2.0)
    >>> box, under, aside = np.array([[0.0, 0, 0], [2, 4, 1]]), [0.5, 0, 0.5], [3, 0, 3]
    >>> [is_floor(floor, box + [0, dy, 0], under, 1) for dy in (0, -0.5, -1, -2, -3)]
    [True, True, True, True, False]
    >>> floor.area = 0.5  # a quarter of the plan
    >>> [is_floor(floor, box + [0, dy, 0], aside, 1) for dy in (0, -0.4, -0.5)]
    [True, True, False]
    >>> is_floor(floor, box + [0, -1, 0], under, 1)
    True
    """
    if receiver.triangles is None:
        return True  # an unbounded plane: it is the floor
    if bounds_the_scene(receiver, bounds):
        return True  # a floor, whichever way is up (a Z-up file read as Y-up)
    up = float(receiver.plane.normal[axis])
    if (abs(up) if receiver.two_sided else up) < FLOOR_COSINE:
        return False
    across = [k for k in range(3) if k != axis]
    height = float(bounds[1, axis] - bounds[0, axis])
    above = float(receiver.triangles[..., axis].max() - bounds[0, axis])
    if above <= FLOOR_FRACTION * height:
        return True
    if above > 0.5 * height:
        return False
    plan = float(np.prod(bounds[1, across] - bounds[0, across]))
    if receiver.area * abs(up) >= FLOOR_COVER * plan:
        return True
    corners = receiver.triangles[..., across].reshape(-1, 2)
    point = np.asarray(lowest, dtype=np.float64)[across]
    return bool(np.all(corners.min(axis=0) <= point) and np.all(point <= corners.max(axis=0)))


def select(
    scene: Scene,
    geometry: list[Shape],
    names: Sequence[str] | None,
    plane: Plane | ArrayLike | None,
    tolerance: Tolerance,
    stacked: CasterSet | None = None,
    ground_fallback: bool = True,
) -> tuple[list[Receiver], list[str]]:
    """The receivers for :func:`shadowgeo.add_shadows` (see the module notes):
    a given plane, the named shapes' patches, or the patches found; with the
    notes on the search (only a search notes anything). ``stacked``: the
    geometry's :class:`~.casters.CasterSet`, when the caller has it (its
    world vertices and boxes are reused). ``ground_fallback``: when no patch
    is found, the ground plane (:func:`ground`), else none."""
    if plane is not None:
        return [given_plane(plane)], []
    if names is not None:
        return named(scene, geometry, names, tolerance), []
    return found(scene, geometry, tolerance, stacked, ground_fallback)


def given_plane(plane: Plane | ArrayLike) -> Receiver:
    """An unbounded plane, lit from either side."""
    if not isinstance(plane, Plane):
        plane = Plane.from_coefficients(plane)
    return Receiver(plane, "plane")


def _patch_receiver(
    shape: Shape,
    world_vertices: np.ndarray,
    fitted: Plane,
    member: np.ndarray,
    area: float,
    count: int,
) -> Receiver:
    name = safe_name(shape.name) if shape.name else "shape"
    return Receiver(
        fitted,
        name if count == 0 else f"{name}_{count + 1}",
        world_vertices[shape.faces[member]],
        two_sided=not shape.solid,
        area=area,
        material=shape.material,
        scopes=shape.scopes,
    )


def named(
    scene: Scene, geometry: list[Shape], names: Sequence[str], tolerance: Tolerance
) -> list[Receiver]:
    """The patches of the named shapes (every instance of a USEd one) of at
    least ``AREA_FRACTION`` of each shape's largest patch."""
    by_name: dict[str, list[Shape]] = {}
    for shape in geometry:
        if shape.name:
            by_name.setdefault(shape.name, []).append(shape)  # USEd: every instance
    result = []
    for name in names:
        if name not in by_name:
            raise SceneError(f"no shape named '{name}' to receive shadows", path=scene.path)
        count = 0
        for shape in by_name[name]:
            world_vertices = shape.world_vertices
            flat = patches(shape, tolerance, world_vertices)
            total = sum(area for _, _, area in flat)
            if not flat or flat[0][2] < NAMED_FRACTION * total:
                share = flat[0][2] / total if flat and total else 0.0
                raise GeometryError(
                    f"receiver '{name}' is not planar: its largest flat part is "
                    f"{100 * share:.3g}% of its area (tolerance "
                    f"{tolerance.coplanar_length:.3g}); give a plane instead"
                )
            for patch in flat:
                if patch[2] >= AREA_FRACTION * flat[0][2]:
                    result.append(_patch_receiver(shape, world_vertices, *patch, count))
                    count += 1
    return result


def _anything_in_front(
    plane: Plane, stacked: CasterSet, tolerance: Tolerance, two_sided: bool
) -> bool:
    """Is any vertex of the scene farther than the coplanar length in front of
    ``plane`` (either side when ``two_sided``)? Decided from the shapes'
    bounding boxes where they settle it (a box wholly in front, or none
    reaching out), so that a scene of many shapes costs a pass over the boxes
    per patch, not over every vertex."""
    limit = tolerance.coplanar_length
    height = plane.signed_distance(stacked.box_corners.reshape(-1, 3)).reshape(-1, 8)
    sides = [height] if not two_sided else [height, -height]
    for side in sides:
        if np.any(side.min(axis=1) > limit):
            return True  # a whole box, so every vertex in it, is in front
    reaching = np.zeros(len(height), dtype=bool)
    for side in sides:
        reaching |= side.max(axis=1) > limit
    for index in np.flatnonzero(reaching):
        vertices = stacked.casters[int(index)].vertices
        distance = plane.signed_distance(vertices)
        if two_sided:
            distance = np.abs(distance)
        if np.any(distance > limit):
            return True
    return False


class _Candidate(NamedTuple):
    """A flat patch large enough to receive: its shape, the shape's world
    vertices, its plane, its faces (a mask) and its area."""

    shape: Shape
    world_vertices: np.ndarray
    fitted: Plane
    member: np.ndarray
    area: float


def _candidates(
    geometry: list[Shape], stacked: CasterSet, tolerance: Tolerance
) -> list[_Candidate]:
    """The patches at least ``SIZE_FRACTION`` of the scene's diagonal across
    with something in front of them, in the scene's order."""
    bounds = stacked.bounds
    scene_size = float(np.linalg.norm(bounds[1] - bounds[0]))
    diagonals = np.linalg.norm(stacked.high - stacked.low, axis=1)
    candidates = []
    searched = np.flatnonzero(diagonals >= SIZE_FRACTION * scene_size)
    searched = searched[may_hold_patch(stacked, searched, SIZE_FRACTION * scene_size, tolerance)]
    for index in searched:
        shape, world_vertices = geometry[index], stacked.casters[index].vertices
        for fitted, member, area in patches(shape, tolerance, world_vertices):
            points = world_vertices[unique_integers(shape.faces[member])]
            low, high = bounding_box(points)
            size = float(np.linalg.norm(high - low))
            if size < SIZE_FRACTION * scene_size:
                continue
            if _anything_in_front(fitted, stacked, tolerance, two_sided=not shape.solid):
                candidates.append(_Candidate(shape, world_vertices, fitted, member, area))
    return candidates


def _largest_receivers(qualify: list[_Candidate]) -> list[Receiver]:
    """At most ``MAX_FOUND`` of the patches ``qualify``, the largest, as
    receivers in the scene's order, numbered within their shape."""
    # the largest first (a stable sort keeps the scene's order among equals)
    ranked = sorted(range(len(qualify)), key=lambda k: -qualify[k].area)[:MAX_FOUND]
    counts: dict[int, int] = {}
    result = []
    for k in sorted(ranked):
        shape, world_vertices, fitted, member, area = qualify[k]
        count = counts.get(id(shape), 0)
        counts[id(shape)] = count + 1
        result.append(_patch_receiver(shape, world_vertices, fitted, member, area, count))
    return result


def found(
    scene: Scene,
    geometry: list[Shape],
    tolerance: Tolerance,
    stacked: CasterSet | None = None,
    ground_fallback: bool = True,
) -> tuple[list[Receiver], list[str]]:
    """The patches found automatically (see the module notes), or the ground
    (none when not ``ground_fallback``); with the notes on what was found.

    World vertices are computed once per shape, and a shape whose bounding
    box is smaller than a found receiver must be (``SIZE_FRACTION`` of the
    scene's diagonal) is skipped before any per-triangle work: its patches,
    subsets of its vertices, cannot be larger than its box.
    """
    if stacked is None:
        stacked = CasterSet(geometry)
    bounds = stacked.bounds
    candidates = _candidates(geometry, stacked, tolerance)
    largest = max((candidate.area for candidate in candidates), default=0.0)
    qualify = [item for item in candidates if item.area >= AREA_FRACTION * largest]
    result = _largest_receivers(qualify)
    if not result:
        if not ground_fallback:
            return [], []
        ground_plane, note = ground(scene, geometry, bounds)
        return [ground_plane], [note]
    notes = ["shadows: receivers found: " + ", ".join(r.name for r in result)]
    if len(qualify) > MAX_FOUND:
        notes.append(
            f"shadows: {len(qualify) - MAX_FOUND} more flat surfaces qualify as receivers; "
            f"the {MAX_FOUND} largest receive (--receiver DEF names others)"
        )
    axis = scene.up_index
    lowest = stacked.vertices[int(np.argmin(stacked.vertices[:, axis]))]
    if ground_fallback and not any(is_floor(r, bounds, lowest, axis) for r in result):
        ground_plane, note = ground(scene, geometry, bounds, besides=result)
        result.append(ground_plane)
        notes.append(note)
    return result, notes
