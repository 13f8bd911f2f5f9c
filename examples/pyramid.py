"""The X3D pyramid example: a light at (8, 9, 10) above the ground y = 0.

The classic shadow matrix gives the shadow's corners
-7 0 -6.5, -1 0 -6.5, -4 0 -2, -10 0 -12.5; shadowgeo gives the exact region
(the hull of those corners), its area and an X3D Shape to paste into a scene.

Run: python examples/pyramid.py
"""

from __future__ import annotations

import numpy as np

import shadowgeo as sg

vertices = np.array([[-2, 3, -1], [2, 3, -1], [0, 3, 2], [0, 5, 0]], dtype=float)
faces = np.array([[1, 0, 3], [2, 1, 3], [0, 2, 3], [0, 1, 2]])
light = sg.PointLight([8, 9, 10])
ground = sg.Plane([0, 1, 0], 0)

matrix = sg.shadow_matrix(ground, light)
print("shadow matrix, row-vector form (x' = x M^T):")
print(matrix.T)

image = np.column_stack([vertices, np.ones(len(vertices))]) @ matrix.T
print("\nvertex -> shadow point")
for vertex, point in zip(vertices, image[:, :3] / image[:, 3:], strict=True):
    print(f"  {vertex}  ->  {np.round(point, 12) + 0.0}")

shadow = sg.project_shadow((vertices, faces), light, ground, offset=0.001)
print(f"\nshadow region: {len(shadow.polygons)} part(s), area {shadow.area:.6g}")
outline = ground.to_3d(shadow.polygons[0][0])
print("outline:", ", ".join(" ".join(f"{c:g}" for c in p + 0.0) for p in outline))

points = ", ".join(" ".join(f"{c:g}" for c in p) for p in shadow.mesh.vertices)
indices = " ".join(f"{a} {b} {c} -1" for a, b, c in shadow.mesh.faces)
print("\nX3D:")
print(
    f'<Shape DEF="shadow">\n  <IndexedFaceSet coordIndex="{indices}" solid="false">\n'
    f'    <Coordinate point="{points}"/>\n  </IndexedFaceSet>\n'
    '  <Appearance><Material diffuseColor="0 0 0" transparency="0.3"/></Appearance>\n</Shape>'
)
