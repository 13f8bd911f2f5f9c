"""Planar shadows: the shadow matrix and exact, robust projection onto a plane.

The classic planar shadow multiplies every caster vertex by one 4x4 matrix
(Blinn 1988) and divides by ``w``. That goes wrong where ``w <= 0``: vertices
at the light's height divide by zero and vertices above it land on the wrong
side of the light as "anti-shadows". :func:`project_shadow` instead clips every
triangle, *before* the divide, against

* the receiving plane itself (parts of a caster below the receiver cast
  nothing), and
* the four planes that join the light to a rectangle on the receiver (the
  receiver's bounding box, or a default bound when there is no receiver).

Because that rectangle is bounded, the pyramid over it contains no point with
``w <= 0`` except the light: clipping removes anti-shadows and the division by
zero in one mechanism. What survives is projected and united exactly by
winding number: triangles that need no clipping contribute only the boundary
of their patch (for a closed caster, its silhouette), so the cost grows with
the outline, not with the triangle count. Concave receivers, spot cones and a
light's range are then applied as exact 2-D intersections.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from functools import cached_property, partial
from typing import TYPE_CHECKING, Literal, cast, overload

import numpy as np
from manifold3d import CrossSection
from numpy.typing import ArrayLike

from . import plane2d as poly
from .batchlights import (
    CASTS,
    LightFrames,
    array_shadows,
    light_frames,
    pieces,
    projected_many,
    settle,
    takes_arrays,
)
from .errors import GeometryError
from .lightframe import clip_batch, clip_one
from .lights import DirectionalLight, Light, SpotLight, is_positional, require_light
from .limits import ANGLE_SLACK, check_coordinates, check_light
from .orientation import MAX_COORDINATE
from .plane import Plane

# Shadow and ShadowDiagnostics live in .shadow; they are re-exported here,
# where they were first defined and are still imported from.
from .shadow import Shadow as Shadow
from .shadow import ShadowDiagnostics as ShadowDiagnostics
from .shadow import triangulated
from .silhouette import (
    boundary_loops,
    check_light_outside,
    silhouette_loops,
    silhouette_loops_many,
    vertex_components,
)
from .tolerance import Tolerance
from .topology import Caster, MeshLike, as_caster, empty_mesh, unique_integers

if TYPE_CHECKING:
    from .lights import PointLight

__all__ = ["project_shadow", "shadow_matrix"]


def shadow_matrix(plane: Plane, light: Light) -> np.ndarray:
    """The planar shadow matrix ``M = (P . L) I - L P^T``.

    For column vectors, ``x' = M @ [x, y, z, 1]`` is the shadow of ``x`` on
    ``plane`` in homogeneous coordinates (divide by ``x'[3]``). Points on the
    plane stay where they are; the light maps to zero.

    Parameters
    ----------
    plane : Plane
        ``P = (a, b, c, d)`` with a unit normal.
    light : PointLight, SpotLight or DirectionalLight
        ``L = (x, y, z, 1)`` or ``(-direction, 0)``.

    Returns
    -------
    (4, 4) float64

    Notes
    -----
    With row vectors (``x'^T = x^T M^T``, the form used by X3D authors and the
    DirectX literature) the matrix is the transpose. This matrix is only the
    textbook method: it gives anti-shadows for points beyond the light and
    divides by zero at the light's height; :func:`project_shadow` does not.

    Examples
    --------
    The ground y = 0 and a light at (8, 9, 10), in row-vector form:

    >>> from shadowgeo import Plane, PointLight
    >>> M = shadow_matrix(Plane([0, 1, 0], 0), PointLight([8, 9, 10]))
    >>> M.T
    array([[  9.,   0.,   0.,   0.],
           [ -8.,   0., -10.,  -1.],
           [  0.,   0.,   9.,   0.],
           [  0.,   0.,   0.,   9.]])
    >>> p = M @ [-2, 3, -1, 1]
    >>> (p[:3] / p[3]).tolist()
    [-7.0, 0.0, -6.5]
    """
    P = plane.vector
    L = light.homogeneous
    return float(P @ L) * np.eye(4) - np.outer(L, P)


@overload
def project_shadow(
    caster: MeshLike,
    light: Light,
    plane: Plane,
    *,
    receiver: ArrayLike | None = None,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
    method: Literal["auto", "triangles"] = "auto",
) -> Shadow: ...


@overload
def project_shadow(
    caster: MeshLike,
    light: Sequence[Light],
    plane: Plane,
    *,
    receiver: ArrayLike | None = None,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
    method: Literal["auto", "triangles"] = "auto",
) -> list[Shadow]: ...


def project_shadow(
    caster: MeshLike,
    light: Light | Sequence[Light],
    plane: Plane,
    *,
    receiver: ArrayLike | None = None,
    offset: float = 0.0,
    tolerance: Tolerance | None = None,
    method: Literal["auto", "triangles"] = "auto",
) -> Shadow | list[Shadow]:
    """The exact shadow of ``caster`` cast by ``light`` on ``plane``.

    Parameters
    ----------
    caster : trimesh.Trimesh, Caster or (vertices, faces)
        Any triangle mesh: closed or open, concave, with degenerate faces or
        duplicate vertices. Open meshes cast from both sides.
    light : PointLight, SpotLight or DirectionalLight, or a sequence of them
        A sequence gives one shadow per light, in order, each equal to what
        the call with that light alone returns; the caster is checked and
        prepared (topology, bounds) once for all of them.
    plane : Plane
        The receiving plane. Its normal gives the lit side: a light behind it
        casts no shadow on it.
    receiver : (n, 3) array_like, optional
        A polygon on the plane (convex or not) that bounds the shadow.
    offset : float
        Lift of the result along the plane normal, towards the light, so that
        it does not z-fight the receiver.
    tolerance : Tolerance, optional
        Defaults to ``Tolerance.for_points`` of the caster, light and receiver.
    method : {"auto", "triangles"}
        ``"auto"`` unites outlines: the silhouette of a closed caster, the
        boundary of each same-facing patch of an open one, and only the
        triangles that need clipping one by one. ``"triangles"`` unites every
        projected triangle separately (the textbook union, made robust); it
        gives the same region, more slowly, and is there to compare against.

    Returns
    -------
    Shadow, or list of Shadow for a sequence of lights
        Guaranteed finite (no NaN or inf), non-overlapping, within the
        receiver if one is given, else within the default bound (a square of
        half-width ``tolerance.bound_length`` centred on the foot of a
        positional light, or on the caster's shadow for a directional light);
        ``diagnostics.bounded_artificially`` says when that bound cut it.

    Raises
    ------
    GeometryError
        Invalid input (NaN, zero normal, faces indexing missing vertices), a
        coordinate, plane offset or light radius outside the range float64
        carries through the shadow formulas (:mod:`shadowgeo.limits`), a
        positional light on the plane, touching the caster, or inside a
        closed caster, a receiver point off the plane. For a sequence of
        lights the message starts with the index of the light at fault.

    Examples
    --------
    The X3D pyramid example: the light at (8, 9, 10) above the ground y = 0.

    >>> vertices = [[-2, 3, -1], [2, 3, -1], [0, 3, 2], [0, 5, 0]]
    >>> faces = [[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]]
    >>> from shadowgeo import Plane, PointLight
    >>> shadow = project_shadow((vertices, faces), PointLight([8, 9, 10]), Plane([0, 1, 0], 0))
    >>> round(shadow.area, 9)
    31.5
    """
    caster = as_caster(caster)
    if not isinstance(plane, Plane):
        raise GeometryError(f"plane must be a shadowgeo.Plane, got {plane!r}")
    receiver_points = _receiver_points(receiver)
    offset = float(offset)
    if not math.isfinite(offset):
        raise GeometryError(f"offset must be finite, got {offset!r}")
    if method not in ("auto", "triangles"):
        raise GeometryError(f"method must be 'auto' or 'triangles', got {method!r}")
    if caster.n_faces:
        check_coordinates(caster.bounds, "caster bounds")
    check_coordinates([plane.offset], "plane offset")
    call = _Call(
        caster, plane, plane.basis, receiver_points, offset, tolerance, method == "triangles"
    )
    if not isinstance(light, Sequence):  # a batch of one: the same stages, the same bits
        return _many_lights(call, [light], single=True)[0]
    return _many_lights(call, light)


@dataclass(frozen=True)
class _Call:
    """What one :func:`project_shadow` call shares between its lights: the
    checked caster, plane (with its basis, computed once), receiver and
    options."""

    caster: Caster
    plane: Plane
    basis: tuple[np.ndarray, np.ndarray]
    receiver: np.ndarray
    offset: float
    tolerance: Tolerance | None
    per_triangle: bool

    @cached_property
    def box_corners(self) -> np.ndarray:
        """(8, 4) homogeneous corners of the caster's box, centred frame."""
        box = self.caster.bounds - self.caster.center
        return np.array([[x, y, z, 1.0] for x in box[:, 0] for y in box[:, 1] for z in box[:, 2]])

    def projector(self, light: Light, tolerance: Tolerance | None = None) -> _Projector:
        """The projector of one light, its tolerance the caller's, else
        ``tolerance``, else found from the scene's points."""
        check_light(require_light(light))
        if self.tolerance is not None:
            tolerance = self.tolerance
        elif tolerance is None:
            tolerance = self.scene_tolerance(light)
        return _Projector(self, light, tolerance)

    def takes_arrays(self, light: Light) -> bool:
        """Whether ``light`` takes the array path (:mod:`shadowgeo.batchlights`):
        a closed caster, no receiver, the outline method, and a point light of
        unlimited range or a directional light."""
        return self.takes_arrays_at_all and takes_arrays(light)

    @cached_property
    def takes_arrays_at_all(self) -> bool:
        """A closed caster, no receiver and the outline method: lights of
        the right kinds take the array path."""
        return self.caster.is_closed and not self.per_triangle and not len(self.receiver)

    @cached_property
    def directional_tolerance(self) -> Tolerance:
        """:meth:`scene_tolerance` of any directional light (it has no point
        of its own), found once."""
        caster = self.caster
        scene = [caster.bounds if caster.n_faces else np.zeros((0, 3))]
        return Tolerance.for_points(*scene, self.receiver)

    def scene_tolerance(self, light: Light) -> Tolerance:
        """``Tolerance.for_points`` of the caster, the light and the receiver."""
        light_points = [light.position] if is_positional(light) else []
        caster = self.caster
        scene = [caster.bounds if caster.n_faces else np.zeros((0, 3))]
        return Tolerance.for_points(*scene, *light_points, self.receiver)


def _many_lights(call: _Call, lights: Sequence[Light], single: bool = False) -> list[Shadow]:
    """One shadow per light, each equal to the single-light call's (which
    comes here too, ``single``, for a light that takes the array path).

    The stages: :func:`_routes` (the frames of the lights that
    :meth:`_Call.takes_arrays`, found together), :func:`_set_up` (the others,
    and those the frames leave unsure, one by one), then the array path's
    shadows (:func:`_array_stage`) and the outlines of the rest, for a closed
    caster found together (:func:`_finished`). Each light's outline goes to
    the 2-D union on its own. Errors found while setting up come in the
    lights' order.
    """
    context = partial(_light_context, prefix=not single)
    routes = _routes(call, lights)
    set_up = _set_up(call, lights, routes, context)
    shadows = dict(set_up.done)
    if routes.frames is not None:
        shadows.update(_array_stage(call, lights, routes.frames, set_up.arrays, context))
    shadows.update(_finished(call, set_up.pending, context))
    return [shadows[index] for index in range(len(lights))]


_Context = Callable[[int], AbstractContextManager[None]]


@dataclass(frozen=True)
class _Routes:
    """Which road each light takes: ``frames`` of the lights on the array
    path (None when none is), ``arrays`` the (light index, frame row) that
    take it as they are, ``checked`` the frame row of those to check first,
    ``one_by_one`` the lights set up on their own or checked, in order."""

    frames: LightFrames | None
    arrays: tuple[tuple[int, int], ...]
    checked: dict[int, int]
    one_by_one: tuple[int, ...]


@dataclass(frozen=True)
class _SetUp:
    """What setting the lights up gave: the shadows it ``done`` already, the
    ``arrays`` (light index, frame row) for the array path, sorted, and the
    ``pending`` projectors whose outlines remain."""

    done: dict[int, Shadow]
    arrays: list[tuple[int, int]]
    pending: list[tuple[int, _Projector]]


def _routes(call: _Call, lights: Sequence[Light]) -> _Routes:
    """The lights' roads, the array path's frames found together."""
    arrays = (
        [index for index, light in enumerate(lights) if takes_arrays(light)]
        if call.takes_arrays_at_all
        else []
    )
    if not arrays:
        return _Routes(None, (), {}, tuple(range(len(lights))))
    frames = light_frames(
        call.caster,
        call.plane.normal,
        call.plane.offset,
        call.basis,
        [lights[index] for index in arrays],
        call.tolerance,
    )
    # Most lights: nothing to check or refuse one by one.
    plain = frames.in_range & (frames.verdict == CASTS) & ~frames.near & frames.inside
    ready = tuple((arrays[row], row) for row in np.flatnonzero(plain).tolist())
    checked = {arrays[row]: row for row in np.flatnonzero(~plain).tolist()}
    taken = set(arrays)
    own = [index for index in range(len(lights)) if index not in taken]
    return _Routes(frames, ready, checked, tuple(sorted(own + list(checked))))


def _set_up(call: _Call, lights: Sequence[Light], routes: _Routes, context: _Context) -> _SetUp:
    """Each light of ``routes.one_by_one`` set up in turn: a shadow already,
    a projector pending, or (checked) back to the array path."""
    done: dict[int, Shadow] = {}
    arrays = list(routes.arrays)
    pending: list[tuple[int, _Projector]] = []
    for index in routes.one_by_one:
        with context(index):
            outcome = _set_up_one(call, lights[index], routes, index)
        if isinstance(outcome, _Projector):
            pending.append((index, outcome))
        elif outcome is None:
            arrays.append((index, routes.checked[index]))
        else:
            done[index] = outcome
    return _SetUp(done, sorted(arrays), pending)


def _set_up_one(
    call: _Call, light: Light, routes: _Routes, index: int
) -> Shadow | _Projector | None:
    """One light set up: its shadow when that already decides it, else its
    projector; None for a checked light that takes the array path after all."""
    row = routes.checked.get(index)
    frames = routes.frames
    if row is not None and frames is not None:
        settled = settle(call.caster, call.plane, frames, row, light, call.tolerance)
        if settled is not None:
            return settled
        if frames.inside[row]:
            return None
        return _prepared(_Projector(call, light, frames.tolerance(row, call.tolerance)))
    shared = call.directional_tolerance if isinstance(light, DirectionalLight) else None
    return _prepared(call.projector(light, shared))


def _prepared(projector: _Projector) -> Shadow | _Projector:
    """The projector set up (:meth:`_Projector.prepare`): the shadow when
    that decides it, else the projector, ready to finish."""
    early = projector.prepare()
    return early if early is not None else projector


def _array_stage(
    call: _Call,
    lights: Sequence[Light],
    frames: LightFrames,
    arrays: list[tuple[int, int]],
    context: _Context,
) -> dict[int, Shadow]:
    """The shadows of the lights on the array path, a chunk at a time; one
    the arrays turn back takes the general path."""
    shadows: dict[int, Shadow] = {}
    for first in range(0, len(arrays), _LIGHT_CHUNK):
        rows = arrays[first : first + _LIGHT_CHUNK]
        found = array_shadows(
            call.caster, call.plane, call.basis, call.offset, frames, lights, rows
        )
        for index, row in rows:
            with context(index):
                shadow = next(found)
                if shadow is None:  # the general path after all
                    tolerance = frames.tolerance(row, call.tolerance)
                    shadow = _Projector(call, lights[index], tolerance).run()
                shadows[index] = shadow
    return shadows


def _finished(
    call: _Call, pending: list[tuple[int, _Projector]], context: _Context
) -> dict[int, Shadow]:
    """The pending projectors' shadows; a closed caster's silhouettes are
    found and projected together, a chunk of lights at a time."""
    shadows: dict[int, Shadow] = {}
    caster = call.caster
    if not caster.is_closed or call.per_triangle:
        for index, projector in pending:
            with context(index):
                shadows[index] = projector.finish()
        return shadows
    for first in range(0, len(pending), _LIGHT_CHUNK):
        chunk = pending[first : first + _LIGHT_CHUNK]
        fronts = [caster.facing(projector.light_h) > 0 for _, projector in chunk]
        outlines = silhouette_loops_many(caster, fronts)
        projected = projected_many(caster.centered, outlines, [p.H for _, p in chunk])
        for (index, projector), front, (loops, _), (flat, box) in zip(
            chunk, fronts, outlines, projected, strict=True
        ):
            with context(index):
                shadows[index] = projector.finish(_Outline(front, loops, flat, box))
    return shadows


# Lights whose silhouettes are found together: bounds the memory of the
# (lights x faces) front bits.
_LIGHT_CHUNK = 256


@contextmanager
def _light_context(index: int, prefix: bool = True) -> Iterator[None]:
    """Prefix a GeometryError's message with the index of the light at fault
    (unless ``prefix`` is False: a single light's call)."""
    try:
        yield
    except GeometryError as error:
        if not prefix:
            raise
        raise GeometryError(f"light {index}: {error}") from error


@dataclass(frozen=True)
class _Outline:
    """A closed caster's front faces and silhouette for one light, found
    beforehand for many lights at once."""

    front: np.ndarray
    loops: list[np.ndarray]  # of vertex indices
    projected: list[np.ndarray] | None  # (k, 2) each, local units; None: a vertex at infinity
    box: np.ndarray  # (2, 2) lower and upper corner of the projected points


def _receiver_points(receiver: ArrayLike | None) -> np.ndarray:
    if receiver is None:
        return np.zeros((0, 3))
    points = np.asarray(receiver, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 3:
        raise GeometryError(f"receiver must be (n >= 3, 3) points, got shape {points.shape}")
    check_coordinates(points, "receiver")
    return points


class _Projector:
    """One light of a :func:`project_shadow` call; holds the light's frame.

    :meth:`run` is the whole computation. It is two halves so that a call
    with many lights can set every frame up first and then find the
    silhouettes of all of them together: :meth:`prepare` (the light's frame
    on the plane, the rectangle the shadow can reach, the 2-D limits) and
    :meth:`finish` (the outline, its 2-D union, the result).
    """

    def __init__(self, call: _Call, light: Light, tol: Tolerance) -> None:
        self.call = call
        self.caster = call.caster
        self.light = light
        self.plane = call.plane
        self.receiver = call.receiver
        self.offset = call.offset
        self.tol = tol
        self.per_triangle = call.per_triangle
        self.clipped: dict[str, int] = {}
        self.limits: list[str] = []

    # -- result helpers -------------------------------------------------------------------

    def empty(self, reason: str | None) -> Shadow:
        info = ShadowDiagnostics(
            n_triangles=self.caster.n_faces,
            clipped=dict(self.clipped),
            limits=tuple(self.limits),
            empty_reason=reason,
        )
        return Shadow(self.plane, self.light, empty_mesh, [], 0.0, info)

    # -- the computation ------------------------------------------------------------------

    def run(self) -> Shadow:
        early = self.prepare()
        return early if early is not None else self.finish()

    def prepare(self) -> Shadow | None:
        """Set up the light's frame, the window and the 2-D limits; the
        (empty) shadow when that already decides it, else None."""
        if self.caster.n_faces == 0:
            return self.empty("the caster has no faces")
        early = self._light_frame()
        if early is not None:
            return early
        receiver2d = self._plane_frame()
        window = self._window(receiver2d)
        if isinstance(window, Shadow):
            return window
        self.low, self.high, self.limit_regions = window
        return None

    def finish(self, outline: _Outline | None = None) -> Shadow:
        """The shadow, from the frame :meth:`prepare` set up. ``outline``: the
        front faces and silhouette of a closed caster, found beforehand."""
        low, high, limit_regions = self.low, self.high, list(self.limit_regions)
        loops, outline_loops, box = self._shadow_loops(low, high, outline)
        self.n_loops = len(loops)
        if loops:
            reached = self._within_reach(loops, box)
            if not limit_regions and (np.any(reached[0] < low) or np.any(reached[1] > high)):
                # Whole faces project past the bound: cut them there.
                corners = np.array([low, [high[0], low[1]], high, [low[0], high[1]]])
                limit_regions.append(poly.unite([corners]))
        groups = partial(self._loop_groups, outline_loops)
        if poly.whole_loop(loops):  # one simple loop: no union, and no cut when inside
            low2d, high2d = loops[0].min(axis=0), loops[0].max(axis=0)
            if all(poly.holds_box(limit, low2d, high2d) for limit in limit_regions):
                return self._result([loops], 1)
        if not limit_regions:
            return self._result(poly.unite(loops, groups=groups, form="parts"), len(loops))
        region = poly.unite(loops, groups=groups)
        for limit in limit_regions:
            region = poly.intersect(region, limit)
        return self._result(poly.components(region), len(loops))

    def _within_reach(self, loops: list[np.ndarray], box: np.ndarray | None) -> np.ndarray:
        """The box of the 2-D ``loops`` (``box`` when known), checked to lie
        within the widened rectangle every face was sorted by (``_REACH``).
        Only rounding puts a point beyond it: a caster whose coordinates
        reach so far past the receiver's size (one vertex at 3e35 beside
        houses of 10 m) that float64's last place of its largest coordinate
        is wider than the receiver. Its shadow cannot be told from rounding,
        so it is a GeometryError rather than a union fed points past the
        range it accepts."""
        if box is None:
            points = np.concatenate(loops)
            box = np.array([points.min(axis=0), points.max(axis=0)])
        if np.abs(box).max() <= _REACH_LIMIT:
            return box
        largest = float(np.abs(self.caster.vertices).max())
        raise GeometryError(
            f"the caster's coordinates (up to {largest:.3g}) are too large beside the "
            f"{MAX_COORDINATE / self.scale:.3g} the shadow is sought within: float64 rounds "
            "them by more than that, so their shadow cannot be told apart from rounding"
        )

    def _light_frame(self) -> Shadow | None:
        """The light in the caster's centred frame (``light_h``) and the
        plane point the 2-D frame starts from (``origin``); an empty shadow
        when the light cannot reach the plane's front."""
        tol = self.tol
        # Work relative to the caster's centre: differences of nearby large
        # coordinates are exact, so a scene far from the origin loses nothing.
        self.center = self.caster.center
        normal = self.plane.normal
        self.d = self.plane.offset + float(normal @ self.center)
        if is_positional(self.light):
            self.light_position = self.light.position - self.center
            height = float(normal @ self.light_position) + self.d
            if abs(height) <= tol.length:
                raise GeometryError(
                    f"the light at {self.light.position.tolist()} lies on the receiving plane "
                    f"(distance {height:.3g}, tolerance {tol.length:.3g})"
                )
            if height < 0:
                return self.empty("the light is behind the plane (its normal points away)")
            if self.light.radius <= height:
                return self.empty("the light's radius does not reach the plane")
            self.height = height
            check_light_outside(self.caster, self.light.position, tol)
            self.light_h = np.append(self.light_position, 1.0)
            self.origin = self.light_position - height * normal  # the light's foot
            return None
        cosine = -float(normal @ self.light.direction)
        if abs(cosine) <= tol.angle:
            return self.empty("the light travels parallel to the plane")
        if cosine < 0:
            return self.empty("the light shines on the back of the plane")
        self.light_h = np.append(-self.light.direction, 0.0)
        # The caster centre's shadow: the shadow lies around it.
        self.origin = self.d / cosine * self.light.direction
        return None

    def _plane_frame(self) -> np.ndarray | None:
        """The projection ``raw`` from the centred frame to the plane's 2-D
        frame around ``origin`` (moved to the receiver's middle when there is
        one); returns the receiver in that frame."""
        normal = self.plane.normal
        u, v = self.call.basis
        self.foot2d = np.zeros(2)
        if len(self.receiver):
            # Coordinates relative to the receiver keep their precision however
            # far the light's foot or the caster's shadow centre lies.
            points = self.receiver - self.center
            middle = 0.5 * (points.min(axis=0) + points.max(axis=0))
            middle -= (normal @ middle + self.d) * normal
            self.foot2d = np.array([u @ (self.origin - middle), v @ (self.origin - middle)])
            self.origin = middle
        homogeneous = self.light_h
        plane4 = np.append(normal, self.d)
        matrix = float(plane4 @ homogeneous) * np.eye(4) - np.outer(homogeneous, plane4)
        to_plane2d = np.array(
            [np.append(u, -u @ self.origin), np.append(v, -v @ self.origin), [0, 0, 0, 1.0]]
        )
        self.raw = to_plane2d @ matrix  # (U, V, W) in scene units, before scaling
        return self._receiver_2d() if len(self.receiver) else None

    def _window(
        self, receiver2d: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, list[CrossSection]] | Shadow:
        """The rectangle [low, high] (local units) the shadow can reach and
        the 2-D regions that limit it (receiver, range, spot cone); sets the
        local ``scale`` and the projection ``H`` into local units. An empty
        shadow when the limits leave nothing."""
        limit_regions = []
        if receiver2d is not None:
            low, high = receiver2d.min(axis=0), receiver2d.max(axis=0)
            self.bound = None
        else:
            self.bound = self.tol.bound_length
            low, high = np.full(2, -self.bound), np.full(2, self.bound)
        extent = float(np.max(np.abs([low, high])))
        self.scale = poly.local_scale(extent)
        self.H = np.diag([self.scale, self.scale, 1.0]) @ self.raw
        low, high = low * self.scale, high * self.scale
        if receiver2d is not None:
            limit_regions.append(poly.unite([receiver2d * self.scale], rule="evenodd"))
            self.limits.append("receiver")
        if is_positional(self.light) and math.isfinite(self.light.radius):
            disc = self._range_disc(low, high)
            if disc is not None and len(disc) < 3:
                return self.empty("the light's range does not reach the receiver or bound")
            if disc is not None:
                low, high = np.maximum(low, disc.min(axis=0)), np.minimum(high, disc.max(axis=0))
                limit_regions.append(poly.unite([disc]))
                self.limits.append("range")
        if isinstance(self.light, SpotLight):
            cone = self._spot_polygon(self.light, low, high)
            if cone is None:
                return self.empty("the spot light's cone misses the receiver")
            low, high = np.maximum(low, cone.min(axis=0)), np.minimum(high, cone.max(axis=0))
            limit_regions.append(poly.unite([cone]))
            self.limits.append("spot_cone")
        if np.any(high <= low):
            return self.empty("the lit part of the plane misses the receiver")
        return low, high, limit_regions

    def _receiver_2d(self) -> np.ndarray:
        points = self.receiver - self.center
        distance = points @ self.plane.normal + self.d
        worst = int(np.argmax(np.abs(distance)))
        limit = self.tol.coplanar_length
        if abs(distance[worst]) > limit:
            raise GeometryError(
                f"receiver point {worst} {self.receiver[worst].tolist()} is "
                f"{abs(distance[worst]):.3g} off the plane (tolerance {limit:.3g})"
            )
        u, v = self.call.basis
        relative = points - self.origin
        return np.column_stack([relative @ u, relative @ v])

    def _range_disc(self, low: np.ndarray, high: np.ndarray) -> np.ndarray | None:
        """The lit disc of a light with a finite radius (an inscribed polygon)
        clipped to the rectangle [low, high], in local units; None when the
        disc covers the rectangle (it limits nothing), an empty array when
        it misses it.

        Only the arc facing the rectangle is cut into segments, and the result
        never leaves the rectangle: a radius far larger than the scene costs
        nothing and stays in the range the 2-D union accepts.
        """
        # called only for a light with a finite radius: a point or spot light
        radius = cast("PointLight | SpotLight", self.light).radius
        height = self.height
        lit = math.sqrt((radius - height) * (radius + height))  # no square to overflow
        corners = np.array(
            [[low[0], low[1]], [high[0], low[1]], [high[0], high[1]], [low[0], high[1]]]
        )
        corners = corners / self.scale - self.foot2d  # scene units, relative to the foot
        farthest = float(np.max(np.hypot(corners[:, 0], corners[:, 1])))
        if farthest <= lit - self.tol.chord_length:
            return None  # the inscribed polygon would cover the rectangle anyway
        nearest = np.clip(np.zeros(2), corners.min(axis=0), corners.max(axis=0))
        if float(np.hypot(*nearest)) >= lit:
            return np.zeros((0, 2))
        if np.all(nearest == 0.0):
            start, sweep = 0.0, 2 * math.pi  # the foot is in the rectangle
        else:
            # The rectangle subtends less than pi from the foot: cut only that arc.
            toward = math.atan2(nearest[1], nearest[0])
            angles = np.arctan2(corners[:, 1], corners[:, 0]) - toward
            angles = (angles + math.pi) % (2 * math.pi) - math.pi
            start, sweep = toward + float(angles.min()), float(angles.max() - angles.min())
        count = self.tol.segments(lit, sweep, minimum=1 if sweep < math.pi else 8)
        closed = sweep >= 2 * math.pi
        # count segments: count points round a circle, count + 1 along an arc
        angles = start + np.linspace(0.0, sweep, count + (not closed), endpoint=not closed)
        arc = lit * np.column_stack([np.cos(angles), np.sin(angles)])
        if not closed:
            arc = np.vstack([[0.0, 0.0], arc])  # a pie slice, convex: its sweep is below pi
        shape = (arc + self.foot2d) * self.scale
        clipped = clip_one(
            np.column_stack([shape, np.ones(len(shape))]), _rectangle_planes(low, high)
        )
        return clipped[:, :2] / clipped[:, 2:3] if len(clipped) >= 3 else np.zeros((0, 2))

    def _spot_polygon(
        self, light: SpotLight, low: np.ndarray, high: np.ndarray
    ) -> np.ndarray | None:
        """The spot light's cone on the plane (an inscribed pyramid), clipped to
        the rectangle [low, high] in local units; None when they miss."""
        axis = light.direction
        side, up = Plane(axis, 0.0).basis  # across the axis; the rim's winding is fixed below
        rectangle_planes = _rectangle_planes(low, high)
        if light.cut_off_angle >= math.pi / 2 - ANGLE_SLACK:
            # A hemisphere: the half-plane of points in front of the light.
            u, v = self.call.basis
            # Points p = origin + (x u + y v) / scale with axis . (p - light) >= 0.
            line = np.array(
                [
                    axis @ u / self.scale,
                    axis @ v / self.scale,
                    axis @ (self.origin - self.light_position),
                ]
            )
            corners = np.array(
                [[low[0], low[1]], [high[0], low[1]], [high[0], high[1]], [low[0], high[1]]]
            )
            clipped = clip_one(np.column_stack([corners, np.ones(4)]), line[None, :])
        else:
            spread = self.tol.segments(float(np.max(np.abs([low, high]))) / self.scale)
            angles = np.linspace(0.0, 2 * np.pi, spread, endpoint=False)
            radius = math.tan(light.cut_off_angle)
            rim = axis + radius * (np.outer(np.cos(angles), side) + np.outer(np.sin(angles), up))
            homogeneous = np.column_stack([rim, np.zeros(len(rim))]) @ self.H.T
            clipped = clip_one(homogeneous, rectangle_planes)
        if len(clipped) < 3:
            return None
        points = clipped[:, :2] / clipped[:, 2:3]
        if poly.signed_areas([points])[0] < 0:
            points = points[::-1]
        cone: np.ndarray = points
        return cone

    def _loop_groups(self, outline_loops: list[np.ndarray]) -> np.ndarray:
        """Labels for :func:`poly.unite`'s ``groups``: each outline loop the
        connected part of the caster it runs on (a part's loops together
        wind >= 0: they count its front faces), each clipped face its own."""
        parts = vertex_components(self.caster)
        n_clipped = self.n_loops - len(outline_loops)
        own = len(self.caster.vertices) + np.arange(n_clipped)
        return np.concatenate([parts[[loop[0] for loop in outline_loops]], own])

    def _shadow_loops(
        self, low: np.ndarray, high: np.ndarray, outline: _Outline | None
    ) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray | None]:
        """Closed 2-D loops (local units) whose positive-winding region is the
        shadow within the rectangle [low, high], the loops of vertex indices
        the first of them come from (the rest are clipped faces), and the
        box of the 2-D loops when it is known already.

        Steps: sort the faces (:meth:`_sort_faces`), chain the outline of the
        faces that project whole (:func:`_outline`, or the silhouette found
        beforehand), project it, then clip the few faces that need it one by
        one (:func:`_clipped_loops`).
        """
        caster = self.caster
        size = high - low
        whole, cut = self._sort_faces(
            self._clip_planes(low, high, lowered=True),
            partial(self._clip_planes, low - _REACH * size, high + _REACH * size, lowered=True),
        )
        if outline is not None and whole is None:
            if outline.projected is None:
                raise GeometryError("the light touches the caster (a vertex projects to infinity)")
            return outline.projected, outline.loops, outline.box
        if whole is None or cut is None:  # every face whole, none cut
            whole = np.ones(caster.n_faces, dtype=bool)
            cut = np.zeros(caster.n_faces, dtype=bool)
        # facing > 0: the face turns its front to the light. For a face whose
        # corners all project (w > 0) this is also the sign of its image's area.
        facing = caster.facing(self.light_h)
        loops, loop_vertices, cut = _outline(caster, whole, cut, facing, self.per_triangle)
        image = _images(caster.centered_rows(loop_vertices), self.H)
        projected = _project_loops(loops, loop_vertices, image)
        if cut.any():
            tight = self._clip_planes(low, high)
            projected += _clipped_loops(caster.centered, caster.faces[cut], tight, self.H)
        return projected, loops, None

    def _clip_planes(self, low: np.ndarray, high: np.ndarray, lowered: bool = False) -> np.ndarray:
        """(5, 4) unit half-spaces ``planes @ x >= 0`` of the caster's centred
        frame: the receiving plane and the four planes joining the light to
        the rectangle [low, high] of the plane's local frame. ``lowered``
        moves the receiving plane down by the coplanar tolerance: for sorting
        faces, so that a caster standing on the plane is not sent to
        clipping by corners that rounding put a hair below it."""
        drop = self.tol.coplanar_length if lowered else 0.0
        planes = np.empty((5, 4))
        planes[0, :3] = self.plane.normal
        planes[0, 3] = self.d + drop
        planes[1:] = _rectangle_planes(low, high) @ self.H
        lengths = np.sqrt(np.einsum("ij,ij->i", planes[:, :3], planes[:, :3]))
        unit: np.ndarray = planes / lengths[:, None]
        return unit

    def _sort_faces(
        self, tight: np.ndarray, reach: Callable[[], np.ndarray]
    ) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
        """(m,) bool ``whole`` (every corner above the plane and projecting
        within the wide ``reach`` rectangle: the outline may take the face as
        it is, the 2-D limits cut it) and ``cut`` (the other faces that reach
        the ``tight`` rectangle: they are clipped one by one). Sets the
        per-reason counts of faces leaving the tight rectangle and the
        number culled. ``(None, None)`` when every face is whole and none is
        cut (the caster's box passes): the common case, told without arrays."""
        if np.all(self.call.box_corners @ tight.T > 0):
            # The caster's box lies inside every half-space, so does each vertex.
            self.culled = 0
            self._count_clipped(np.zeros((0, 4)), self.caster.faces[:0], np.zeros((0, 3, 5), bool))
            return None, None
        homogeneous, faces = self.caster.centered, self.caster.faces
        whole = ~np.any(np.any(homogeneous @ reach().T < 0, axis=1)[faces], axis=1)
        touched = np.flatnonzero(np.any(np.any(homogeneous @ tight.T < 0, axis=1)[faces], axis=1))
        outside = (homogeneous[faces[touched]] @ tight.T) < 0  # (k, 3, 5)
        culled = np.all(outside, axis=1).any(axis=1)
        self.culled = int(culled.sum())
        self._count_clipped(homogeneous, faces[touched], outside)
        cut = ~whole
        cut[touched[culled]] = False
        return whole, cut

    def _count_clipped(
        self, homogeneous: np.ndarray, faces: np.ndarray, outside: np.ndarray
    ) -> None:
        """Per-reason counts over the faces that are not whole."""
        outside_key = "outside_receiver" if len(self.receiver) else "outside_bound"
        if len(faces) == 0:
            zero = {"below_plane": 0, "at_or_above_light": 0, outside_key: 0}
            if not is_positional(self.light):
                del zero["at_or_above_light"]
            self.clipped.update(zero)
            return
        self.clipped["below_plane"] = int(np.any(outside[:, :, 0], axis=1).sum())
        beyond_bound = outside[:, :, 1:].any(axis=2)
        if is_positional(self.light):
            weight = (homogeneous @ self.raw[2])[faces]  # w of each corner, scene units
            self.clipped["at_or_above_light"] = int(np.any(weight <= 0, axis=1).sum())
            beyond_bound &= weight > 0
        self.clipped[outside_key] = int(np.any(beyond_bound, axis=1).sum())

    def _result(self, parts: list[list[np.ndarray]], n_loops: int) -> Shadow:
        area = poly.parts_area(parts) / self.scale / self.scale  # no square to over/underflow
        bounded = False
        if self.bound is not None and parts:
            reach = max(float(np.abs(np.concatenate([p[0] for p in parts])).max()), 0.0)
            bounded = reach >= (self.bound - self.tol.length) * self.scale
        info = ShadowDiagnostics(
            n_triangles=self.caster.n_faces,
            clipped=dict(self.clipped),
            culled=self.culled,
            limits=tuple(self.limits),
            bounded_artificially=bounded,
            bound=self.bound,
            n_loops=n_loops,
        )
        if not parts:
            return Shadow(self.plane, self.light, empty_mesh, [], 0.0, info)
        u, v = self.call.basis
        relative = self.origin + self.center - self.plane.origin
        origin2d = np.array([relative @ u, relative @ v])
        polygons = [[loop / self.scale + origin2d for loop in loops] for loops in parts]
        lift = self.origin + self.offset * self.plane.normal + self.center
        build = partial(triangulated, parts, self.scale, lift, self.call.basis)
        return Shadow(self.plane, self.light, build, polygons, area, info)


# Faces whose corners project within the rectangle widened by this many times
# its size on each side are projected whole and cut in 2-D: a building whose
# shadow runs past the receiver's edge takes the outline path, not the
# per-triangle clipping. The widened rectangle stays far inside the range the
# 2-D union accepts (9 * MAX_COORDINATE).
_REACH = 4.0
# Twice the widened rectangle's reach in local units: a projected point past
# it is rounding, not geometry (:meth:`_Projector._within_reach`).
_REACH_LIMIT = 2.0 * (1.0 + 2.0 * _REACH) * MAX_COORDINATE


def _outline(
    caster: Caster, whole: np.ndarray, cut: np.ndarray, facing: np.ndarray, per_triangle: bool
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Loops of vertex indices whose positive winding is the shadow of the
    ``whole`` faces, the vertices they use, and ``cut`` narrowed to the faces
    that can add to the shadow."""
    if caster.is_closed:
        # With the light outside a closed caster every shadow ray first
        # meets a face turned to the light: the others add nothing.
        front = facing > 0
        cut = cut & front
        if per_triangle:
            loops, vertices = _triangle_loops(caster, whole & front, facing)
        elif whole.all():
            loops, vertices = silhouette_loops(caster, front)
        else:
            loops, vertices = boundary_loops(caster, whole & front, front.astype(np.int64))
        return loops, vertices, cut
    # An open caster unites its triangles: copies and zero-area faces add
    # nothing but work (quadratic in the copies), so they go first.
    distinct = caster.distinct
    cut = cut & distinct
    if per_triangle:
        loops, vertices = _triangle_loops(caster, whole & distinct, facing)
    else:
        orientation = np.sign(facing).astype(np.int64)
        loops, vertices = boundary_loops(caster, whole & distinct, orientation)
    return loops, vertices, cut


def _images(points: np.ndarray, H: np.ndarray) -> np.ndarray:
    """(k, 3) homogeneous images ``H @ p`` of (k, 4) points with w = 1, by an explicit
    sum in a fixed order: the same bits whether one light's points are
    projected or many lights' at once (:func:`_images_many`)."""
    rows = [
        points[:, 0] * H[i, 0] + points[:, 1] * H[i, 1] + points[:, 2] * H[i, 2] + H[i, 3]
        for i in range(3)
    ]
    return np.column_stack(rows)


def _project_loops(
    loops: list[np.ndarray], vertices: np.ndarray, image: np.ndarray
) -> list[np.ndarray]:
    """Loops of vertex indices -> (k, 2) loops of their images; ``image`` is
    that of the sorted ``vertices``, every vertex the loops use."""
    if not vertices.size:
        return []
    if np.any(image[:, 2] <= 0):
        raise GeometryError("the light touches the caster (a vertex projects to infinity)")
    points = image[:, :2] / image[:, 2:3]
    if len(loops) == 1:
        return [points[np.searchsorted(vertices, loops[0])]]
    # vertices is sorted: find each loop corner's row by bisection, all at once
    corners = points[np.searchsorted(vertices, np.concatenate(loops))]
    return pieces(corners, [len(loop) for loop in loops])


def _clipped_loops(
    homogeneous: np.ndarray, faces: np.ndarray, planes: np.ndarray, H: np.ndarray
) -> list[np.ndarray]:
    """Each face clipped to ``planes`` and projected, turned counter-clockwise.

    All faces are clipped at once (:func:`clip_batch`): a mesh whose
    faces mostly leave a small receiver would otherwise pay a Python loop per
    face, for every receiver."""
    corners, counts = clip_batch(homogeneous[faces], np.full(len(faces), faces.shape[1]), planes)
    kept = counts >= 3
    corners, counts = corners[kept], counts[kept]
    if not len(counts):
        return []
    width = corners.shape[1]
    used = np.arange(width)[None, :] < counts[:, None]
    image = corners @ H.T
    if np.any(image[:, :, 2][used] <= 0):
        raise GeometryError("the light touches the caster (a clipped point projects to infinity)")
    with np.errstate(divide="ignore", invalid="ignore"):
        points = np.where(used[:, :, None], image[:, :, :2] / image[:, :, 2:3], 0.0)
    following = np.where(np.arange(1, width + 1)[None, :] < counts[:, None], 1, 1 - counts[:, None])
    following = following + np.arange(width)[None, :]
    after = np.take_along_axis(points, following[:, :, None], axis=1)
    cross = points[:, :, 0] * after[:, :, 1] - after[:, :, 0] * points[:, :, 1]
    areas = 0.5 * np.where(used, cross, 0.0).sum(axis=1)
    loops = []
    for loop, count, area in zip(points, counts, areas, strict=True):
        if area == 0:
            continue
        loop = loop[:count]
        loops.append(loop if area > 0 else loop[::-1])
    return loops


def _rectangle_planes(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(4, 3) homogeneous 2-D half-planes ``l . (U, V, W) >= 0`` of the
    rectangle [low, high] (points (U / W, V / W) with W > 0)."""
    return np.array(
        [
            [1.0, 0.0, -low[0]],
            [-1.0, 0.0, high[0]],
            [0.0, 1.0, -low[1]],
            [0.0, -1.0, high[1]],
        ]
    )


def _triangle_loops(
    caster: Caster, selected: np.ndarray, facing: np.ndarray
) -> tuple[list[np.ndarray], np.ndarray]:
    """Every selected triangle as its own loop, turned to project counter-clockwise."""
    faces = caster.faces[selected & (facing != 0)]
    back = facing[selected & (facing != 0)] < 0
    faces = np.where(back[:, None], faces[:, ::-1], faces)
    return list(faces), unique_integers(faces)
