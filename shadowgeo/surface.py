"""Shadows on every surface: the exact shadow on each face of a triangle mesh.

For every face of the receiving surface that turns its front to the light, the
shadow is the union of what every caster triangle strictly between the face
and the light hides, clipped to the face. :func:`shadow_on_surface` computes it
face by face, with the same clipping before the divide as
:func:`shadowgeo.project_shadow`:

1. **Index** (:mod:`shadowgeo.lightframe`): the bounding boxes of receiver
   faces and caster triangles *seen from the light* pair each face with the
   few triangles whose images overlap it.
2. **Clip**: each candidate triangle is cut, in homogeneous coordinates, to
   the region between the face and the light: the front of the face's plane
   and the three planes joining the light to the face's edges. That region
   holds no point with ``w <= 0`` but the light, so there are no anti-shadows
   and no division by zero, and what survives projects inside the face.
3. **Project and unite**: the clipped pieces are projected onto the face's
   plane, in its own 2-D frame, and united by winding number (Clipper2 through
   :mod:`shadowgeo.plane2d`; all faces in one call, each stretched into its
   own cell of one plane, or under a light with a range each face in a call
   of its own: one road, the layout chosen as data); spot cones and a
   light's range are applied as exact 2-D intersections.
4. **Stitch** (:mod:`shadowgeo.simplify`, :mod:`shadowgeo.seams`): corners
   that a straight run between two kept corners passes within the tolerance
   length of are dropped (where clipped pieces met along one shadow edge),
   region corners on a face edge are snapped to one parameter along that
   edge, shared by both faces, and every such point is inserted on both
   sides, so the triangulated shadow has no cracks or T-junctions where the
   surface has none.

Closed casters (the light outside them) contribute their light-facing
triangles only: every blocked ray leaves the caster through one of them last.
A closed caster wholly in front of a face, or resting on it (a building on
the ground, dipping below it by no more than rounding), needs no triangles at
all: its silhouette, projected once into the light's frame
(:class:`shadowgeo.outline.Outline`), is cut to the face's image there and
mapped back; faces wholly inside it are shadowed whole, and a face its edge
crosses is cut from the few edge segments near it (:meth:`Outline.cut`), so
the cost follows the outline's length near the surface, not faces x outline.
Under a point light a face reaching behind the light in the caster's frame is
first cut to the part deep enough for the caster to shade. All closed casters
of a light are handled together (:class:`shadowgeo.outline.OutlineSet`): their
outlines made, paired with faces and cut in a few numpy passes and one
Clipper2 call, not one Python call each.

:func:`shadow_layers_on_surface` takes groups of casters (of decreasing
opacity, in the scene converter) and gives one shadow per group, none
overlapping another: steps 1 to 3 run for each group in one frame, each
group's regions less the earlier groups' are cut face by face
(:func:`shadowgeo.seams.face_regions`), and then each is stitched.

Per-mesh work on the surface (merged vertices, normals, face frames, whether
it is a single sheet) is kept on the mesh (:func:`shadowgeo.sheets.surface_geometry`):
a second light or a second call pays only for what the light changes.

Cost: the index is O((F + T) log(F + T)) for F surface faces and T caster
triangles; the clipping is linear in the candidate pairs, about F times the
number of caster triangles whose images overlap one face's (for a surface
shadowing itself, its neighbours); the union and the stitching are linear in
the size of the shadow's outline.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, cast

import numpy as np
import shapely
from numpy.typing import ArrayLike

from . import plane2d as poly
from .bodies import Bodies, convex_bodies, light_bodies, ring_pieces
from .cells import column_cells
from .compiled import use_compiled
from .errors import GeometryError
from .lightframe import (
    candidate_pairs,
    clip_batch,
    corner_max,
    corner_min,
    misses_boxes,
    twice_areas,
)
from .lights import DirectionalLight, Light, PointLight, SpotLight, is_positional, require_light
from .limits import ANGLE_SLACK, MAX_CURVE_SEGMENTS, MAX_PIECE_PAIRS, RELATIVE_ROUNDING
from .outline import Outline, OutlineSet, make_outlines
from .seams import face_regions, stitch
from .sheets import SurfaceGeometry, face_frames, lift_directions, surface_geometry
from .silhouette import check_light_outside, light_homogeneous, silhouette_loops
from .simplify import Loops, without_collinear
from .tolerance import Tolerance
from .topology import Caster, MeshLike, as_caster, closed_each, loops_taken, unique_integers

if TYPE_CHECKING:
    import trimesh
    from manifold3d import CrossSection

__all__ = [
    "LightRegions",
    "SurfaceDiagnostics",
    "SurfaceShadow",
    "caster_list",
    "closed_silhouettes",
    "regions_per_light",
    "shadow_layers_on_surface",
    "shadow_on_surface",
    "shadowed_fractions",
]

# Candidate pairs clipped per batch: bounds the memory of the (pairs, 7, 4) arrays.
_BATCH = 200_000

# A closed caster's outline, its light-facing triangles (vertices, faces), and (its box
# half-sizes, its box centre, its bounding radius about that centre).
_Outlined = tuple[Outline, tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, float]]

# Polygons in face frames, (n, k, 2) padded by repeating the last corner, and
# (n,) the face of each.
_Pieces = tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class SurfaceDiagnostics:
    """What :func:`shadow_on_surface` did.

    Attributes
    ----------
    n_surface_faces : int
    n_lit_faces : int
        Surface faces that turn their front to the light (and that it reaches).
    n_caster_triangles : int
        Caster triangles considered (for a closed caster, its light-facing ones).
    n_candidate_pairs : int
        (face, triangle) pairs whose images overlap seen from the light.
    n_clipped_pairs : int
        Those with the triangle partly strictly in front of the face: clipped
        and projected.
    n_shadowed_faces : int
        Faces with a non-empty shadow.
    n_outlined_casters : int
        Closed casters handled by their outline seen from the light (for the
        faces they lie wholly in front of) rather than triangle by triangle.
    n_full_faces : int
        Faces found wholly inside such an outline.
    limits : tuple[str, ...]
        ``"spot_cone"``, ``"range"``: limits of the light applied per face.
    """

    n_surface_faces: int = 0
    n_lit_faces: int = 0
    n_caster_triangles: int = 0
    n_candidate_pairs: int = 0
    n_clipped_pairs: int = 0
    n_shadowed_faces: int = 0
    n_outlined_casters: int = 0
    n_full_faces: int = 0
    limits: tuple[str, ...] = ()


@dataclass(frozen=True)
class FaceRegions:
    """What the first steps found: each shadowed face's region (loops in
    its frame), the faces (sorted), (m,) bool the faces turned to the light,
    and the diagnostics so far."""

    regions: Loops
    faces: np.ndarray
    facing: np.ndarray
    diagnostics: SurfaceDiagnostics


@dataclass(frozen=True)
class SurfaceShadow:
    """The shadow cast on a triangle mesh.

    Attributes
    ----------
    light : Light
    vertices : (k, 3) float64
    faces : (t, 3) int64
        The shadow's triangles (``mesh`` is the same as a ``trimesh.Trimesh``,
        built on first use).
    mesh : trimesh.Trimesh
        The shadowed parts of the light-facing faces, as triangles lying in
        those faces (moved ``offset`` along each face's normal towards the
        light), wound as their faces, with no overlaps. Triangles of
        neighbouring faces share their vertices on the shared edge. With an
        offset, a point on an edge of two faces moves to where both faces'
        offset planes meet; at a mesh vertex where three or more faces meet
        at an angle, the triangles leave their offset planes by at most about
        ``offset`` times the square of the angle between the faces.
    face_index : (t,) int64
        For each triangle of ``mesh``, the surface face it lies in.
    fraction : (m,) float64
        The shadowed fraction of every surface face: the cast shadow on faces
        that turn their front to the light, 1.0 on faces turned away from it
        (or edge-on). Parts of a face the light does not reach (outside a spot
        light's cone, beyond its range) count as unshadowed, as in
        :func:`shadowgeo.project_shadow`.
    area : float
        Total area of the shadow.
    diagnostics : SurfaceDiagnostics
    """

    light: Light
    vertices: np.ndarray
    faces: np.ndarray
    face_index: np.ndarray
    fraction: np.ndarray
    area: float
    diagnostics: SurfaceDiagnostics
    _mesh: trimesh.Trimesh | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def mesh(self) -> trimesh.Trimesh:
        """``vertices`` and ``faces`` as a ``trimesh.Trimesh`` (built on
        first use: a caller that needs the arrays only, such as the scene
        converter, never imports trimesh)."""
        if self._mesh is None:
            import trimesh

            mesh = trimesh.Trimesh(self.vertices, self.faces, process=False)
            object.__setattr__(self, "_mesh", mesh)
        return cast("trimesh.Trimesh", self._mesh)

    @property
    def is_empty(self) -> bool:
        return self.area == 0.0


def shadow_on_surface(
    casters: MeshLike | Sequence[MeshLike],
    light: Light,
    surface: MeshLike,
    *,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
    not_shadowed_by: ArrayLike | None = None,
) -> SurfaceShadow:
    """The exact shadow that ``casters`` cast on every face of ``surface``.

    Parameters
    ----------
    casters : mesh or list of meshes
        Each a ``trimesh.Trimesh``, :class:`~shadowgeo.Caster` or
        ``(vertices, faces)``. Pass ``surface`` among them for it to shadow
        itself (a hill its valley, a torus its far side).
    light : PointLight, SpotLight or DirectionalLight
    surface : trimesh.Trimesh, Caster or (vertices, faces)
        Any triangle mesh: open or closed, flat, curved or jagged. Each face's
        winding gives its front.
    offset : float
        Lift of each shadow triangle along its face's normal, towards the
        light, so that it does not z-fight the surface.
    tolerance : Tolerance, optional
        Defaults to ``Tolerance.for_points`` of the casters, surface and light.
    not_shadowed_by : (m,) int array_like, optional
        For each face of ``surface``, the index in ``casters`` of one caster
        that does not shadow it (-1: every caster does). The scene converter
        uses it past a smooth shape's terminator, where the shape's own facets
        would shadow their neighbours (:mod:`shadowgeo.scene.terminator`).

    Returns
    -------
    SurfaceShadow
        Finite; for each light-facing face, the region hidden by caster
        triangles strictly between the face and the light, clipped to the
        face, triangulated without overlaps and without cracks along edges
        the faces share (corners a straight run passes within the
        tolerance length of dropped first: the region up to that length).

    Raises
    ------
    GeometryError
        Invalid input, a positional light touching a caster or inside a
        closed caster.

    Examples
    --------
    A unit square on the ground, half shadowed by a wall standing on it:

    >>> import numpy as np
    >>> from shadowgeo import DirectionalLight
    >>> ground = ([[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]], [[0, 1, 2], [0, 2, 3]])
    >>> wall = ([[0.5, 0, 1], [0.5, 0, -2], [0.5, 9, -2], [0.5, 9, 1]], [[0, 1, 2], [0, 2, 3]])
    >>> shadow = shadow_on_surface(wall, DirectionalLight([1, -1, 0]), ground)
    >>> round(shadow.area, 12), np.round(shadow.fraction, 12).tolist()
    (0.5, [0.75, 0.25])
    """
    (layer,) = shadow_layers_on_surface(
        [casters],
        light,
        surface,
        offset=offset,
        tolerance=tolerance,
        not_shadowed_by=not_shadowed_by,
    )
    return layer


def shadow_layers_on_surface(
    groups: Sequence[MeshLike | Sequence[MeshLike]],
    light: Light,
    surface: MeshLike,
    *,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
    not_shadowed_by: ArrayLike | None = None,
) -> list[SurfaceShadow]:
    """The shadows of groups of casters on ``surface`` as layers that do not
    overlap: the i-th is what :func:`shadow_on_surface` gives for
    ``groups[i]`` less, face by face, the shadows of every earlier group. A
    point of the surface is in the layer of the first group that hides it
    (casters of decreasing opacity: each point takes the darkness of the most
    opaque caster in front of it). One group is :func:`shadow_on_surface`.

    Parameters are those of :func:`shadow_on_surface`, ``groups`` a list of
    its ``casters`` (``not_shadowed_by`` numbers the casters of all groups in
    turn); each layer's ``fraction`` is the share of each face in
    that layer. Each layer is stitched on its own: a layer has no cracks, and
    two layers meet along a common edge up to the tolerance length.

    Examples
    --------
    Two walls on a unit square of ground; the second's shadow, over the
    first's on the square's right half, keeps the part the first leaves:

    >>> from shadowgeo import DirectionalLight
    >>> ground = ([[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]], [[0, 1, 2], [0, 2, 3]])
    >>> def wall(x):
    ...     return [[x, 0, 1], [x, 0, -2], [x, 9, -2], [x, 9, 1]], [[0, 1, 2], [0, 2, 3]]
    >>> first, second = shadow_layers_on_surface(
    ...     [wall(0.5), wall(0.25)], DirectionalLight([1, -1, 0]), ground
    ... )
    >>> round(first.area, 12), round(second.area, 12)
    (0.5, 0.25)
    """
    receiver, lists, every, offset, tolerance = _prepared(
        groups, [light], surface, offset, tolerance
    )
    exclude = None
    if not_shadowed_by is not None:
        exclude = np.asarray(not_shadowed_by, dtype=np.int64).reshape(-1)
        if len(exclude) != receiver.n_faces:
            raise GeometryError(
                f"not_shadowed_by has {len(exclude)} entries for {receiver.n_faces} surface faces"
            )
    # one frame for every layer: their regions are in the same face frames
    center = _center(every, receiver)
    layers = []
    covered: tuple[Loops, np.ndarray] | None = None  # the earlier layers' regions
    start = 0
    for group in lists:
        own_exclude = None
        if exclude is not None:  # the group's own numbering, -1 for another group's caster
            inside = (exclude >= start) & (exclude < start + len(group))
            own_exclude = np.where(inside, exclude - start, -1)
        start += len(group)
        projector = _SurfaceProjector(
            group, light, receiver, offset, tolerance, center, own_exclude
        )
        found = projector.regions()
        own = (found.regions, found.faces)
        if covered is not None:
            regions, faces = face_regions(own, covered, "subtract")
            found = replace(found, regions=regions, faces=faces)
        covered = own if covered is None else face_regions(covered, own, "unite")
        layers.append(projector.shadow(found))
    return layers


def shadowed_fractions(
    casters: MeshLike | Sequence[MeshLike],
    light: DirectionalLight,
    surface: MeshLike,
    *,
    tolerance: Tolerance | None = None,
    compiled: bool | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The share of each face of ``surface`` that ``casters`` shadow under
    the sun, without the shadow itself: (m,) fractions, 1 on faces turned
    away from the light, and (m,) bool, the faces turned to it.

    The same numbers as :func:`shadow_on_surface`'s ``fraction`` to about
    1e-12 of a face's area, from the area of the union of each face's convex
    pieces measured by compiled loops (:func:`shadowgeo.kernels.union_areas`),
    not a 2-D union and its triangles: for studies that need the hours of
    each face, not where on it the shadow lies. A convex closed body of a
    caster (a box of a city block, :mod:`shadowgeo.bodies`) casts one piece
    a face, the hull of its corners' images, made by compiled loops
    (:func:`shadowgeo.kernels.ring_pieces`), and a face one such piece holds
    whole is shadowed whole without more; other casters give their
    triangles' pieces (a closed one's light-facing triangles). Where a face
    has too many pieces for the loops (:data:`shadowgeo.limits.MAX_PIECE_PAIRS`
    pairs), the 2-D union measures it.

    ``compiled``: whether to take the compiled loops; None, the default: as
    :mod:`shadowgeo.compiled`'s rule says for the job ``"areas"`` of this
    surface's faces. Without them, :func:`shadow_on_surface`'s fractions
    (the same to rounding).
    """
    receiver, (group,), _, _, tolerance = _prepared([casters], [light], surface, 0.0, tolerance)
    if compiled is None:
        compiled = use_compiled("areas", receiver.n_faces)
    projector = _SurfaceProjector(group, light, receiver, 0.0, tolerance)
    return projector.fractions(compiled)


def _prepared(
    groups: Sequence[MeshLike | Sequence[MeshLike]],
    lights: Sequence[Light],
    surface: MeshLike,
    offset: float,
    tolerance: Tolerance | None,
) -> tuple[Caster, list[list[Caster]], list[Caster], float, Tolerance]:
    """The arguments checked: the surface and the casters (each group's and
    all) as :class:`Caster`, the offset, and the tolerance (default: of the
    casters, the surface and the positional lights)."""
    for light in lights:
        require_light(light)
    receiver = as_caster(surface)
    lists = [[as_caster(caster) for caster in caster_list(group)] for group in groups]
    every = [caster for group in lists for caster in group]
    _settle_casters(every)
    offset = float(offset)
    if not math.isfinite(offset):
        raise GeometryError(f"offset must be finite, got {offset!r}")
    positions = [light.position[None] for light in lights if is_positional(light)]
    if tolerance is None:
        boxes = [c.bounds for c in [*every, receiver] if c.n_faces]
        tolerance = Tolerance.for_points(*boxes, *positions)
    for position, caster in itertools.product(positions, every):
        if caster.n_faces:
            check_light_outside(caster, position[0], tolerance)
    return receiver, lists, every, offset, tolerance


@dataclass(frozen=True)
class LightRegions:
    """Each face's shadow region from each of several lights, in face frames
    all of them share (:func:`regions_per_light`), ready to be combined face
    by face and stitched back into a :class:`SurfaceShadow`.

    Attributes
    ----------
    found : list of FaceRegions
        For each light, its regions (:data:`~shadowgeo.simplify.Loops`, one
        region per face in ``faces``) and the faces turned to it.
    outlines : (m, 3, 2) float64
        Each surface face's corners in its own frame.
    """

    found: list[FaceRegions]
    outlines: np.ndarray
    stitcher: _SurfaceProjector = field(repr=False)

    def stitched(self, regions: Loops, faces: np.ndarray, facing: np.ndarray) -> SurfaceShadow:
        """Regions (one per face of ``faces``, sorted, in the face frames)
        stitched, triangulated and lifted as :func:`shadow_on_surface`'s;
        ``facing`` (m,) the faces whose ``fraction`` is measured (1.0 on the
        others)."""
        info = SurfaceDiagnostics(n_surface_faces=len(self.outlines))
        return self.stitcher.shadow(FaceRegions(regions, faces, facing, info))


def regions_per_light(
    casters: MeshLike | Sequence[MeshLike],
    lights: Sequence[Light],
    surface: MeshLike,
    *,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
) -> LightRegions:
    """Steps 1 to 3 of :func:`shadow_on_surface` for each of ``lights`` (the
    samples of a light with a size), every region in the same face frames;
    :meth:`LightRegions.stitched` is step 4. Arguments as
    :func:`shadow_on_surface`'s."""
    receiver, (every,), _, offset, tolerance = _prepared(
        [casters], lights, surface, offset, tolerance
    )
    center = _center(every, receiver)
    found = []
    projector = None
    for light in lights:
        projector = _SurfaceProjector(every, light, receiver, offset, tolerance, center)
        found.append(projector.regions())
    if projector is None:
        raise GeometryError("regions_per_light needs at least one light")
    corners = projector.vertices[projector.faces] - projector.origin[:, None]
    outlines = np.stack(
        [np.einsum("fij,fj->fi", corners, axis) for axis in (projector.u, projector.v)], axis=-1
    )
    return LightRegions(found, outlines, projector)


def _settle_casters(casters: list[Caster]) -> None:
    """Work out for many separate casters at once what each would work out
    alone when first asked: :attr:`Caster.is_closed` of those that do not
    know it yet, by one sort of all their edge keys
    (:func:`~shadowgeo.topology.closed_each`), and the boxes of the vertices
    their faces use (:attr:`Caster.bounds`), by one reduction."""
    with_faces = [caster for caster in casters if caster.n_faces]
    if len(with_faces) < 2:
        return
    unknown = [caster for caster in with_faces if not caster.closedness_known]
    if len(unknown) >= 2:
        found = closed_each([(caster.faces, len(caster.vertices)) for caster in unknown])
        if found is not None:
            for caster, closed in zip(unknown, found.tolist(), strict=True):
                caster.take_known(closed=closed)
    sizes = np.array([len(caster.vertices) for caster in with_faces], dtype=np.int64)
    starts = np.cumsum(sizes) - sizes
    used = np.zeros(int(sizes.sum()), dtype=bool)
    for caster, start in zip(with_faces, starts.tolist(), strict=True):
        used[caster.faces.reshape(-1) + start] = True
    vertices = np.concatenate([caster.vertices for caster in with_faces])
    low = np.where(used[:, None], vertices, np.inf)
    high = np.where(used[:, None], vertices, -np.inf)
    lows = np.minimum.reduceat(low, starts, axis=0)
    highs = np.maximum.reduceat(high, starts, axis=0)
    for k, caster in enumerate(with_faces):
        caster.take_known(bounds=np.array([lows[k], highs[k]]))


def caster_list(casters: MeshLike | Sequence[MeshLike]) -> list[MeshLike]:
    """A single mesh as a list of one; a list of meshes as it is."""
    if isinstance(casters, Caster) or hasattr(casters, "faces"):
        return [cast("MeshLike", casters)]
    if isinstance(casters, tuple | list) and len(casters) == 2:
        first = casters[0]
        if not (isinstance(first, Caster | tuple | list) or hasattr(first, "faces")):
            return [cast("MeshLike", casters)]  # (vertices array, faces)
        try:
            array = np.asarray(first, dtype=np.float64)
        except (TypeError, ValueError):
            array = None
        if array is not None and array.ndim == 2 and array.shape[1] == 3:
            return [cast("MeshLike", casters)]  # (vertices as nested lists, faces)
    if isinstance(casters, tuple | list):
        return list(casters)
    raise GeometryError(
        "casters must be a mesh (trimesh.Trimesh, Caster or (vertices, faces)) or a list "
        f"of meshes, got {type(casters).__name__}"
    )


@dataclass(frozen=True)
class _OutlinedPairs:
    """What closed casters' outlines leave: (face, triangle) pairs still to
    clip, the outline ``pieces`` on faces, and each caster's
    ``front_triangles`` (t, 3, 3)."""

    faces: np.ndarray
    triangles: np.ndarray
    pieces: list[_Pieces]
    front_triangles: list[np.ndarray]


class _SurfaceProjector:
    """One call of :func:`shadow_on_surface`."""

    # Set by _faces, in the frame centred on the scene's bounds.
    center: np.ndarray
    vertices: np.ndarray
    faces: np.ndarray
    face_area: np.ndarray
    unit: np.ndarray
    light_point: np.ndarray | None  # None for a directional light
    height: np.ndarray  # positional lights only
    cosine: np.ndarray  # directional lights only
    origin: np.ndarray
    u: np.ndarray
    v: np.ndarray
    geometry: SurfaceGeometry
    # Set by _caster_triangles: the index in casters of each triangle handled
    # one by one, and of each outlined caster.
    triangle_caster: np.ndarray
    outlined_caster: np.ndarray

    def __init__(
        self,
        casters: list[Caster],
        light: Light,
        surface: Caster,
        offset: float,
        tol: Tolerance,
        center: np.ndarray | None = None,
        exclude: np.ndarray | None = None,
    ) -> None:
        self.casters = casters
        self.given_center = center
        self.exclude = exclude  # (m,) per face: the caster that does not shadow it, or -1
        self.light = light
        self.surface = surface
        self.offset = offset
        self.tol = tol
        self.limits: list[str] = []

    def run(self) -> SurfaceShadow:
        return self.shadow(self.regions())

    def regions(self) -> FaceRegions:
        """Each face's shadow region, in its face's frame (step 1 to 3)."""
        corners, facing, lit = self._faces()
        receivers, triangles, caster_triangles, full, extra, counts = self._pairs(corners, lit)
        regions, region_faces = self._regions(
            receivers, triangles, caster_triangles, corners, full, extra
        )
        info = SurfaceDiagnostics(
            n_surface_faces=self.surface.n_faces,
            n_lit_faces=int(lit.sum()),
            n_caster_triangles=len(caster_triangles),
            n_candidate_pairs=counts[0],
            n_clipped_pairs=len(receivers),
            n_outlined_casters=counts[1],
            n_full_faces=int(full.sum()),
            limits=tuple(self.limits),
        )
        return FaceRegions(regions, region_faces, facing, info)

    def shadow(self, found: FaceRegions) -> SurfaceShadow:
        """The regions stitched, triangulated and lifted (step 4)."""
        regions = without_collinear(found.regions, self.tol.length)
        points, shadow_faces, face_index = stitch(
            self.vertices,
            self.faces,
            found.faces,
            (self.origin, self.u, self.v),
            regions,
            self.tol.length,
        )
        vertices, triangles = self._lifted(points, shadow_faces, face_index)
        # Areas from the triangles in their faces, before any lift.
        flat = points[shadow_faces]
        areas = 0.5 * np.linalg.norm(
            np.cross(flat[:, 1] - flat[:, 0], flat[:, 2] - flat[:, 0]), axis=1
        )
        n_faces, facing = self.surface.n_faces, found.facing
        shadowed = np.bincount(face_index, weights=areas, minlength=n_faces)
        fraction = np.ones(n_faces)
        fraction[facing] = np.minimum(shadowed[facing] / self.face_area[facing], 1.0)
        info = replace(found.diagnostics, n_shadowed_faces=len(unique_integers(face_index)))
        area = float(areas.sum())
        return SurfaceShadow(self.light, vertices, triangles, face_index, fraction, area, info)

    def fractions(self, compiled: bool) -> tuple[np.ndarray, np.ndarray]:
        """The shadowed share of each face and the faces turned to the light
        (see :func:`shadowed_fractions`)."""
        corners, facing, lit = self._faces()
        if compiled and self.exclude is None and not is_positional(self.light):
            shares = self._convex_fractions(corners, facing, lit)
            if shares is not None:
                return shares, facing
        receivers, triangles, caster_triangles, full, extra, _ = self._pairs(corners, lit)
        found = self._regions(receivers, triangles, caster_triangles, corners, full, extra)
        diagnostics = SurfaceDiagnostics(n_surface_faces=self.surface.n_faces)
        shadow = self.shadow(FaceRegions(*found, facing, diagnostics))
        return shadow.fraction, facing

    def _convex_fractions(
        self, corners: np.ndarray, facing: np.ndarray, lit: np.ndarray
    ) -> np.ndarray | None:
        """:meth:`fractions` from convex pieces, their union's area by compiled
        loops: each caster's convex bodies (:mod:`shadowgeo.bodies`) as one
        convex ring a face (the body cut to the part ahead of the face's
        plane), the other casters' triangles as ever (a closed one's
        light-facing triangles, not its outline, whose pieces are not
        convex). None where the faces' pieces are too many for the loops
        (:data:`shadowgeo.limits.MAX_PIECE_PAIRS`)."""
        found = [convex_bodies(caster, self.tol.length) for caster in self.casters]
        rest = [
            caster if bodies.count == 0 else Caster(caster.vertices, caster.faces[bodies.rest],
                                                    copy=False)
            for caster, bodies in zip(self.casters, found, strict=True)
            if len(bodies.rest)
        ]  # fmt: skip
        receivers, triangles, caster_triangles, full, _, _ = self._pairs(
            corners, lit, rest, outlines=False
        )
        ring_flat, ring_owner = self._ring_pairs(found, corners, lit, full)
        keep = ~full[receivers]  # (faces a body's shadow holds whole need no pieces)
        flat, owner = self._pieces(receivers[keep], triangles[keep], caster_triangles, corners)
        flat = _pad_polygons([flat, ring_flat])
        owner = np.concatenate([owner, ring_owner])
        order = np.argsort(owner, kind="stable")
        return self._union_fractions(flat[order], owner[order], facing, full)

    def _union_fractions(
        self, flat: np.ndarray, owner: np.ndarray, facing: np.ndarray, full: np.ndarray
    ) -> np.ndarray | None:
        """Each face's shadowed share from its convex pieces ``flat`` (sorted
        by their faces ``owner``): the area of their union by the compiled
        loops; 1 on faces ``full`` or turned away, 0 on others without one.
        None where the loops would test more than
        :data:`shadowgeo.limits.MAX_PIECE_PAIRS` pairs of pieces."""
        fraction = np.where(facing, 0.0, 1.0)
        fraction[full] = 1.0
        if len(owner) == 0:
            return fraction
        from .kernels import union_areas

        faces, start, count = np.unique(owner, return_index=True, return_counts=True)
        if np.sum(count.astype(np.float64) ** 2) > MAX_PIECE_PAIRS:
            return None
        corners_each = np.full(len(flat), flat.shape[1], dtype=np.int64)
        areas = union_areas(flat, corners_each, start, count, self.tol.length)
        partial = ~full[faces]
        faces, areas = faces[partial], areas[partial]
        fraction[faces] = np.minimum(areas / self.face_area[faces], 1.0)
        return fraction

    def _ring_pairs(
        self, found: list[Bodies], corners: np.ndarray, lit: np.ndarray, full: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The convex bodies' shadows on the lit faces (not ``full``) that
        their images meet (:func:`shadowgeo.bodies.ring_pieces`): (n, k, 2)
        convex pieces in the faces' frames (those of :meth:`_pieces`),
        padded, and (n,) their faces. Faces that one body's
        shadow holds whole are marked in ``full`` and get none."""
        if not any(bodies.count for bodies in found):
            return np.zeros((0, 3, 2)), np.zeros(0, np.int64)
        direction = cast(DirectionalLight, self.light).direction
        bodies = light_bodies(self.casters, found, self.center, direction)
        lit_faces = np.flatnonzero(lit & ~full)
        face, triangle = candidate_pairs(
            (self.vertices, self.faces[lit_faces]),
            (bodies.points, bodies.triangles),
            None,
            direction,
            self.tol.length,
        )
        n_bodies = np.int64(bodies.count)
        near = unique_integers(lit_faces[face] * n_bodies + bodies.triangle_body[triangle])
        face, body = np.divmod(near, n_bodies)  # by face, then body
        frames = np.concatenate(
            [corners, self.unit[:, None], self.u[:, None], self.v[:, None], self.origin[:, None]],
            axis=1,
        )
        pieces, counts, covers = ring_pieces(bodies, body, face, frames, direction, self.tol.length)
        full[face[covers]] = True
        kept = (counts >= 3) & ~full[face]
        return pieces[kept], face[kept]

    def _faces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The surface in the centred frame, with vertices merged by position:
        (m, 3, 3) corners, the faces turned to the light, and those it reaches."""
        surface, tol, light = self.surface, self.tol, self.light
        if self.given_center is None:
            self.center = _center(self.casters, surface)
        else:
            self.center = self.given_center
        # One index per position (faces that share a corner position share an
        # edge), normals and frames: once per mesh, in its own centred frame.
        geometry = surface.derived("surface_geometry", surface_geometry)
        self.geometry = geometry
        shift = surface.center - self.center
        self.vertices = geometry.positions + shift
        self.faces = geometry.faces
        corners = self.vertices[self.faces]
        length = geometry.length
        self.face_area = 0.5 * length
        proper = length > tol.length**2
        unit = np.where(proper[:, None], geometry.unit, 0.0)
        self.unit = unit
        if is_positional(light):
            self.light_point = light.position - self.center
            height = np.einsum("ij,ij->i", unit, self.light_point - corners[:, 0])
            facing = proper & (height > tol.length)
            lit = facing & (height < light.radius)
            if math.isfinite(light.radius):
                self.limits.append("range")
            self.height = height
        else:
            self.light_point = None
            self.cosine = -(unit @ light.direction)
            facing = proper & (self.cosine > tol.angle)
            lit = facing
        if isinstance(light, SpotLight):
            self.limits.append("spot_cone")
        self.origin = geometry.centroid + shift
        self.u, self.v = geometry.u, geometry.v
        return corners, facing, lit

    def _pairs(
        self,
        corners: np.ndarray,
        lit: np.ndarray,
        casters: list[Caster] | None = None,
        outlines: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, _Pieces, tuple[int, int]]:
        """(face, caster triangle) pairs to clip, sorted by face; the caster
        triangles; faces wholly inside an outline; outline pieces on the
        others; and (candidate pairs, outlined casters) counts. ``casters``:
        those of the call unless given; ``outlines``: closed casters by their
        outlines (False: by their light-facing triangles, each a convex piece)."""
        tol, light = self.tol, self.light
        lit_faces = np.flatnonzero(lit)
        chosen = self.casters if casters is None else casters
        caster_triangles, outlined = self._caster_triangles(chosen, outlines)
        direction = None if is_positional(light) else light.direction
        pad = RELATIVE_ROUNDING if is_positional(light) else tol.length
        found_faces, found_triangles = candidate_pairs(
            (self.vertices, self.faces[lit_faces]),
            caster_triangles,
            self.light_point,
            direction,
            pad,
        )
        found_faces = lit_faces[found_faces]
        if self.exclude is not None:  # a face's own excluded caster: no pair
            mine = self.triangle_caster[found_triangles] == self.exclude[found_faces]
            found_faces, found_triangles = found_faces[~mine], found_triangles[~mine]
        receiver_parts = [found_faces]
        triangle_parts = [found_triangles]
        # Closed casters wholly in front of a face: their outline, not their triangles.
        full = np.zeros(len(corners), dtype=bool)
        extra: list[_Pieces] = []
        all_triangles = [caster_triangles]
        # Each closed caster's front triangles meet the lit faces whose
        # images overlap theirs, all casters in one search (a few ms each,
        # called per caster, was most of the time for a scene of a thousand
        # boxes). Only those faces can take the caster's shadow: its outline
        # (whose image lies within its triangles') settles the faces it lies
        # wholly in front of, and the others keep their pairs with its triangles.
        if outlined:
            found = self._outlined_pairs(
                outlined, lit_faces, direction, pad, corners, full, len(caster_triangles)
            )
            receiver_parts.append(found.faces)
            triangle_parts.append(found.triangles)
            extra += found.pieces
            all_triangles += found.front_triangles
        receivers, triangles = np.concatenate(receiver_parts), np.concatenate(triangle_parts)
        caster_triangles = np.concatenate(all_triangles)
        order = np.argsort(receivers, kind="stable")
        receivers, triangles = receivers[order], triangles[order]
        n_candidates = len(receivers)
        # Only triangles with a corner strictly in front of the face's plane,
        # and only for faces not already wholly in shadow.
        heights = np.einsum(
            "pkd,pd->pk",
            caster_triangles[triangles] - corners[receivers, :1],
            self.unit[receivers],
        )
        front = (corner_max(heights) > tol.length) & ~full[receivers]
        counts = (n_candidates, len(outlined))
        pieces = _pad_polygons([part[0] for part in extra])
        owners = np.concatenate([part[1] for part in extra] + [np.zeros(0, np.int64)])
        return receivers[front], triangles[front], caster_triangles, full, (pieces, owners), counts

    def _outlined_pairs(
        self,
        outlined: list[_Outlined],
        lit_faces: np.ndarray,
        direction: np.ndarray | None,
        pad: float,
        corners: np.ndarray,
        full: np.ndarray,
        offset: int,
    ) -> _OutlinedPairs:
        """What the closed casters' outlines settle on the lit faces: the
        faces wholly in front of an outline marked in ``full``, the outline's
        pieces on others, and the pairs with their front triangles (numbered
        from ``offset``) that they leave to clip."""
        pieces: list[_Pieces] = []
        fronts = [front for _, front, _ in outlined]
        pair_faces, pair_triangles, owner = self._front_pairs(fronts, lit_faces, direction, pad)
        if self.exclude is not None:
            mine = self.outlined_caster[owner[pair_triangles]] == self.exclude[pair_faces]
            pair_faces, pair_triangles = pair_faces[~mine], pair_triangles[~mine]
        n_faces = np.int64(len(self.faces))
        keys = owner[pair_triangles] * n_faces + pair_faces  # (caster, face) of each pair
        near = np.unique(keys)
        # (caster, face) pairs, by caster, then face
        owner_of, faces = np.divmod(near, n_faces)
        together = OutlineSet([outline for outline, _, _ in outlined])
        bounds = [bound for _, _, bound in outlined]
        in_front, ahead = self._outline_faces(together, bounds, owner_of, faces, corners)
        eligible = in_front & ahead
        pieces.append(
            self._apply_outline(together, faces[eligible], owner_of[eligible], corners, full)
        )
        # A face reaching behind the light in the caster's frame (a floor
        # far wider than the lamp is high): its part ahead, the only part
        # the caster can shade, cut by the outline.
        partly = in_front & ~ahead
        pieces.append(self._apply_outline_ahead(together, faces[partly], owner_of[partly], corners))
        eligible |= partly
        # the pairs of each caster's others that it may shadow, by face,
        # then triangle
        others = np.flatnonzero(~eligible)
        reach = together.may_reach(self.vertices, self.faces[faces[others]], owner_of[others])
        wanted = near[others[reach]]
        own = np.isin(keys, wanted)
        fronts_triangles = [front[0][front[1]] for _, front, _ in outlined]
        return _OutlinedPairs(
            pair_faces[own], pair_triangles[own] + offset, pieces, fronts_triangles
        )

    def _front_pairs(
        self,
        fronts: list[tuple[np.ndarray, np.ndarray]],
        faces: np.ndarray,
        direction: np.ndarray | None,
        pad: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(face, front triangle) pairs, faces among ``faces`` and triangles
        numbered one caster's ``fronts`` after another, whose images from the
        light overlap (sorted by face, then triangle); and the caster of each
        triangle."""
        starts = np.cumsum([0, *(len(points) for points, _ in fronts[:-1])])
        points = np.concatenate([points for points, _ in fronts])
        triangles = np.concatenate(
            [front + start for (_, front), start in zip(fronts, starts, strict=True)]
        )
        found, their = candidate_pairs(
            (self.vertices, self.faces[faces]),
            (points, triangles),
            self.light_point,
            direction,
            pad,
        )
        owner = np.repeat(np.arange(len(fronts)), [len(front) for _, front in fronts])
        return faces[found], their, owner

    def _caster_triangles(
        self, casters: list[Caster], outlines: bool
    ) -> tuple[np.ndarray, list[_Outlined]]:
        """(t, 3, 3) triangles of ``casters`` handled one by one, in the
        centred frame (a closed caster's light-facing ones only), and for each
        closed caster with an outline (none without ``outlines``): (outline,
        its light-facing triangles, (its box half-sizes, box centre, bounding
        radius about it))."""
        chunks: list[np.ndarray] = []
        outlined: list[_Outlined] = []
        # the index in casters of each chunk's caster and each outlined one
        chunk_casters: list[int] = []
        outlined_casters: list[int] = []
        silhouettes = self._closed_outlines(casters) if outlines else {}
        for index, caster in enumerate(casters):
            if caster.n_faces == 0:
                continue
            silhouette = silhouettes.get(id(caster))
            outline = None if silhouette is None else silhouette[2]
            if silhouette is not None and outline is not None:
                front, vertices, _, radius = silhouette
                low, high = caster.bounds - self.center
                centre = 0.5 * (low + high)
                half = 0.5 * (high - low)
                outlined.append((outline, (vertices, caster.faces[front]), (half, centre, radius)))
                outlined_casters.append(index)
                continue
            # Repeated and zero-area faces cast nothing more: each would be
            # one more candidate pair per face it covers.
            faces = caster.faces[self._casting(caster, silhouette) & caster.distinct]
            chunks.append(caster.vertices[faces] - self.center)
            chunk_casters.append(index)
        self.outlined_caster = np.array(outlined_casters, dtype=np.int64)
        self.triangle_caster = np.repeat(
            np.array(chunk_casters, dtype=np.int64), [len(chunk) for chunk in chunks]
        )
        if not chunks:
            return np.zeros((0, 3, 3)), outlined
        return np.concatenate(chunks), outlined

    def _closed_outlines(
        self, casters: list[Caster]
    ) -> dict[int, tuple[np.ndarray, np.ndarray, Outline | None, float]]:
        """Each closed caster (by id) with faces: its light-facing faces, its
        vertices in the centred frame, its outline (None where it has none)
        and its bounding radius, all casters' outlines made at once."""
        # Without a light point the light is directional.
        direction = (
            None if self.light_point is not None else cast(DirectionalLight, self.light).direction
        )
        closed = [caster for caster in casters if caster.n_faces and caster.is_closed]
        found = closed_silhouettes(closed, self.light)
        centred = [caster.vertices - self.center for caster in closed]
        outlines = make_outlines(
            [(vertices, loops) for vertices, (_, loops) in zip(centred, found, strict=True)],
            self.light_point,
            direction,
            self.tol.length,
        )
        radii = _bounding_radii(closed)
        return {
            id(caster): (front, vertices, outline, radius)
            for caster, (front, _), vertices, outline, radius in zip(
                closed, found, centred, outlines, radii, strict=True
            )
        }

    def _casting(
        self,
        caster: Caster,
        silhouette: tuple[np.ndarray, np.ndarray, Outline | None, float] | None,
    ) -> np.ndarray:
        """(f,) the faces of a caster handled one by one that can cast: a
        closed caster's light-facing ones (from its silhouette where it has
        one), else all."""
        if silhouette is not None:
            front: np.ndarray = silhouette[0]
            return front
        if caster.is_closed:  # (taken without its outline)
            facing: np.ndarray = caster.facing(light_homogeneous(caster, self.light)) > 0
            return facing
        if caster is self.surface and self.geometry.single_sheet:
            # Seen from the surface itself, a blocked ray enters the sheet's
            # back side first, through a face turned away from the light.
            turned: np.ndarray = caster.facing(light_homogeneous(caster, self.light)) <= 0
            return turned
        return np.ones(caster.n_faces, dtype=bool)

    def _outline_faces(
        self,
        outlines: OutlineSet,
        bounds: list[tuple[np.ndarray, np.ndarray, float]],
        owner: np.ndarray,
        faces: np.ndarray,
        corners: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Two (len(faces),) bool: for each pair of a closed caster
        ``owner[i]`` and a lit face ``faces[i]``, whether the caster lies
        wholly in front of the face or rests on it (its box or its bounding
        ball does: ``bounds``, each caster's box half-sizes, centre and
        bounding radius about it), and whether the face's corners lie ahead
        of the light in the caster outline's frame, at least half as deep
        along its axis as the caster."""
        half = np.array([b[0] for b in bounds]).reshape(-1, 3)[owner]
        centre = np.array([b[1] for b in bounds]).reshape(-1, 3)[owner]
        radius = np.array([b[2] for b in bounds], dtype=float)[owner]
        unit = self.unit[faces]
        x, y, z = unit[:, 0], unit[:, 1], unit[:, 2]
        first = corners[faces, 0]
        # Each face plane's height of the caster's centre; the box's lowest
        # corner lies lower by the half-sizes along the normal's components.
        middle = (
            x * (centre[:, 0] - first[:, 0])
            + y * (centre[:, 1] - first[:, 1])
            + z * (centre[:, 2] - first[:, 2])
        )
        reach = np.abs(x) * half[:, 0] + np.abs(y) * half[:, 1] + np.abs(z) * half[:, 2]
        lowest = middle - np.minimum(reach, radius)
        # A caster resting on the face (a building on the ground) may dip
        # below its plane by rounding: its outline then reaches past its true
        # shadow by at most that depth over the cosine of the light's rays
        # through it with the face's normal, which is kept within the
        # tolerance length.
        if self.light_point is None:
            along = cast(DirectionalLight, self.light).direction
            cosine = np.abs(x * along[0] + y * along[1] + z * along[2])
        else:
            # rays from the light to the caster's ball: the light's height over
            # the face's plane against the farthest the ball reaches from it
            toward = self.light_point - first
            height = x * toward[:, 0] + y * toward[:, 1] + z * toward[:, 2]
            reach_out = np.linalg.norm(self.light_point - centre, axis=1) + radius
            cosine = np.clip(height / reach_out, 0.0, 1.0)
        in_front: np.ndarray = lowest > -self.tol.length * cosine
        ahead = np.ones(len(faces), dtype=bool)  # (ahead of a directional light is everything)
        if self.light_point is not None:
            # corners at least half as deep as the caster along its outline's
            # axis: their images (slopes) stay bounded by the face's reach over
            # that depth (others: _apply_outline_ahead cuts the face there)
            relative = corners[faces] - self.light_point
            depth = np.einsum("pcd,pd->pc", relative, outlines.frames[owner, 0])
            ahead = corner_min(depth) >= 0.5 * outlines.nearest[owner]
        return in_front, ahead

    def _apply_outline(
        self,
        outlines: OutlineSet,
        faces: np.ndarray,
        owner: np.ndarray,
        corners: np.ndarray,
        full: np.ndarray,
    ) -> _Pieces:
        """Mark faces wholly inside their caster's outline (face i, outline
        ``owner[i]``) as full; return the outlines' part of the others,
        mapped onto each face: signed pieces (their winding numbers add up
        to it) and their faces."""
        nothing = (np.zeros((0, 3, 2)), np.zeros(0, np.int64))
        if len(faces) == 0:
            return nothing
        with np.errstate(divide="ignore", invalid="ignore"):
            if outlines.shared:
                # Each vertex once: the faces share their corners (those of
                # other faces, maybe behind the light, are not used).
                used, corner_ids = np.unique(self.faces[faces], return_inverse=True)
                vertex_images = outlines.to_frame(self.vertices[used], owner)
                images = vertex_images[corner_ids.reshape(-1, 3)]
            else:
                images = outlines.to_frame(corners[faces], owner)
        near = ~misses_boxes(images, outlines.bounds[owner])
        faces, owner = faces[near], owner[near]
        covered, pieces = self._cut_onto_faces(outlines, images[near], faces, owner, corners)
        full[faces[covered]] = True
        return pieces

    def _cut_onto_faces(
        self,
        outlines: OutlineSet,
        images: np.ndarray,
        faces: np.ndarray,
        owner: np.ndarray,
        corners: np.ndarray,
    ) -> tuple[np.ndarray, _Pieces]:
        """Triangles' ``images`` (each within face ``faces[i]``, in the frame
        of outline ``owner[i]``) cut by their outlines: which are wholly
        inside, and the outlines' part of the others mapped onto the faces
        (signed pieces, their winding numbers adding up to it)."""
        # The map from the frame back to a face keeps or flips orientation as
        # the triangle's image does (it runs counter-clockwise in the face's frame).
        flips = twice_areas(images) < 0
        extent = np.abs(images - images.mean(axis=1, keepdims=True)).max(axis=(1, 2))
        covered, pieces, owners = outlines.cut(images, RELATIVE_ROUNDING * extent, owner)
        if len(pieces) == 0:
            return covered, (np.zeros((0, 3, 2)), np.zeros(0, np.int64))
        mapped = self._onto_faces(
            outlines, pieces, faces[owners], owner[owners], flips[owners], corners
        )
        return covered, mapped

    def _onto_faces(
        self,
        outlines: OutlineSet,
        pieces: np.ndarray,
        faces: np.ndarray,
        owner: np.ndarray,
        flips: np.ndarray,
        corners: np.ndarray,
    ) -> _Pieces:
        """(n, k, 2) outline pieces in the frames of outlines ``owner`` mapped
        onto their ``faces`` (into the faces' 2-D frames), each reversed
        where ``flips``; and the faces."""
        width = pieces.shape[1]
        point_face = np.repeat(faces, width)
        normal = self.unit[point_face]
        offset = -np.einsum("ij,ij->i", normal, corners[point_face, 0])
        point_owner = np.repeat(owner, width)
        points = outlines.onto_planes(pieces.reshape(-1, 2), normal, offset, point_owner)
        flat = self._in_face_frames(points, point_face).reshape(-1, width, 2)
        flat = np.where(flips[:, None, None], flat[:, ::-1], flat)
        return flat, faces

    def _in_face_frames(self, points: np.ndarray, point_face: np.ndarray) -> np.ndarray:
        """(n, 2) coordinates of (n, 3) points in the frames of their faces."""
        points = points - self.origin[point_face]
        return np.column_stack(
            [
                np.einsum("ij,ij->i", points, self.u[point_face]),
                np.einsum("ij,ij->i", points, self.v[point_face]),
            ]
        )

    def _apply_outline_ahead(
        self, outlines: OutlineSet, faces: np.ndarray, owner: np.ndarray, corners: np.ndarray
    ) -> _Pieces:
        """Under a point light, the outlines' part (face i, outline
        ``owner[i]``) of faces that reach behind the light in the outline's
        frame: each face cut first to where its depth along the outline's
        axis passes half the caster's least depth. A ray to the light from a
        point of the face shallower than the caster misses it: only the part
        kept can be shaded, and it is cut as a face wholly ahead is, its
        images (slopes) bounded. Its pieces on the faces, signed as
        :meth:`_apply_outline` gives them (a sub-triangle wholly inside the
        outline as itself)."""
        nothing = (np.zeros((0, 3, 2)), np.zeros(0, np.int64))
        if len(faces) == 0:
            return nothing
        light = cast(np.ndarray, self.light_point)
        axis = outlines.frames[owner, 0]
        shallowest = 0.5 * outlines.nearest[owner]
        planes = np.column_stack([axis, -np.einsum("ij,j->i", axis, light) - shallowest])
        homogeneous = np.concatenate([corners[faces], np.ones((len(faces), 3, 1))], axis=2)
        clipped, counts = clip_batch(homogeneous, np.full(len(faces), 3), planes[:, None, :])
        # each kept polygon (convex, three or four corners) as a fan of triangles
        parent, first = [], []
        for corner in range(1, int(counts.max(initial=0)) - 1):
            rows = np.flatnonzero(counts >= corner + 2)
            parent.append(rows)
            first.append(np.full(len(rows), corner))
        if not parent:
            return nothing
        rows, second = np.concatenate(parent), np.concatenate(first)
        triangles = np.stack(
            [clipped[rows, 0, :3], clipped[rows, second, :3], clipped[rows, second + 1, :3]], axis=1
        )
        faces, owner = faces[rows], owner[rows]
        with np.errstate(divide="ignore", invalid="ignore"):
            images = outlines.to_frame(triangles, owner)
        solid = twice_areas(images) != 0  # (a sliver of no area casts nothing)
        triangles, faces, owner = triangles[solid], faces[solid], owner[solid]
        covered, cut = self._cut_onto_faces(outlines, images[solid], faces, owner, corners)
        # a part wholly inside: the sub-triangle itself, counter-clockwise in
        # its face's frame (it keeps the face's winding)
        whole = np.flatnonzero(covered)
        point_face = np.repeat(faces[whole], 3)
        flat = self._in_face_frames(triangles[whole].reshape(-1, 3), point_face).reshape(-1, 3, 2)
        flat = np.where((twice_areas(flat) < 0)[:, None, None], flat[:, ::-1], flat)
        return _pad_polygons([cut[0], flat]), np.concatenate([cut[1], faces[whole]])

    def _side_planes(self, faces: np.ndarray, corners: np.ndarray) -> np.ndarray:
        """(f, 4, 4) unit half-spaces of the region between each face and the
        light: the face's front, and the three planes joining the light to its
        edges (the face's side of each)."""
        triangle = corners[faces]
        normal = self.unit[faces]
        planes = np.empty((len(faces), 4, 4))
        planes[:, 0, :3] = normal
        planes[:, 0, 3] = -np.einsum("ij,ij->i", normal, triangle[:, 0])
        for k in range(3):
            a, b, c = triangle[:, k], triangle[:, (k + 1) % 3], triangle[:, (k + 2) % 3]
            if self.light_point is not None:
                side = np.cross(a - self.light_point, b - self.light_point)
            else:
                # Without a light point the light is directional.
                direction = cast(DirectionalLight, self.light).direction
                side = np.cross(b - a, np.broadcast_to(direction, a.shape))
            side /= np.linalg.norm(side, axis=1, keepdims=True)
            offset = -np.einsum("ij,ij->i", side, a)
            sign = np.sign(np.einsum("ij,ij->i", side, c) + offset)
            planes[:, k + 1, :3] = side * sign[:, None]
            planes[:, k + 1, 3] = offset * sign
        return planes

    def _project(
        self,
        points: np.ndarray,
        faces: np.ndarray,
        planes: np.ndarray,
        origin: np.ndarray,
        u: np.ndarray,
        v: np.ndarray,
    ) -> np.ndarray:
        """(n, k, 2) face-frame coordinates of clipped points (n, k, 4) of the
        pairs' faces, projected from the light onto each face's plane."""
        height = np.einsum("nkd,nd->nk", points, planes[:, 0])
        position = points[:, :, :3]
        if self.light_point is not None:
            light_height = self.height[faces][:, None]
            scale = light_height / (light_height - height)
            image = self.light_point + (position - self.light_point) * scale[:, :, None]
        else:
            along = height / self.cosine[faces][:, None]
            # Without a light point the light is directional.
            direction = cast(DirectionalLight, self.light).direction
            image = position + along[:, :, None] * direction
        relative = image - origin[faces][:, None, :]
        return np.stack(
            [
                np.einsum("nkd,nd->nk", relative, u[faces]),
                np.einsum("nkd,nd->nk", relative, v[faces]),
            ],
            axis=2,
        )

    def _regions(
        self,
        receivers: np.ndarray,
        triangles: np.ndarray,
        caster_triangles: np.ndarray,
        corners: np.ndarray,
        full: np.ndarray,
        extra: _Pieces,
    ) -> tuple[Loops, np.ndarray]:
        """The shadow region of each face that has one: loops in the face's
        frame (region by region), and the faces (sorted)."""
        origin, u, v = self.origin, self.u, self.v
        flat, owner = self._pieces(receivers, triangles, caster_triangles, corners)
        flat = _pad_polygons([flat, extra[0]])
        owner = np.concatenate([owner, extra[1]])
        order = np.argsort(owner, kind="stable")
        flat, owner = flat[order], owner[order]
        faces_with = unique_integers(np.concatenate([owner, np.flatnonzero(full)]))
        lit = self._lit_polygons(faces_with, corners, origin, u, v)
        limits = self._face_limits(faces_with, lit, full)
        return _face_loops(limits, _FacePieces.of(flat, owner, limits.faces))

    def _face_limits(
        self, faces_with: np.ndarray, lit: tuple[np.ndarray, np.ndarray], full: np.ndarray
    ) -> _FaceLimits:
        """The faces ``faces_with`` whose lit outline ``lit`` (padded, and
        its corner counts) has an area and that the light's range reaches,
        with what bounds each one's shadow (:class:`_FaceLimits`)."""
        outlines, counts = lit
        valid = counts >= 3
        discs = None
        if is_positional(self.light) and math.isfinite(self.light.radius):
            # faces the range surely holds need no disc (the same loops)
            inside = self._inside_range(faces_with, outlines)
            discs = [
                _disc_near(self._range_disc(face), padded[:count]) if keep and not held else None
                for face, padded, count, keep, held in zip(
                    faces_with, outlines, counts, valid, inside, strict=True
                )
            ]
            # (a face the range misses has no region)
            valid &= np.array([disc is None or len(disc) >= 3 for disc in discs], dtype=bool)
            discs = [disc for disc, keep in zip(discs, valid, strict=True) if keep]
        faces = faces_with[valid]
        return _FaceLimits(faces, outlines[valid], counts[valid], discs, full[faces])

    def _inside_range(self, faces: np.ndarray, outlines: np.ndarray) -> np.ndarray:
        """(f,) bool: True where the light's lit disc on the face's plane (the
        inscribed polygon :meth:`_range_disc` makes) surely holds the box of
        the face's lit ``outlines`` (f, k, 2, padded), so that
        :func:`_disc_near` would leave the face alone: the box lies within
        the disc's radius less the polygon's sagitta (at most the chord
        length, or that of ``MAX_CURVE_SEGMENTS`` sides where the count is
        capped), with a margin for rounding."""
        (centre_x, centre_y), radius = self._range_circles(faces)
        capped = radius * (1.0 - math.cos(math.pi / MAX_CURVE_SEGMENTS))
        inner = radius - np.maximum(self.tol.chord_length, capped) - RELATIVE_ROUNDING * radius
        low, high = outlines.min(axis=1), outlines.max(axis=1)
        reach_x = np.maximum(np.abs(low[:, 0] - centre_x), np.abs(high[:, 0] - centre_x))
        reach_y = np.maximum(np.abs(low[:, 1] - centre_y), np.abs(high[:, 1] - centre_y))
        inside: np.ndarray = (inner > 0) & (reach_x * reach_x + reach_y * reach_y < inner * inner)
        return inside

    def _pieces(
        self,
        receivers: np.ndarray,
        triangles: np.ndarray,
        caster_triangles: np.ndarray,
        corners: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each pair's triangle clipped to the region between its face and the
        light and projected onto the face: (n, k, 2) counter-clockwise polygons
        in the face frames (padded by repeating the last corner), and (n,) faces,
        sorted by face."""
        if len(receivers) == 0:
            return np.zeros((0, 3, 2)), np.zeros(0, np.int64)
        shadowed = unique_integers(receivers)
        slot = np.searchsorted(shadowed, receivers)
        planes = self._side_planes(shadowed, corners)
        pieces: list[np.ndarray] = []
        owners: list[np.ndarray] = []
        for start in range(0, len(receivers), _BATCH):
            part = slice(start, start + _BATCH)
            faces, pair_slot = receivers[part], slot[part]
            homogeneous = np.concatenate(
                [caster_triangles[triangles[part]], np.ones((len(faces), 3, 1))], axis=2
            )
            # A triangle within a length tolerance of outside one plane casts
            # nothing there (at most a sliver that thin): drop it unclipped.
            sides = np.einsum("nkd,npd->nkp", homogeneous, planes[pair_slot])
            keep = ~np.any(np.all(sides < self.tol.length, axis=1), axis=1)
            homogeneous, faces, pair_slot = homogeneous[keep], faces[keep], pair_slot[keep]
            clipped, counts = clip_batch(homogeneous, np.full(len(faces), 3), planes[pair_slot])
            keep = counts >= 3
            clipped, counts, faces, pair_slot = (
                clipped[keep],
                counts[keep],
                faces[keep],
                pair_slot[keep],
            )
            flat = self._project(clipped, faces, planes[pair_slot], self.origin, self.u, self.v)
            # Pad each polygon with its last corner: repeated points add no edges.
            slots = np.arange(flat.shape[1])
            last = np.minimum(slots[None, :], counts[:, None] - 1)
            flat = np.take_along_axis(flat, last[:, :, None], axis=1)
            x, y = flat[:, :, 0], flat[:, :, 1]
            area = np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
            flat = np.where((area < 0)[:, None, None], flat[:, ::-1], flat)
            nonzero = area != 0
            pieces.append(flat[nonzero])
            owners.append(faces[nonzero])
        width = max(p.shape[1] for p in pieces)
        pieces = [np.pad(p, ((0, 0), (0, width - p.shape[1]), (0, 0)), mode="edge") for p in pieces]
        return np.concatenate(pieces), np.concatenate(owners)

    def _lit_polygons(
        self,
        faces: np.ndarray,
        corners: np.ndarray,
        origin: np.ndarray,
        u: np.ndarray,
        v: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each face's part that the light reaches, in the face's frame (the
        whole face unless a spot cone or range limits it): (f, k, 2) polygons
        padded by repeating the last corner, and (f,) their corner counts
        (below 3 where nothing is lit)."""
        triangle = corners[faces]
        planes = self._limit_planes(faces)
        if planes is None:
            counts = np.full(len(faces), 3)
            points = triangle
        else:
            homogeneous = np.concatenate([triangle, np.ones((len(faces), 3, 1))], axis=2)
            clipped, counts = clip_batch(homogeneous, np.full(len(faces), 3), planes)
            slots = np.arange(clipped.shape[1])
            last = np.minimum(slots[None, :], np.maximum(counts, 1)[:, None] - 1)
            points = np.take_along_axis(clipped, last[:, :, None], axis=1)[:, :, :3]
        relative = points - origin[faces][:, None, :]
        flat = np.stack(
            [
                np.einsum("nkd,nd->nk", relative, u[faces]),
                np.einsum("nkd,nd->nk", relative, v[faces]),
            ],
            axis=2,
        )
        return flat, counts

    def _range_disc(self, face: int) -> np.ndarray | None:
        """The light's lit disc on a face's plane (an inscribed polygon, as
        :func:`shadowgeo.project_shadow` makes it) in the face frame, or None
        for a light without a range."""
        light = self.light
        if not (is_positional(light) and math.isfinite(light.radius)):
            return None
        (centre_x, centre_y), radii = self._range_circles(np.array([face]))
        radius = float(radii[0])
        count = self.tol.segments(radius)
        angles = np.linspace(0.0, 2 * np.pi, count, endpoint=False)
        center = np.array([centre_x[0], centre_y[0]])
        return center + radius * np.column_stack([np.cos(angles), np.sin(angles)])

    def _range_circles(self, faces: np.ndarray) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
        """The circles where the light's range meets the faces' planes: each
        face frame's centre (x and y columns) and radius (0 where the range
        does not reach the plane)."""
        light = cast("PointLight | SpotLight", self.light)
        height = self.height[faces]
        radius = np.sqrt(np.maximum(light.radius**2 - height**2, 0.0))
        foot = self.light_point - height[:, None] * self.unit[faces] - self.origin[faces]
        centre = (
            np.einsum("ij,ij->i", foot, self.u[faces]),
            np.einsum("ij,ij->i", foot, self.v[faces]),
        )
        return centre, radius

    def _limit_planes(self, faces: np.ndarray) -> np.ndarray | None:
        """(f, p, 4) half-spaces of the spot cone (an inscribed pyramid), or None."""
        light, tol = self.light, self.tol
        chunks: list[np.ndarray] = []
        if isinstance(light, SpotLight):
            axis = light.direction
            apex = cast(np.ndarray, self.light_point)  # a spot light is positional
            if light.cut_off_angle >= math.pi / 2 - ANGLE_SLACK:
                planes = np.append(axis, -axis @ apex)[None]
            else:
                count = tol.segments(tol.scale)
                angles = np.linspace(0.0, 2 * np.pi, count, endpoint=False)
                side, up = face_frames(axis[None])
                radius = math.tan(light.cut_off_angle)
                rim = axis + radius * (
                    np.outer(np.cos(angles), side[0]) + np.outer(np.sin(angles), up[0])
                )
                normal = np.cross(rim, np.roll(rim, -1, axis=0))
                normal *= np.sign(normal @ axis)[:, None]
                planes = np.column_stack([normal, -normal @ apex])
            chunks.append(np.broadcast_to(planes, (len(faces), *planes.shape)))
        if not chunks:
            return None
        return np.concatenate(chunks, axis=1)

    def _lifted(
        self, points: np.ndarray, faces: np.ndarray, face_index: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The shadow's vertices (those its faces use, moved ``offset`` off
        their faces, in scene coordinates) and faces."""
        if len(faces) == 0:
            return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
        used, inverse = unique_integers(faces, return_inverse=True)
        vertices = points[used]
        if self.offset != 0.0:
            vertices = vertices + self.offset * lift_directions(
                inverse.reshape(-1, 3), self.unit[face_index], len(used)
            )
        return vertices + self.center, inverse.reshape(-1, 3)


def _center(casters: list[Caster], surface: Caster) -> np.ndarray:
    """(3,) the centre of the box of the casters' boxes (those with faces)
    and the surface's: the frame the work is done in."""
    stacked = np.concatenate([c.bounds for c in casters if c.n_faces] + [surface.bounds])
    center: np.ndarray = 0.5 * (stacked.min(axis=0) + stacked.max(axis=0))
    return center


def closed_silhouettes(
    casters: list[Caster], light: Light
) -> list[tuple[np.ndarray, list[np.ndarray]]]:
    """Each closed caster's front faces (in its own frame, as
    :meth:`Caster.facing` has them) and silhouette loops (its own vertex
    indices), as :func:`~shadowgeo.silhouette.silhouette_loops` gives them
    caster by caster, the loops of all found at once: the casters stacked,
    which share no vertex, give each one's loops in the same order and from
    the same corner as alone (the outline's edges keep their order, and the
    walk starts each cycle at its lowest edge)."""
    if len(casters) < 2:
        fronts = [caster.facing(light_homogeneous(caster, light)) > 0 for caster in casters]
        return [
            (front, silhouette_loops(caster, front)[0])
            for caster, front in zip(casters, fronts, strict=True)
        ]
    sizes = np.array([len(caster.vertices) for caster in casters], dtype=np.int64)
    starts = np.cumsum(sizes) - sizes
    stacked = Caster(
        np.concatenate([caster.vertices for caster in casters]),
        np.concatenate(
            [caster.faces + start for caster, start in zip(casters, starts, strict=True)]
        ),
        copy=False,
        closed=True,  # each is, and they share no vertex
    )
    face_counts = [caster.n_faces for caster in casters]
    stacked_front = _stacked_facing(stacked, casters, face_counts, light) > 0
    fronts = np.split(stacked_front, np.cumsum(face_counts)[:-1])
    loops, _ = silhouette_loops(stacked, stacked_front)
    owners = np.searchsorted(starts, [int(loop[0]) for loop in loops], side="right") - 1
    each: list[list[np.ndarray]] = [[] for _ in casters]
    for loop, owner in zip(loops, owners.tolist(), strict=True):
        each[owner].append(loop - starts[owner])
    return list(zip(fronts, each, strict=True))


def _stacked_facing(
    stacked: Caster, casters: list[Caster], face_counts: list[int], light: Light
) -> np.ndarray:
    """(m,) each caster's :meth:`Caster.facing` of ``light`` (in its own
    centred frame), the casters' faces one after another in ``stacked``, all
    at once: the same products, a row each (a point light's position, and
    the face planes, relative to each caster's own centre)."""
    normals = stacked.face_normals  # each face's own numbers (stacked or alone)
    if isinstance(light, DirectionalLight):
        toward: np.ndarray = light_homogeneous(stacked, light)[:3]  # the same for all
    else:  # light_homogeneous of each caster, face by face
        centres = np.repeat(np.array([caster.center for caster in casters]), face_counts, axis=0)
        toward = light.position - centres
    # products written out, as Caster.facing writes them
    facing: np.ndarray = normals[:, 0] * toward[..., 0]
    facing += normals[:, 1] * toward[..., 1]
    facing += normals[:, 2] * toward[..., 2]
    if not isinstance(light, DirectionalLight):
        corners = stacked.vertices[stacked.faces[:, 0]] - centres  # as Caster.face_offsets
        facing -= np.einsum("ij,ij->i", normals, corners)
    return facing


def _bounding_radii(casters: list[Caster]) -> list[float]:
    """Each caster's largest distance of a vertex from the centre of its
    mesh's box, all at once."""
    if not casters:
        return []
    sizes = np.array([len(caster.vertices) for caster in casters], dtype=np.int64)
    centres = np.repeat(np.array([caster.center for caster in casters]), sizes, axis=0)
    relative = np.concatenate([caster.vertices for caster in casters]) - centres
    squared = relative[:, 0] ** 2 + relative[:, 1] ** 2 + relative[:, 2] ** 2
    # (the root of the largest square is the largest root: both are rounded once)
    radii: list[float] = np.sqrt(np.maximum.reduceat(squared, np.cumsum(sizes) - sizes)).tolist()
    return radii


def _pad_polygons(polygons: list[np.ndarray]) -> np.ndarray:
    """(n_i, k_i, 2) polygon arrays as one (n, k, 2), each padded by repeating
    its last corner (repeated points add no edges)."""
    polygons = [p for p in polygons if len(p)]
    if not polygons:
        return np.zeros((0, 3, 2))
    width = max(p.shape[1] for p in polygons)
    return np.concatenate(
        [np.pad(p, ((0, 0), (0, width - p.shape[1]), (0, 0)), mode="edge") for p in polygons]
    )


@dataclass(frozen=True)
class _FaceLimits:
    """The faces that may hold a shadow region and what bounds each: its lit
    outline (``outlines`` (f, k, 2), padded by repeating the last corner, of
    ``counts`` (f,) corners), the light's range where it cuts the face
    (``discs``: (d, 2) or None each; None for a light without a range), and
    whether the face is wholly in shadow (``full`` (f,) bool)."""

    faces: np.ndarray
    outlines: np.ndarray
    counts: np.ndarray
    discs: list[np.ndarray | None] | None
    full: np.ndarray


@dataclass(frozen=True)
class _FacePieces:
    """The pieces ``flat`` (n, k, 2) padded, sorted by face, and where each
    face's run of them starts (``start``) and how long it is (``count``),
    face by face of a :class:`_FaceLimits`."""

    flat: np.ndarray
    start: np.ndarray
    count: np.ndarray

    @classmethod
    def of(cls, flat: np.ndarray, owner: np.ndarray, faces: np.ndarray) -> _FacePieces:
        """The pieces ``flat`` of the faces ``owner`` (sorted), run by run
        for ``faces`` (sorted)."""
        start = np.searchsorted(owner, faces, side="left")
        return cls(flat, start, np.searchsorted(owner, faces, side="right") - start)

    def rows(self, slots: np.ndarray, cell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rows of ``flat`` of the faces ``slots``, run after run, and
        the ``cell`` of each face repeated for its rows."""
        start, count = self.start[slots], self.count[slots]
        first = np.repeat(start - (np.cumsum(count) - count), count)
        return np.arange(len(first), dtype=np.int64) + first, np.repeat(cell, count)


_Chunk = tuple[np.ndarray, np.ndarray, np.ndarray]  # loops' points, sizes and faces


def _face_loops(limits: _FaceLimits, pieces: _FacePieces) -> tuple[Loops, np.ndarray]:
    """Each face's shadow region, as loops in its frame: the lit outline of a
    face wholly in shadow that the light's range does not cut; for the
    others, their ``pieces`` cut to their bounds. The loops region by region,
    and the faces (sorted).

    The one choice between the two layouts: under a light with a range, each
    face alone at its own scale (:func:`_cut_alone`), cut to the range's disc
    with it, as such shadows have always been rounded; else all in one call
    (:func:`_cut`), in one column of cells: Clipper2 sweeps along y, so its
    scanlines meet one face at a time (x is stretched to the full width)."""
    uncut = limits.full.copy()
    if limits.discs is not None:
        uncut &= np.array([disc is None for disc in limits.discs], dtype=bool)
    chunks = [_outlines_of(limits, np.flatnonzero(uncut))]
    cut = np.flatnonzero(~uncut)
    if limits.discs is not None:
        chunks += [_cut_alone(limits, slot, pieces) for slot in cut.tolist()]
    elif len(cut):
        chunks.append(_cut(limits, cut, pieces))
    points = np.concatenate([chunk[0] for chunk in chunks])
    sizes = np.concatenate([chunk[1] for chunk in chunks])
    loop_face = np.concatenate([chunk[2] for chunk in chunks])
    order = np.argsort(loop_face, kind="stable")
    index, sizes = loops_taken(sizes, order)
    region_faces, loop_region = unique_integers(loop_face[order], return_inverse=True)
    return (points[index], sizes, loop_region), region_faces


def _outlines_of(limits: _FaceLimits, slots: np.ndarray) -> _Chunk:
    """The lit outlines of the faces ``slots``, as they are."""
    counts = limits.counts[slots]
    corners = np.arange(limits.outlines.shape[1])
    points = limits.outlines[slots][corners[None, :] < counts[:, None]]
    return points, counts, limits.faces[slots]


def _reach(limits: _FaceLimits, slot: int) -> float:
    """The largest coordinate of the lit outline of face ``slot``."""
    return float(np.abs(limits.outlines[slot, : limits.counts[slot]]).max())


def _cut(limits: _FaceLimits, slots: np.ndarray, pieces: _FacePieces) -> _Chunk:
    """The regions of the faces ``slots`` under a light without a range, in
    one clipper call, each face in its own cell of one column: each face's
    pieces (a face wholly in shadow: its lit outline) within its lit outline.
    The cells are given to the union's budget, which then counts crossings
    cell by cell."""
    cells = column_cells(np.abs(limits.outlines[slots].reshape(len(slots), -1)).max(axis=1))
    cell = np.arange(len(slots))
    partial = ~limits.full[slots]
    rows, mine = pieces.rows(slots[partial], cell[partial])
    whole = cell[~partial]
    subject = [*cells.place(pieces.flat[rows], mine[:, None])]
    if len(whole):
        subject += [*cells.place(limits.outlines[slots[whole]], whole[:, None])]
    region = poly.unite(subject, cells=np.concatenate([mine, whole]))
    if partial.any():
        bounds = cells.place(limits.outlines[slots[partial]], cell[partial][:, None])
        region = poly.intersect(region, poly.unite([*bounds], cells=cell[partial]))
    points, sizes = _region_loops(region)
    cell = cells.cell_of(points[np.cumsum(sizes) - sizes])
    return cells.restore(points, np.repeat(cell, sizes)), sizes, limits.faces[slots[cell]]


def _cut_alone(limits: _FaceLimits, slot: int, pieces: _FacePieces) -> _Chunk:
    """:func:`_cut` of the one face ``slot`` in the whole plane, scaled about
    its frame's origin (the largest coordinate of its outline at half
    Clipper2's range) and cut to the light's range where that cuts the face:
    thousands of faces under a light with a range come one by one, so this
    keeps to the clipping, with no cells' bookkeeping."""
    outline = limits.outlines[slot]
    scale = poly.local_scale(2.0 * _reach(limits, slot))
    if limits.full[slot]:
        region = poly.unite([outline * scale])
    else:
        start, stop = pieces.start[slot], pieces.start[slot] + pieces.count[slot]
        region = poly.intersect(
            poly.unite(list(pieces.flat[start:stop] * scale)), poly.unite([outline * scale])
        )
    disc = None if limits.discs is None else limits.discs[slot]
    if disc is not None:
        region = poly.intersect(region, poly.unite([disc * scale]))
    points, sizes = _region_loops(region)
    return points / scale, sizes, np.full(len(sizes), limits.faces[slot])


def _region_loops(region: CrossSection) -> tuple[np.ndarray, np.ndarray]:
    """The corners of the loops of ``region`` of at least three corners, one
    loop after another, and the corners of each."""
    loops = [loop for loop in region.to_polygons() if len(loop) >= 3]
    if not loops:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    return np.concatenate(loops), np.array([len(loop) for loop in loops], dtype=np.int64)


def _disc_near(disc: np.ndarray | None, outline: np.ndarray) -> np.ndarray | None:
    """The lit disc cut to the bounding box of a face's ``outline``: None when
    it covers the box (it limits nothing), an empty array when it misses it.
    A disc far larger than the face would otherwise leave the range the 2-D
    union accepts once scaled to the face."""
    if disc is None:
        return None
    low, high = outline.min(axis=0), outline.max(axis=0)
    box = shapely.box(low[0], low[1], high[0], high[1])
    region = shapely.Polygon(disc)
    if region.contains(box):
        return None
    cut = region.intersection(box)
    if cut.is_empty or cut.area == 0.0 or not isinstance(cut, shapely.Polygon):
        return np.zeros((0, 2))
    # counter-clockwise, as the positive fill rule keeps it (GEOS may return it clockwise)
    cut = shapely.geometry.polygon.orient(cut, 1.0)
    return np.asarray(cut.exterior.coords, dtype=np.float64)[:-1]
