"""Soft shadows baked into a scene, for :func:`~shadowgeo.add_shadows`.

A light with a size (:attr:`SceneLight.emitter`: a sun's ``angle``, a
sphere or spot light's ``source_radius``, a rectangle or disc light) bakes
graded layers instead of one hard shadow: one shape per level of the hidden
fraction ``k / levels`` (:func:`shadowgeo.soft_shadow` on each planar
receiver, :func:`shadowgeo.soft_shadow_on_surface` on every other surface),
each as dark as the hard shadow would be times its fraction (its material's
transparency ``1 - darkness * k / levels``), so the umbra is the darkest and
the penumbra fades out. The layers do not overlap. A light with no size
never comes here: it bakes what it always did.

What is simpler than the hard path: every caster that casts at all casts
as if opaque (a note says so when some are translucent); a smooth shape's
shadow is cut at the terminator of the light's centre, and not carried
past it onto the faces the shading still lights.

:func:`with_light_sizes` gives a scene's lights a size (``shadowgeo convert
--sun-angle``, ``--light-size``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .. import plane2d as poly
from ..errors import GeometryError, SceneError
from ..lights import DirectionalLight, PointLight, SpotLight
from ..soft import checked_counts, has_size, soft_shadow
from ..soft_surface import soft_shadow_on_surface
from ..tolerance import Tolerance
from ..topology import Caster
from .casters import CasterSet
from .darkness import Lighting
from .model import Scene, SceneLight, Shape, lights, shadow_shape
from .receivers import Receiver
from .surfaces import ReceivingSurface, surface_darkness
from .terminator import clip_to_lit, lit_values

__all__ = [
    "SoftSettings",
    "UnknownLight",
    "is_soft",
    "soft_on_receiver",
    "soft_on_surface",
    "soft_suffix",
    "translucent_note",
    "with_light_sizes",
]


@dataclass(frozen=True)
class SoftSettings:
    """How finely a light with a size is baked: ``levels`` graded layers
    (``k / levels``), from ``samples`` point lights (None:
    :data:`shadowgeo.soft.DEFAULT_SAMPLES`)."""

    levels: int = 8
    samples: int | None = None

    def __post_init__(self) -> None:
        # checked now, not when a light with a size first asks (a note, then)
        checked_counts(DirectionalLight([0, -1, 0], 0.01), self.levels, self.samples)


class UnknownLight(SceneError):
    """A light named to be given a size is not in the scene."""


def is_soft(scene_light: SceneLight) -> bool:
    """Whether ``scene_light`` has a size: its shadows bake as graded layers."""
    return has_size(scene_light.emitter)


def soft_suffix(fraction: float) -> str:
    """The end of the name of a graded layer: ``_soft25`` for the points
    hidden from a quarter of the light, ``_soft100`` for its umbra."""
    return f"_soft{round(100 * fraction)}"


def soft_on_receiver(
    receiver: Receiver,
    scene_light: SceneLight,
    *,
    casters: CasterSet,
    opacity: np.ndarray,
    tolerance: Tolerance,
    lift: float,
    light_name: str,
    lighting: Lighting,
    settings: SoftSettings,
) -> tuple[list[tuple[float, Shape]], list[str]]:
    """The graded layers (hidden fraction, shape) of the casters' soft shadow
    on one planar receiver, cut to it and lifted ``lift`` towards the light;
    none when the light does not face it or nothing falls on it. With a note
    when the shadow could not be made."""
    plane = receiver.facing(scene_light.light, tolerance)
    if plane is None or not lights(scene_light, receiver.scopes) or not (opacity > 0).any():
        return [], []
    rectangle = region2d = None
    if receiver.triangles is not None:
        region2d = plane.to_2d(receiver.triangles.reshape(-1, 3)).reshape(-1, 3, 2)
        low, high = region2d.reshape(-1, 2).min(axis=0), region2d.reshape(-1, 2).max(axis=0)
        rectangle = plane.to_3d([low, [high[0], low[1]], high, [low[0], high[1]]])
    faces = casters.faces_of(opacity > 0) & casters.off_plane(plane, tolerance)
    if not faces.any():
        return [], []
    try:
        soft = soft_shadow(
            casters.mesh(faces),
            scene_light.emitter,
            plane,
            receiver=rectangle,
            levels=settings.levels,
            samples=settings.samples,
            tolerance=tolerance,
        )
    except GeometryError as error:
        return [], [f"shadows: no soft shadow of light {light_name} on {receiver.name}: {error}"]
    shapes = []
    for fraction, level in soft.levels:
        parts = _cut_to(level.polygons, region2d, tolerance)
        flat, triangles = poly.triangulate_parts(parts) if parts else (None, np.zeros((0, 3)))
        if flat is None or not len(triangles):
            continue
        vertices = plane.to_3d(flat) + lift * plane.normal
        darkness = lighting.darkness(
            scene_light, vertices, triangles, receiver.material, receiver.scopes
        )
        where = f"soft shadow of light {light_name} on {receiver.name}, hidden from {fraction:g}"
        shape = shadow_shape(vertices, triangles, scene_light, where, fraction, darkness)
        shapes.append((fraction, shape))
    return shapes, []


def _cut_to(
    parts: list[list[np.ndarray]], region2d: np.ndarray | None, tolerance: Tolerance
) -> list[list[np.ndarray]]:
    """``parts`` (plane 2-D) cut to the receiver's triangles ``region2d``
    (t, 3, 2; None: unbounded), in a frame Clipper2 works in exactly."""
    if region2d is None or not parts:
        return parts
    points = np.concatenate([loop for part in parts for loop in part] + [region2d.reshape(-1, 2)])
    center = 0.5 * (points.min(axis=0) + points.max(axis=0))
    scale = poly.local_scale(max(float(np.abs(points - center).max()), tolerance.length))
    region = poly.intersect(
        poly.unite([(loop - center) * scale for part in parts for loop in part]),
        poly.triangles_region((region2d - center) * scale),
    )
    return [[loop / scale + center for loop in part] for part in poly.components(region)]


def soft_on_surface(
    surface: ReceivingSurface,
    casters: list[Caster],
    scene_light: SceneLight,
    tolerance: Tolerance,
    lift: float,
    light_name: str,
    lighting: Lighting,
    settings: SoftSettings,
) -> tuple[list[tuple[float, Shape]], list[str]]:
    """The graded layers (hidden fraction, shape) of the casters' soft shadow
    on every face of ``surface``, cut where the shading of the light's
    centre stops lighting it (as :func:`~.surfaces.surface_shadow` cuts the
    hard one); with a note when the shadow could not be made."""
    keep = [caster for caster in casters if caster.n_faces]
    if not len(surface.faces) or not keep:
        return [], []
    try:
        soft = soft_shadow_on_surface(
            keep,
            scene_light.emitter,
            (surface.vertices, surface.faces),
            levels=settings.levels,
            samples=settings.samples,
            offset=lift,
            tolerance=tolerance,
        )
    except GeometryError as error:
        return [], [f"shadows: no soft shadows on the surfaces for light {light_name}: {error}"]
    corners = surface.vertices[surface.faces]
    values = lit_values(corners, surface.normals, scene_light.light)
    shapes = []
    for fraction, level in soft.levels:
        vertices, triangles, index = clip_to_lit(
            level.vertices, level.faces, level.face_index, corners, values
        )
        if not len(triangles):
            continue
        darkness = surface_darkness(surface, lighting, scene_light, vertices, triangles, index)
        where = (
            f"soft shadow of light {light_name} on the scene's surfaces, hidden from {fraction:g}"
        )
        shape = shadow_shape(vertices, triangles, scene_light, where, fraction, darkness)
        shapes.append((fraction, shape))
    return shapes, []


def translucent_note(opacity: np.ndarray, light_name: str) -> str | None:
    """The note for a light with a size whose casters include translucent
    ones (``opacity`` (k,) each caster's, 0 for none): they cast as opaque."""
    some = int(((opacity > 0) & (opacity < 1)).sum())
    if not some:
        return None
    return (
        f"shadows: light {light_name} has a size: its soft shadow takes the {some} translucent "
        "caster(s) as opaque"
    )


def with_light_sizes(
    scene: Scene,
    *,
    sun_angle: float | None = None,
    light_sizes: Sequence[tuple[str, float]] = (),
) -> Scene:
    """``scene`` with its lights given a size: every directional light the
    angular diameter ``sun_angle`` (radians; the sun's is 0.53 degrees), and
    each point or spot light named in ``light_sizes`` (name, source radius in
    scene units) that radius.

    Raises
    ------
    UnknownLight
        A name in ``light_sizes`` is no light of the scene (the names it has
        are listed).
    SceneError
        A named light is a directional light (its size is ``sun_angle``) or a
        rectangle or disc light (its size is its shape).
    """
    changed = list(scene.lights)
    if sun_angle is not None:
        changed = [
            dataclasses.replace(each, light=DirectionalLight(each.light.direction, sun_angle))
            if isinstance(each.light, DirectionalLight) and each.area is None
            else each
            for each in changed
        ]
    for name, radius in light_sizes:
        matches = [k for k, each in enumerate(changed) if each.name == name]
        if not matches:
            known = ", ".join(sorted({each.name for each in changed if each.name})) or "none"
            raise UnknownLight(f"no light named {name!r} (the lights: {known})")
        for k in matches:
            changed[k] = _sized(changed[k], name, radius)
    return dataclasses.replace(scene, lights=changed)


def _sized(scene_light: SceneLight, name: str, radius: float) -> SceneLight:
    """A point or spot light given the source radius ``radius``."""
    light = scene_light.light
    if scene_light.area is not None or isinstance(light, DirectionalLight):
        kind = "a rectangle or disc light" if scene_light.area else "a directional light"
        how = "its shape" if scene_light.area else "--sun-angle"
        raise SceneError(f"light {name!r} is {kind}: its size is {how}, not a source radius")
    if not (math.isfinite(radius) and radius >= 0):
        raise SceneError(f"light {name!r}: a source radius must be >= 0, got {radius!r}")
    sized: PointLight | SpotLight
    if isinstance(light, SpotLight):
        sized = SpotLight(
            light.position, light.direction, light.cut_off_angle, light.radius, radius
        )
    else:
        sized = PointLight(light.position, light.radius, radius)
    return dataclasses.replace(scene_light, light=sized)
