"""X3D lights and materials to the scene model.

Lights go to world coordinates: a light's location is transformed as a
point, its direction as a vector (then normalised), and its ``radius`` by
the transform's mean scale ``|det M|^(1/3)`` (exact for uniform scaling).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from ...errors import GeometryError
from ...lights import DirectionalLight, Light, PointLight, SpotLight
from ...limits import check_coordinates, check_length
from ...scene import Material, SceneLight
from ...scene.model import MARK
from .. import float_triple
from .fields import Context, Element, local_name

__all__ = ["BAKED", "LIGHTS", "MATERIALS", "material", "scene_light"]

LIGHTS = {"PointLight", "SpotLight", "DirectionalLight"}
# The class token of a light whose shadows shadowgeo baked (see write.py).
BAKED = f"{MARK}-baked"
MATERIALS = {"Material", "PhysicalMaterial", "UnlitMaterial", "TwoSidedMaterial"}


def _color(value: Any) -> tuple[float, float, float]:
    """The colour clipped to [0, 1] (the values are finite: parsed fields)."""
    return float_triple(min(max(float(c), 0.0), 1.0) for c in value)


def scene_light(context: Context, element: Element, matrix: np.ndarray) -> SceneLight | None:
    """The light of ``element`` under the world ``matrix`` (4x4, column
    vectors); None, with a warning, for a light that lights nothing."""
    tag = local_name(element)

    def field(name: str) -> Any:
        return context.field(element, name)

    light: Light
    linear = matrix[:3, :3]
    scale = float(np.cbrt(abs(np.linalg.det(linear))))
    try:
        if tag == "DirectionalLight":
            light = DirectionalLight(linear @ field("direction"))
        else:
            location = linear @ field("location") + matrix[:3, 3]
            radius = field("radius") * scale
            if not radius > 0:
                context.warn(element, f"radius {field('radius')!r} lights nothing; skipped")
                return None
            _check_range(context, element, location, radius)
            if tag == "PointLight":
                light = PointLight(location, radius)
            else:
                cut_off = field("cutOffAngle")
                if not cut_off > 0:
                    context.warn(element, f"cutOffAngle {cut_off!r} lights nothing; skipped")
                    return None
                if cut_off > math.pi / 2:
                    context.warn(element, f"cutOffAngle {cut_off!r} > pi/2 taken as pi/2")
                    cut_off = math.pi / 2
                light = SpotLight(location, linear @ field("direction"), cut_off, radius)
    except GeometryError as problem:
        context.warn(element, f"light skipped: {problem}")
        return None
    extra: dict[str, Any] = {}
    baked = BAKED in (element.get("class") or "").split()
    if tag != "DirectionalLight":
        extra["attenuation"] = tuple(float(a) for a in field("attenuation"))
    if tag == "SpotLight":
        extra["beam_width"] = float(field("beamWidth"))
    return SceneLight(
        light=light,
        name=element.get("DEF"),
        color=_color(field("color")),
        intensity=float(field("intensity")),
        ambient_intensity=float(field("ambientIntensity")),
        on=bool(field("on")),
        global_=bool(field("global")),
        # a light shadowgeo baked had shadows="true" before it was turned off
        shadows=bool(field("shadows")) or baked,
        shadow_intensity=float(field("shadowIntensity")),
        baked=baked,
        **extra,
    )


def _check_range(context: Context, element: Element, location: np.ndarray, radius: float) -> None:
    """SceneError unless the world location and radius are within the range
    the geometry carries (:mod:`shadowgeo.limits`): a light is never
    silently dropped for a number that is merely too large."""
    try:
        check_coordinates(location, "location (world)")
        check_length(radius, "radius (world)")
    except GeometryError as problem:
        raise context.error(element, str(problem)) from None


def material(context: Context, appearance: Element | None) -> Material:
    """The Material of an Appearance element (USE resolved), or X3D's rule
    for a Shape without one: unlit white (emissive 1 1 1, diffuse 0 0 0)."""
    unlit = Material(diffuse_color=(0.0, 0.0, 0.0), emissive_color=(1.0, 1.0, 1.0))
    if appearance is None:
        return unlit
    # X3D 4's backMaterial colours back faces only; the front material is the one
    front = [child for child in appearance if child.get("containerField") != "backMaterial"]
    # context.node is None for a ProtoInstance that could not be expanded (already warned)
    nodes = [node for node in map(context.node, front) if node is not None]
    nodes = [node for node in nodes if local_name(node) in MATERIALS]
    if not nodes:
        return unlit
    node = nodes[0]
    key = ("material", node.tag, tuple(node.attrib.items()))
    if key not in context.by_content:
        said = len(context.warnings)
        made = _material(context, node)
        if len(context.warnings) > said:
            return _alpha_mode(context, appearance, made)  # each bad one named in its warning
        context.by_content[key] = made
    known: Material = context.by_content[key]
    return _alpha_mode(context, appearance, known)


def _alpha_mode(context: Context, appearance: Element, look: Material) -> Material:
    """``look`` as X3D 4's Appearance ``alphaMode`` draws it: ``OPAQUE``
    opaque whatever its transparency, ``MASK`` opaque or not at all as its
    alpha (``1 - transparency``) reaches ``alphaCutoff`` or not; ``AUTO``
    and ``BLEND`` as it is. (A texture's own alpha is not modelled.)"""
    mode = str(context.field(appearance, "alphaMode")).upper()
    if mode == "OPAQUE":
        transparency = 0.0
    elif mode == "MASK":
        cutoff = float(context.field(appearance, "alphaCutoff"))
        transparency = 0.0 if 1.0 - look.transparency >= cutoff else 1.0
    else:
        return look
    return look if look.transparency == transparency else replace(look, transparency=transparency)


def _material(context: Context, node: Element) -> Material:
    tag = local_name(node)

    def field(name: str) -> Any:
        return context.field(node, name)

    name = node.get("DEF")
    if tag in ("Material", "TwoSidedMaterial"):
        return Material(
            diffuse_color=_color(field("diffuseColor")),
            emissive_color=_color(field("emissiveColor")),
            specular_color=_color(field("specularColor")),
            shininess=float(field("shininess")),
            transparency=float(field("transparency")),
            name=name,
            ambient_intensity=float(field("ambientIntensity")),
        )
    if tag == "PhysicalMaterial":
        return Material(
            diffuse_color=_color(field("baseColor")),
            emissive_color=_color(field("emissiveColor")),
            transparency=float(field("transparency")),
            name=name,
        )
    return Material(
        diffuse_color=(0.0, 0.0, 0.0),
        emissive_color=_color(field("emissiveColor")),
        transparency=float(field("transparency")),
        name=name,
    )
