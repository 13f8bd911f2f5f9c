"""Adding shadows to a scene: which lights cast, which shapes receive, what casts.

:func:`add_shadows` turns a :class:`~shadowgeo.scene.Scene` into the same scene
with its shadows added as shapes (role ``"shadow"``, one group per light), ready
for any writer.

Selection rules
---------------
Lights
    The lights with ``shadows=True`` (X3D 4's ``shadows="true"``) cast. When no
    light has it, every light that is on casts, and a note in
    ``scene.warnings`` says so. ``lights=`` names the lights (DEF names) to use
    instead. A non-global light (``SceneLight.scope``, X3D's
    ``global="false"``) shadows only the receivers it lights: the patches
    and faces of shapes in its scope (the added ground lies outside every
    scope; a ``plane=`` given takes every light's shadows), and only the
    shapes in its scope cast for it, as X_ITE draws only the light's parent
    group into its shadow map. A scene with no light that is on gets :func:`default_sun` (high,
    slightly oblique: travelling along ``(0.3, -1, 0.2)`` when Y is up), with
    a note; ``extra_lights`` replaces it.
Receivers
    Flat patches of the shapes (a ground, a floor, a slab's top, a wall),
    found automatically or from the shapes named in ``receivers=``, or one
    unbounded ``plane=``; the rules are in :mod:`shadowgeo.scene.receivers`.
Casters
    Every shape, as much as it is opaque (:mod:`.opacity`): one that says it
    casts no shadow (X3D 4 ``castShadow="false"``, Castle's ``shadowCaster
    FALSE``, ``Shape.casts_shadow``) or whose opacity ``1 - transparency``
    rounds to 0 in 1/16 steps (below 1/32) casts nothing and costs no pass;
    it still receives. A receiver's own triangles (and an open shape's
    triangles lying in its plane) do not shadow it; a closed shape resting on
    it keeps its footprint. Only what can shadow a receiver is modelled: a caster
    wholly behind the receiver's plane, wholly at or beyond a positional
    light's height, out of a light's radius, outside a spot light's cone, or
    whose shadow misses the receiver's bounding box is skipped. A caster the
    light touches, or a closed one it sits inside no larger than a bulb
    (:data:`BULB_FRACTION` of the scene's size: a lamp's own bulb), casts
    nothing for that light, on every receiver and every surface, with one
    note naming it; the other casters cast as they would without it. A
    larger closed caster round the light (a dome, a closed room) shuts it
    in: inside it the others cast as ever, and every receiver and surface
    outside it (a shape judged by a few of its corners) is in its shadow
    where the light faces it, the ground plane wholly.

The shadows of the casters of one light and one opacity on one receiver are
united into one region (so overlaps do not darken twice), cut to the
receiver's outline (the union of its triangles), triangulated and lifted
towards the light by ``offset`` (default ``1e-3`` of the diagonal of the
geometry and the lights; the i-th of n lights is lifted ``offset * (1 + i /
n)`` so that shadows of different lights do not z-fight).
Each becomes a shape with a black material whose darkness (one less its
transparency) is ``shadow_intensity`` times the casters' opacity. A point
takes the darkness of the most opaque caster that hides it from the light:
from each translucent opacity's region the regions of every more opaque one
are cut out first (a polygon difference), so the layers never overlap; the
opaque layer is named ``shadow_<light>_<receiver>``, one of opacity 1/2
``shadow_<light>_<receiver>_opacity50``. Shadows on every other surface
(:mod:`.surfaces`) are layered the same way.
The opaque layer is as dark as the browser's own shadow would darken the
receiver: ``shadow_intensity`` times the light's share of the receiver's
lighting (:mod:`.darkness`); a translucent layer that times its opacity.
When the ground plane receives (no receiver of the scene's own), a visible
ground is added under the scene (role ``"ground"``, :mod:`.ground`).

Soft shadows
    A light with a size (a sun's ``angle``, a ``source_radius``, a rectangle
    or disc light: :attr:`SceneLight.emitter`) bakes graded layers instead:
    one shape per level of the hidden fraction ``k / soft_levels``, as dark
    as the hard shadow times that fraction, named ``..._soft25`` (a quarter
    of the light hidden) up to ``..._soft100`` (the umbra); :mod:`.softbake`.
Runtime shadows
    A light whose shadows are baked and that has ``shadows=True`` gets
    ``baked=True``: the writers write X3D's ``shadows`` false for it (a
    browser drawing its own shadow map over the baked shadow darkens it
    twice), with a mark their readers give back, so a second run casts the
    same lights. ``keep_runtime_shadows=True`` leaves them drawn. A note says
    which lights still draw runtime shadows.

``method="volume"`` instead adds one closed shadow volume
(:func:`shadowgeo.shadow_volume`) per shape and light, role
``"volume"``, ending one scene size past the scene's farthest corner.
X3D's headlight follows the viewer and casts no fixed shadow, so a scene with
no light that is on is lit by :func:`default_sun`, which is not added to the
scene. ``extra_lights`` gives other lights that cast without being added to
the scene.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Literal, cast

import numpy as np
from numpy.typing import ArrayLike

from .. import limits
from .. import plane2d as poly
from ..errors import GeometryError, SceneError
from ..lights import DirectionalLight, Light, is_positional
from ..limits import check_coordinates, check_light
from ..plane import Plane
from ..projection import project_shadow
from ..threads import one_blas_thread
from ..tolerance import Tolerance
from ..topology import Caster
from ..volume import shadow_volume
from .casters import CasterSet, distinct
from .darkness import Lighting
from .ground import visible_ground
from .model import (
    Material,
    Placement,
    Scene,
    SceneLight,
    Shape,
    lights,
    safe_name,
    shadow_shape,
    unique_name,
)
from .opacity import opacities
from .receivers import Receiver, ground
from .receivers import select as select_receivers
from .softbake import (
    SoftSettings,
    is_soft,
    soft_on_receiver,
    soft_on_surface,
    soft_suffix,
    translucent_note,
)
from .surfaces import ReceivingSurface, receiving_faces, surface_covered, surface_shadow

if TYPE_CHECKING:
    from manifold3d import CrossSection

__all__ = [
    "BULB_FRACTION",
    "DEFAULT_SUN_DIRECTION",
    "DEFAULT_SUN_ELEVATION",
    "Progress",
    "add_shadows",
    "default_sun",
    "in_scope",
]

# A closed caster round a positional light is its bulb (or a marker drawn
# where the light is), casting nothing for it, when its box diagonal is at most
# this fraction of the scene's; a larger one shuts the light in (_enclosing).
BULB_FRACTION = 0.1
# Receivers found automatically: at least this fraction of the largest planar
# shape's area and of the scene's bounding-box diagonal.
_RECEIVER_AREA_FRACTION = 0.25
_RECEIVER_SIZE_FRACTION = 0.25
# An open shape at least this fraction of the scene's width in both horizontal
# directions is a terrain: it receives in place of a fallback ground plane.
_TERRAIN_SPAN = 0.9
# ... when it is a height field: its faces, projected down, cover its footprint
# (its box's) at most this many times over (a car's open shell covers it twice:
# roof and floor).
_TERRAIN_COVER = 1.25
# Default lift of shadows off their receiver, relative to the scene's size.
_DEFAULT_OFFSET = 1e-3
# The sun that casts in a scene with no light that is on, for a Y-up scene:
# high (about 70 degrees above the horizon) and slightly oblique, so that
# shadows fall beside their casters, towards +x and +z (the X3D default
# viewpoint looks down -z, so they fall towards the viewer, to the right).
DEFAULT_SUN_DIRECTION = (0.3, -1.0, 0.2)
DEFAULT_SUN_ELEVATION = math.degrees(math.atan2(1.0, math.hypot(0.3, 0.2)))

Progress = Callable[[int, int], None]


def add_shadows(
    scene: Scene,
    *,
    method: Literal["planar", "volume"] = "planar",
    lights: Sequence[str] | None = None,
    receivers: Sequence[str] | None = None,
    plane: Plane | ArrayLike | None = None,
    tolerance: Tolerance | float | None = None,
    offset: float | None = None,
    progress: Progress | None = None,
    extra_lights: Sequence[SceneLight] = (),
    surfaces: bool | None = None,
    keep_runtime_shadows: bool = False,
    soft_levels: int = 8,
    soft_samples: int | None = None,
) -> Scene:
    """The scene with the shadows of its lights added as shapes.

    Parameters
    ----------
    scene : Scene
        Not modified.
    method : {"planar", "volume"}
        ``"planar"``: shadows on the receivers (role ``"shadow"``).
        ``"volume"``: closed shadow volumes (role ``"volume"``).
    lights : sequence of str, optional
        Names (DEF) of the lights that cast; default: see the module notes.
    receivers : sequence of str, optional
        Names (DEF) of the receiving shapes; they must be planar.
    plane : Plane or (4,) array_like, optional
        One receiving plane ``a x + b y + c z + d = 0`` instead of shapes.
    tolerance : Tolerance or float, optional
        Defaults to ``Tolerance.for_points`` of the geometry and the lights; a
        float sets that tolerance's ``chord`` (spot cones, light ranges).
    offset : float, optional
        Lift of the shadows off their receiver (scene units).
    progress : callable, optional
        Called as ``progress(done, total)`` as casters are processed.
    surfaces : bool, optional
        Also shadow every other face of the geometry (terrain, steps, walls,
        the casters themselves) exactly, through
        :func:`shadowgeo.shadow_on_surface` (:mod:`.surfaces`). Default: when
        neither ``receivers`` nor ``plane`` narrows the receivers.
    extra_lights : sequence of SceneLight
        Lights that cast shadows but are not added to the scene, e.g. a sun
        for a scene with no light of its own. When given, they cast together
        with the lights named in ``lights`` (none by default): the scene's own
        lights then cast only when named.
    keep_runtime_shadows : bool
        Let the lights whose shadows are baked draw them at run time too (a
        browser then darkens them twice). By default their runtime shadows
        are turned off (see *Runtime shadows* in the module notes).
    soft_levels, soft_samples : int
        A light with a size (:attr:`SceneLight.emitter`) bakes ``soft_levels``
        graded layers, each as dark as its share of the light hidden, from
        ``soft_samples`` point lights (default
        :data:`shadowgeo.soft.DEFAULT_SAMPLES`; :mod:`.softbake`).

    Returns
    -------
    Scene
        A new scene: the input's shapes, then the added ones (group
        ``"shadows_<light>"``, unique DEF-safe names; a ground under the
        scene when the ground plane receives), its lights with ``baked`` set
        on those whose runtime shadows are turned off, and ``warnings`` with
        notes on what was chosen and skipped. ``document`` is shared.
        Shadows and grounds an earlier run added (role ``"shadow"``,
        ``"volume"``, ``"ground"``, or baked into the X3D document) are
        replaced, so running it again on its own output gives the same scene.

    Raises
    ------
    SceneError
        A named light or receiver does not exist, or a named light is off.
    GeometryError
        A named receiver is not planar; a coordinate or light radius outside
        the range of :mod:`shadowgeo.limits`.

    Examples
    --------
    >>> import numpy as np, shadowgeo as sg
    >>> ground = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]],
    ...                   [[0, 2, 1], [0, 3, 2]], name="ground")
    >>> box = sg.Shape([[0, 1, 0], [1, 1, 0], [1, 1, 1]], [[0, 1, 2]], name="roof")
    >>> light = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), name="sun", shadows=True)
    >>> result = sg.add_shadows(sg.Scene([ground, box], [light]))
    >>> shadow = result.shapes_with_role("shadow")[0]
    >>> shadow.name, shadow.group, round(float(shadow.vertices[:, 1].max()), 4)
    ('shadow_sun_ground', 'shadows_sun', 0.0142)
    """
    with one_blas_thread():  # thin products: see shadowgeo.threads
        options = _Options(
            method,
            lights,
            receivers,
            plane,
            tolerance,
            offset,
            progress,
            extra_lights,
            surfaces,
            keep_runtime_shadows,
            SoftSettings(soft_levels, soft_samples),
        )
        return _add_shadows(scene, options)


@dataclasses.dataclass(frozen=True)
class _Options:
    """What :func:`add_shadows` was asked besides the scene."""

    method: Literal["planar", "volume"]
    lights: Sequence[str] | None
    receivers: Sequence[str] | None
    plane: Plane | ArrayLike | None
    tolerance: Tolerance | float | None
    offset: float | None
    progress: Progress | None
    extra_lights: Sequence[SceneLight]
    surfaces: bool | None
    keep_runtime_shadows: bool
    soft: SoftSettings

    def check(self) -> None:
        if self.method not in ("planar", "volume"):
            raise GeometryError(f"method must be 'planar' or 'volume', got {self.method!r}")
        if self.receivers is not None and self.plane is not None:
            raise GeometryError("give receivers or plane, not both")


@dataclasses.dataclass(frozen=True)
class _Shapes:
    """The scene's shapes less earlier shadows (``kept``), those with faces
    (``every_shape``) and those once each (``geometry``), with the notes."""

    kept: list[Shape]
    every_shape: list[Shape]
    geometry: list[Shape]
    notes: tuple[str, ...]


@dataclasses.dataclass(frozen=True)
class _ShadowPlan:
    """Everything every light's step shares: the shapes, the casting lights,
    the casters stacked once, the tolerance and the lift, the names in use
    (a collector: each step takes its names from it, in the run's order)."""

    scene: Scene
    options: _Options
    shapes: _Shapes
    lights: list[SceneLight]
    casters: CasterSet
    bounds: np.ndarray
    tolerance: Tolerance
    lift: float
    names: _Names
    opacity: np.ndarray
    lighting: Lighting


@dataclasses.dataclass(frozen=True)
class _Receiving:
    """What receives a planar run's shadows: the planar receivers ``found``,
    every other surface (or None), the ground's home, with the notes."""

    found: list[Receiver]
    surface: ReceivingSurface | None
    home: tuple[int, Placement] | None
    notes: tuple[str, ...]


@dataclasses.dataclass(frozen=True)
class _LightCasting:
    """One light's casting: its name and group, the lift of its shadows, its
    graded settings (a light with a size), each caster's opacity for it, the
    casters round it that shut it in (``shell``) and their opacity."""

    scene_light: SceneLight
    name: str
    group: str
    height: float
    graded: SoftSettings | None
    casting: np.ndarray
    shell: list[int]
    shut: float


@dataclasses.dataclass(frozen=True)
class _LightResult:
    """One light's shadows, named; the vertices of those on the ground
    plane; the casting when a shell round it covers the ground; the notes."""

    added: list[Shape]
    on_ground: list[np.ndarray]
    covered: _LightCasting | None
    notes: tuple[str, ...]


def _add_shadows(scene: Scene, options: _Options) -> Scene:
    """:func:`add_shadows` as its steps: the shapes, the lights, the plan,
    then the shadows (one step per light) and the lights' runtime shadows;
    the steps' notes become ``scene.warnings`` in the order they come."""
    options.check()
    shapes = _shapes_of(scene)
    chosen, light_notes = _select_lights(scene, options.lights, options.extra_lights)
    for index, light in enumerate(chosen):
        check_light(light.light, f"light '{light.name or index}'")  # see shadowgeo.limits
    notes = [*shapes.notes, *light_notes]
    if not shapes.geometry and options.receivers is None:
        notes.append("shadows: the scene has no geometry, so nothing casts or receives")
        return dataclasses.replace(scene, shapes=shapes.kept, warnings=[*scene.warnings, *notes])
    plan = _plan(scene, options, shapes, chosen)
    notes.extend(_scoped_notes(plan))
    added, shadow_notes = _volumes(plan) if options.method == "volume" else _planar(plan)
    baked = chosen if options.method == "planar" else []
    marked, runtime_notes = _runtime_shadows(
        scene.lights, baked, options.keep_runtime_shadows, plan.names
    )
    warnings = [*scene.warnings, *notes, *shadow_notes, *runtime_notes]
    return dataclasses.replace(
        scene, shapes=[*shapes.kept, *added], lights=marked, warnings=warnings
    )


def _shapes_of(scene: Scene) -> _Shapes:
    """The scene's shapes that cast and receive, each distinct one once."""
    kept, notes = _without_baked(scene)
    every_shape = [s for s in kept if s.role == "geometry" and s.n_faces]
    geometry = distinct(every_shape)
    if len(every_shape) > len(geometry):
        notes.append(
            f"shadows: {len(every_shape) - len(geometry)} shapes repeat another's geometry "
            "exactly (same vertices, faces and transform); each casts and receives once"
        )
    return _Shapes(kept, every_shape, geometry, tuple(notes))


def _plan(
    scene: Scene, options: _Options, shapes: _Shapes, chosen: list[SceneLight]
) -> _ShadowPlan:
    """The plan of a run: the casters stacked (world vertices once per shape,
    in one array), the tolerance and the lift of the shadows."""
    positions = [light.light.position for light in chosen if is_positional(light.light)]
    stacked = CasterSet(shapes.geometry)
    bounds = stacked.bounds if shapes.geometry else np.zeros((0, 3))
    check_coordinates(bounds, "scene bounds")  # whatever the tolerance: see shadowgeo.limits
    tolerance = options.tolerance
    if not isinstance(tolerance, Tolerance):
        settings = {} if tolerance is None else {"chord": float(tolerance)}
        tolerance = Tolerance.for_points(bounds, *positions, **settings)
    offset = options.offset
    lift = _DEFAULT_OFFSET * tolerance.scale if offset is None else float(offset)
    if not math.isfinite(lift) or lift < 0:
        raise GeometryError(f"offset must be finite and >= 0, got {offset!r}")
    names = _Names(shapes.kept, scene.lights)
    opacity = opacities(shapes.geometry)  # (see .opacity: 0 casts nothing)
    return _ShadowPlan(
        scene,
        options,
        shapes,
        chosen,
        stacked,
        bounds,
        tolerance,
        lift,
        names,
        opacity,
        Lighting.of(scene),
    )


def _scoped_notes(plan: _ShadowPlan) -> list[str]:
    """The note on the casting lights with a scope (X3D ``global="false"``)."""
    scoped = [
        plan.names.light(light, i) for i, light in enumerate(plan.lights) if light.scope is not None
    ]
    if not scoped:
        return []
    return [
        f'shadows: {_listed(scoped)}: global="false", so only the shapes of the '
        "light's parent group receive and cast its shadows"
    ]


def _planar(plan: _ShadowPlan) -> tuple[list[Shape], list[str]]:
    """The shadows on the receivers, one step per light, then a visible
    ground under the scene when the ground plane receives."""
    receiving = _receiving(plan)
    results = [_light_shadows(plan, receiving, index) for index in range(len(plan.lights))]
    if plan.options.progress is not None:
        total = len(plan.lights) * len(receiving.found) * len(plan.casters)
        plan.options.progress(total, total)
    added = [shape for result in results for shape in result.added]
    notes = [*receiving.notes, *(note for result in results for note in result.notes)]
    covered = [result.covered for result in results if result.covered is not None]
    if not added and not covered:
        listed = ", ".join(receiver.name for receiver in receiving.found)
        notes.append(f"shadows: no shadow falls on the receivers ({listed})")
    if not any(_is_ground(receiver) for receiver in receiving.found):
        return added, notes
    floor, on_floor, note = _visible_ground(plan, receiving, results, covered)
    return [floor, *added, *on_floor], [*notes, note]


def _receiving(plan: _ShadowPlan) -> _Receiving:
    """The planar receivers (:mod:`.receivers`) and the other surfaces that
    receive (:mod:`.surfaces`); the ground plane when nothing else does."""
    options, geometry, stacked = plan.options, plan.shapes.geometry, plan.casters
    own = dataclasses.replace(plan.scene, shapes=geometry)  # without earlier shadows
    surfaces = options.surfaces
    if surfaces is None:
        surfaces = options.receivers is None and options.plane is None
    terrain = _terrain(stacked, plan.scene.up_index) if surfaces else None
    found, notes = select_receivers(  # a named shape is looked for among every copy
        own,
        geometry if options.receivers is None else plan.shapes.every_shape,
        options.receivers,
        options.plane,
        plan.tolerance,
        stacked,
        terrain is None,
    )
    surface, surface_notes = _other_surfaces(plan, found) if surfaces else (None, [])
    notes.extend(surface_notes)
    if not found and surface is None:  # the terrain cannot receive after all
        ground_plane, note = ground(own, geometry, stacked.bounds)
        found = [ground_plane]
        notes.append(note)
    elif not found:
        notes.append(
            f"shadows: no flat receiver found; {terrain} spans the scene and receives with "
            "every other surface (no ground plane is added under it; --plane a,b,c,d adds one)"
        )
    home = _ground_home(plan.lights)
    if home is not None:  # the ground lies in the scoped lights' group, lit by them
        found = [
            dataclasses.replace(r, scopes=frozenset({home[0]})) if _is_ground(r) else r
            for r in found
        ]
    return _Receiving(found, surface, home, tuple(notes))


def _other_surfaces(
    plan: _ShadowPlan, found: list[Receiver]
) -> tuple[ReceivingSurface | None, list[str]]:
    """Every face besides the planar receivers ``found``, or None past
    :data:`shadowgeo.limits.MAX_SURFACE_FACES` (with a note)."""
    stacked = plan.casters
    # at most this many faces receive besides the planar receivers (fewer
    # when faces repeat): past the budget, nothing is computed for them
    besides = len(stacked.faces) - sum(
        len(receiver.triangles) for receiver in found if receiver.triangles is not None
    )
    surface = None
    if besides <= limits.MAX_SURFACE_FACES:
        surface = receiving_faces(plan.shapes.geometry, found, plan.tolerance, stacked)
        besides = len(surface.faces)  # an open shape's faces count twice, one each way
    if besides <= limits.MAX_SURFACE_FACES:
        return surface, []
    return None, [
        f"shadows: {besides:,} faces besides the planar receivers, more than "
        f"{limits.MAX_SURFACE_FACES:,} (shadowgeo.limits.MAX_SURFACE_FACES): shadows "
        "on the planar receivers only"
    ]


def _light_shadows(plan: _ShadowPlan, receiving: _Receiving, index: int) -> _LightResult:
    """The step of one light: its shadows on each receiver, then on every
    other surface."""
    light, notes = _casting_of(plan, index)
    added: list[Shape] = []
    on_ground: list[np.ndarray] = []  # the shadows on the ground plane, if it receives
    total = len(plan.lights) * len(receiving.found) * len(plan.casters)
    for number, receiver in enumerate(receiving.found):
        start = (index * len(receiving.found) + number) * len(plan.casters)
        layers, receiver_notes = _on_receiver(plan, light, receiver, _step(plan, start, total))
        if _is_ground(receiver):
            on_ground.extend(layer.vertices for layer in layers)
        added.extend(layers)
        notes.extend(receiver_notes)
    if receiving.surface is not None:
        layers, surface_notes = _on_surfaces(plan, light, receiving.surface)
        added.extend(layers)
        notes.extend(surface_notes)
    # a shell round the light covers the ground plane wholly
    covers = bool(light.shell) and any(_is_ground(receiver) for receiver in receiving.found)
    return _LightResult(added, on_ground, light if covers else None, tuple(notes))


def _step(plan: _ShadowPlan, start: int, total: int) -> Callable[[int], None]:
    """``progress`` for one receiver, its casters counted from ``start``."""
    progress = plan.options.progress

    def step(count: int) -> None:
        if progress is not None:
            progress(start + count, total)

    return step


def _casting_of(plan: _ShadowPlan, index: int) -> tuple[_LightCasting, list[str]]:
    """What casts for the ``index``-th light: what it lights (X3D light
    scope); a caster the light touches or sits inside casts nothing for it,
    on any receiver; the others cast as ever."""
    scene_light = plan.lights[index]
    name = plan.names.light(scene_light, index)
    group = plan.names.unique(f"shadows_{name}")
    graded, notes = _soft_for(scene_light, plan.options.soft, plan.opacity, name)
    casting = plan.opacity * in_scope(scene_light, plan.shapes.geometry)
    held = plan.casters.holding(scene_light.light, plan.tolerance, casting > 0)
    # a closed caster round the light that is no mere bulb: the light
    # lights nothing outside it, all of which is in its shadow
    shell = _enclosing(plan.casters, held, scene_light, casting)
    shut = float(casting[shell].max()) if shell else 0.0
    if held:
        casting[list(held)] = 0.0
        for caster in shell:
            del held[caster]
        if held:
            notes.append(_held_note(plan.casters, held, name))
    if shell:
        notes.append(_enclosed_note(plan.casters, shell, name))
    height = plan.lift * (1 + index / len(plan.lights))
    casting_of = _LightCasting(scene_light, name, group, height, graded, casting, shell, shut)
    return casting_of, notes


def _on_receiver(
    plan: _ShadowPlan, light: _LightCasting, receiver: Receiver, step: Callable[[int], None]
) -> tuple[list[Shape], list[str]]:
    """The named shadow layers of ``light`` on one planar receiver."""
    stem = f"shadow_{light.name}_{receiver.name}"
    if light.shell and (_is_ground(receiver) or _outside(plan.casters, light.shell, receiver)):
        if receiver.triangles is None:  # the ground's: with the visible ground
            return [], []
        patch = receiver.triangles.reshape(-1, 3)
        faces = np.arange(len(patch)).reshape(-1, 3)
        covered = _covered(
            receiver,
            patch,
            faces,
            light.scene_light,
            light.shut,
            plan.tolerance,
            light.height,
            plan.lighting,
        )
        return _named(plan, covered, stem, _layer_suffix, light.group), []
    layers, notes = _receiver_layers(plan, light, receiver, step)
    return _named(plan, layers, stem, _suffix_for(light.graded), light.group), notes


def _on_surfaces(
    plan: _ShadowPlan, light: _LightCasting, surface: ReceivingSurface
) -> tuple[list[Shape], list[str]]:
    """The named shadow layers of ``light`` on every other surface."""
    stem = f"shadow_{light.name}_surfaces"
    receiving = surface.lit_by(light.scene_light)
    added: list[Shape] = []
    if light.shell:  # the faces outside the shell are all in its shadow
        outside = _outside_faces(plan.casters, light.shell, receiving)
        covered = surface_covered(
            receiving.only(outside),
            light.scene_light,
            light.shut,
            light.height,
            light.name,
            plan.lighting,
        )
        added = _named(plan, covered, stem, _layer_suffix, light.group)
        receiving = receiving.only(~outside)
    # only casters the light reaches (its radius, its cone): a ray to a lit
    # point runs inside them; each caster's topology made once for every light
    stacked = plan.casters
    reached = np.flatnonzero(stacked.lit(light.scene_light.light) & (light.casting > 0))
    layers, notes = _surface_layers(plan, light, receiving, reached)
    return [*added, *_named(plan, layers, stem, _suffix_for(light.graded), light.group)], notes


def _named(
    plan: _ShadowPlan,
    layers: list[tuple[float, Shape]],
    stem: str,
    suffix: Callable[[float], str],
    group: str,
) -> list[Shape]:
    """The ``layers`` (level, shape) named ``stem`` and the level's suffix,
    unique in the scene, in ``group``."""
    named = []
    for level, layer in layers:
        layer.name = plan.names.unique(f"{stem}{suffix(level)}")
        layer.group = group
        named.append(layer)
    return named


def _visible_ground(
    plan: _ShadowPlan,
    receiving: _Receiving,
    results: list[_LightResult],
    covered: list[_LightCasting],
) -> tuple[Shape, list[Shape], str]:
    """The ground shown under the scene (:mod:`.ground`) when the ground
    plane receives, reaching every shadow on it; the shadows of the shells
    round lights that cover it; the note."""
    plane_receiver = next(receiver for receiver in receiving.found if _is_ground(receiver))
    up = plan.scene.up_index
    height = -plane_receiver.plane.offset / plane_receiver.plane.normal[up]
    on_ground = [vertices for result in results for vertices in result.on_ground]
    floor = visible_ground(np.vstack([plan.bounds, *on_ground]), height, up)
    floor.name, floor.group = plan.names.unique("ground"), plan.names.unique("shadowgeo_ground")
    on_floor = []
    for light in covered:  # (placed as the ground was made, before it moves to its home)
        layers = _covered(
            plane_receiver,
            floor.world_vertices,
            floor.faces,
            light.scene_light,
            light.shut,
            plan.tolerance,
            light.height,
            plan.lighting,
        )
        on_floor.extend(
            _named(plan, layers, f"shadow_{light.name}_ground", _layer_suffix, light.group)
        )
    where = ""
    if receiving.home is not None:
        floor.scopes, floor.placement = frozenset({receiving.home[0]}), receiving.home[1]
        where = " (in the group of its non-global lights, so that they light it)"
    note = (
        f"shadows: a light-grey ground ({floor.name}) is added under the scene{where} "
        "to show the shadows on the ground plane"
    )
    return floor, on_floor, note


def _enclosing(
    casters: CasterSet, held: dict[int, str], scene_light: SceneLight, casting: np.ndarray
) -> list[int]:
    """Of the casters ``held`` (:meth:`.CasterSet.holding`), the closed ones the
    light lies inside that are more than its bulb: whose box diagonal is over
    :data:`BULB_FRACTION` of the scene's. A smaller one is the lamp's bulb or a
    marker drawn where the light is: it casts nothing for that light (its
    reason in ``held`` says so)."""
    light = scene_light.light
    if not held or not is_positional(light):
        return []
    scene = float(np.linalg.norm(casters.bounds[1] - casters.bounds[0]))
    shells = []
    for index in held:
        caster = casters.caster(index)
        if not (caster.is_closed and abs(caster.winding_number(light.position)) > 0.5):
            continue  # it touches the light
        size = float(np.linalg.norm(casters.high[index] - casters.low[index]))
        if size > BULB_FRACTION * scene and casting[index] > 0:
            shells.append(index)
        else:
            held[index] = (
                f"the light at {light.position.tolist()} is inside the closed caster, no "
                f"larger than a bulb (at most {BULB_FRACTION:g} of the scene's size): taken "
                "for the lamp's own"
            )
    return shells


def _outside(casters: CasterSet, shell: list[int], receiver: Receiver) -> bool:
    """Whether a bounded planar ``receiver`` lies outside one of the casters
    ``shell`` round the light (judged by its area's centre)."""
    if receiver.triangles is None:
        return True
    corners = receiver.triangles
    doubled = np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    weights = (
        doubled / doubled.sum() if doubled.sum() > 0 else np.full(len(doubled), 1 / len(doubled))
    )
    centre = (corners.mean(axis=1) * weights[:, None]).sum(axis=0)
    return bool(_outside_points(casters, shell, centre[None])[0])


def _outside_faces(casters: CasterSet, shell: list[int], surface: ReceivingSurface) -> np.ndarray:
    """(m,) bool: the faces of ``surface`` outside one of the casters ``shell``
    round the light, judged per shape (a shape rarely straddles a shell round
    a light) by :data:`_SAMPLES` of its corners, most of them outside; the
    shells' own faces, which the light reaches from inside, are not."""
    outside = np.zeros(len(surface.faces), dtype=bool)
    for shape in np.unique(surface.owner).tolist():
        if shape in shell:
            continue
        rows = surface.owner == shape
        corners = np.unique(surface.faces[rows])
        picked = corners[np.linspace(0, len(corners) - 1, min(_SAMPLES, len(corners))).astype(int)]
        outside[rows] = _outside_points(casters, shell, surface.vertices[picked]).mean() > 0.5
    return outside


# Corners of a shape tested against a shell round the light (_outside_faces).
_SAMPLES = 16


def _outside_points(casters: CasterSet, shell: list[int], points: np.ndarray) -> np.ndarray:
    """(p,) bool: ``points`` (p, 3) outside one of the closed casters
    ``shell`` (generalised winding number under a half)."""
    outside = np.zeros(len(points), dtype=bool)
    for index in shell:
        low, high = casters.low[index], casters.high[index]
        boxed = np.flatnonzero(np.all((low <= points) & (points <= high), axis=1))
        out = np.ones(len(points), dtype=bool)
        out[boxed] = np.abs(casters.caster(index).winding_numbers(points[boxed])) <= 0.5
        outside |= out
    return outside


def _enclosed_note(casters: CasterSet, shell: list[int], light_name: str) -> str:
    named = _first_ten([repr(casters.casters[index].name) for index in shell])
    return (
        f"shadows: light {light_name} lies inside {named} (closed, larger than a bulb: "
        f"over {BULB_FRACTION:g} of the scene's size), so it lights nothing outside it; "
        "all it would light there is baked in shadow"
    )


def _covered(
    receiver: Receiver,
    points: np.ndarray,
    faces: np.ndarray,
    scene_light: SceneLight,
    opacity: float,
    tolerance: Tolerance,
    lift: float,
    lighting: Lighting,
) -> list[tuple[float, Shape]]:
    """The shadow of a closed caster round the light on a planar receiver
    facing it: all of the triangles ``points`` (n, 3), ``faces`` (m, 3) (the
    receiver's patch or, for the ground plane, the visible ground), lifted
    towards the light."""
    plane = receiver.facing(scene_light.light, tolerance)
    if plane is None or not lights(scene_light, receiver.scopes):
        return []
    vertices = points + lift * plane.normal
    darkness = lighting.darkness(scene_light, vertices, faces, receiver.material, receiver.scopes)
    where = f"shadow on {receiver.name} of a caster round the light"
    return [(opacity, shadow_shape(vertices, faces, scene_light, where, opacity, darkness))]


def _held_note(casters: CasterSet, held: dict[int, str], light_name: str) -> str:
    """The note on the casters (``held``: index to reason) that the light
    touches or sits inside, which cast nothing for it."""
    if len(held) == 1:
        ((index, reason),) = held.items()
        return (
            f"shadows: {casters.casters[index].name} does not cast for light {light_name}: {reason}"
        )
    by_reason: dict[str, list[str]] = {}  # (a light inside nested shells: one reason)
    for index, reason in held.items():
        by_reason.setdefault(reason, []).append(repr(casters.casters[index].name))
    parts = []
    for reason, named in by_reason.items():
        each = "each: " if len(named) > 1 else ""
        parts.append(f"{_first_ten(named)} ({each}{reason})")
    return f"shadows: {len(held):,} casters do not cast for light {light_name}: {'; '.join(parts)}"


def in_scope(scene_light: SceneLight, shapes: Sequence[Shape]) -> np.ndarray:
    """(n,) float64: 1 for each shape ``scene_light`` lights (all of them
    for a light with no scope), else 0."""
    if scene_light.scope is None:
        return np.ones(len(shapes))
    return np.array([float(lights(scene_light, shape.scopes)) for shape in shapes])


def _ground_home(chosen: Sequence[SceneLight]) -> tuple[int, Placement] | None:
    """Where the added ground goes when the casting lights that have a scope
    (X3D ``global="false"``) share one, a grouping node of the scene's own
    document: there, those lights light it and shadow it, in a browser that
    keeps to the scope and in one that does not (X_ITE takes a
    DirectionalLight of X3D 3.0 and VRML 97 as global). Its scope and the
    group; None when no casting light has a scope, or they have several (the
    ground stays at the top, lit by the global lights only)."""
    scoped = [light for light in chosen if light.scope is not None]
    if not scoped or len({light.scope for light in scoped}) > 1:
        return None
    scope, group = scoped[0].scope, scoped[0].scope_group
    return None if scope is None or group is None else (scope, group)


def _is_ground(receiver: Receiver) -> bool:
    """Whether ``receiver`` is the ground plane :func:`.receivers.ground` made."""
    return receiver.triangles is None and receiver.name == "ground"


def _runtime_shadows(
    lights: list[SceneLight],
    baked: list[SceneLight],
    keep: bool,
    names: _Names,
) -> tuple[list[SceneLight], list[str]]:
    """The scene's lights with ``baked`` set on those whose shadows are now
    ``baked`` and that would draw them at run time (``shadows`` true), unless
    ``keep``: a browser drawing its own shadow over the baked one darkens it
    twice. ``baked`` is cleared on the others (a light an earlier run baked
    and this one does not draws its runtime shadows again). One note says
    which lights still draw runtime shadows."""
    result, notes = [], []
    turned_off, drawing = [], []
    casting = {id(light) for light in baked}  # the scene's own objects, alive meanwhile
    for index, light in enumerate(lights):
        name = names.light(light, index)
        chosen = id(light) in casting
        turn_off = chosen and light.shadows and not keep
        if turn_off:
            turned_off.append(name)
        if light.baked != turn_off:
            light = dataclasses.replace(light, baked=turn_off)
        if light.runtime_shadows and light.on:
            drawing.append(name + (" (its shadows are baked too)" if chosen else ""))
        result.append(light)
    if turned_off:
        notes.append(
            f'shadows: runtime shadows turned off (shadows="false") for {_listed(turned_off)}: '
            "their shadows are baked, and a browser drawing its own over them would darken "
            "twice (--keep-runtime-shadows keeps them)"
        )
    if drawing:
        notes.append(f"shadows: runtime shadows still drawn by {_listed(drawing)}")
    elif baked:
        notes.append("shadows: no light draws runtime shadows over the baked ones")
    return result, notes


def _listed(names: list[str]) -> str:
    return f"light{'s' if len(names) > 1 else ''} {_first_ten(names)}"


def _first_ten(names: Sequence[str]) -> str:
    """``names`` joined, at most the first ten, and how many more."""
    more = f", and {len(names) - 10:,} more" if len(names) > 10 else ""
    return f"{', '.join(names[:10])}{more}"


def _layer_suffix(opacity: float) -> str:
    """The end of the name of a shadow layer of casters of ``opacity``:
    nothing for opaque ones, ``_opacity50`` for half-transparent ones."""
    return "" if opacity >= 1 else f"_opacity{round(100 * opacity)}"


def _terrain(stacked: CasterSet, axis: int) -> str | None:
    """The name of an open shape spanning the scene's whole width that is a
    height field (a terrain, a curved floor: its faces projected down cover
    its footprint about once), or None. When every surface receives, it takes
    the shadows in place of a fallback ground plane, which under it would only
    show as a dark rim along its edges."""
    if not len(stacked):
        return None
    across = [k for k in range(3) if k != axis]
    low, high = stacked.bounds
    width = (high - low)[across]
    spans = np.all((stacked.high - stacked.low)[:, across] >= _TERRAIN_SPAN * width, axis=1)
    if not spans.any() or not np.all(width > 0):
        return None
    terrain = np.flatnonzero(spans & ~stacked.closed)  # closedness only when it can matter
    for index in terrain:
        caster = stacked.casters[int(index)]
        corners = caster.vertices[caster.shape.faces]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        covered = 0.5 * float(np.abs(normals[:, axis]).sum())
        footprint = float(np.prod((stacked.high - stacked.low)[index, across]))
        if covered <= _TERRAIN_COVER * footprint:
            return caster.name
    return None


def _without_baked(scene: Scene) -> tuple[list[Shape], list[str]]:
    """The scene's shapes less the shadows an earlier run added: shapes with
    role "shadow" or "volume" (every reader keeps roles; X3D through the
    ``MARK`` class of the groups). They are replaced, neither cast nor stay."""
    kept = [s for s in scene.shapes if s.role not in ("shadow", "volume", "ground")]
    if len(kept) == len(scene.shapes):
        return kept, []
    return kept, [
        f"shadows: {len(scene.shapes) - len(kept)} shadow shapes added by an earlier run "
        "are replaced"
    ]


class _Names:
    """Unique DEF-safe names, avoiding every name the scene already uses."""

    def __init__(self, shapes: list[Shape], lights: list[SceneLight]) -> None:
        self.used = {s.name for s in shapes if s.name} | {
            light.name for light in lights if light.name
        }
        self.used |= set(s.group for s in shapes if s.group)

    def unique(self, text: str) -> str:
        return unique_name(text, self.used)

    @staticmethod
    def light(light: SceneLight, index: int) -> str:
        return safe_name(light.name) if light.name else f"light{index}"


def default_sun(up_axis: str = "Y") -> SceneLight:
    """The sun :func:`add_shadows` uses for a scene with no light that is on.

    It travels along :data:`DEFAULT_SUN_DIRECTION` ``(0.3, -1, 0.2)`` in a
    Y-up scene, ``(0.3, -0.2, -1)`` in a Z-up one (the same sun: Y-up ``(x,
    y, z)`` is Z-up ``(x, -z, y)``), named ``"sun"``, with ``shadows=True``.

    Examples
    --------
    >>> default_sun().light.direction.round(3).tolist()
    [0.282, -0.941, 0.188]
    >>> default_sun("Z").light.direction.round(3).tolist()
    [0.282, -0.188, -0.941]
    """
    x, y, z = DEFAULT_SUN_DIRECTION
    direction = (x, -z, y) if (up_axis or "Y").upper() == "Z" else (x, y, z)
    return SceneLight(DirectionalLight(direction), name="sun", shadows=True)


def _select_lights(
    scene: Scene,
    names: Sequence[str] | None,
    extra: Sequence[SceneLight] = (),
) -> tuple[list[SceneLight], list[str]]:
    """The lights that cast (see the module notes), with the notes on the
    choice: the named ones and ``extra``, else the scene's own."""
    extra = _checked_extra(extra)
    if extra and names is None:
        return extra, []
    if names is not None:
        return [*_named_lights(scene, names), *extra], []
    lit = [light for light in scene.lights if light.on]
    if not lit:
        sun = default_sun(scene.up_axis)
        return [sun], [_default_sun_note(scene, sun)]
    return _casting_lights(lit)


def _checked_extra(extra: Sequence[SceneLight]) -> list[SceneLight]:
    extra = list(extra)
    for light in extra:
        if not isinstance(light, SceneLight):
            raise GeometryError(f"extra_lights must hold SceneLight values, got {light!r}")
    return extra


def _named_lights(scene: Scene, names: Sequence[str]) -> list[SceneLight]:
    """The scene's lights named ``names`` (DEF), each on."""
    by_name = {light.name: light for light in scene.lights if light.name}
    chosen = []
    for name in names:
        if name not in by_name:
            known = ", ".join(sorted(by_name)) or "none has a DEF name"
            raise SceneError(f"no light named '{name}' (lights: {known})", path=scene.path)
        if not by_name[name].on:
            raise SceneError(f"light '{name}' is off (on=\"false\")", path=scene.path)
        chosen.append(by_name[name])
    return chosen


def _default_sun_note(scene: Scene, sun: SceneLight) -> str:
    """The note on the default ``sun`` casting in a scene with no light on."""
    what = "no lights" if not scene.lights else "no light that is on"
    sun_direction = cast(DirectionalLight, sun.light).direction
    direction = ", ".join(f"{value:.3g}" for value in sun_direction)
    return (
        f"shadows: the scene has {what}; a default sun casts, travelling along "
        f"({direction}), {DEFAULT_SUN_ELEVATION:.0f} degrees above the horizon "
        "(X3D's headlight follows the viewer and casts none; shadowgeo convert "
        "--sun DX,DY,DZ gives another)"
    )


def _casting_lights(lit: list[SceneLight]) -> tuple[list[SceneLight], list[str]]:
    """Of the lights that are on, those with ``shadows=True`` (all when none
    has it), at most :data:`shadowgeo.limits.MAX_CASTING_LIGHTS`."""
    notes = []
    chosen = [light for light in lit if light.shadows]
    if not chosen:
        listed = _first_ten([_Names.light(light, i) for i, light in enumerate(lit)])
        notes.append(
            f'shadows: no light has shadows="true"; all {len(lit)} lights that are on cast '
            f"shadows ({listed})"
        )
        chosen = lit
    if len(chosen) > limits.MAX_CASTING_LIGHTS:
        notes.append(
            f"shadows: {len(chosen):,} lights would cast; the first "
            f"{limits.MAX_CASTING_LIGHTS} in the scene's order do (each is a shadow pass; "
            "shadowgeo.limits.MAX_CASTING_LIGHTS; --light NAME chooses)"
        )
        chosen = chosen[: limits.MAX_CASTING_LIGHTS]
    return chosen, notes


def _caster_loops(
    casters: CasterSet,
    faces: np.ndarray,
    light: Light,
    plane: Plane,
    rectangle: np.ndarray | None,
    tolerance: Tolerance,
    light_name: str,
) -> tuple[list[np.ndarray], list[str]]:
    """The loops of the shadows of the stacked faces ``faces`` (a mask) on
    ``plane``, in plane 2-D coordinates.

    All casters go through :func:`project_shadow` as one mesh: the shadow of a
    union of meshes is the union of their shadows, and one call does the work
    in numpy for every caster at once instead of paying a Python call's fixed
    cost per shape. When that call fails (a light inside or touching one of
    them), each caster is projected alone so that only the one at fault is
    skipped, with a note (the notes are returned with the loops).
    """
    owners = casters.owners(faces)
    if not len(owners):
        return [], []
    try:
        shadow = project_shadow(
            casters.mesh(faces), light, plane, receiver=rectangle, tolerance=tolerance
        )
        return [loop for part in shadow.polygons for loop in part], []
    except GeometryError as error:
        if len(owners) == 1:
            name = casters.casters[owners[0]].name
            return [], [f"shadows: {name} does not cast for light {light_name}: {error}"]
    # find the caster at fault: each alone
    loops, notes = [], []
    for owner in owners:
        caster = casters.casters[owner]
        own = faces[casters.face_owner == owner]
        mesh = caster.caster if own.all() else Caster(caster.vertices, caster.shape.faces[own])
        try:
            shadow = project_shadow(mesh, light, plane, receiver=rectangle, tolerance=tolerance)
        except GeometryError as error:
            notes.append(f"shadows: {caster.name} does not cast for light {light_name}: {error}")
            continue
        for part in shadow.polygons:
            loops.extend(part)
    return loops, notes


def _shadow_on(
    receiver: Receiver,
    scene_light: SceneLight,
    *,
    casters: CasterSet,
    opacity: np.ndarray,
    tolerance: Tolerance,
    lift: float,
    light_name: str,
    step: Callable[[int], None],
    lighting: Lighting,
) -> tuple[list[tuple[float, Shape]], list[str]]:
    """The shadow of the casters on one receiver as shapes, one per casting
    opacity (``opacity``: (k,) each caster's, :mod:`.opacity`), most opaque
    first, each with that opacity: raised ``lift`` off the receiver's plane,
    ``step(count)`` called once the casters are chosen, with a note for
    each caster that cannot cast. The layers do not overlap: each
    is its casters' united shadow less the shadows of every more opaque
    layer, so a point takes the darkness of the most opaque caster that hides
    it. Each layer is as dark as ``lighting`` says (:mod:`.darkness`) times
    its opacity."""
    light = scene_light.light
    plane = receiver.facing(light, tolerance)
    if plane is None or not lights(scene_light, receiver.scopes):
        return [], []  # behind a one-sided receiver, in its plane, or out of the light's scope
    region2d = None if receiver.triangles is None else _flat_patch(receiver.triangles, plane)
    box2d = None if region2d is None else _box_of(region2d)
    rectangle = None if box2d is None else _rectangle(plane, box2d)
    chosen = casters.may_shadow(light, plane, box2d, tolerance) & (opacity > 0)
    off_plane = casters.off_plane(plane, tolerance) if chosen.any() else None
    step(len(casters))
    layers: list[tuple[float, list[np.ndarray]]] = []
    notes: list[str] = []
    for level in np.unique(opacity[chosen])[::-1].tolist():  # most opaque first
        faces = casters.faces_of(chosen & (opacity == level)) & off_plane
        loops, loop_notes = _caster_loops(
            casters, faces, light, plane, rectangle, tolerance, light_name
        )
        notes.extend(loop_notes)
        if loops:
            layers.append((level, loops))
    if not layers:
        return [], notes
    frame = _frame(plane, layers, region2d, tolerance, lift)
    shapes = []
    for level, parts in _layer_parts(layers, frame):
        where = f"shadow of light {light_name} on {receiver.name}"
        if level < 1:
            where += f", of casters of opacity {level:g}"
        shape = _layer_shape(frame, parts, receiver, scene_light, where, level, lighting)
        if shape is not None:
            shapes.append((level, shape))
    return shapes, notes


@dataclasses.dataclass(frozen=True)
class _Frame:
    """The receiver's plane and the 2-D frame its shadows are cut in: centred
    on them, scaled for the polygon library (:func:`shadowgeo.plane2d.local_scale`);
    the receiver's patch in it (None for an unbounded plane) and the lift."""

    plane: Plane
    center: np.ndarray
    scale: float
    receiving: CrossSection | None
    lift: float


def _flat_patch(triangles: np.ndarray, plane: Plane) -> np.ndarray:
    """(n, 3, 2): a receiver's triangles in ``plane``'s 2-D coordinates."""
    return plane.to_2d(triangles.reshape(-1, 3)).reshape(-1, 3, 2)


def _box_of(flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return flat.reshape(-1, 2).min(axis=0), flat.reshape(-1, 2).max(axis=0)


def _rectangle(plane: Plane, box2d: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """(4, 3): the corners of the 2-D box ``box2d`` in ``plane``."""
    low, high = box2d
    corners = np.array([low, [high[0], low[1]], high, [low[0], high[1]]], dtype=np.float64)
    return plane.to_3d(corners)


def _frame(
    plane: Plane,
    layers: list[tuple[float, list[np.ndarray]]],
    region2d: np.ndarray | None,
    tolerance: Tolerance,
    lift: float,
) -> _Frame:
    """The frame of the shadow loops ``layers`` and the receiver's patch."""
    points = np.concatenate([loop for _, loops in layers for loop in loops])
    center = 0.5 * (points.min(axis=0) + points.max(axis=0))
    extent = float(np.abs(points - center).max())
    if region2d is not None:
        extent = max(extent, float(np.abs(region2d.reshape(-1, 2) - center).max()))
    scale = poly.local_scale(max(extent, tolerance.length))
    receiving = None
    if region2d is not None:
        receiving = poly.triangles_region((region2d - center) * scale)
    return _Frame(plane, center, scale, receiving, lift)


def _layer_parts(
    layers: list[tuple[float, list[np.ndarray]]], frame: _Frame
) -> list[tuple[float, list[list[np.ndarray]]]]:
    """Each layer's region in the frame, cut to the receiver, less every more
    opaque layer's, as parts (outer loop, holes); empty ones left out."""
    parts_of = []
    covered = None  # the more opaque layers' region
    for level, loops in layers:
        local = [(loop - frame.center) * frame.scale for loop in loops]
        if len(layers) == 1 and _simple_on_receiver(local, frame.receiving):
            parts = [local]  # no union and no cut (a sweep over the loop each)
        else:
            region = poly.unite(local)
            if frame.receiving is not None:
                region = poly.intersect(region, frame.receiving)
            layer = region if covered is None else poly.subtract(region, covered)
            covered = region if covered is None else poly.add(covered, region)
            parts = poly.components(layer)
        if parts:
            parts_of.append((level, parts))
    return parts_of


def _simple_on_receiver(local: list[np.ndarray], receiving: CrossSection | None) -> bool:
    """Whether the loops ``local`` are one simple loop lying on the receiver."""
    if not poly.whole_loop(local, keep_triangles=True):
        return False
    return receiving is None or poly.holds_box(
        receiving, local[0].min(axis=0), local[0].max(axis=0)
    )


def _layer_shape(
    frame: _Frame,
    parts: list[list[np.ndarray]],
    receiver: Receiver,
    scene_light: SceneLight,
    where: str,
    level: float,
    lighting: Lighting,
) -> Shape | None:
    """One layer's parts triangulated, lifted off the receiver, as a shadow
    shape; None for slivers narrower than rounding (no shadow to draw)."""
    flat_points, faces = poly.triangulate_parts(parts)
    if not len(faces):
        return None
    plane = frame.plane
    vertices = plane.to_3d(flat_points / frame.scale + frame.center) + frame.lift * plane.normal
    darkness = lighting.darkness(scene_light, vertices, faces, receiver.material, receiver.scopes)
    return shadow_shape(vertices, faces, scene_light, where, level, darkness)


def _soft_for(
    scene_light: SceneLight,
    settings: SoftSettings,
    opacity: np.ndarray,
    light_name: str,
) -> tuple[SoftSettings | None, list[str]]:
    """``settings`` for a light with a size, whose shadows bake as graded
    layers (:mod:`.softbake`), with a note when translucent casters cast
    for it as opaque; None for one without."""
    if not is_soft(scene_light):
        return None, []
    note = translucent_note(opacity, light_name)
    return settings, [] if note is None else [note]


def _suffix_for(graded: SoftSettings | None) -> Callable[[float], str]:
    """How a layer's name ends: by its casters' opacity, or its level."""
    return _layer_suffix if graded is None else soft_suffix


def _receiver_layers(
    plan: _ShadowPlan, light: _LightCasting, receiver: Receiver, step: Callable[[int], None]
) -> tuple[list[tuple[float, Shape]], list[str]]:
    """:func:`_shadow_on`, or for a light with a size (``light.graded``) its
    graded layers (:func:`.softbake.soft_on_receiver`)."""
    if light.graded is None:
        return _shadow_on(
            receiver,
            light.scene_light,
            casters=plan.casters,
            opacity=light.casting,
            tolerance=plan.tolerance,
            lift=light.height,
            light_name=light.name,
            step=step,
            lighting=plan.lighting,
        )
    step(len(plan.casters))
    return soft_on_receiver(
        receiver,
        light.scene_light,
        casters=plan.casters,
        opacity=light.casting,
        tolerance=plan.tolerance,
        lift=light.height,
        light_name=light.name,
        lighting=plan.lighting,
        settings=light.graded,
    )


def _surface_layers(
    plan: _ShadowPlan, light: _LightCasting, surface: ReceivingSurface, reached: np.ndarray
) -> tuple[list[tuple[float, Shape]], list[str]]:
    """:func:`.surfaces.surface_shadow` of the casters ``reached`` (indices
    in ``plan.casters``), or for a light with a size (``light.graded``) their
    graded layers (:func:`.softbake.soft_on_surface`)."""
    casters = [plan.casters.caster(int(k)) for k in reached]
    if light.graded is None:
        return surface_shadow(
            surface,
            casters,
            light.casting[reached],
            reached,
            light.scene_light,
            plan.tolerance,
            light.height,
            light.name,
            plan.lighting,
        )
    return soft_on_surface(
        surface,
        casters,
        light.scene_light,
        plan.tolerance,
        light.height,
        light.name,
        plan.lighting,
        light.graded,
    )


def _volumes(plan: _ShadowPlan) -> tuple[list[Shape], list[str]]:
    """Shadow volumes of every shape that casts (``opacity`` above 0) for every
    light, one step per light (:func:`_light_volumes`), ending one scene size
    past the farthest corner of the scene (a sweep of twice its size for a
    sun)."""
    bounds = plan.casters.bounds
    corners = np.array(
        [[x, y, z] for x in bounds[:, 0] for y in bounds[:, 1] for z in bounds[:, 2]]
    )
    added: list[Shape] = []
    notes: list[str] = []
    for index in range(len(plan.lights)):
        volumes, volume_notes = _light_volumes(plan, index, corners)
        added.extend(volumes)
        notes.extend(volume_notes)
    return added, notes


def _light_volumes(
    plan: _ShadowPlan, index: int, corners: np.ndarray
) -> tuple[list[Shape], list[str]]:
    """The step of the ``index``-th light: the shadow volume of each caster it
    lights, reaching past the scene's box ``corners`` (8, 3), with a note for
    each caster that has none."""
    stacked, tolerance, names = plan.casters, plan.tolerance, plan.names
    progress = plan.options.progress
    scene_light = plan.lights[index]
    light = scene_light.light
    if is_positional(light):
        extent = float(np.linalg.norm(corners - light.position, axis=1).max()) + tolerance.scale
    else:
        extent = 2 * tolerance.scale
    light_name = names.light(scene_light, index)
    group = names.unique(f"shadows_{light_name}")
    casting = stacked.lit(light) & (
        plan.opacity * in_scope(scene_light, [caster.shape for caster in stacked.casters]) > 0
    )
    added, notes = [], []
    total, done = len(plan.lights) * len(stacked), index * len(stacked)
    for caster, lit in zip(stacked.casters, casting, strict=True):
        done += 1
        if progress is not None:
            progress(done, total)
        if not lit:
            continue
        try:
            volume = shadow_volume(caster.caster, light, extent=extent, tolerance=tolerance)
        except GeometryError as error:
            notes.append(f"shadows: {caster.name} has no volume for {light_name}: {error}")
            continue
        if len(volume.faces) == 0:
            continue
        added.append(
            Shape(
                np.asarray(volume.vertices, dtype=np.float64),
                np.asarray(volume.faces, dtype=np.int64),
                material=Material(diffuse_color=(0.0, 0.0, 0.0), transparency=0.8),
                name=names.unique(f"volume_{light_name}_{safe_name(caster.name)}"),
                solid=False,
                role="volume",
                group=group,
                source=f"shadow volume of {caster.name} for light {light_name}",
                casts_shadow=False,
            )
        )
    return added, notes
