"""Viewpoints: read from X3D in world coordinates, turned into axis-angle
rotations, checked against hand-derived directions and an independent
rotation formula."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import shadowgeo as sg
from shadowgeo.scene.model import axis_angle


def rotation(axis, angle):
    """Rodrigues' formula as a matrix, written out independently of shadowgeo."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def write(tmp_path, body: str, name: str = "scene.x3d", head: str = ""):
    path = tmp_path / name
    path.write_text(f'<X3D version="4.0"><head>{head}</head><Scene>\n{body}\n</Scene></X3D>')
    return path


def test_viewpoints_are_read_in_world_coordinates(tmp_path):
    write(tmp_path, '<Viewpoint description="inlined"/>', "part.x3d")
    body = (
        '<Transform translation="10 0 0" rotation="0 1 0 1.5707963267948966" scale="2 2 2">'
        '<Viewpoint DEF="side" position="1 2 3" orientation="1 0 0 0.5" fieldOfView="0.6"'
        ' description="From the side"/></Transform>\n'
        '<Switch whichChoice="-1"><Viewpoint description="hidden"/></Switch>\n'
        "<Inline url='\"part.x3d\"'/>\n"
        '<Viewpoint description="second"/>'
    )
    scene = sg.load(write(tmp_path, body))
    side, second = scene.viewpoints  # not the hidden one, nor the inlined one
    # By hand: turning (x, y, z) by a quarter turn about +y gives (z, y, -x).
    # (1, 2, 3) -> (3, 2, -1), scaled by 2 and moved by (10, 0, 0).
    assert side.position == pytest.approx((16, 4, -2), abs=1e-12)
    # About +x by 0.5: -z -> (0, sin .5, -cos .5), +y -> (0, cos .5, sin .5); then the quarter turn.
    direction = np.array([-math.cos(0.5), math.sin(0.5), 0])
    up = np.array([math.sin(0.5), math.cos(0.5), 0])
    turn = rotation(side.orientation[:3], side.orientation[3])
    np.testing.assert_allclose(turn @ [0, 0, -1], direction, atol=1e-12)
    np.testing.assert_allclose(turn @ [0, 1, 0], up, atol=1e-12)
    np.testing.assert_allclose(side.direction, direction, atol=1e-12)
    np.testing.assert_allclose(side.up, up, atol=1e-12)
    assert side.field_of_view == 0.6 and side.name == "side"
    assert side.description == "From the side"
    # X3D's defaults.
    assert second.position == (0, 0, 10) and second.field_of_view == pytest.approx(0.7854)
    np.testing.assert_allclose(second.direction, [0, 0, -1], atol=1e-15)
    (note,) = [w for w in scene.warnings if "Viewpoint" in w]  # only the inlined one
    assert "part.x3d line 2, Viewpoint: skipped, a Viewpoint of an inlined file" in note


def test_viewpoint_field_of_view_follows_the_angle_unit(tmp_path):
    head = '<unit category="angle" name="degree" conversionFactor="0.017453292519943295"/>'
    body = '<Viewpoint fieldOfView="30" orientation="0 1 0 90"/>'
    (view,) = sg.load(write(tmp_path, body, head=head)).viewpoints
    assert view.field_of_view == pytest.approx(math.pi / 6)
    np.testing.assert_allclose(view.direction, [-1, 0, 0], atol=1e-12)


def test_a_bad_field_of_view_takes_the_default_with_a_note(tmp_path):
    path = write(tmp_path, '<Viewpoint fieldOfView="4"/><Viewpoint fieldOfView="x"/>')
    scene = sg.load(path)
    assert [view.field_of_view for view in scene.viewpoints] == [math.pi / 4, 0.7854]
    assert "line 2, Viewpoint: fieldOfView 4 is not in (0, pi)" in scene.warnings[0]
    assert "field fieldOfView: 'x' is not numbers" in scene.warnings[1]


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3),
    st.floats(0, math.pi),
    st.lists(st.floats(0.1, 10), min_size=3, max_size=3),
)
def test_axis_angle_gives_back_the_rotation(axis, angle, scale):
    turn = rotation(axis, angle)
    found = axis_angle(turn @ np.diag(scale))  # a scale does not change the rotation
    assert np.linalg.norm(found[:3]) == pytest.approx(1.0)
    assert 0 <= found[3] <= math.pi + 1e-12
    np.testing.assert_allclose(rotation(found[:3], found[3]), turn, atol=1e-9)


@pytest.mark.parametrize(
    "axis, angle", [((0, 0, 1), 0.0), ((1, 0, 0), math.pi), ((0, 1, 1), math.pi), ((1, 2, 3), 1e-9)]
)
def test_axis_angle_at_its_hard_cases(axis, angle):
    turn = rotation(axis, angle)
    found = axis_angle(turn)
    np.testing.assert_allclose(rotation(found[:3], found[3]), turn, atol=1e-12)
    if angle == math.pi:
        assert found[3] == pytest.approx(math.pi)


def corners(points):
    low, high = points.min(axis=0), points.max(axis=0)
    return np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                     for z in (low[2], high[2])])  # fmt: skip


@pytest.mark.parametrize("up_axis", ["Y", "Z"])
def test_a_fresh_document_gets_a_viewpoint_over_the_scene_and_its_shadows(
    tmp_path, up_axis, x3d_schema
):
    from x3d_schema import x3d_schema_errors

    up = np.array([0, 1, 0]) if up_axis == "Y" else np.array([0, 0, 1])
    flat = np.array([1, 1, 1]) - up
    ground = sg.Shape(
        np.array([[-5, -5, -5], [5, -5, -5], [5, -5, 5], [-5, -5, 5]]) * flat,
        [[0, 2, 1], [0, 3, 2]] if up_axis == "Y" else [[0, 1, 2], [0, 2, 3]],
        name="ground",
    )
    box = trimesh.creation.box(bounds=[up * 1 - flat * 0.5, up * 2 + flat * 0.5])
    sun = sg.SceneLight(sg.DirectionalLight(-up + flat * [1, 0.5, 0.2]), name="sun")
    scene = sg.Scene([ground, sg.Shape(box.vertices, box.faces, name="box")], [sun])
    scene.up_axis = up_axis
    result = sg.add_shadows(scene)
    path = tmp_path / "fresh.x3d"
    sg.save(result, path)
    assert x3d_schema_errors(path, x3d_schema) == []
    (view,) = sg.load(path).viewpoints
    # X3D is Y-up: a Z-up scene is written turned, (x, y, z) -> (x, z, -y).
    turn = np.eye(3) if up_axis == "Y" else np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    everything = np.concatenate([s.world_vertices for s in result.shapes]) @ turn.T
    position = np.array(view.position)
    # From above, at an angle: higher than everything, looking down, not straight down.
    assert position[1] > everything[:, 1].max()
    assert -0.95 < view.direction[1] < -0.3
    assert view.up[1] > 0.5  # the picture's up is the world's
    # Every corner of the scene and its shadows is inside the field of view.
    rays = corners(everything) - position
    angles = np.arccos(rays @ view.direction / np.linalg.norm(rays, axis=1))
    assert np.all(angles < view.field_of_view / 2)
    assert view.name == "shadowgeo_overview"


def test_a_fresh_document_keeps_the_scenes_viewpoints(tmp_path):
    ground = sg.Shape([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], [[0, 2, 1], [0, 3, 2]])
    views = [
        sg.Viewpoint((1, 2, 3), (0, 1, 0, 0.25), 0.5, "first", "one"),
        sg.Viewpoint((0, 9, 0), (1, 0, 0, -math.pi / 2), 1.0, "from above"),
    ]
    path = tmp_path / "kept.x3d"
    sg.save(sg.Scene([ground], viewpoints=views), path)
    read = sg.load(path).viewpoints
    assert [v.name for v in read] == ["one", None]
    for written, back in zip(views, read, strict=True):
        assert back.position == written.position and back.description == written.description
        np.testing.assert_allclose(back.direction, written.direction, atol=1e-12)
        np.testing.assert_allclose(back.up, written.up, atol=1e-12)
        assert back.field_of_view == written.field_of_view


def test_gltf_cameras_become_viewpoints_of_the_fresh_x3d(tmp_path):
    """A glTF camera node turned 90 degrees about +X (looking straight down)
    at (1, 5, 2), under a parent translated by (0, 1, 0): the Viewpoint is at
    (1, 6, 2), looks along -Y with -Z up; a portrait aspect makes the smaller
    angle the horizontal one, 2 atan(tan(yfov / 2) aspect)."""
    import json

    from validators import one_triangle_gltf

    document = one_triangle_gltf()
    half = math.sqrt(0.5)
    document["nodes"] += [
        {"name": "rig", "translation": [0, 1, 0], "children": [2]},
        {"name": "top", "camera": 0, "translation": [1, 5, 2], "rotation": [-half, 0, 0, half]},
    ]
    document["scenes"][0]["nodes"] = [0, 1]
    document["cameras"] = [
        {"name": "from above", "type": "perspective",
         "perspective": {"yfov": 0.8, "aspectRatio": 0.5, "znear": 0.1}},
    ]  # fmt: skip
    path = tmp_path / "camera.gltf"
    path.write_text(json.dumps(document))
    (view,) = sg.load(path).viewpoints
    np.testing.assert_allclose(view.position, [1, 6, 2], atol=1e-12)
    np.testing.assert_allclose(view.direction, [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(view.up, [0, 0, -1], atol=1e-12)
    assert view.field_of_view == pytest.approx(2 * math.atan(math.tan(0.4) * 0.5))
    assert view.description == "from above" and view.name == "top"
    out = tmp_path / "camera.x3d"
    sg.save(sg.load(path), out)
    (again,) = sg.load(out).viewpoints
    np.testing.assert_allclose(again.position, view.position, atol=1e-12)
    np.testing.assert_allclose(again.direction, view.direction, atol=1e-12)
    assert again.field_of_view == pytest.approx(view.field_of_view)


def test_a_cyclic_gltf_node_graph_with_a_camera_ends(tmp_path):
    import json

    from validators import one_triangle_gltf

    document = one_triangle_gltf()
    document["nodes"] += [{"camera": 0, "children": [2]}, {"children": [1]}]
    document["scenes"][0]["nodes"] = [0, 1]
    document["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}]
    path = tmp_path / "cycle.gltf"
    path.write_text(json.dumps(document))
    try:
        scene = sg.load(path)
    except sg.SceneError:
        return  # refused as malformed: also an answer
    assert len(scene.viewpoints) == 1
