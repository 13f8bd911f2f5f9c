"""Shadows on every surface: rolling hills, a tower, a ball and a post under a low sun.

shadow_on_surface gives the exact shadow on every face of the terrain: the
objects' shadows drape over the hills, the hills shadow their own valleys, and
the post that stands in the ground casts only from where it comes out of it.

Run: python examples/terrain.py [picture.png]
(default docs/images/terrain.png)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

import shadowgeo as sg

HERE = Path(__file__).resolve().parent
picture = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs/images/terrain.png"

# A 60 x 60 grid of hills (7,200 faces), y up.
cells, half = 60, 6.0
xs = np.linspace(-half, half, cells + 1)
x, z = np.meshgrid(xs, xs, indexing="ij")
y = 0.7 * np.sin(0.9 * x) * np.cos(0.7 * z) + 0.25 * np.sin(2.1 * x + 1.0) * np.sin(1.7 * z)
index = np.arange((cells + 1) ** 2).reshape(cells + 1, cells + 1)
a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
faces = np.concatenate([np.column_stack([a, d, c]), np.column_stack([a, c, b])])
hills = trimesh.Trimesh(np.column_stack([x.ravel(), y.ravel(), z.ravel()]), faces, process=False)

tower = trimesh.creation.box(extents=[1.0, 3.0, 1.0])
tower.apply_translation([-2.0, 1.6, -1.5])
ball = trimesh.creation.icosphere(subdivisions=3, radius=0.8)
ball.apply_translation([1.5, 2.3, 1.0])
post = trimesh.creation.cylinder(radius=0.15, height=4.0, sections=24)
post.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
post.apply_translation([3.0, 0.5, -2.5])  # from y = -1.5, through the ground, to 2.5

sun = sg.DirectionalLight([1.0, -0.45, 0.35])  # about 22 degrees above the horizon
shadow = sg.shadow_on_surface([hills, tower, ball, post], sun, hills, offset=0.005)

lit = hills.face_normals @ -sun.direction > 0
print(f"terrain: {len(hills.faces):,} faces, {int(lit.sum()):,} facing the sun")
print(f"shadow: {shadow.area:.4f} square units on {len(np.unique(shadow.face_index)):,} faces")
print(f"  mean shadowed fraction of the sunlit faces: {shadow.fraction[lit].mean():.3f}")
print(f"  {shadow.diagnostics}")

ground = sg.Shape(hills.vertices, hills.faces, material=sg.Material((0.55, 0.7, 0.45)))
shapes = [
    ground,
    sg.Shape(tower.vertices, tower.faces, material=sg.Material((0.8, 0.55, 0.4))),
    sg.Shape(ball.vertices, ball.faces, material=sg.Material((0.3, 0.5, 0.85))),
    sg.Shape(post.vertices, post.faces, material=sg.Material((0.85, 0.85, 0.8))),
]
sg.plot(
    shapes,
    shadows=shadow.mesh,
    lights=[sun],
    screenshot=picture,
    window_size=(800, 560),
    view=(-0.6, 0.9, 1.0),
)
print(f"wrote {picture}")
