"""Every file of the shared corpus converts and validates no worse than its
input, or fails with the one clear message we judged right for it.

A scene with no light (most of the corpus: test files for containerField,
metadata, prototypes, text) has nothing to cast a shadow and says so; it then
converts with a sun given as ``shadowgeo convert --sun`` does. Whether a file
really has no light is checked by looking for light elements in the XML
directly. Files whose reader warnings matter (missing textures, invalid
fields) must still read.
"""

from __future__ import annotations

import re

import numpy as np
from lxml import etree
from x3d_schema import new_schema_errors, x3d_schema_errors

import shadowgeo as sg

SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)
LIGHTS = ("PointLight", "SpotLight", "DirectionalLight")
NCNAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")


def lights_in_xml(path) -> int:
    root = etree.parse(str(path), SAFE).getroot()
    return sum(len(root.findall(f".//{name}")) for name in LIGHTS)


SUN = sg.SceneLight(sg.DirectionalLight([0.3, -1.0, 0.2]), name="sun", shadows=True)


def convert(path, extra_lights=()):
    """What ``shadowgeo convert`` does: own lights (or ``--sun``), found
    receivers, else ``--plane 0,1,0,0``."""
    scene = sg.load(path)
    try:
        return sg.add_shadows(scene, extra_lights=extra_lights)
    except sg.SceneError as error:
        if "no receiver found" not in str(error):
            raise
        return sg.add_shadows(scene, plane=(0, 1, 0, 0), extra_lights=extra_lights)


def check_shadows(result) -> None:
    for shape in result.shapes_with_role("shadow"):
        points = shape.world_vertices
        assert np.all(np.isfinite(points)) and len(shape.faces)
        # Flat: every shadow lies in one plane (its receiver's, lifted).
        centered = points - points.mean(axis=0)
        thickness = np.linalg.svd(centered, compute_uv=False)[-1] if len(points) > 3 else 0.0
        assert thickness <= 1e-9 * max(1.0, float(np.abs(points).max())) * np.sqrt(len(points))
        assert NCNAME.match(shape.name) and NCNAME.match(shape.group)
        assert shape.material.diffuse_color == (0.0, 0.0, 0.0)


def test_every_corpus_file_converts_or_fails_clearly(corpus_dir, x3d_schema, tmp_path):
    files = sorted(corpus_dir.rglob("*.x3d"))
    assert len(files) >= 20
    outcomes = {}
    for path in files:
        name = str(path.relative_to(corpus_dir))
        out = tmp_path / (path.stem + ".out.x3d")
        try:
            result = convert(path)
        except (sg.SceneError, sg.GeometryError) as error:
            message = str(error)
            assert "\n" not in message and path.name in message, message
            # Judged right: no light at all in the file; a sun then casts.
            assert "has no lights" in message, f"{name}: {message}"
            assert lights_in_xml(path) == 0, name
            result = convert(path, extra_lights=[SUN])
            assert not result.lights, name  # the sun is not added to the scene
            name += " (--sun)"
        check_shadows(result)
        sg.save(result, out)
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
        outcomes[name] = f"{len(shadows)} shadows"
    # Every file converts, with its own lights where it has them.
    assert len(outcomes) == len(files)
    with_sun = [n for n in outcomes if n.endswith("(--sun)")]
    assert len(with_sun) == sum(lights_in_xml(p) == 0 for p in files)
    # The scenes with lights of their own cast something.
    lit = [n for n in outcomes if n not in with_sun]
    assert all(outcomes[n] != "0 shadows" for n in lit), outcomes
