"""Shadow volumes: the region of space a caster hides from a light, as a closed mesh.

The volume is built the way stencil shadow renderers build it, from the faces
that turn to the light (the *light cap*), a quad on every edge that bounds
those faces, swept away from the light (the *sides*), and the light cap moved
out along the light's rays and reversed (the *far cap*). Every cap half-edge is
paired with exactly one other half-edge by construction, so the result is
closed whatever the rounding:

* each face is front or not by one bit (:mod:`shadowgeo.silhouette`): two
  faces can never disagree about the edge between them;
* an edge where the cap touches itself at a vertex (a saddle on a non-convex
  caster, where the lit faces meet at one vertex only) gets one copy of that
  vertex per lit fan, so no side edge is shared by more than two triangles;
* far vertices lie on rays from the light, at a distance larger than any cap
  vertex, so no side quad or far triangle turns over.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .deprecation import renamed_keyword
from .errors import GeometryError
from .lights import DirectionalLight, Light, is_positional, require_light
from .limits import check_geometry, check_length
from .silhouette import check_light_outside, light_homogeneous
from .tolerance import Tolerance, below_resolution
from .topology import Caster, MeshLike, as_caster, empty_mesh

if TYPE_CHECKING:
    import trimesh

__all__ = ["shadow_volume"]


@renamed_keyword("mesh", "caster")
def shadow_volume(
    caster: MeshLike,
    light: Light,
    *,
    extent: float | None = None,
    tolerance: Tolerance | None = None,
) -> trimesh.Trimesh:
    """The closed region ``caster`` hides from ``light``, as a triangle mesh.

    A point is inside (winding number >= 1) when the segment from it to the
    light crosses the caster and the point lies before the far cap. The
    caster's own interior is inside.

    Parameters
    ----------
    caster : trimesh.Trimesh, Caster or (vertices, faces)
        A closed, 2-manifold, consistently wound mesh casts from its outer
        side. Any other mesh (open, with holes, inconsistently wound, an X3D
        ``solid="false"`` surface) is treated as two-sided: every face that is
        not edge-on casts, and the border edges are swept too. Edges used by
        more than two faces raise :class:`GeometryError`.
    light : PointLight, SpotLight or DirectionalLight
        A spot light counts as a point light at its position: outside its
        cone nothing is lit, so the volume is not cut to the cone.
    extent : float, optional
        How far the volume reaches. Point and spot lights: the distance D
        from the light within which it holds every shadowed point (see
        below). Directional lights: how far every cap point is swept along
        the light direction.
    tolerance : Tolerance, optional
        Defaults to ``Tolerance.for_points`` of the caster's bounds and the
        light's position.

    Returns
    -------
    trimesh.Trimesh
        Closed: every edge is used by exactly two triangles in opposite
        directions, outward-wound (positive volume), finite. It is built with
        ``process=False``: vertices shared by two lit fans at a saddle are
        separate copies and must stay so. ``metadata["shadowgeo"]`` records
        the far distances (point and spot lights, below) or the sweep length
        (``"sweep"``, directional), the face counts of the light cap and the
        sides (``"n_cap_faces"``, ``"n_side_faces"``), and whether the caster
        was treated as two-sided (``"two_sided"``). Empty (no faces) when no
        face casts: an empty caster, a flat one edge-on to the light, one
        whose faces have no height at ``tolerance.length`` (degenerate), or
        one a sun grazes so closely that the sweep moves its faces off their
        own planes by no more than ``tolerance.length`` (far from the origin,
        float64's spacing there): the far cap would round onto the near one.

        Where the volume ends. Point and spot lights: it holds every
        shadowed point within a distance D of the light, and its far vertices
        lie on rays from the light at ``D / h`` (``metadata
        ["far_vertex_distance"]``), where ``h <= 1`` is the least distance
        from the light to a cap triangle projected onto the unit sphere about
        it: a flat far triangle dips towards the light between its vertices,
        and this pushes it out so no part of it is nearer than D. D
        (``metadata["far_distance"]``) is, in order: the smaller of the
        light's finite ``radius`` and ``extent``; else ``extent``; else the
        distance from the light to the farthest corner of the caster's
        bounding box plus ``tolerance.bound_length`` (100 caster diagonals by
        default). A radius that ends inside the caster is lengthened to
        ``tolerance.chord_length`` past its farthest lit vertex (nothing
        there is lit either way); an ``extent`` that short is an error.
        Directional lights: every cap point is swept by ``extent``, else by
        ``tolerance.bound_length``.

    Raises
    ------
    GeometryError
        Invalid input, a coordinate, light radius or ``extent`` outside
        the supported range (:mod:`shadowgeo.limits`), a positional light
        touching the caster, inside a
        closed caster or so close to a lit face's plane that it sees the face
        across 180 degrees to within ``tolerance.relative``, edges used by
        more than two faces (named), an ``extent`` that does not reach past
        the caster, a caster no larger than float64's resolution where it
        sits (its volume would be zero).

    Examples
    --------
    A unit cube lit from straight above: its top face swept 2 units down, a
    1 x 1 x 2 box that holds the cube and the 1 unit of shadow below it.

    >>> import trimesh
    >>> cube = trimesh.creation.box()
    >>> volume = shadow_volume(cube, DirectionalLight([0, 0, -1]), extent=2.0)
    >>> volume.is_watertight, volume.is_winding_consistent, round(float(volume.volume), 12)
    (True, True, 2.0)
    """
    caster = as_caster(caster)
    require_light(light)
    check_geometry(caster, light)
    if extent is not None:
        extent = check_length(extent, "extent")
    if caster.n_faces == 0:
        return empty_mesh()
    if below_resolution(caster.bounds):
        low, high = caster.bounds
        raise GeometryError(
            f"caster from {low.tolist()} to {high.tolist()} is below float64 resolution "
            "where it sits: its volume would be zero (move the scene nearer the origin)"
        )
    if tolerance is None:
        tolerance = Tolerance.for_points(
            caster.bounds, *([light.position] if is_positional(light) else [])
        )
    if is_positional(light):
        check_light_outside(caster, light.position, tolerance)

    facing = _cap_facing(caster, light, extent, tolerance)
    two_sided = not caster.is_closed
    if two_sided:
        _check_edge_manifold(caster)
        orientation = np.sign(facing).astype(np.int8)
    else:
        orientation = (facing > 0).astype(np.int8)
    cap = np.flatnonzero(orientation)
    if len(cap) == 0:
        return empty_mesh()

    corner_vertex, boundary = _cap_corners(caster, cap, orientation[cap])
    # Compact the used ids: near vertices first, their far copies after.
    used = np.zeros(int(corner_vertex.max()) + 1, dtype=bool)
    used[corner_vertex] = True
    compact = np.cumsum(used) - 1
    n_used = int(used.sum())
    source = np.empty(n_used, dtype=np.int64)
    source[compact[corner_vertex]] = _original_vertex(caster, cap, orientation[cap])
    relative = caster.vertices[source] - caster.center
    near_faces = compact[corner_vertex].reshape(-1, 3)
    far, info = _far_points(caster, light, relative, near_faces, extent, tolerance)
    starts = near_faces.reshape(-1)[boundary]
    ends = near_faces.reshape(-1)[boundary - boundary % 3 + (boundary % 3 + 1) % 3]
    sides = np.concatenate(
        [
            np.column_stack([ends, starts, starts + n_used]),
            np.column_stack([ends, starts + n_used, ends + n_used]),
        ]
    )
    faces = np.concatenate([near_faces, near_faces[:, ::-1] + n_used, sides])
    vertices = np.concatenate([caster.vertices[source], far + caster.center])
    import trimesh

    result = trimesh.Trimesh(vertices, faces, process=False, validate=False)
    info.update(n_cap_faces=len(cap), n_side_faces=len(sides), two_sided=two_sided)
    result.metadata["shadowgeo"] = info
    return result


def _cap_facing(
    caster: Caster, light: Light, extent: float | None, tolerance: Tolerance
) -> np.ndarray:
    """(f,) each face's facing towards the light, 0 for a face edge-on to it
    (within the tolerances)."""
    facing = caster.facing(light_homogeneous(caster, light))
    # A face with no height at the length tolerance (two corners at one point,
    # or all three on a line) is edge-on to every light: the sign of its
    # facing is rounding, and a cap of such faces would enclose no volume.
    triangles = caster.triangles
    longest = np.abs(triangles - triangles[:, [1, 2, 0]]).max(axis=(1, 2))
    doubled = np.abs(caster.face_normals).max(axis=1)
    edge_on = doubled <= tolerance.length * longest
    if isinstance(light, DirectionalLight):
        # a sun within ``tolerance.angle`` of a face's plane grazes it: edge-on
        scale = np.where(doubled > 0, doubled, 1.0)
        lengths = doubled * np.linalg.norm(caster.face_normals / scale[:, None], axis=1)
        edge_on |= np.abs(facing) <= tolerance.angle * lengths * np.linalg.norm(light.direction)
        # ... and so does one that the sweep moves off its own plane by no more
        # than the length tolerance (far from the origin, float64's spacing
        # there): the far cap would round onto the near one, a zero volume.
        sweep = tolerance.bound_length if extent is None else extent
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            cosine = np.abs(facing) / (lengths * np.linalg.norm(light.direction))
        edge_on |= cosine * sweep <= tolerance.length
    edge_free: np.ndarray = np.where(edge_on, 0.0, facing)
    return edge_free


def _check_edge_manifold(caster: Caster) -> None:
    crowded = np.flatnonzero(caster.edge_face_count > 2)
    if len(crowded):
        shown = ", ".join(
            f"{caster.edges[index].tolist()} ({int(caster.edge_face_count[index])} faces)"
            for index in crowded[:8]
        )
        more = f" and {len(crowded) - 8} more" if len(crowded) > 8 else ""
        raise GeometryError(
            f"the caster has {len(crowded)} edges used by more than two faces, so no closed "
            f"manifold volume can be swept from it: vertex pairs {shown}{more}"
        )


def _oriented_faces(caster: Caster, cap: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    """(c, 3) cap faces wound to face the light (faces with orientation -1 reversed)."""
    faces = caster.faces[cap]
    oriented: np.ndarray = np.where(orientation[:, None] > 0, faces, faces[:, [0, 2, 1]])
    return oriented


def _original_vertex(caster: Caster, cap: np.ndarray, orientation: np.ndarray) -> np.ndarray:
    return _oriented_faces(caster, cap, orientation).reshape(-1)


def _cap_corners(
    caster: Caster, cap: np.ndarray, orientation: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Vertex id of each cap corner (c * 3,) and the boundary half-edges.

    Corner ``3 * i + j`` is corner j of cap face i as wound towards the light;
    half-edge ``3 * i + j`` runs from it to corner ``j + 1``. A half-edge is
    interior when its edge has exactly two faces in the cap, run in opposite
    directions, and no other face; every other cap half-edge is boundary and
    gets a side quad. Ids are the caster's vertex ids, except at a vertex
    where the cap is pinched (more than one boundary half-edge leaves it):
    there each fan of cap faces joined through interior edges gets its own id
    (from ``len(caster.vertices)`` up), so every id has at most one boundary
    half-edge in and one out.
    """
    oriented = _oriented_faces(caster, cap, orientation)
    corner_vertex = oriented.reshape(-1)
    # Edge of each oriented half-edge: reversed faces run edges 2, 1, 0 backwards.
    edge_ids = np.where(
        orientation[:, None] > 0, caster.face_edges[cap], caster.face_edges[cap][:, [2, 1, 0]]
    ).reshape(-1)
    signs = np.where(
        orientation[:, None] > 0,
        caster.face_edge_signs[cap],
        -caster.face_edge_signs[cap][:, [2, 1, 0]],
    ).reshape(-1)
    n_edges = len(caster.edges)
    cap_count = np.bincount(edge_ids, minlength=n_edges)
    net = np.bincount(edge_ids, weights=signs, minlength=n_edges)
    interior_edge = (cap_count == 2) & (caster.edge_face_count == 2) & (net == 0)
    interior = interior_edge[edge_ids]
    boundary = np.flatnonzero(~interior)

    out_degree = np.bincount(corner_vertex[boundary], minlength=len(caster.vertices))
    pinched = out_degree > 1
    if not pinched.any():
        return corner_vertex, boundary
    # Pair the interior half-edges that touch a pinched vertex with their twins.
    half = np.arange(len(corner_vertex))
    following = half - half % 3 + (half % 3 + 1) % 3
    touches = interior & (pinched[corner_vertex] | pinched[corner_vertex[following]])
    candidates = np.flatnonzero(touches)
    # Each such edge has both its half-edges here (both touch the same vertex).
    candidates = candidates[np.argsort(edge_ids[candidates], kind="stable")]
    first, second = candidates[0::2], candidates[1::2]
    # first runs a -> b, second b -> a: join their corners at a and at b.
    left = np.concatenate([first, following[first]])
    right = np.concatenate([following[second], second])
    labels = np.arange(len(corner_vertex))
    while True:
        low = np.minimum(labels[left], labels[right])
        before = labels.copy()
        np.minimum.at(labels, left, low)
        np.minimum.at(labels, right, low)
        labels = labels[labels]
        if np.array_equal(labels, before):
            break
    at_pinch = np.flatnonzero(pinched[corner_vertex])
    _, fan = np.unique(labels[at_pinch], return_inverse=True)
    corner_vertex = corner_vertex.copy()
    corner_vertex[at_pinch] = len(caster.vertices) + fan
    return corner_vertex, boundary


def _far_points(
    caster: Caster,
    light: Light,
    relative: np.ndarray,
    faces: np.ndarray,
    extent: float | None,
    tolerance: Tolerance,
) -> tuple[np.ndarray, dict[str, object]]:
    """Far copies of the cap vertices (in the caster's centred frame) and
    what decided the far distance."""
    if isinstance(light, DirectionalLight):
        sweep = tolerance.bound_length if extent is None else extent
        if sweep <= tolerance.length:
            raise GeometryError(f"extent {sweep!r} is too short to sweep (tolerance)")
        return relative + sweep * light.direction, {"sweep": sweep}
    position = light.position - caster.center
    rays = relative - position
    distance = np.sqrt(np.einsum("ij,ij->i", rays, rays))
    reach = float(distance.max())
    shortest = reach + tolerance.chord_length
    if extent is not None:
        far = min(extent, light.radius)
        if far < shortest and extent < shortest:
            raise GeometryError(
                f"extent {extent!r} does not reach past the caster: its farthest lit vertex is "
                f"{reach:.6g} from the light (the volume needs at least {shortest:.6g})"
            )
        far = max(far, shortest)
    elif math.isfinite(light.radius):
        far = max(light.radius, shortest)
    else:
        corners = np.array(np.meshgrid(*caster.bounds.T)).reshape(3, -1).T - caster.center
        far = float(np.linalg.norm(corners - position, axis=1).max()) + tolerance.bound_length
    units = rays / distance[:, None]
    nearest = _nearest_chord(units, faces)
    if nearest <= tolerance.relative:
        raise GeometryError(
            f"the light at {light.position.tolist()} is so close to the plane of a lit face "
            f"that it sees it across nearly 180 degrees (chord distance {nearest:.3g}); "
            "move it away from the caster"
        )
    # Flat far triangles dip towards the light between their vertices: push
    # the vertices out so that no point of the far cap is nearer than `far`.
    vertex_distance = far / nearest
    return position + units * vertex_distance, {
        "far_distance": far,
        "far_vertex_distance": vertex_distance,
    }


def _nearest_chord(units: np.ndarray, faces: np.ndarray) -> float:
    """Smallest distance from the light to the cap triangles projected onto
    the unit sphere about it (<= 1).

    The corners of such a triangle are equidistant from the light, so the
    foot of the perpendicular from the light on its plane is its
    circumcentre: for an acute triangle the nearest point is that foot, at
    ``sqrt(1 - r^2)`` (circumradius ``r``); otherwise it is the midpoint of
    the longest side ``c``, at ``sqrt(1 - c^2 / 4)``.
    """
    corners = units[faces]  # (c, 3, 3)
    sides = corners - corners[:, [1, 2, 0]]
    squared = np.einsum("ijk,ijk->ij", sides, sides)  # (c, 3) squared side lengths
    longest = squared.max(axis=1)
    total = squared.sum(axis=1)
    acute = longest < total - longest
    # 16 area^2 = 2 (a2 b2 + b2 c2 + c2 a2) - (a2^2 + b2^2 + c2^2)
    products = squared * squared[:, [1, 2, 0]]
    area16 = 2.0 * products.sum(axis=1) - np.einsum("ij,ij->i", squared, squared)
    with np.errstate(divide="ignore", invalid="ignore"):
        circum = np.where(acute & (area16 > 0), squared.prod(axis=1) / area16, np.inf)
    nearest_squared = np.where(acute & np.isfinite(circum), 1.0 - circum, 1.0 - longest / 4.0)
    return math.sqrt(min(max(float(nearest_squared.min()), 0.0), 1.0))
