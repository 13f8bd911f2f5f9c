"""A shadow volume: the closed region a caster hides from a point light.

The volume of a box under a lamp reaches past the ground; where it crosses
the ground it is exactly the planar shadow, which this script checks by
slicing it there.

Run: python examples/shadow_volume.py [picture.png]
(default docs/images/shadow_volume.png)
"""

from __future__ import annotations

import sys
from pathlib import Path

import manifold3d
import numpy as np
import trimesh

import shadowgeo as sg

HERE = Path(__file__).resolve().parent
picture = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs/images/shadow_volume.png"

box = trimesh.creation.box(extents=[1.2, 0.6, 1.2])
box.apply_transform(trimesh.transformations.rotation_matrix(0.6, [0, 1, 0]))
box.apply_translation([0.0, 2.5, 0.0])
light = sg.PointLight([1.2, 5.5, 0.8])
ground = sg.Plane([0, 1, 0], 0)

volume = sg.shadow_volume(box, light, extent=8.0)  # reaches about 2 units below the ground
print(
    f"shadow volume: {len(volume.faces)} triangles, closed: {volume.is_watertight}, "
    f"volume {volume.volume:.4f}"
)

shadow = sg.project_shadow(box, light, ground, offset=0.01)
# Slice the volume at the ground with manifold3d (float32): turned so +y is +z.
turned = volume.vertices @ np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])
solid = manifold3d.Manifold(
    manifold3d.Mesh(
        vert_properties=np.ascontiguousarray(turned, dtype=np.float32),
        tri_verts=np.ascontiguousarray(volume.faces, dtype=np.uint32),
    )
)
sliced = solid.slice(0.0).area()
print(f"volume sliced at the ground: area {sliced:.6f}; planar shadow: {shadow.area:.6f}")

half = 5.0
floor = sg.Shape(
    [[-half, 0, -half], [half, 0, -half], [half, 0, half], [-half, 0, half]],
    [[0, 2, 1], [0, 3, 2]],
    material=sg.Material(diffuse_color=(0.75, 0.75, 0.7)),
)
caster = sg.Shape(box.vertices, box.faces, material=sg.Material((0.85, 0.55, 0.25)))
sg.plot(
    [floor, caster, shadow],
    volumes=[volume],
    screenshot=picture,
    window_size=(640, 480),
    view=(1.0, 0.9, -0.7),
)
print(f"wrote {picture}")
