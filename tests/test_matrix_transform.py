"""MatrixTransform (Castle Game Engine's and old VRML browsers' node, not X3D)
is written as the Transform of the same matrix: X_ITE and the X3D schema know
no MatrixTransform, so a scene written with it shows nothing under it."""

from __future__ import annotations

import numpy as np
import pytest
from lxml import etree
from x3d_schema import x3d_schema_errors

import shadowgeo as sg

# Rows as X3D writes an SFMatrix4f (the translation in the last row): a shear,
# an uneven scale and a turn, then a translation; determinant -3 (a mirror).
MATRIX = np.array(
    [
        [0.0, 2.0, 0.0, 0.0],
        [1.0, 0.5, 0.0, 0.0],
        [0.0, 0.0, 1.5, 0.0],
        [3.0, -1.0, 2.0, 1.0],
    ]
)


def _scene(path, routed: bool = False):
    matrix = " ".join(map(repr, MATRIX.ravel().tolist()))
    route = (
        '<TimeSensor DEF="clock"/><ROUTE fromNode="clock" fromField="fraction_changed" '
        'toNode="m" toField="set_matrix"/>'
        if routed
        else ""
    )
    path.write_text(
        '<X3D profile="Immersive" version="4.0"><Scene><DirectionalLight direction="0 -1 0"/>'
        f'<MatrixTransform DEF="m" matrix="{matrix}">'
        '<Shape DEF="prism"><IndexedFaceSet coordIndex="0 1 2 -1 0 2 3 -1 0 3 1 -1 1 3 2 -1">'
        '<Coordinate point="0 1 0 1 0 0 0 0 1 -1 0 -1"/></IndexedFaceSet></Shape>'
        f"</MatrixTransform>{route}</Scene></X3D>"
    )
    return path


def _prism(scene: sg.Scene) -> np.ndarray:
    (shape,) = [s for s in scene.shapes if s.name == "prism"]
    return shape.world_vertices


def test_written_as_the_transform_of_the_same_matrix(tmp_path, x3d_schema):
    source = _scene(tmp_path / "in.x3d")
    scene = sg.load(source)
    expected = np.c_[scene.shapes[0].vertices, np.ones(4)] @ MATRIX  # row vectors, as X3D
    np.testing.assert_allclose(_prism(scene), expected[:, :3], atol=1e-12)
    out = tmp_path / "out.x3d"
    result = sg.add_shadows(scene)
    sg.save(result, out)
    tree = etree.parse(str(out))
    assert not tree.xpath("//MatrixTransform")
    (transform,) = tree.xpath("//Transform[@DEF='m']")
    assert transform.get("scale") is not None  # the shear and scale, exactly
    np.testing.assert_allclose(_prism(sg.load(out)), expected[:, :3], atol=1e-12)
    assert any("MatrixTransform" in note for note in result.warnings)
    assert x3d_schema_errors(out, x3d_schema) == []


def test_a_routed_matrix_transform_stays(tmp_path):
    scene = sg.load(_scene(tmp_path / "in.x3d", routed=True))
    out = tmp_path / "out.x3d"
    sg.save(scene, out)
    assert etree.parse(str(out)).xpath("//MatrixTransform[@DEF='m']")


@pytest.mark.parametrize("name", ["x3d/matrix_transform.x3d"])
def test_corpus_matrix_transform_converts_schema_valid(corpus_dir, tmp_path, x3d_schema, name):
    source = corpus_dir / name
    assert x3d_schema_errors(source, x3d_schema)  # the input is not X3D ...
    out = tmp_path / "out.x3d"
    scene = sg.add_shadows(sg.load(source))
    sg.save(scene, out)
    assert x3d_schema_errors(out, x3d_schema) == []  # ... its conversion is
    back = sg.load(out)
    spheres = sorted(
        np.round(s.world_vertices.mean(axis=0), 9).tolist()
        for s in back.shapes
        if s.role == "geometry"
    )
    assert [c[0] for c in spheres] == [0.0, 2.0, 4.0]  # the three spheres where they were
