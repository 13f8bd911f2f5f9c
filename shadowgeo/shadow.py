"""The result of a planar shadow: :class:`Shadow` and its :class:`ShadowDiagnostics`.

Both the general path of :func:`shadowgeo.project_shadow` and the array path
of many lights (:mod:`shadowgeo.batchlights`) build these.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from . import plane2d as poly
from .lights import Light
from .plane import Plane

if TYPE_CHECKING:
    import shapely
    import trimesh

__all__ = ["Shadow", "ShadowDiagnostics", "triangulated"]


@dataclass(frozen=True)
class ShadowDiagnostics:
    """What :func:`project_shadow` did to get its result.

    Attributes
    ----------
    n_triangles : int
        Caster triangles considered.
    clipped : dict[str, int]
        Triangles cut (partly or wholly) for each reason: ``"below_plane"``
        (the caster pierces the receiver), ``"at_or_above_light"`` (the
        anti-shadow and divide-by-zero region), ``"outside_receiver"`` or
        ``"outside_bound"`` (the shadow leaves the receiver's bounding box or
        the default bound).
    culled : int
        Triangles that cast nothing at all.
    limits : tuple[str, ...]
        2-D limits applied after projection: ``"receiver"``, ``"spot_cone"``,
        ``"range"``.
    bounded_artificially : bool
        The shadow runs past the default bound (it is truly unbounded, or
        larger than ``bound``): no receiver limited it.
    bound : float or None
        Half-width of the default bound square used, in scene units.
    empty_reason : str or None
        Why the shadow is empty, when it is empty for a reason other than
        geometry (light behind or parallel to the plane, out of range, ...).
    n_loops : int
        Loops handed to the 2-D union (outline edges chained, plus clipped
        triangles): a measure of the work done.
    """

    n_triangles: int = 0
    clipped: dict[str, int] = field(default_factory=dict)
    culled: int = 0
    limits: tuple[str, ...] = ()
    bounded_artificially: bool = False
    bound: float | None = None
    empty_reason: str | None = None
    n_loops: int = 0


@dataclass(frozen=True)
class Shadow:
    """A planar shadow.

    Attributes
    ----------
    plane : Plane
        The receiving plane.
    light : Light
        The light that casts it.
    mesh : trimesh.Trimesh
        The shadow region triangulated on the plane (lifted by ``offset``
        towards the light), with no overlapping triangles, wound
        counter-clockwise seen from the light's side. A property, computed
        on first use from ``mesh_source`` (a mesh, or a function that builds
        it).
    polygons : list of list of (k, 2) float64
        The region in ``plane.to_2d`` coordinates: one ``[outer, hole, ...]``
        list per connected part, outer loops counter-clockwise.
    area : float
        Exact area of the region (scene units squared).
    diagnostics : ShadowDiagnostics
    """

    plane: Plane
    light: Light
    mesh_source: trimesh.Trimesh | Callable[[], trimesh.Trimesh] = field(repr=False)
    polygons: list[list[np.ndarray]]
    area: float
    diagnostics: ShadowDiagnostics

    @property
    def mesh(self) -> trimesh.Trimesh:
        """The region triangulated, built on first use: a caller that needs
        only ``polygons`` or ``area`` (a sun study, a union of many
        buildings) never pays for the triangulation."""
        source = self.mesh_source
        if not callable(source):  # built already (a Trimesh is not callable)
            return source
        mesh = source()
        object.__setattr__(self, "mesh_source", mesh)
        return mesh

    @property
    def is_empty(self) -> bool:
        return self.area == 0.0

    def to_shapely(self) -> shapely.MultiPolygon:
        """The region as a ``shapely.MultiPolygon`` in plane 2-D coordinates."""
        import shapely

        parts = [shapely.Polygon(loops[0], loops[1:]) for loops in self.polygons]
        return shapely.MultiPolygon(parts)


def triangulated(
    parts: list[list[np.ndarray]],
    scale: float,
    lift: np.ndarray,
    basis: tuple[np.ndarray, np.ndarray],
) -> trimesh.Trimesh:
    """The mesh of a shadow's parts (local units) on the plane of ``basis``,
    ``lift`` being the scene point of the local origin."""
    u, v = basis
    flat, faces = poly.triangulate_parts(parts)
    flat = flat / scale
    points = lift + np.outer(flat[:, 0], u) + np.outer(flat[:, 1], v)
    import trimesh  # (imported when a mesh is first asked for: its import takes 1 s)

    return trimesh.Trimesh(points, faces, process=False)
