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
  (:func:`may_hold_patch`);
* named (``--receiver DEF``): the named shape's patches of at least a quarter
  of its largest patch's area; its largest patch must cover at least a tenth
  of the shape's area, else it is not planar;
* a plane ``a x + b y + c z + d = 0``: unbounded, lit from either side;
* when none is found: the ground plane under the scene's lowest point (along
  its up axis), unbounded, lit from above, with a note. The ground plane also
  receives, besides those found, when none of them is a floor under the scene
  (:func:`is_floor`): a car's flat hood or a facade's wall is found, but the
  shadow a reader looks for is the one on the ground.

A patch of a ``solid`` shape receives only on its front (the side its
triangles face, as a renderer culls the back); a patch of a ``solid="false"``
shape receives on whichever side a light is on.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..boxes import bounding_box
from ..errors import GeometryError, SceneError
from ..lights import Light, is_positional
from ..plane import Plane
from ..tolerance import Tolerance
from ..topology import point_ids, row_groups, unique_integers
from .casters import CasterSet
from .model import Scene, Shape, safe_name

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
# Side of the cells of the normal histogram (unit-normal components), and the
# faces binned per pass (bounds its memory).
_NORMAL_CELL = 1.0 / 16.0
_FACES_PER_PASS = 1 << 19


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
    """

    plane: Plane
    name: str
    triangles: np.ndarray | None = None
    two_sided: bool = True
    area: float = float("inf")

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
    notes: list[str],
    bounds: np.ndarray | None = None,
    besides: Sequence[Receiver] = (),
) -> Receiver:
    """The unbounded ground plane through the lowest point of the geometry
    (height along the scene's up axis), facing up, with a note: the receiver
    when none is found, or when those found (``besides``) hold no floor under
    the scene. ``bounds``: the geometry's world box, when known."""
    axis = scene.up_index
    if bounds is None and geometry:
        bounds = bounding_box(np.concatenate([shape.world_vertices for shape in geometry]))
    lowest = float(bounds[0, axis]) if bounds is not None else 0.0
    normal = np.zeros(3)
    normal[axis] = 1.0
    name = "xyz"[axis]
    plane = f"the ground plane {name} = {lowest:.6g} under the scene's lowest point receives"
    if besides:
        notes.append(
            f"shadows: none of the receivers found is a floor under the scene; {plane} too "
            "(--receiver DEF or --plane a,b,c,d chooses others)"
        )
    else:
        notes.append(
            "shadows: no receiver found (no large flat surface with something in front of "
            f"it); {plane} (--receiver DEF or --plane a,b,c,d chooses another)"
        )
    return Receiver(Plane(normal, -lowest), "ground", two_sided=False)


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
    notes: list[str],
    stacked: CasterSet | None = None,
    ground_fallback: bool = True,
) -> list[Receiver]:
    """The receivers for :func:`shadowgeo.add_shadows` (see the module notes):
    a given plane, the named shapes' patches, or the patches found.
    ``stacked``: the geometry's :class:`~.casters.CasterSet`, when the caller
    has it (its world vertices and boxes are reused). ``ground_fallback``:
    when no patch is found, the ground plane (:func:`ground`), else none."""
    if plane is not None:
        return [given_plane(plane)]
    if names is not None:
        return named(scene, geometry, names, tolerance)
    return found(scene, geometry, tolerance, notes, stacked, ground_fallback)


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


def may_hold_patch(
    stacked: CasterSet, indices: np.ndarray, size: float, tolerance: Tolerance
) -> np.ndarray:
    """(len(indices),) bool: False for a shape none of whose flat patches
    (:func:`patches`) can reach ``size`` across. Decided from a histogram of
    its face normals, before any per-patch work (a sphere has no large flat
    part: each of its patches is a face or two).

    A patch's faces all lie within ``coplanar_length`` of its seed face's
    plane. A face whose smallest height is ``w`` turns by at most an angle
    ``t`` with ``sin t <= 2 coplanar_length / w`` from that plane, so its unit
    normal (or its opposite) lies within ``pi coplanar_length / w`` of the
    seed's, and its plane's offset (from the middle of the faces, ``R`` away
    at most) within ``R`` times that plus ``coplanar_length`` of the seed's.
    Faces with ``w`` large enough that the turn is below half a cell of the
    histogram (cells of direction and offset) fall in the cells next to the
    seed's; thinner faces (and degenerate ones) may join any patch. A patch
    therefore lies in the box of the faces binned in the 81 cells around its
    seed's plus the thin faces, and a shape where every such box is smaller
    than ``size`` is skipped:
    exactly the shapes whose patches :func:`found` would all have dropped.
    """
    keep = np.zeros(len(indices), dtype=bool)
    limit = tolerance.coplanar_length
    cell = _NORMAL_CELL
    width = 2.0 * np.pi * limit / cell
    side = int(np.ceil(1.0 / cell))  # cells from the middle to a side, each axis
    offsets = np.array(
        [
            (i, j, k, m)
            for i in (-1, 0, 1)
            for j in (-1, 0, 1)
            for k in (-1, 0, 1)
            for m in (-1, 0, 1)
        ],
        dtype=np.int64,
    )
    counts = stacked.face_counts[indices]
    # A big shape is first tried by its normals' cells alone (no offsets, no
    # sort): a sphere of a million faces is ruled out in one pass.
    coarse = np.flatnonzero(counts >= _COARSE_FACES)
    ruled_out = np.zeros(len(indices), dtype=bool)
    for k in coarse.tolist():
        ruled_out[k] = not _normal_bound(stacked, int(indices[k]), size, limit)
    remaining = np.flatnonzero(~ruled_out)
    indices, counts = indices[remaining], counts[remaining]
    start = 0
    while start < len(indices):
        stop = start + 1
        total = counts[start]
        while stop < len(indices) and total + counts[stop] <= _FACES_PER_PASS:
            total += counts[stop]
            stop += 1
        chunk = np.arange(start, stop)
        keep[remaining[chunk]] = _patch_bound(
            stacked, indices[chunk], size, limit, width, side, offsets
        )
        start = stop
    return keep


def _normal_bound(stacked: CasterSet, index: int, size: float, limit: float) -> bool:
    """Whether shape ``index`` may hold a patch ``size`` across, by a bound
    coarser than :func:`_patch_bound`'s and with no sort: faces binned by
    their unit normal in cells of side ``_COARSE_CELL`` and by their plane's
    offset in levels of ``band``, each cell's box accumulated in a dense grid.

    With ``C = _COARSE_CELL``, a face is sharp here when its smallest height
    ``w`` is at least ``2 pi limit / C``. A sharp member of a patch turns
    from the seed's plane by ``t`` with ``sin t <= 2 limit / w <= C / pi``
    (:func:`may_hold_patch`), so two sharp members' unit normals differ by
    less than ``2 asin(C / pi) < C`` in each component, or their opposites
    do, and their offsets (from the middle of the shape's box, ``R`` away at
    most) by less than ``R 2 asin(C / pi) + 2 limit < band``. Take any sharp
    member's cell ``c``: every other sharp member lies in the cells within
    one of ``c``, or within one of the cell of its opposite normal and
    offset, which is the mirrored cell (the grid flipped along each axis) or
    the one before it along an axis (a value on a cell's edge mirrors to an
    edge), so within two of the mirror of ``c``. The patch therefore lies in
    the box of those cells and of the thin faces; a patch with no sharp face
    lies in the thin faces' box. A shape where all such boxes are smaller
    than ``size`` has no patch that large.

    Most faces are filed a run of ``_CHUNK`` at a time (:meth:`_Cells.runs`):
    a run whose faces all fall within two cells along each axis is filed
    under each of those cells with the run's box, which holds each face's;
    every cell a face would be filed under then holds a box at least as
    large, so the bound stands (a cell filed with no face of its own only
    adds boxes to look at)."""
    start, count = int(stacked.face_starts[index]), int(stacked.face_counts[index])
    low_box, high_box = stacked.low[index], stacked.high[index]
    middle = 0.5 * (low_box + high_box)
    radius = float(np.sqrt(((high_box - low_box) ** 2).sum())) / 2.0
    cell = _COARSE_CELL
    band = cell * radius * (1.0 + 1e-9) + 2.0 * limit
    if not (np.isfinite(band) and band > 0):
        return True
    side = int(np.ceil(1.0 / cell))
    levels = int(np.ceil(radius / band))
    span, depth = 2 * side + 3, 2 * levels + 3  # an empty cell past each end
    grid_low = np.full((3, depth * span**3), np.inf)
    grid_high = np.full((3, depth * span**3), -np.inf)
    loose_low = np.full(3, np.inf)
    loose_high = np.full(3, -np.inf)
    faces = stacked.faces[start : start + count]
    # the face normals, kept for the casters' mesh of the first light
    normals = stacked.normal_rows(index)
    used_low, used_high = [np.inf] * 3, [-np.inf] * 3  # the box of the faces' corners
    cells = _Cells(
        scales=(1.0 / cell, 1.0 / cell, 1.0 / cell, 1.0 / band),
        bounds=(side, side, side, levels),
        weights=(1, span, span * span, span**3),
        width=2.0 * np.pi * limit / cell,
    )
    records: list[_Records] = []
    for first in range(0, count, _BIN_BLOCK):
        stop = first + _BIN_BLOCK
        corners, normal = _corner_normals(faces[first:stop], stacked.columns, normals[first:stop])
        low = [np.minimum(np.minimum(a, b), c) for a, b, c in corners]
        high = [np.maximum(np.maximum(a, b), c) for a, b, c in corners]
        doubled = np.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            unit = [axis / doubled for axis in normal]
            height = sum(
                u * (a - m) for u, (a, _, _), m in zip(unit, corners, middle.tolist(), strict=True)
            )
        values = [*unit, height]
        whole, runs = cells.runs(low, high, values, doubled, size)
        records.append(runs)
        for axis in range(3):
            used_low[axis] = min(used_low[axis], float(low[axis].min()))
            used_high[axis] = max(used_high[axis], float(high[axis].max()))
        if whole.all():
            continue
        # the other runs' faces one by one, each under its own cell
        rest = np.flatnonzero(np.repeat(~whole, _CHUNK)[: len(doubled)])
        low, high = [x[rest] for x in low], [x[rest] for x in high]
        values, doubled = [x[rest] for x in values], doubled[rest]
        with np.errstate(invalid="ignore", over="ignore"):
            binned = np.isfinite(values[0]) & np.isfinite(values[1]) & np.isfinite(values[2])
            sharp = binned & (doubled > 0) & (doubled >= cells.width * _diagonal(low, high))
        if not sharp.all():
            loose = ~sharp
            for axis in range(3):
                loose_low[axis] = min(loose_low[axis], float(low[axis][loose].min()))
                loose_high[axis] = max(loose_high[axis], float(high[axis][loose].max()))
            chosen = np.flatnonzero(sharp)
            if not len(chosen):
                continue
            low, high = [x[chosen] for x in low], [x[chosen] for x in high]
            values = [x[chosen] for x in values]
        records.append(cells.faces(low, high, values))
    for offset, at, box_low, box_high in _Records.filed(records, cells.weights):
        for axis in range(3):
            np.minimum.at(grid_low[axis], at + offset, box_low[axis])
            np.maximum.at(grid_high[axis], at + offset, box_high[axis])
    stacked.normals_known(index, np.array([used_low, used_high]))
    shape = (3, depth, span, span, span)
    grid_low, grid_high = grid_low.reshape(shape), grid_high.reshape(shape)
    occupied = np.nonzero(np.isfinite(grid_low[0]))
    # the mirror of each occupied cell (the grid flipped along each axis)
    mirrored = tuple(length - 1 - at for length, at in zip(shape[1:], occupied, strict=True))
    near_low = np.minimum(
        _window_at(grid_low, 1, np.minimum, occupied, occupied),
        _window_at(grid_low, 2, np.minimum, occupied, mirrored),
    )
    near_high = np.maximum(
        _window_at(grid_high, 1, np.maximum, occupied, occupied),
        _window_at(grid_high, 2, np.maximum, occupied, mirrored),
    )
    near_low = np.minimum(near_low, loose_low[:, None])
    near_high = np.maximum(near_high, loose_high[:, None])
    with np.errstate(invalid="ignore", over="ignore"):
        reach = np.sqrt(((near_high - near_low) ** 2).sum(axis=0))
        loose_reach = float(np.sqrt(((loose_high - loose_low) ** 2).sum()))
    if np.any(~(reach < size * (1.0 - 1e-9))):  # NaN or inf: keep the shape
        return True
    return bool(np.isfinite(loose_low).all() and not loose_reach < size * (1.0 - 1e-9))


def _window_at(
    grid: np.ndarray,
    reach: int,
    pick: np.ufunc,
    occupied: tuple[np.ndarray, ...],
    cells: tuple[np.ndarray, ...],
) -> np.ndarray:
    """(rows, k) :func:`_window` of ``grid`` at the ``cells`` (index arrays,
    one per cell axis), its ``occupied`` cells given (every other cell holds
    ``pick``'s identity, inf or -inf): the window is taken over the box of
    the occupied cells and ``reach`` around it only, and a cell beyond that
    box has no occupied cell within reach."""
    empty = np.inf if pick is np.minimum else -np.inf
    if not len(occupied[0]):
        return np.full((grid.shape[0], len(cells[0])), empty)
    starts = [max(int(at.min()) - reach, 0) for at in occupied]
    stops = [
        min(int(at.max()) + reach + 1, length)
        for at, length in zip(occupied, grid.shape[1:], strict=True)
    ]
    crop = (slice(None), *(slice(a, b) for a, b in zip(starts, stops, strict=True)))
    window = _window(grid[crop], reach, pick)
    inside = np.ones(len(cells[0]), dtype=bool)
    for at, a, b in zip(cells, starts, stops, strict=True):
        inside &= (at >= a) & (at < b)
    result = np.full((grid.shape[0], len(inside)), empty)
    local: tuple[slice | np.ndarray, ...] = (
        slice(None),
        *(at[inside] - a for at, a in zip(cells, starts, strict=True)),
    )
    result[:, inside] = window[local]
    return result


def _window(grid: np.ndarray, reach: int, pick: np.ufunc) -> np.ndarray:
    """``pick`` (minimum or maximum) of the cells of ``grid`` (a leading axis
    of rows, then the cells' axes) within ``reach`` cells of each cell along
    every axis, row by row."""
    result = grid
    for axis in range(1, grid.ndim):
        out = result.copy()
        length = result.shape[axis]
        for shift in range(1, reach + 1):
            ahead = [slice(None)] * grid.ndim
            behind = [slice(None)] * grid.ndim
            ahead[axis], behind[axis] = slice(shift, length), slice(0, length - shift)
            pick(out[tuple(behind)], result[tuple(ahead)], out=out[tuple(behind)])
            pick(out[tuple(ahead)], result[tuple(behind)], out=out[tuple(ahead)])
        result = out
    return result


@dataclasses.dataclass(frozen=True)
class _Records:
    """Boxes filed under cells of :func:`_normal_bound`'s grid: ``cells``
    (k,) each box's lowest cell, ``spans`` (k,) a bit per axis of the four
    (normal x, y, z, offset) along which it is filed under the next cell
    too, and the boxes' ``low`` and ``high`` columns."""

    cells: np.ndarray
    spans: np.ndarray
    low: _Columns
    high: _Columns

    @staticmethod
    def filed(
        records: list[_Records], weights: tuple[int, ...]
    ) -> Iterator[tuple[int, np.ndarray, _Columns, _Columns]]:
        """Every ``(offset, cells, low, high)`` to file, for each of the 16
        ways of stepping to the next cell along some of the axes: the boxes
        spanning those axes, under their lowest cell plus ``offset``."""
        if not records:
            return
        cells = np.concatenate([r.cells for r in records])
        spans = np.concatenate([r.spans for r in records])
        low = [np.concatenate([r.low[axis] for r in records]) for axis in range(3)]
        high = [np.concatenate([r.high[axis] for r in records]) for axis in range(3)]
        for step in range(16):
            at = np.flatnonzero((spans & step) == step) if step else np.arange(len(cells))
            if len(at):
                offset = sum(weights[k] for k in range(4) if step >> k & 1)
                yield offset, cells[at], [x[at] for x in low], [x[at] for x in high]


@dataclasses.dataclass(frozen=True)
class _Cells:
    """The cells of :func:`_normal_bound`'s grid along its four axes (a
    face's unit normal x, y and z, and its plane's offset): ``scales``,
    the inverse cell sides; ``bounds``, the highest cell each way (values
    past it are clipped to it); ``weights``, each axis's step in a cell's
    number; ``width``, the smallest height of a sharp face."""

    scales: tuple[float, ...]
    bounds: tuple[int, ...]
    weights: tuple[int, ...]
    width: float

    @property
    def base(self) -> int:
        """The number of the cell of all values 0 (cells count from an empty
        one below each axis's lowest)."""
        return sum((b + 1) * w for b, w in zip(self.bounds, self.weights, strict=True))

    def runs(
        self,
        low: _Columns,
        high: _Columns,
        values: _Columns,
        doubled: np.ndarray,
        size: float,
    ) -> tuple[np.ndarray, _Records]:
        """Runs of ``_CHUNK`` consecutive faces (a mesh's faces mostly follow
        each other across its surface) filed whole: the run's box under every
        cell its faces' values (the four axes' columns) may fall in, where
        that is a cell or two along each axis, every face is sharp by the
        run's box (a face's diagonal is at most the run's) and the run is
        small beside ``size``. Returns (runs,) bool, the runs taken whole, and
        their records; ``low``, ``high``: the faces' boxes, ``doubled``:
        twice their areas."""
        starts = np.arange(0, len(doubled), _CHUNK)
        box_low = [_runs_reduced(np.minimum, x, starts) for x in low]
        box_high = [_runs_reduced(np.maximum, x, starts) for x in high]
        with np.errstate(invalid="ignore", over="ignore"):
            diagonal = _diagonal(box_low, box_high)
            least = _runs_reduced(np.minimum, doubled, starts)
            whole = (least > 0) & (least >= self.width * diagonal)
            whole &= diagonal <= size * _CHUNK_REACH
            whole &= _runs_reduced(np.maximum, doubled, starts) < np.inf
            cells = np.full(len(starts), self.base, dtype=np.int64)
            spans = np.zeros(len(starts), dtype=np.int64)
            for k, (column, scale, bound) in enumerate(
                zip(values, self.scales, self.bounds, strict=True)
            ):
                a = np.floor(_runs_reduced(np.minimum, column, starts) * scale)
                b = np.floor(_runs_reduced(np.maximum, column, starts) * scale)
                whole &= b - a <= 1  # False for NaN
                np.clip(a, -bound, bound, out=a)
                np.clip(b, -bound, bound, out=b)
                a[~whole] = 0  # (runs not taken: any whole number)
                cells += a.astype(np.int64) * self.weights[k]
                spans |= (b > a).astype(np.int64) << k
        taken = np.flatnonzero(whole)
        return whole, _Records(
            cells[taken], spans[taken], [x[taken] for x in box_low], [x[taken] for x in box_high]
        )

    def faces(self, low: _Columns, high: _Columns, values: _Columns) -> _Records:
        """Sharp faces each filed under its own cell, runs of faces in one
        cell reduced first (each run's box filed once)."""
        key = np.full(len(values[0]), float(self.base))
        for column, scale, bound, weight in zip(
            values, self.scales, self.bounds, self.weights, strict=True
        ):
            bin_ = np.floor(column * scale)
            np.clip(bin_, -bound, bound, out=bin_)
            bin_ *= weight
            key += bin_  # whole numbers, exact in floats
        cells = key.astype(np.int64)
        runs = np.flatnonzero(np.concatenate([[True], cells[1:] != cells[:-1]]))
        return _Records(
            cells[runs],
            np.zeros(len(runs), dtype=np.int64),
            [np.minimum.reduceat(x, runs) for x in low],
            [np.maximum.reduceat(x, runs) for x in high],
        )


def _diagonal(low: _Columns, high: _Columns) -> np.ndarray:
    """The diagonals of boxes given by their ``low`` and ``high`` columns."""
    extent = [b - a for a, b in zip(low, high, strict=True)]
    result: np.ndarray = np.sqrt(
        extent[0] * extent[0] + extent[1] * extent[1] + extent[2] * extent[2]
    )
    return result


def _patch_bound(
    stacked: CasterSet,
    indices: np.ndarray,
    size: float,
    limit: float,
    width: float,
    side: int,
    offsets: np.ndarray,
) -> np.ndarray:
    """:func:`may_hold_patch` of the shapes ``indices``, a block of faces at a
    time: each block's faces binned and their boxes reduced per cell, then
    the cells of all blocks merged (the temporaries stay a few MB however
    large the shape)."""
    count = len(indices)
    rows = np.concatenate(
        [np.arange(stacked.face_starts[i], stacked.face_starts[i] + stacked.face_counts[i])
         for i in indices.tolist()]
    )  # fmt: skip
    owner = np.repeat(np.arange(count), stacked.face_counts[indices])
    # Offsets from the middle of the shapes' boxes: every face (its
    # centroid) lies within ``radius`` of it, as the band below needs.
    low_all, high_all = stacked.low[indices].min(axis=0), stacked.high[indices].max(axis=0)
    middle = 0.5 * (low_all + high_all)
    radius = float(np.sqrt(((high_all - low_all) ** 2).sum())) / 2.0
    band = 0.5 * _NORMAL_CELL * radius * (1.0 + 1e-9) + 2.0 * limit
    if not np.isfinite(band) or band <= 0:
        band = np.inf
    levels = int(min(np.ceil(radius / band), 1 << 20)) if np.isfinite(band) else 0
    span = 2 * side + 3
    depth = 2 * levels + 3
    per_shape = span**3 * depth
    # thin and degenerate faces: members of any patch of their shape
    loose_low = np.full((count, 3), np.inf)
    loose_high = np.full((count, 3), -np.inf)
    cells: list[tuple[np.ndarray, _Columns, _Columns]] = []
    for start in range(0, len(rows), _BIN_BLOCK):
        block = rows[start : start + _BIN_BLOCK]
        holder = owner[start : start + _BIN_BLOCK]
        low, high, unit, height, binned, sharp = _face_bins(
            stacked.faces[block], stacked.columns, middle, width
        )
        loose = np.flatnonzero(~sharp)
        if len(loose):  # owners are non-decreasing: the shapes' faces follow each other
            held = holder[loose]
            runs = np.flatnonzero(np.concatenate([[True], held[1:] != held[:-1]]))
            for axis in range(3):
                np.minimum.at(
                    loose_low[:, axis], held[runs], np.minimum.reduceat(low[axis][loose], runs)
                )
                np.maximum.at(
                    loose_high[:, axis], held[runs], np.maximum.reduceat(high[axis][loose], runs)
                )
        chosen = np.flatnonzero(binned)
        if not len(chosen):
            continue
        # every face with a normal binned by it and by its opposite, and by
        # its plane's offset from the middle: a member's offset is within
        # (cell / 2) * reach + limit of its seed's
        keys = []
        for sign in (1.0, -1.0):
            code = holder[chosen] * per_shape
            for axis, weight in enumerate((1, span, span * span)):
                cell = np.floor(sign * unit[axis][chosen] / _NORMAL_CELL)
                code += (np.clip(cell, -side, side).astype(np.int64) + side + 1) * weight
            if levels:
                level = np.floor(sign * height[chosen] / band)
                code += (np.clip(level, -levels, levels).astype(np.int64) + levels + 1) * span**3
            else:
                code += span**3
            keys.append(code)
        cells.append(_cell_boxes(np.concatenate(keys), np.concatenate([chosen, chosen]), low, high))
    keep = np.zeros(count, dtype=bool)
    if cells:
        group_keys, group_low, group_high = cells[0]
        if len(cells) > 1:  # the blocks' cells merged: one box per cell
            group_keys = np.concatenate([keys for keys, _, _ in cells])
            group_low = [np.concatenate([c[1][axis] for c in cells]) for axis in range(3)]
            group_high = [np.concatenate([c[2][axis] for c in cells]) for axis in range(3)]
            everyone = np.arange(len(group_keys))
            group_keys, group_low, group_high = _cell_boxes(
                group_keys, everyone, group_low, group_high
            )
        box_low, box_high = np.column_stack(group_low), np.column_stack(group_high)
        group_owner = group_keys // per_shape
        near_low = loose_low[group_owner]
        near_high = loose_high[group_owner]
        for shift in offsets:
            wanted = group_keys + int(
                shift[0] + span * shift[1] + span * span * shift[2] + span**3 * shift[3]
            )
            at = np.minimum(np.searchsorted(group_keys, wanted), len(group_keys) - 1)
            hit = np.flatnonzero(group_keys[at] == wanted)
            near_low[hit] = np.minimum(near_low[hit], box_low[at[hit]])
            near_high[hit] = np.maximum(near_high[hit], box_high[at[hit]])
        with np.errstate(invalid="ignore", over="ignore"):
            reach = np.sqrt(((near_high - near_low) ** 2).sum(axis=1))
        large = ~(reach < size * (1.0 - 1e-9))  # NaN or inf: keep the shape
        keep[group_owner[large]] = True
    # a shape whose faces are all thin or degenerate has no sharp seed
    # cell; its patches lie within its loose box
    with np.errstate(invalid="ignore", over="ignore"):
        loose_reach = np.sqrt(((loose_high - loose_low) ** 2).sum(axis=1))
    keep |= np.isfinite(loose_low).all(axis=1) & ~(loose_reach < size * (1.0 - 1e-9))
    return keep


# Faces binned at a time by _patch_bound and _normal_bound.
_BIN_BLOCK = 1 << 14
# Shapes of this many faces or more are tried by _normal_bound first, with
# normal cells of this side (its grid: 19 x 19 x 19 cells by 19 levels).
_COARSE_FACES = 1 << 16
_COARSE_CELL = 1.0 / 8.0
# _normal_bound files runs of this many consecutive faces whole, when a run's
# box is at most _CHUNK_REACH of the size looked for across.
_CHUNK = 32
_CHUNK_REACH = 1.0 / 16.0
# x, y and z of points or vectors, one array each.
_Columns = list[np.ndarray]


def _face_bins(
    faces: np.ndarray,
    columns: np.ndarray,
    middle: np.ndarray,
    width: float,
    normals: np.ndarray | None = None,
) -> tuple[_Columns, _Columns, _Columns, np.ndarray, np.ndarray, np.ndarray]:
    """Per face of ``faces`` (rows of vertex indices into the coordinate
    ``columns``, (3, n)): its box (low and high columns), unit normal
    (columns), the offset of its plane from ``middle`` (through its first
    corner), whether it has a normal, and whether it is sharp (its smallest
    height at least ``width``, so that it turns from a patch's plane by less
    than half a cell). ``normals``, when given, (k, 3): the faces'
    unnormalised normals written into it, the numbers of
    :func:`shadowgeo.topology.block_normals`.

    A face is taken for sharp when twice its area is at least ``width``
    times its box's diagonal, which is at least its longest side: a face
    taken is sharp, and one on the edge counts as thin, which only widens a
    bound."""
    corners, normal = _corner_normals(faces, columns, normals)
    low = [np.minimum(np.minimum(a, b), c) for a, b, c in corners]
    high = [np.maximum(np.maximum(a, b), c) for a, b, c in corners]
    doubled = np.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        unit = [axis / doubled for axis in normal]
        binned = np.isfinite(unit[0]) & np.isfinite(unit[1]) & np.isfinite(unit[2])
        binned &= doubled > 0
        sharp = binned & (doubled >= width * _diagonal(low, high))
        height = sum(
            u * (a - m) for u, (a, _, _), m in zip(unit, corners, middle.tolist(), strict=True)
        )
    return low, high, unit, height, binned, sharp


def _runs_reduced(pick: np.ufunc, values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``pick`` (minimum or maximum) of each run of ``_CHUNK`` consecutive
    ``values`` (``starts``: every run's first), the last run perhaps shorter:
    ``pick.reduceat(values, starts)``, by halving the whole runs (twice as
    quick). NaN propagates, as it does through reduceat."""
    whole = len(values) // _CHUNK * _CHUNK
    if whole < len(values) or _CHUNK & (_CHUNK - 1):
        return pick.reduceat(values, starts)
    runs = values
    while len(runs) > len(starts):
        runs = pick(runs[0::2], runs[1::2])
    return runs


def _corner_normals(
    faces: np.ndarray, columns: np.ndarray, normals: np.ndarray | None = None
) -> tuple[list[_Columns], _Columns]:
    """The corners of ``faces`` (rows of vertex indices into the coordinate
    ``columns``, (3, n)), as ``corners[axis][corner]``, and their unnormalised
    normals (columns), by :func:`shadowgeo.topology.block_normals`'
    arithmetic; written into ``normals`` ((k, 3)) when given."""
    first, second, third = faces[:, 0], faces[:, 1], faces[:, 2]
    corners = [[column[first], column[second], column[third]] for column in columns]
    (ux, uy, uz), (vx, vy, vz) = ([b - a for a, b, _ in corners], [c - a for a, _, c in corners])
    normal = [uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx]
    if normals is not None:
        for axis in range(3):
            normals[:, axis] = normal[axis]
    return corners, normal


def _cell_boxes(
    keys: np.ndarray, faces: np.ndarray, low: _Columns, high: _Columns
) -> tuple[np.ndarray, _Columns, _Columns]:
    """The distinct ``keys`` (sorted) and the box of the boxes filed under
    each (box ``faces[i]`` of the columns ``low``, ``high`` under
    ``keys[i]``): a block's faces into cells, and the blocks' cells into one."""
    order = np.argsort(keys, kind="stable")
    keys, faces = keys[order], faces[order]
    starts = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
    box_low = [np.minimum.reduceat(column[faces], starts) for column in low]
    box_high = [np.maximum.reduceat(column[faces], starts) for column in high]
    return keys[starts], box_low, box_high


def found(
    scene: Scene,
    geometry: list[Shape],
    tolerance: Tolerance,
    notes: list[str],
    stacked: CasterSet | None = None,
    ground_fallback: bool = True,
) -> list[Receiver]:
    """The patches found automatically (see the module notes), or the ground
    (none when not ``ground_fallback``).

    World vertices are computed once per shape, and a shape whose bounding
    box is smaller than a found receiver must be (``SIZE_FRACTION`` of the
    scene's diagonal) is skipped before any per-triangle work: its patches,
    subsets of its vertices, cannot be larger than its box.
    """
    if stacked is None:
        stacked = CasterSet(geometry)
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
                candidates.append((shape, world_vertices, fitted, member, area))
    largest = max((area for *_, area in candidates), default=0.0)
    qualify = [item for item in candidates if item[-1] >= AREA_FRACTION * largest]
    # the largest first (a stable sort keeps the scene's order among equals)
    ranked = sorted(range(len(qualify)), key=lambda k: -qualify[k][-1])[:MAX_FOUND]
    counts: dict[int, int] = {}
    result = []
    for k in sorted(ranked):
        shape, world_vertices, fitted, member, area = qualify[k]
        count = counts.get(id(shape), 0)
        counts[id(shape)] = count + 1
        result.append(_patch_receiver(shape, world_vertices, fitted, member, area, count))
    if not result:
        return [ground(scene, geometry, notes, bounds)] if ground_fallback else []
    notes.append("shadows: receivers found: " + ", ".join(r.name for r in result))
    if len(qualify) > MAX_FOUND:
        notes.append(
            f"shadows: {len(qualify) - MAX_FOUND} more flat surfaces qualify as receivers; "
            f"the {MAX_FOUND} largest receive (--receiver DEF names others)"
        )
    axis = scene.up_index
    lowest = stacked.vertices[int(np.argmin(stacked.vertices[:, axis]))]
    if ground_fallback and not any(is_floor(r, bounds, lowest, axis) for r in result):
        result.append(ground(scene, geometry, notes, bounds, besides=result))
    return result
