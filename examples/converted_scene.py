"""Convert an X3D scene: read it, bake its lights' shadows in, write X3D, glTF and
USD, and draw the result.

The same as ``shadowgeo convert examples/scenes/courtyard.x3d out.x3d`` (once
per format), written out in Python.

Run: python examples/converted_scene.py [output folder]
(default: the files go to a temporary folder and the picture to
docs/images/converted_scene.png; given a folder, everything goes there)
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import shadowgeo as sg

HERE = Path(__file__).resolve().parent
if len(sys.argv) > 1:
    folder = Path(sys.argv[1])
    picture = folder / "converted_scene.png"
else:
    folder = Path(tempfile.mkdtemp(prefix="shadowgeo-"))
    picture = HERE.parent / "docs" / "images" / "converted_scene.png"
folder.mkdir(parents=True, exist_ok=True)

scene = sg.load(HERE / "scenes" / "courtyard.x3d")
print(f"read {len(scene.shapes)} shapes and {len(scene.lights)} lights")
converted = sg.add_shadows(scene)
for note in converted.warnings:
    print("note:", note)
for shape in converted.shapes_with_role("shadow"):
    print(f"added {shape.name} in group {shape.group}: {shape.n_faces} triangles")

for name in ("courtyard_shadows.x3d", "courtyard_shadows.glb", "courtyard_shadows.usda"):
    sg.save(converted, folder / name)
    print(f"wrote {folder / name}")

# Draw the glTF file read back: the shadows travel with the scene.
written = sg.load(folder / "courtyard_shadows.glb")
sg.plot(written, screenshot=picture, window_size=(640, 480))
print(f"wrote {picture}")
