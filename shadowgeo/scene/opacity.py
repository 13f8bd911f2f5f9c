"""How much of a light a shape stops: its casting opacity, in a few levels.

A shape casts as much shadow as it is opaque, as the author set it:

- ``Shape.casts_shadow`` False (X3D 4 ``castShadow="false"``, Castle's
  ``Appearance { shadowCaster FALSE }``, glTF/USD ``castsShadow`` in
  extras/custom data): it casts nothing (it still receives and is drawn);
- else its opacity ``1 - Material.transparency`` (X3D Material
  ``transparency``; glTF ``baseColorFactor`` alpha under ``alphaMode``
  ``BLEND``, MASK and OPAQUE being opaque; USD ``displayOpacity`` or the
  preview surface's ``opacity``), rounded to the nearest multiple of
  :data:`STEP` (1/16; halves up). A shape whose opacity rounds to 0 (below
  1/32) casts nothing and costs no pass.

Rounding keeps the passes few: a scene of many slightly different glass
panes casts one translucent layer per level, at most 16 per light and
receiver, not one per pane. Sun studies weigh translucent casters by the same
rule (:mod:`shadowgeo.opacity`).
"""

from __future__ import annotations

import math

import numpy as np

from ..opacity import LEVELS, STEP
from .model import Shape

__all__ = ["LEVELS", "STEP", "casting_opacity", "opacities"]


def casting_opacity(shape: Shape) -> float:
    """The opacity ``shape`` casts with: 0, or a multiple of :data:`STEP` up
    to 1 (see the module notes).

    Examples
    --------
    >>> from shadowgeo.scene.model import Material
    >>> glass = Shape([[0, 0, 0]], [[0, 0, 0]], material=Material(transparency=0.8))
    >>> casting_opacity(glass)
    0.1875
    >>> casting_opacity(Shape([[0, 0, 0]], [[0, 0, 0]], casts_shadow=False))
    0.0
    """
    if not shape.casts_shadow:
        return 0.0
    opacity = 1.0 - float(shape.material.transparency)
    if not math.isfinite(opacity):
        return 1.0  # (readers keep transparency finite; an unset one is opaque)
    return math.floor(min(max(opacity, 0.0), 1.0) * LEVELS + 0.5) / LEVELS


def opacities(shapes: list[Shape]) -> np.ndarray:
    """(k,) float64 :func:`casting_opacity` of each shape."""
    return np.array([casting_opacity(shape) for shape in shapes], dtype=np.float64)
