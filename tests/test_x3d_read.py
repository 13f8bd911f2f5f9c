"""The X3D reader against hand-derived transforms, analytic areas, XPath counts
and the real files of the shared corpus."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from lxml import etree

import shadowgeo as sg
from shadowgeo.io import x3d_read

DATA = Path(__file__).parent / "data"


def scene_of(tmp_path, body: str, version: str = "4.0", head: str = "", **options):
    path = tmp_path / "scene.x3d"
    path.write_text(
        f'<?xml version="1.0" encoding="UTF-8"?>\n<X3D profile="Interchange" version="{version}">'
        f"<head>{head}</head><Scene>\n{body}\n</Scene></X3D>\n"
    )
    return x3d_read.read(path, **options)


def rotation(axis, angle):
    """Rodrigues' formula, written out independently of the reader."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


TRIANGLE = (
    '<Shape><IndexedFaceSet coordIndex="0 1 2"><Coordinate point="{}"/></IndexedFaceSet></Shape>'
)


# -- the basic scene ---------------------------------------------------------------


def test_basic_scene_shapes_names_and_instances():
    scene = sg.load(DATA / "basic.x3d")
    names = [shape.name for shape in scene.shapes]
    # Crate is used twice: two Shapes; the roof's name comes from its geometry's DEF
    assert names == ["Floor", "Crate", "Crate", "Roof"]
    floor, left, right, roof = scene.shapes
    assert floor.n_faces == 12 and left.n_faces == 12
    assert np.shares_memory(right.vertices, left.vertices)  # one node, two instances
    np.testing.assert_allclose(left.world_vertices.min(axis=0), [-4, 0, -1])
    np.testing.assert_allclose(right.world_vertices.min(axis=0), [1, -1, -2])
    np.testing.assert_allclose(right.world_vertices.max(axis=0), [5, 3, 2])
    assert left.material.diffuse_color == (1.0, 0.0, 0.0)
    assert left.material.transparency == 0.25 and left.material.name == "Red"
    assert roof.material.diffuse_color == (1.0, 0.0, 0.0)  # USE of the Material
    assert roof.solid is False and floor.solid is True
    assert "line" in roof.source and "IndexedFaceSet DEF='Roof'" in roof.source
    assert isinstance(scene.document, etree._ElementTree)
    assert any(isinstance(node, etree._Comment) for node in scene.document.iter())
    assert scene.path == str(DATA / "basic.x3d")


def test_basic_scene_lights_in_world_coordinates():
    scene = sg.load(DATA / "basic.x3d")
    lights = {light.name: light for light in scene.lights}
    assert set(lights) == {"Sun", "Lamp", "Spot"}
    sun, lamp, spot = lights["Sun"], lights["Lamp"], lights["Spot"]
    assert isinstance(sun.light, sg.DirectionalLight)
    np.testing.assert_allclose(sun.light.direction, [0, -1, 0])
    assert sun.shadows is True and sun.shadow_intensity == 0.5
    assert sun.global_ is False  # DirectionalLight's X3D default
    # location (1, 0, 0) rotated 90 degrees about +Z is (0, 1, 0), then lifted by 10
    np.testing.assert_allclose(lamp.light.position, [0, 11, 0], atol=1e-12)
    assert lamp.light.radius == 50 and lamp.intensity == 0.8 and lamp.color == (1, 0.5, 0)
    assert lamp.shadows is False and lamp.global_ is True
    np.testing.assert_allclose(spot.light.position, [0, 10, 0], atol=1e-12)
    np.testing.assert_allclose(spot.light.direction, [0, 1, 0], atol=1e-12)
    assert spot.light.cut_off_angle == 0.5 and spot.beam_width == 0.25
    assert spot.light.radius == 100  # X3D default radius


def test_basic_scene_warnings_name_what_was_skipped():
    scene = sg.load(DATA / "basic.x3d")
    text = "\n".join(scene.warnings)
    assert "Viewpoint" in text and "ROUTE" in text
    assert all("basic.x3d line" in warning for warning in scene.warnings)
    assert "WorldInfo" not in text


# -- transforms, derived by hand ------------------------------------------------------


def test_transform_order_translation_rotation_scale_center(tmp_path):
    # P = (2, 0, 0): -C -> (1, 0, 0); S (2, 1, 1) -> (2, 0, 0); R 90 deg about z -> (0, 2, 0);
    # C -> (1, 2, 0); T -> (2, 4, 3)
    body = (
        '<Transform translation="1 2 3" rotation="0 0 1 1.5707963267948966" scale="2 1 1" '
        'center="1 0 0">' + TRIANGLE.format("2 0 0  0 1 0  0 0 1") + "</Transform>"
    )
    (shape,) = scene_of(tmp_path, body).shapes
    world = shape.world_vertices
    np.testing.assert_allclose(world[0], [2, 4, 3], atol=1e-12)
    # (0, 1, 0): -C (-1, 1, 0); S (-2, 1, 0); R (-1, -2, 0); C (0, -2, 0); T (1, 0, 3)
    np.testing.assert_allclose(world[1], [1, 0, 3], atol=1e-12)


def test_scale_orientation(tmp_path):
    # scaleOrientation turns x onto y: scale (2, 1, 1) then stretches along y only
    body = (
        '<Transform scale="2 1 1" scaleOrientation="0 0 1 1.5707963267948966">'
        + TRIANGLE.format("1 0 0  0 1 0  0 0 1")
        + "</Transform>"
    )
    (shape,) = scene_of(tmp_path, body).shapes
    np.testing.assert_allclose(shape.world_vertices, [[1, 0, 0], [0, 2, 0], [0, 0, 1]], atol=1e-12)


def test_nested_transforms_and_rotation_about_an_oblique_axis(tmp_path):
    axis, angle = np.array([1.0, 2.0, 3.0]), 0.7
    body = (
        '<Transform translation="5 0 0"><Transform rotation="1 2 3 0.7">'
        + TRIANGLE.format("1 0 0  0 1 0  0 0 1")
        + "</Transform></Transform>"
    )
    (shape,) = scene_of(tmp_path, body).shapes
    expected = np.eye(3) @ rotation(axis, angle).T + [5, 0, 0]
    np.testing.assert_allclose(shape.world_vertices, expected, atol=1e-12)


def test_matrix_transform_row_major_translation_in_last_row(tmp_path):
    body = (
        '<MatrixTransform matrix="1 0 0 0  0 1 0 0  0 0 1 0  2 0 0 1">'
        + TRIANGLE.format("0 0 0  1 0 0  0 1 0")
        + "</MatrixTransform>"
    )
    (shape,) = scene_of(tmp_path, body, version="3.0").shapes
    np.testing.assert_allclose(shape.world_vertices[0], [2, 0, 0])


# -- the corpus -----------------------------------------------------------------------


def test_corpus(corpus_dir):
    """Every file reads or fails with a SceneError naming the file; the number of
    rendered Shapes matches an independent count where one is easy."""
    files = sorted(corpus_dir.rglob("*.x3d"))
    assert len(files) >= 20
    for path in files:
        try:
            scene = sg.load(path)
        except sg.SceneError as error:
            assert str(path) in str(error)
            continue
        for shape in scene.shapes:
            assert shape.n_faces > 0
            assert np.all(np.isfinite(shape.world_vertices))
            assert shape.faces.min() >= 0 and shape.faces.max() < len(shape.vertices)
        assert all(isinstance(warning, str) for warning in scene.warnings)


def test_corpus_matrix_transform_spheres(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "matrix_transform.x3d")
    centres = sorted(shape.world_vertices.mean(axis=0)[0] for shape in scene.shapes)
    np.testing.assert_allclose(centres, [0, 2, 4], atol=1e-9)
    (light,) = scene.lights
    np.testing.assert_allclose(light.light.position, [0, 3, 0])


def test_corpus_use_goes_to_its_default_container_field(corpus_dir):
    # the file's comment: browsers (and we) show the yellow sphere and the USEd
    # one at x = 4, not the DEF'd one (it is Collision's proxy)
    scene = sg.load(corpus_dir / "x3d" / "container_field_def_use.x3d")
    centres = sorted(float(shape.world_vertices.mean(axis=0)[0]) for shape in scene.shapes)
    np.testing.assert_allclose(centres, [2, 4], atol=1e-9)


def _expanded_count(document, tags) -> int:
    """Elements with a tag in ``tags`` reached from <Scene>, a USE counting its
    DEF's subtree again: a brute-force count independent of the reader."""
    defs = {element.get("DEF"): element for element in document.xpath("//*[@DEF]")}

    def count(element) -> int:
        if element.get("USE"):
            element = defs[element.get("USE")]
        here = int(element.tag in tags)
        return here + sum(count(child) for child in element if isinstance(child.tag, str))

    return count(document.find("Scene"))


def test_corpus_counts_match_an_independent_count(corpus_dir):
    """Files without Switch, LOD, Collision proxies or unmodelled geometry:
    one Shape per Shape instance, one light per light instance."""
    for name in ["blender/simple/test1.x3d", "navigation/avatar_climb_stairs_geometry.x3d",
                 "lights_materials/light_street_lights_radius.x3d", "x3d/axis.x3d",
                 "x3d/regular_labirynth.x3d", "x3d/axis_simple.x3d"]:  # fmt: skip
        path = corpus_dir / name
        document = etree.parse(str(path), etree.XMLParser(load_dtd=False, no_network=True))
        assert not document.xpath("//Switch | //LOD | //*[@containerField='proxy'] | //Text")
        n_shapes = _expanded_count(document, {"Shape"})
        n_lights = _expanded_count(document, {"PointLight", "SpotLight", "DirectionalLight"})
        scene = sg.load(path)
        assert (len(scene.shapes), len(scene.lights)) == (n_shapes, n_lights), name


def test_corpus_maze_uses_one_shape_many_times(corpus_dir):
    path = corpus_dir / "x3d" / "regular_labirynth.x3d"
    document = etree.parse(str(path), etree.XMLParser(load_dtd=False, no_network=True))
    # one Shape inside a DEF'd Group, which is USEd again and again
    assert len(document.xpath("//Shape")) == 1
    n_uses = len(document.xpath("//Group[@USE='group_ME_Cube']"))
    scene = sg.load(path)
    assert len(scene.shapes) == n_uses + 1 == 720
    first = scene.shapes[0].vertices
    assert all(np.shares_memory(shape.vertices, first) for shape in scene.shapes)
    # the inner Transforms are identities, so the outer translations are the places
    outer = document.xpath("//Transform[not(contains(@DEF, 'ifs'))]/@translation")
    places = {tuple(float(x) for x in text.split()) for text in outer}
    centres = {tuple(np.round(shape.transform[:3, 3], 9)) for shape in scene.shapes}
    assert centres == places


def test_corpus_units(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "units.x3d")
    assert scene.meters_per_unit == 1000
    (cylinder,) = scene.shapes
    # rotation="0.001 0 0 90" in degrees: the cylinder's axis (y) turns onto z
    extent = np.ptp(cylinder.world_vertices, axis=0)
    np.testing.assert_allclose(extent, [0.002, 0.002, 0.002], rtol=1e-3)
    axis = cylinder.transform[:3, :3] @ [0, 1, 0]
    np.testing.assert_allclose(axis, [0, 0, 1], atol=1e-6)
    assert any("units_helper.x3dv" in warning for warning in scene.warnings)


def test_corpus_invalid_unit_warns(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "warnings" / "units_invalid.x3d")
    assert any("unit" in warning and "line 5" in warning for warning in scene.warnings)


def test_corpus_missing_textures_are_named(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "car" / "car.x3d")
    missing = [warning for warning in scene.warnings if "texture not found" in warning]
    assert any("car_wheel.png" in warning for warning in missing)
    assert any("car_shell.png" in warning for warning in missing)
    assert len(scene.shapes) == 3


# keep the imports honest for later tests
_ = (pytest, shapely)
