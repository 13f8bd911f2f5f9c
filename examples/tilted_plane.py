"""A shadow on a tilted plane: a torus above a ramp, lit by a point light.

The shadow matrix handles any plane, not only y = 0; shadowgeo also keeps the
torus's hole and cuts the shadow where the ramp ends.

Run: python examples/tilted_plane.py [picture.png]
(default docs/images/tilted_plane.png)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

import shadowgeo as sg

HERE = Path(__file__).resolve().parent
picture = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs/images/tilted_plane.png"

ramp_plane = sg.Plane([0.3, 1.0, -0.2], 0.0)  # 0.3 x + y - 0.2 z = 0, through the origin
corners = ramp_plane.to_3d([[-4.0, -3.0], [0.0, -3.0], [0.0, 3.0], [-4.0, 3.0]])  # ends at u = 0
ramp = trimesh.Trimesh(corners, [[0, 1, 2], [0, 2, 3]], process=False)

torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3, major_sections=64)
torus.apply_transform(trimesh.transformations.rotation_matrix(0.5, [1, 0, 0]))
torus.apply_translation([0.0, 2.0, 0.0])
light = sg.PointLight([0.8, 6.0, 0.6])

shadow = sg.project_shadow(torus, light, ramp_plane, receiver=corners, offset=0.01)
holes = sum(len(loops) - 1 for loops in shadow.polygons)
print(
    f"shadow on the ramp: {len(shadow.polygons)} part(s), {holes} hole(s), area {shadow.area:.6f}"
)
print(
    f"every shadow vertex on the plane (lifted 0.01): "
    f"{np.allclose(ramp_plane.signed_distance(shadow.mesh.vertices), 0.01)}"
)

ramp_shape = sg.Shape(corners, ramp.faces, material=sg.Material(diffuse_color=(0.75, 0.75, 0.7)))
torus_shape = sg.Shape(torus.vertices, torus.faces, material=sg.Material((0.3, 0.5, 0.85)))
sg.plot(
    [ramp_shape, torus_shape, shadow],
    screenshot=picture,
    window_size=(640, 480),
    view=(-0.2, 1.0, 0.9),
)
print(f"wrote {picture}")
