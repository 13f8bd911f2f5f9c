"""The X3D reader against hand-derived transforms, analytic areas, XPath counts
and the real files of the shared corpus."""

from __future__ import annotations

import base64
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from lxml import etree

import shadowgeo as sg
from shadowgeo.io.x3d import extrusion as x3d_extrusion
from shadowgeo.io.x3d import read as x3d_read
from shadowgeo.io.x3d.tables import DEFAULTS

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
    # the document is the file as parsed, untouched
    fresh = etree.parse(str(DATA / "basic.x3d"), etree.XMLParser(load_dtd=False, no_network=True))
    assert etree.tostring(scene.document) == etree.tostring(fresh)
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
    assert "ROUTE" in text and "Viewpoint" not in text  # read, not skipped
    assert [view.position for view in scene.viewpoints] == [(0, 5, 20)]
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


def test_a_translation_alone_gives_the_numbers_of_the_whole_transform(tmp_path):
    # A Transform with only a translation takes a short way: the same bits as
    # the same Transform with every other field written out at its default.
    points = "0.1 0.2 0.3  1e-3 7 -2  3.3 0 1e5"
    short = '<Transform translation="0.7 -1.3 2.9">' + TRIANGLE.format(points) + "</Transform>"
    whole = (
        '<Transform translation="0.7 -1.3 2.9" rotation="0 0 1 0" scale="1 1 1" '
        'scaleOrientation="0 0 1 0" center="0 0 0">' + TRIANGLE.format(points) + "</Transform>"
    )
    (one,) = scene_of(tmp_path, short).shapes
    (other,) = scene_of(tmp_path, whole).shapes
    assert np.array_equal(one.world_vertices, other.world_vertices)
    assert np.array_equal(one.world_vertices[1], np.array([1e-3, 7, -2]) + [0.7, -1.3, 2.9])


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


# -- geometry nodes -------------------------------------------------------------------

STAR = [(0, 0), (4, 0), (4, 3), (2, 1), (0, 3), (-1, 2)]  # concave at (2, 1)


def shoelace(points) -> float:
    x, y = np.asarray(points, float).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def plane_frame():
    """An oblique plane: origin and two orthonormal in-plane axes."""
    u = np.array([1.0, 2.0, 2.0]) / 3.0
    v = np.cross(u, [0.0, 0.0, 1.0])
    v /= np.linalg.norm(v)
    return np.array([3.0, -1.0, 2.0]), u, v


def test_concave_polygon_triangulated_in_its_own_plane(tmp_path):
    origin, u, v = plane_frame()
    points = [origin + x * u + y * v for x, y in STAR]
    index = " ".join(str(i) for i in range(len(STAR)))
    body = (
        f'<Shape><IndexedFaceSet convex="false" coordIndex="{index} -1">'
        f'<Coordinate point="{" ".join(repr(float(c)) for p in points for c in p)}"/>'
        "</IndexedFaceSet></Shape>"
    )
    (shape,) = scene_of(tmp_path, body).shapes
    assert shape.n_faces == len(STAR) - 2
    corners = shape.vertices[shape.faces]
    flat = np.stack([(corners - origin) @ u, (corners - origin) @ v], axis=-1)
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    # every triangle is wound like the polygon (counter-clockwise in (u, v))
    assert np.all(normals @ np.cross(u, v) > 0)
    areas = [shoelace(triangle) for triangle in flat]
    assert sum(areas) == pytest.approx(shoelace(STAR), rel=1e-12)
    polygon = shapely.Polygon(STAR)
    union = shapely.union_all([shapely.Polygon(triangle) for triangle in flat])
    assert union.symmetric_difference(polygon).area < 1e-9
    for triangle in flat:
        assert polygon.buffer(1e-9).contains(shapely.Polygon(triangle))


@settings(max_examples=40, deadline=None)
@given(
    gaps=st.lists(st.floats(0.4, 1.0), min_size=4, max_size=14),
    radii=st.lists(st.floats(0.2, 1.0), min_size=14, max_size=14),
    tilt=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.1, 1)),
)
def test_random_star_polygons_triangulate_exactly(tmp_path_factory, gaps, radii, tilt):
    """Star-shaped (hence simple) polygons, concave or not, on random planes."""
    # angular gaps all below pi (0.4 * 3 > 1): the origin is inside, the polygon
    # is star-shaped about it and runs counter-clockwise
    angles = 2 * math.pi * np.cumsum(gaps) / np.sum(gaps)
    flat = np.column_stack([np.cos(angles), np.sin(angles)]) * np.array(radii[: len(gaps)])[:, None]
    normal = np.array(tilt) / np.linalg.norm(tilt)
    u = np.cross(normal, [0.0, 1.0, 0.0] if abs(normal[1]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    points = flat[:, :1] * u + flat[:, 1:] * v + [1.0, 2.0, 3.0]
    index = " ".join(map(str, range(len(points))))
    body = (
        f'<Shape><IndexedFaceSet convex="false" coordIndex="{index}">'
        f'<Coordinate point="{" ".join(repr(float(c)) for c in points.ravel())}"/>'
        "</IndexedFaceSet></Shape>"
    )
    (shape,) = scene_of(tmp_path_factory.mktemp("star"), body).shapes
    corners = shape.vertices[shape.faces] - [1.0, 2.0, 3.0]
    in_plane = np.stack([corners @ u, corners @ v], axis=-1)
    areas = np.array([shoelace(triangle) for triangle in in_plane])
    assert len(areas) == len(points) - 2
    assert np.all(areas > -1e-12)  # all wound like the polygon
    assert areas.sum() == pytest.approx(shoelace(flat), rel=1e-9)
    polygon = shapely.Polygon(flat)
    for triangle in in_plane:
        assert polygon.buffer(1e-9).contains(shapely.Polygon(triangle))


def test_convex_polygons_are_fanned_and_ccw_false_is_flipped(tmp_path):
    square = '<Coordinate point="0 0 0  1 0 0  1 0 -1  0 0 -1"/>'
    body = (
        f'<Shape><IndexedFaceSet coordIndex="0 1 2 3">{square}</IndexedFaceSet></Shape>'
        f'<Shape><IndexedFaceSet ccw="false" coordIndex="0 1 2 3">{square}</IndexedFaceSet></Shape>'
    )
    upward, downward = scene_of(tmp_path, body).shapes
    for shape, sign in [(upward, 1), (downward, -1)]:
        corners = shape.vertices[shape.faces]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        # (1, 0, 0) x (1, 0, -1) = (0, 1, 0): the square as written faces +y
        np.testing.assert_allclose(normals / np.linalg.norm(normals, axis=1)[:, None],
                                   [[0, sign, 0]] * 2, atol=1e-15)  # fmt: skip
        assert 0.5 * np.linalg.norm(normals, axis=1).sum() == pytest.approx(1.0)


def _area(shape) -> float:
    corners = shape.world_vertices[shape.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return 0.5 * float(np.linalg.norm(normals, axis=1).sum())


def test_triangle_and_quad_sets(tmp_path):
    quad = "0 0 0  2 0 0  2 3 0  0 3 0"
    body = (
        f'<Shape><IndexedTriangleSet index="0 1 2 0 2 3"><Coordinate point="{quad}"/>'
        "</IndexedTriangleSet></Shape>"
        '<Shape><TriangleSet><Coordinate point="0 0 0 1 0 0 0 1 0  5 5 5 6 5 5 5 7 5"/>'
        "</TriangleSet></Shape>"
        f'<Shape><IndexedQuadSet index="0 1 2 3"><Coordinate point="{quad}"/></IndexedQuadSet>'
        "</Shape>"
        f'<Shape><QuadSet><CoordinateDouble point="{quad}"/></QuadSet></Shape>'
        f'<Shape><IndexedTriangleFanSet index="0 1 2 3 -1"><Coordinate point="{quad}"/>'
        "</IndexedTriangleFanSet></Shape>"
        f'<Shape><TriangleStripSet stripCount="4"><Coordinate point="0 0 0 2 0 0 0 3 0 2 3 0"/>'
        "</TriangleStripSet></Shape>"
    )
    shapes = scene_of(tmp_path, body).shapes
    assert [s.n_faces for s in shapes] == [2, 2, 2, 2, 2, 2]
    assert [_area(s) for s in shapes] == pytest.approx([6, 0.5 + 1.0, 6, 6, 6, 6])
    for shape in shapes:  # all written counter-clockwise seen from +z
        corners = shape.vertices[shape.faces]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert np.all(normals[:, 2] > 0)


def test_elevation_grid(tmp_path):
    heights = [0, 1, 2, 3, 4, 5]  # xDimension 3, zDimension 2: height[i + j * 3]
    body = (
        '<Shape><ElevationGrid xDimension="3" zDimension="2" xSpacing="2" zSpacing="5" '
        f'height="{" ".join(map(str, heights))}"/></Shape>'
    )
    (grid,) = scene_of(tmp_path, body).shapes
    assert grid.n_faces == 2 * 2 * 1
    expected = {(2.0 * i, float(heights[i + 3 * j]), 5.0 * j) for j in range(2) for i in range(3)}
    assert {tuple(v) for v in grid.vertices.tolist()} == expected
    corners = grid.vertices[grid.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(normals[:, 1] > 0)  # ccw: the surface faces up
    flat = scene_of(tmp_path, body.replace(" ".join(map(str, heights)), "0 0 0 0 0 0")).shapes[0]
    assert _area(flat) == pytest.approx(4 * 5)


def _extrusion(tmp_path, attributes: str) -> trimesh.Trimesh:
    (shape,) = scene_of(tmp_path, f"<Shape><Extrusion {attributes}/></Shape>").shapes
    mesh = trimesh.Trimesh(shape.vertices, shape.faces)  # merges the seam's duplicates
    assert mesh.is_watertight and mesh.is_winding_consistent
    return mesh


def test_extrusion_default_is_the_unit_box(tmp_path):
    box = _extrusion(tmp_path, "")
    np.testing.assert_allclose(box.bounds, [[-1, 0, -1], [1, 1, 1]])
    assert box.volume == pytest.approx(4.0)  # positive: faces point outwards


@pytest.mark.parametrize(
    "attributes, volume",
    [
        ('spine="0 0 0 1 1 1"', 4 * math.sqrt(3)),  # a straight spine, any direction
        ('spine="0 0 0 0 0 -3"', 12.0),
        ('scale="1 1 0.5 0.5"', (4 + 1 + 2) / 3),  # frustum: h (A1 + A2 + sqrt(A1 A2)) / 3
        ('scale="2 1" orientation="0 1 0 0.5"', 8.0),  # one value for every spine point
        # concave caps; written clockwise in (x, z), like the default square
        ('crossSection="0 0 0 1 1 0.5 2 1 2 0 0 0" convex="false"', 2 - 0.5),
    ],
)
def test_extrusion_volumes(tmp_path, attributes, volume):
    assert _extrusion(tmp_path, attributes).volume == pytest.approx(volume, rel=1e-12)


def test_extrusion_written_the_other_way_round_faces_inwards(tmp_path):
    # X3D's ccw is about the order as written: the reversed square gives inward faces
    box = _extrusion(tmp_path, 'crossSection="1 1 -1 1 -1 -1 1 -1 1 1"')
    assert box.volume == pytest.approx(-4.0)
    assert _extrusion(tmp_path, 'crossSection="1 1 -1 1 -1 -1 1 -1 1 1" ccw="false"').volume > 0


def test_extrusion_frames_at_a_bend_by_hand():
    # at the corner of (0,0,0) -> (0,1,0) -> (1,1,0): Y = (1, 1, 0) / sqrt 2,
    # Z = (s2 - s1) x (s0 - s1) = (1, 0, 0) x (0, -1, 0) = (0, 0, -1), X = Y x Z
    spine = np.array([[0.0, 0, 0], [0, 1, 0], [1, 1, 0]])
    axes = x3d_extrusion.frames(spine)
    root = math.sqrt(0.5)
    np.testing.assert_allclose(axes[1], np.column_stack([[-root, root, 0], [root, root, 0],
                                                         [0, 0, -1]]), atol=1e-15)  # fmt: skip
    # the ends: Y along their segment, Z borrowed from the corner
    np.testing.assert_allclose(axes[0][:, 1], [0, 1, 0])
    np.testing.assert_allclose(axes[2][:, 1], [1, 0, 0])
    np.testing.assert_allclose(axes[0][:, 2], [0, 0, -1])
    np.testing.assert_allclose(axes[2][:, 2], [0, 0, -1])


def test_extrusion_along_a_closed_circle_obeys_pappus(tmp_path):
    # a square of side 0.2 swept round a circle of radius 2: V = 2 pi R A (Pappus)
    angles = np.linspace(0, 2 * math.pi, 257)
    spine = np.column_stack([2 * np.cos(angles), np.zeros_like(angles), 2 * np.sin(angles)])
    spine[-1] = spine[0]
    text = " ".join(f"{c!r}" for c in spine.ravel().tolist())
    section = "0.1 0.1 0.1 -0.1 -0.1 -0.1 -0.1 0.1 0.1 0.1"
    ring = _extrusion(tmp_path, f'spine="{text}" crossSection="{section}"')
    assert abs(ring.volume) == pytest.approx(2 * math.pi * 2 * 0.04, rel=1e-3)


# -- grouping nodes ---------------------------------------------------------------------


def _x_positions(scene):
    return sorted(round(float(s.world_vertices.mean(axis=0)[0]), 9) for s in scene.shapes)


def place(x):
    return f'<Transform translation="{x} 0 0"><Shape><Box/></Shape></Transform>'


def test_switch_lod_collision_anchor_billboard(tmp_path):
    body = (
        f'<Switch whichChoice="1">{place(1)}{place(2)}{place(3)}</Switch>'
        f"<Switch>{place(4)}</Switch>"
        f'<Switch whichChoice="7">{place(5)}</Switch>'
        f'<LOD range="10">{place(6)}{place(7)}</LOD>'
        f'<Collision><Shape containerField="proxy"><Box/></Shape>{place(8)}</Collision>'
        f"<Anchor url='\"http://example.com\"'>{place(9)}</Anchor>"
        f"<Billboard>{place(10)}</Billboard><StaticGroup>{place(11)}</StaticGroup>"
    )
    scene = scene_of(tmp_path, body)
    assert _x_positions(scene) == [2, 6, 8, 9, 10, 11]
    text = "\n".join(scene.warnings)
    assert "LOD: level 0 of 2 used" in text and "Billboard" in text


def test_names_come_from_shape_geometry_or_ancestor(tmp_path):
    body = (
        '<Transform DEF="Outer"><Group DEF="Inner"><Shape><Box/></Shape></Group>'
        '<Shape><Box DEF="TheBox"/></Shape><Shape DEF="TheShape"><Box DEF="Ignored"/></Shape>'
        "</Transform><Shape><Sphere/></Shape>"
    )
    names = [shape.name for shape in scene_of(tmp_path, body).shapes]
    assert names == ["Inner", "TheBox", "TheShape", None]


def test_materials(tmp_path):
    body = (
        '<Shape><Appearance><PhysicalMaterial baseColor="0 1 0" transparency="0.5"/></Appearance>'
        "<Box/></Shape>"
        '<Shape><Appearance><UnlitMaterial emissiveColor="0 0 1"/></Appearance><Box/></Shape>'
        "<Shape><Box/></Shape>"
        '<Shape><Appearance><Material emissiveColor="1 0 0" specularColor="0.5 0.5 0.5" '
        'shininess="0.7"/></Appearance><Box/></Shape>'
    )
    body += (
        '<Shape><Appearance><Material containerField="backMaterial" diffuseColor="1 0 0"/>'
        '<Material diffuseColor="0 1 0"/></Appearance><Box/></Shape>'
    )
    physical, unlit, bare, classic, two_sided = (
        s.material for s in scene_of(tmp_path, body).shapes
    )
    assert two_sided.diffuse_color == (0, 1, 0)  # the front, not the backMaterial
    assert physical.diffuse_color == (0, 1, 0) and physical.transparency == 0.5
    assert unlit.emissive_color == (0, 0, 1)
    # X3D: a Shape without a Material is unlit white
    assert bare.emissive_color == (1, 1, 1) and bare.diffuse_color == (0, 0, 0)
    assert classic.diffuse_color == (0.8, 0.8, 0.8)  # the X3D default
    assert classic.emissive_color == (1, 0, 0) and classic.specular_color == (0.5, 0.5, 0.5)
    assert classic.shininess == 0.7


def test_materials_written_alike_are_read_alike_and_each_bad_one_is_named(tmp_path):
    good = '<Material diffuseColor="0.1 0.2 0.3" transparency="0.25"/>'
    bad = '<Material diffuseColor="0.1 zero 0.3"/>'
    body = "\n".join(
        f"<Shape><Appearance>{material}</Appearance><Box/></Shape>"
        for material in (good, good, bad, bad, '<Material diffuseColor="0.3 0.2 0.1"/>')
    )
    scene = scene_of(tmp_path, body)
    first, second, third, fourth, other = (s.material for s in scene.shapes)
    assert first.diffuse_color == second.diffuse_color == (0.1, 0.2, 0.3)
    assert first.transparency == second.transparency == 0.25
    assert third.diffuse_color == fourth.diffuse_color == (0.8, 0.8, 0.8)  # the default
    assert other.diffuse_color == (0.3, 0.2, 0.1)
    named = [w for w in scene.warnings if "diffuseColor" in w]
    assert len(named) == 2 and named[0] != named[1]  # one per element, by its line


# -- prototypes -------------------------------------------------------------------------

PROTOS = """
<ProtoDeclare name="Post">
  <ProtoInterface>
    <field name="height" type="SFFloat" accessType="initializeOnly" value="2"/>
    <field name="where" type="SFVec3f" accessType="initializeOnly" value="0 0 0"/>
    <field name="look" type="SFNode" accessType="initializeOnly"/>
  </ProtoInterface>
  <ProtoBody>
    <Transform DEF="Base"><IS><connect nodeField="translation" protoField="where"/></IS>
      <Shape DEF="Pole"><IS><connect nodeField="appearance" protoField="look"/></IS>
        <Cylinder radius="0.5"><IS><connect nodeField="height" protoField="height"/></IS></Cylinder>
      </Shape>
      <Transform translation="0 3 0"><Shape USE="Pole"/></Transform>
    </Transform>
    <TimeSensor/>
  </ProtoBody>
</ProtoDeclare>
<ProtoDeclare name="Loop"><ProtoBody><Group><ProtoInstance name="Loop"/></Group></ProtoBody>
</ProtoDeclare>
<ExternProtoDeclare name="Far" url='"http://example.com/far.x3d#Far"'/>
"""


def test_prototype_instances_are_copies_of_their_body(tmp_path):
    body = PROTOS + (
        '<ProtoInstance DEF="First" name="Post"><fieldValue name="where" value="5 0 0"/>'
        '<fieldValue name="height" value="4"/><fieldValue name="look">'
        '<Appearance><Material diffuseColor="0 0 1"/></Appearance></fieldValue></ProtoInstance>'
        '<ProtoInstance name="Post"/><ProtoInstance name="Far"/>'
    )
    scene = scene_of(tmp_path, body)
    assert [shape.name for shape in scene.shapes] == ["Pole"] * 4
    first, first_top, second, second_top = scene.shapes
    # the instance's values: at x = 5, height 4, blue; the defaults: at 0, height 2, unlit
    assert np.ptp(first.world_vertices[:, 1]) == pytest.approx(4)
    np.testing.assert_allclose(first.transform[:3, 3], [5, 0, 0])
    np.testing.assert_allclose(first_top.transform[:3, 3], [5, 3, 0])
    assert first.material.diffuse_color == (0, 0, 1)
    assert np.ptp(second.world_vertices[:, 1]) == pytest.approx(2)
    np.testing.assert_allclose(second_top.transform[:3, 3], [0, 3, 0])
    assert second.material.emissive_color == (1, 1, 1)
    (warning,) = [w for w in scene.warnings if "ProtoInstance" in w]
    assert "ProtoInstance name='Far' skipped" in warning
    # the document is untouched: the body still holds its IS elements
    assert len(scene.document.xpath("//IS")) == 3


def test_prototype_inside_itself_is_refused(tmp_path):
    with pytest.raises(sg.SceneError, match="prototype 'Loop' is used inside its own body"):
        scene_of(tmp_path, PROTOS + '<ProtoInstance name="Loop"/>')


def test_def_given_again_in_a_prototype_and_in_the_scene(tmp_path):
    body = (
        '<ProtoDeclare name="Pair"><ProtoBody><Group>'
        '<Transform DEF="A" translation="1 0 0"><Shape><Box/></Shape></Transform>'
        '<Transform DEF="A" translation="2 0 0"><Shape><Box/></Shape></Transform>'
        '<Transform USE="A"/></Group></ProtoBody></ProtoDeclare>'
        '<Transform DEF="B"><Shape><Box/></Shape></Transform>'
        '<Transform DEF="B" translation="9 0 0"/><Transform USE="B"/><ProtoInstance name="Pair"/>'
    )
    # each tree (the document, the prototype's copy) is ordered on its own
    centres = [shape.world_vertices.mean(axis=0)[0] for shape in scene_of(tmp_path, body).shapes]
    assert centres == pytest.approx([0, 1, 2, 2])  # the USE takes the later DEF


def test_each_use_of_a_name_defined_many_times_takes_the_latest_def_before_it(tmp_path):
    # 300 DEFs of one name, each followed by a USE (moved up by 10), and
    # USEs before the first DEF and after the last: each USE takes the
    # latest DEF before it, one before any takes the first.
    count = 300
    body = '<Transform translation="0 10 0"><Transform USE="a"/></Transform>' + "".join(
        f'<Transform DEF="a" translation="{k} 0 0"><Shape><Box/></Shape></Transform>'
        f'<Transform translation="0 10 0"><Transform USE="a"/></Transform>'
        for k in range(count)
    )
    scene = scene_of(tmp_path, body)
    centres = np.array([shape.world_vertices.mean(axis=0) for shape in scene.shapes])
    used = centres[centres[:, 1] > 5]
    assert used[:, 0].tolist() == pytest.approx([0.0, *range(count)])
    assert centres[centres[:, 1] < 5][:, 0].tolist() == pytest.approx(list(range(count)))


def test_corpus_prototype_of_a_material(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "proto_of_material.x3d")
    (shape,) = scene.shapes
    assert shape.material.diffuse_color == (1, 0, 0)  # the instance's fieldValue
    assert shape.n_faces == 12 and not scene.warnings


# -- lights -----------------------------------------------------------------------------


def test_spot_light_defaults_follow_the_file_version(tmp_path):
    (x3d4,) = scene_of(tmp_path, "<SpotLight/>").lights
    (x3d3,) = scene_of(tmp_path, "<SpotLight/>", version="3.3").lights
    # X3D 4.0: beamWidth 3 pi / 16, cutOffAngle pi / 2; X3D 3.3: pi / 2 and pi / 4
    assert x3d4.beam_width == pytest.approx(3 * math.pi / 16, abs=1e-6)
    assert x3d4.light.cut_off_angle == pytest.approx(math.pi / 2, abs=1e-6)
    assert x3d3.beam_width == pytest.approx(math.pi / 2, abs=1e-6)
    assert x3d3.light.cut_off_angle == pytest.approx(math.pi / 4, abs=1e-6)
    for light in (x3d4, x3d3):
        np.testing.assert_array_equal(light.light.position, [0, 0, 0])
        np.testing.assert_array_equal(light.light.direction, [0, 0, -1])
        assert light.light.radius == 100 and light.attenuation == (1, 0, 0)
        assert light.on and light.global_ and not light.shadows and light.shadow_intensity == 1


def test_light_fields_and_scaled_radius(tmp_path):
    body = (
        '<Transform scale="2 2 2" translation="0 1 0"><PointLight location="1 1 1" radius="5" '
        'on="false" global="false" attenuation="0 1 0" ambientIntensity="0.3" shadows="true"/>'
        '</Transform><DirectionalLight/><Transform rotation="1 0 0 1.5707963267948966">'
        '<DirectionalLight direction="0 0 -2"/></Transform>'
    )
    point, default, turned = scene_of(tmp_path, body).lights
    np.testing.assert_allclose(point.light.position, [2, 3, 2])
    assert (
        point.light.radius == pytest.approx(10)
        and not point.on
        and not point.global_
        and point.shadows
    )
    assert point.attenuation == (0, 1, 0) and point.ambient_intensity == 0.3
    np.testing.assert_allclose(default.light.direction, [0, 0, -1])
    # (0, 0, -1) turned 90 degrees about +x is (0, 1, 0)
    np.testing.assert_allclose(turned.light.direction, [0, 1, 0], atol=1e-15)


def test_lights_that_light_nothing_warn(tmp_path):
    scene = scene_of(tmp_path, '<PointLight radius="0"/><SpotLight cutOffAngle="2"/>')
    assert len(scene.lights) == 1 and scene.lights[0].light.cut_off_angle == math.pi / 2
    text = "\n".join(scene.warnings)
    assert "line 3, PointLight: radius 0.0 lights nothing; skipped" in text
    assert "cutOffAngle 2.0 > pi/2 taken as pi/2" in text


# -- Inline -----------------------------------------------------------------------------


def test_inline_x3d_and_gltf(tmp_path):
    parts = tmp_path / "parts"
    parts.mkdir()
    (parts / "crate.x3d").write_text(
        '<X3D version="4.0"><Scene><Transform DEF="Lid" translation="0 1 0">'
        '<Shape><Box size="2 2 2"/></Shape></Transform><PointLight DEF="Inside"/></Scene></X3D>'
    )
    box = trimesh.creation.box(extents=[1, 1, 1])
    trimesh.Scene({"cube": box}).export(parts / "cube.glb")
    body = (
        '<Transform DEF="Here" translation="10 0 0"><Inline url=\'"parts/crate.x3d"\'/></Transform>'
        '<Transform translation="0 0 -5"><Inline DEF="Glb" url=\'"missing.glb" "parts/cube.glb"\'/>'
        "</Transform>"
    )
    scene = scene_of(tmp_path, body)
    crate, cube = scene.shapes
    assert crate.name == "Lid"
    np.testing.assert_allclose(crate.world_vertices.min(axis=0), [9, 0, -1])
    np.testing.assert_allclose(cube.world_vertices.mean(axis=0), [0, 0, -5], atol=1e-12)
    assert cube.n_faces == 12
    assert trimesh.Trimesh(cube.world_vertices, cube.faces).volume == pytest.approx(1.0)
    (light,) = scene.lights
    assert light.name == "Inside"
    np.testing.assert_allclose(light.light.position, [10, 0, 0])
    assert not scene.warnings


def _triangle_gltf(**material) -> dict:
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype="<f4").tobytes()
    return {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(positions).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "nodes": [{"mesh": 0, "name": "leaf"}],
        "scenes": [{"nodes": [0]}],
    }  # fmt: skip


def test_inlined_gltf_is_read_by_the_gltf_reader(tmp_path):
    colour = {"baseColorFactor": [0.25, 0.5, 0.75, 1.0]}
    leaf = _triangle_gltf(pbrMetallicRoughness=colour, doubleSided=True)
    (tmp_path / "leaf.gltf").write_text(json.dumps(leaf))
    (shape,) = scene_of(tmp_path, "<Inline url='\"leaf.gltf\"'/>").shapes
    assert shape.name == "leaf"
    assert shape.material.diffuse_color == (0.25, 0.5, 0.75)  # not rounded to 8 bits
    assert shape.solid is False  # doubleSided
    packed = _triangle_gltf()
    packed["extensionsUsed"] = packed["extensionsRequired"] = ["EXT_meshopt_compression"]
    (tmp_path / "packed.gltf").write_text(json.dumps(packed))
    # A glTF the reader cannot read is skipped, naming it; the next url is tried.
    loaded = scene_of(tmp_path, '<Inline url=\'"packed.gltf" "leaf.gltf"\'/>')
    assert [shape.name for shape in loaded.shapes] == ["leaf"]
    loaded = scene_of(tmp_path, "<Inline url='\"packed.gltf\"'/>")
    assert loaded.shapes == []
    (warning,) = [w for w in loaded.warnings if "Inline skipped" in w]
    assert re.search(r"line \d+, Inline: Inline skipped: 'packed\.gltf' cannot be read: ", warning)
    assert "EXT_meshopt_compression" in warning


def test_an_inline_used_again_is_read_once(tmp_path):
    (tmp_path / "leaf.gltf").write_text(json.dumps(_triangle_gltf()))
    (tmp_path / "post.x3d").write_text(
        '<X3D version="4.0"><Scene><Shape><TriangleSet><Coordinate point="0 0 0 1 0 0 0 1 0"/>'
        "</TriangleSet></Shape></Scene></X3D>"
    )
    body = (
        "<Inline DEF='leaf' url='\"leaf.gltf\"'/><Inline USE='leaf'/>"
        "<Inline DEF='post' url='\"post.x3d\"'/><Inline USE='post'/>"
    )
    leaf, leaf_again, post, post_again = scene_of(tmp_path, body).shapes
    assert np.shares_memory(leaf.vertices, leaf_again.vertices)  # one read, one mesh
    assert np.shares_memory(post.vertices, post_again.vertices)


# -- the defaults table ------------------------------------------------------------------


def test_the_table_is_what_the_schemas_say(x3d_schema, shared_dir):
    """The committed table is what tools/x3d_tables.py makes of the two schemas."""
    import importlib.util

    from shadowgeo.io.x3d import tables

    spec = importlib.util.spec_from_file_location(
        "x3d_tables_tool", Path(__file__).parents[1] / "tools" / "x3d_tables.py"
    )
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    json_schema = shared_dir / "schemas" / "x3d" / "x3d-4.0-JSONSchema.json"
    nodes, values, common = tool.tables(x3d_schema, json_schema)
    assert {node: (entry[0], entry[1]) for node, entry in tables.FIELDS.items()} == nodes
    assert tables.DEFAULT_VALUES == values and tables.FIELD_TYPES == common
    assert {node: fields for node, fields in DEFAULTS.items()} == {
        node: {field: (nodes[node][1][field], value) for field, value in fields.items()}
        for node, fields in values.items()
    }


@pytest.mark.parametrize(
    "node, field, kind",
    [  # types printed in ISO/IEC 19775-1 (X3D 4.0) node definitions
        ("Transform", "rotation", "SFRotation"), ("IndexedFaceSet", "coordIndex", "MFInt32"),
        ("Tangent", "vector", "MFVec4f"), ("Shape", "castShadow", "SFBool"),
        ("Shape", "-geometry", "SFNode"), ("Group", "-children", "MFNode"),
        ("ExternProtoDeclare", "url", "MFString"), ("unit", "conversionFactor", "SFDouble"),
    ],
)  # fmt: skip
def test_field_types_match_the_specification(node, field, kind):
    from shadowgeo.io.x3d.tables import FIELDS, field_type

    assert FIELDS[node][1][field] == kind
    if not field.startswith("-"):
        assert field_type(node, field) == kind


@pytest.mark.parametrize(
    "node, container",
    [("Box", "geometry"), ("Material", "material"), ("Coordinate", "coord"),
     ("VariationPhysicsModel", "physics"), ("Transform", None), ("Appearance", "appearance")],
)  # fmt: skip
def test_one_default_container_field_for_every_encoding(node, container):
    """ClassicVRML and JSON read a node's default containerField from one
    table (X3D 4.0's, inherited from the node's abstract type)."""
    from shadowgeo.io.x3d import classic_read, classic_write, json, tables

    assert tables.CONTAINER_FIELDS.get(node) == container
    for module in (classic_read, classic_write):
        assert module.CONTAINER_FIELDS is tables.CONTAINER_FIELDS
    assert json.FIELDS[node][0] == (container or "children")


@pytest.mark.parametrize(
    "node, field, value",
    [  # values printed in ISO/IEC 19775-1 (X3D 4.0) field tables
        ("Transform", "scale", "1 1 1"), ("Transform", "rotation", "0 0 1 0"),
        ("Box", "size", "2 2 2"), ("Sphere", "radius", "1"), ("Cone", "bottomRadius", "1"),
        ("Cone", "height", "2"), ("Cylinder", "radius", "1"), ("IndexedFaceSet", "ccw", "true"),
        ("IndexedFaceSet", "convex", "true"), ("ElevationGrid", "xSpacing", "1.0"),
        ("Material", "diffuseColor", "0.8 0.8 0.8"), ("Material", "shininess", "0.2"),
        ("PointLight", "radius", "100"), ("PointLight", "attenuation", "1 0 0"),
        ("DirectionalLight", "direction", "0 0 -1"), ("SpotLight", "cutOffAngle", "1.570796"),
        ("SpotLight", "beamWidth", "0.589049"), ("SpotLight", "shadows", "false"),
        ("Switch", "whichChoice", "-1"), ("DirectionalLight", "global", "false"),
    ],
)  # fmt: skip
def test_defaults_match_the_specification(node, field, value):
    assert DEFAULTS[node][field][1] == value


# -- the corpus -----------------------------------------------------------------------


# Corpus files with no geometry the reader models: HAnim motion, metadata, only
# Text (skipped with a warning), a stray Coordinate, nothing but a unit.
CORPUS_WITHOUT_GEOMETRY = {
    "x3d/hanimmotion_containerfield.x3d", "x3d/metadata_containerfield_x3d_3.x3d",
    "x3d/metadata_containerfield_x3d_4.x3d", "x3d/test_mfstring_quotes.x3d",
    "x3d/warnings/backslashes.x3d", "x3d/warnings/invalid_container_field_on_use.x3d",
    "x3d/warnings/units_invalid.x3d",
}  # fmt: skip


def test_corpus(corpus_dir):
    """Every file reads (the deliberately wrong ones with warnings), with finite,
    in-range geometry; every file outside CORPUS_WITHOUT_GEOMETRY has some."""
    files = sorted(corpus_dir.rglob("*.x3d"))
    assert len(files) >= 20
    empty = set()
    for path in files:
        scene = sg.load(path)
        if not scene.shapes:
            empty.add(path.relative_to(corpus_dir).as_posix())
        for shape in scene.shapes:
            assert shape.n_faces > 0
            assert np.all(np.isfinite(shape.world_vertices))
            assert shape.faces.min() >= 0 and shape.faces.max() < len(shape.vertices)
        assert all(isinstance(warning, str) for warning in scene.warnings)
    assert empty == CORPUS_WITHOUT_GEOMETRY


def test_corpus_matrix_transform_spheres(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "matrix_transform.x3d")
    centres = sorted(shape.world_vertices.mean(axis=0)[0] for shape in scene.shapes)
    np.testing.assert_allclose(centres, [0, 2, 4], atol=1e-9)
    # three unit spheres, inscribed within the chord of the scene's size
    chord = sg.Tolerance.for_points(*[s.world_vertices for s in scene.shapes]).chord_length
    np.testing.assert_allclose(scene.bounds, [[-1, -1, -1], [5, 1, 1]], atol=chord)
    (light,) = scene.lights
    np.testing.assert_allclose(light.light.position, [0, 3, 0])


def test_corpus_blender_cube_bounds_by_hand(corpus_dir):
    # points span x, y in [-1, 1], z in [-1, 4]; scale (5, 5, 1); a half turn about
    # (0, 1, 1) / sqrt 2 is (x, y, z) -> (-x, z, y); then up by 1:
    # (x, y, z) -> (-5 x, z + 1, 5 y), so the box is [-5, 5] x [0, 5] x [-5, 5]
    scene = sg.load(corpus_dir / "x3d" / "test_world.x3d")
    np.testing.assert_allclose(scene.bounds, [[-5, 0, -5], [5, 5, 5]], atol=1e-5)
    assert scene.shapes[0].name == "group_ME_Cube" and scene.shapes[0].n_faces == 12
    assert scene.shapes[0].material.diffuse_color == (0.5, 0.5, 1.0)


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
    chord = sg.Tolerance.for_points(cylinder.world_vertices).chord_length
    np.testing.assert_allclose(extent, [0.002, 0.002, 0.002], atol=2 * chord)
    axis = cylinder.transform[:3, :3] @ [0, 1, 0]
    np.testing.assert_allclose(axis, [0, 0, 1], atol=1e-6)
    assert any("units_helper.x3dv" in warning for warning in scene.warnings)


def test_a_default_namespace_changes_nothing(tmp_path):
    path = tmp_path / "namespaced.x3d"
    path.write_text(
        '<X3D xmlns="http://www.web3d.org/specifications/x3d-namespace" version="4.0"><head>'
        '<unit category="length" name="cm" conversionFactor="0.01"/></head><Scene>'
        '<Transform translation="1 0 0"><Shape DEF="s"><Appearance><ImageTexture url=\'"no.png"\'/>'
        "</Appearance><Box/></Shape></Transform></Scene></X3D>"
    )
    scene = sg.load(path)
    (shape,) = scene.shapes
    assert shape.name == "s" and scene.meters_per_unit == 0.01
    np.testing.assert_allclose(shape.world_vertices.min(axis=0), [0, -1, -1])
    assert any("texture not found: no.png" in warning for warning in scene.warnings)


def test_angle_unit_scales_every_angle_field(tmp_path):
    head = '<unit category="angle" name="degrees" conversionFactor="0.017453292519943295"/>'
    body = (
        '<Transform rotation="0 0 1 90"><SpotLight direction="1 0 0" cutOffAngle="30" '
        'beamWidth="15"/></Transform><Shape><Extrusion orientation="0 1 0 90" '
        'crossSection="2 1 2 -1 -2 -1 -2 1 2 1"/></Shape>'
    )
    scene = scene_of(tmp_path, body, head=head)
    (spot,) = scene.lights
    np.testing.assert_allclose(spot.light.direction, [0, 1, 0], atol=1e-15)
    assert spot.light.cut_off_angle == pytest.approx(math.pi / 6)
    assert spot.beam_width == pytest.approx(math.pi / 12)
    # the 4 x 2 section turned a quarter about y: 2 wide in x, 4 deep in z
    np.testing.assert_allclose(np.ptp(scene.shapes[0].vertices, axis=0), [2, 1, 4], atol=1e-12)


def test_corpus_invalid_unit_warns(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "warnings" / "units_invalid.x3d")
    assert any("unit" in warning and "line 5" in warning for warning in scene.warnings)


def test_textures_found_only_inside_the_scene_folder(tmp_path):
    folder = tmp_path / "scene"
    (folder / "maps").mkdir(parents=True)
    (folder / "maps" / "wood.png").write_bytes(b"png")
    (tmp_path / "outside.png").write_bytes(b"png")
    body = (
        "<Shape><Appearance><ImageTexture url='\"maps/wood.png\"'/></Appearance><Box/></Shape>"
        "<Shape><Appearance><ImageTexture url='\"../outside.png\"'/></Appearance><Box/></Shape>"
        "<Shape><Appearance><ImageTexture url='\"http://example.com/a.png\"'/></Appearance>"
        "<Box/></Shape>"
    )
    scene = scene_of(folder, body)
    text = "\n".join(scene.warnings)
    assert "texture not found: ../outside.png" in text
    assert "texture not found: http://example.com/a.png" in text
    assert "texture not found: maps/wood.png" not in text
    assert "ImageTexture: skipped, textures not modelled" in text
    assert len(scene.shapes) == 3


def test_corpus_missing_textures_are_named(corpus_dir):
    scene = sg.load(corpus_dir / "x3d" / "car" / "car.x3d")
    missing = [warning for warning in scene.warnings if "texture not found" in warning]
    assert any("car_wheel.png" in warning for warning in missing)
    assert any("car_shell.png" in warning for warning in missing)
    assert len(scene.shapes) == 3
