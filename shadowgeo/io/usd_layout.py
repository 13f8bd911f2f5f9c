"""What the USD reader and writer share: usd-core's modules, opening a file
with a clear error, and the layout of what shadowgeo stores in USD.

Layout written
--------------
``/World`` (an Xform, the default prim) holds one ``UsdGeom.Mesh`` per scene
shape, one Xform per light group holding that group's shadows, the lights, and
``/World/Looks`` with one ``UsdPreviewSurface`` material per distinct look.
Stage metadata ``upAxis`` and ``metersPerUnit`` come from the scene.

- Meshes: ``points``, ``faceVertexCounts`` (all 3), ``faceVertexIndices``,
  face normals (``faceVarying``, so shading is flat as in glTF), ``extent``,
  ``orientation = rightHanded``, ``doubleSided`` when not solid,
  ``subdivisionScheme = none`` (these are polygons, not cages), the shape's
  transform as one double-precision ``xformOp:transform``, ``displayColor`` /
  ``displayOpacity`` and a bound material.
- Lights: a point light is a ``SphereLight`` with ``treatAsPoint``; a spot
  light the same with ``ShapingAPI`` (``shaping:cone:angle`` = the cut-off
  angle in degrees, softness from the beam width); a directional light a
  ``DistantLight``. Lights shine down their -Z, so the transform turns -Z onto
  the light's direction. ``ShadowAPI``'s ``inputs:shadow:enable`` carries X3D's
  ``shadows`` as a browser draws them (false once shadowgeo baked them, with
  ``shadowgeo:shadowsBaked``); a light that is off is ``invisible``.
- Cameras: a ``UsdGeom.Camera`` per viewpoint of the scene, else one
  framing the scene and its shadows, with its ``xformOp:transform``; the
  vertical aperture gives the field of view at the default focal length.
  Written only: the reader does not read cameras.
- Names: prims get valid, unique identifiers; the original name is the prim's
  ``displayName`` (USD strings end at a NUL character). A shape or light
  without a name gets a generated prim name and reads back as unnamed.
- Fields USD has no place for (a light's range, beam width, shadow intensity,
  attenuation, shape roles, group names, the scene's shape order) are
  ``shadowgeo:`` attributes (:func:`set_custom`, :func:`custom`).

Precision
---------
USD's ``points`` are float32. The writer also stores the float64 vertices as
``shadowgeo:points`` (``point3d[]``); the reader uses them when they agree
with ``points`` to float32 precision (so a tool that edits ``points`` and
leaves the copy stale is still obeyed), which makes round trips exact.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import SceneError

__all__ = [
    "PREFIX",
    "custom",
    "error_text",
    "opened",
    "pxr",
    "set_custom",
    "stored_name",
    "usd_text",
]

PREFIX = "shadowgeo:"


@functools.cache
def pxr() -> tuple[Any, ...]:
    """usd-core's modules ``Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt``,
    imported when first needed (it is slow to load)."""
    from pxr import Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt

    return Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt


def opened(opener: Callable[[str], Any], path: Path, failure: str) -> Any:
    """``opener(path)`` (a layer or a stage); a SceneError saying ``failure``
    and usd-core's last message line when it raises or returns None."""
    from pxr import Tf

    try:
        result = opener(str(path))
    except Tf.ErrorException as error:
        raise SceneError(f"{failure}: {error_text(error)}", path=str(path)) from None
    if result is None:
        raise SceneError(failure, path=str(path))
    return result


def error_text(error: Exception, first: bool = False) -> str:
    """The last (or ``first``) line of a ``Tf.ErrorException``'s messages.

    ``str(error)`` itself raises UnicodeDecodeError when usd-core quotes bytes
    of a file that are not UTF-8, so each message is decoded with
    replacement characters instead.
    """
    lines: list[str] = []
    for item in error.args:
        try:
            text = str(getattr(item, "commentary", item))
        except UnicodeDecodeError as problem:
            raw = problem.object
            text = bytes(raw).decode("utf-8", "replace")
        lines.extend(line.strip() for line in text.splitlines() if line.strip())
    if not lines:
        return type(error).__name__
    return lines[0] if first else lines[-1]


def usd_text(name: str) -> str:
    """``name`` as USD can store it: UTF-8, so a lone surrogate (which no
    parsed file holds, but a Python string can) becomes U+FFFD."""
    return "".join("\ufffd" if 0xD800 <= ord(c) <= 0xDFFF else c for c in name)


def set_custom(prim: Any, name: str, type_name: Any, value: Any) -> None:
    """Author the custom attribute ``shadowgeo:<name>`` on ``prim``."""
    prim.CreateAttribute(PREFIX + name, type_name, custom=True).Set(value)


def custom(prim: Any, name: str, default: Any = None) -> Any:
    """The authored value of ``shadowgeo:<name>`` on ``prim``, else ``default``."""
    attribute = prim.GetAttribute(PREFIX + name)
    if attribute and attribute.HasAuthoredValue():
        return attribute.Get()
    return default


def stored_name(prim: Any, marker: str) -> str | None:
    """The original name: the displayName; for an unnamed shape or light that
    shadowgeo wrote (it has the ``shadowgeo:<marker>`` attribute), None;
    otherwise the prim's name."""
    if prim.GetDisplayName():
        return str(prim.GetDisplayName())
    return None if prim.GetAttribute(PREFIX + marker) else str(prim.GetName())
