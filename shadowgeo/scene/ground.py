"""The visible ground shadowgeo adds when the ground plane receives.

When :func:`~shadowgeo.add_shadows` finds no receiver of the scene's own, the
ground plane under the scene's lowest point receives
(:func:`~shadowgeo.scene.receivers.ground`). Its shadows alone would float in
the air, so a ground is drawn under them: a plain light-grey quad (role
``"ground"``, casting and receiving nothing, two-sided) in that plane,
covering the scene's footprint and every shadow on the plane, with a margin of
:data:`MARGIN` of its larger side on each side. Like the shadows, it is
replaced when shadows are added again.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..boxes import bounding_box
from .model import Material, Shape

__all__ = ["MARGIN", "MATERIAL", "visible_ground"]

# A plain light grey, X3D's default material otherwise (no emissive light).
MATERIAL = Material(diffuse_color=(0.7, 0.7, 0.7), name="shadowgeo_ground")
# The quad reaches this fraction of its larger side past what it covers.
MARGIN = 0.1


def visible_ground(points: np.ndarray, height: float, axis: int) -> Shape:
    """A quad at ``height`` along ``axis`` (the up axis: 1 for Y, 2 for Z),
    facing up, covering ``points`` (n, 3) seen from above with a margin
    (role ``"ground"``).

    >>> ground = visible_ground(np.array([[0.0, 5, 0], [10, 7, 4]]), 0.0, 1)
    >>> ground.vertices.min(axis=0).tolist(), ground.vertices.max(axis=0).tolist()
    ([-1.0, 0.0, -1.0], [11.0, 0.0, 5.0])
    """
    across = [k for k in range(3) if k != axis]
    low, high = bounding_box(np.asarray(points, dtype=np.float64))[:, across]
    reach = MARGIN * max(float((high - low).max()), 1e-6)
    low, high = low - reach, high + reach
    corners = np.full((4, 3), float(height))
    corners[:, across] = [low, [high[0], low[1]], high, [low[0], high[1]]]
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    if normal[axis] < 0:
        faces = faces[:, ::-1]
    return Shape(
        corners,
        faces,
        material=dataclasses.replace(MATERIAL),
        solid=False,
        role="ground",
        source="the ground shadowgeo adds under the scene",
        casts_shadow=False,
    )
