"""Every file of the shared corpus converts and validates no worse than its
input, or fails with the one clear message we judged right for it.

Every file converts with no flags, as ``shadowgeo convert IN OUT``. A scene
with no light (most of the corpus: test files for containerField, metadata,
prototypes, text) is lit by the default sun, with a note; whether a file
really has no light is checked by looking for light elements in the XML
directly. A scene with no receiver of its own gets the ground plane under its
lowest point, with a note. Files whose reader warnings matter (missing
textures, invalid fields) must still read.
"""

from __future__ import annotations

import re

import numpy as np
from lxml import etree
from x3d_schema import new_schema_errors, x3d_schema_errors

import shadowgeo as sg
from cli.main import main

SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
LIGHTS = ("PointLight", "SpotLight", "DirectionalLight")
NCNAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")


def lights_in_xml(path) -> int:
    root = etree.parse(str(path), SAFE).getroot()
    return sum(len(root.findall(f".//{name}")) for name in LIGHTS)


def convert(capsys, path, out):
    """``shadowgeo convert IN OUT``, no flags, in this process: (notes, result)."""
    code = main(["convert", str(path), str(out)])
    _, err = capsys.readouterr()
    assert code == 0 and "Traceback" not in err, err
    return [line for line in err.splitlines() if line.startswith("note: ")]


def check_shadows(result) -> None:
    for shape in result.shapes_with_role("shadow"):
        points = shape.world_vertices
        assert np.all(np.isfinite(points)) and len(shape.faces)
        if shape.name.endswith("_surfaces"):
            continue  # on every other surface: tests/test_surfaces_baked.py checks those
        # Flat: every planar shadow lies in one plane (its receiver's, lifted).
        centered = points - points.mean(axis=0)
        thickness = np.linalg.svd(centered, compute_uv=False)[-1] if len(points) > 3 else 0.0
        assert thickness <= 1e-9 * max(1.0, float(np.abs(points).max())) * np.sqrt(len(points))
        assert NCNAME.match(shape.name) and NCNAME.match(shape.group)
        assert shape.material.diffuse_color == (0.0, 0.0, 0.0)


def test_every_corpus_file_converts_with_no_flags(corpus_dir, x3d_schema, tmp_path, capsys):
    files = sorted(corpus_dir.rglob("*.x3d"))
    assert len(files) >= 20
    outcomes = {}
    for path in files:
        name = str(path.relative_to(corpus_dir))
        out = tmp_path / (path.stem + ".out.x3d")
        notes = convert(capsys, path, out)
        sunny = any("a default sun casts" in note for note in notes)
        assert sunny == (lights_in_xml(path) == 0), name
        result = sg.load(out)
        assert len(result.lights) == lights_in_xml(path), name  # the sun is not added
        check_shadows(result)
        before = x3d_schema_errors(path, x3d_schema)
        new = new_schema_errors(before, x3d_schema_errors(out, x3d_schema))
        assert new == [], f"{name}: {new[:3]}"
        # Nothing removed: the input's elements plus, per shadow, Shape,
        # Appearance, Material, IndexedTriangleSet and Coordinate, and a Group per light.
        shadows = result.shapes_with_role("shadow")
        original = etree.parse(str(path), SAFE).getroot()
        written = etree.parse(str(out), SAFE).getroot()
        added = 5 * len(shadows) + len({s.group for s in shadows})
        assert len(written.xpath("//*")) == len(original.xpath("//*")) + added, name
        casters = len(result.shapes_with_role("geometry"))
        outcomes[name] = (len(shadows), sunny, any("ground plane" in n for n in notes))
        # Everything with geometry casts (a few files hold only text or metadata).
        assert len(shadows) > 0 or casters == 0, name
    assert len(outcomes) == len(files)
    # Most files are lit by the default sun; the few that have no large flat
    # surface (a lone cube, spheres) receive on the ground under them.
    assert sum(sunny for _, sunny, _ in outcomes.values()) >= 15
    grounded = [name for name, (_, _, ground) in outcomes.items() if ground]
    assert "blender/simple/test1.x3d" in grounded and "x3d/matrix_transform.x3d" in grounded
    assert sum(count > 0 for count, _, _ in outcomes.values()) >= 15, outcomes
