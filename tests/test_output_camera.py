"""Every output opens with a camera that shows the scene: X3D output of an X3D
input without a Viewpoint gets one, every glTF a camera node. Checked
geometrically and independently: each corner of the scene's hand-derived
bounding box, turned into the camera's frame (Rodrigues' formula, a
quaternion written out here), lies in front of it and inside its field of
view."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from lxml import etree
from validators import gltf_problems, gltf_report

import shadowgeo as sg

# A unit-ish crate on a 10 x 10 slab, lit by a sun: by hand, the box of all
# geometry is x, z in [-5, 5] and y in [-0.1, 2] (the crate's top).
SCENE = """<X3D profile="Interchange" version="{version}"><head>{head}</head><Scene>
  <DirectionalLight direction="0.3 -1 -0.2" shadows="true"/>
  <Transform translation="0 1 0"><Shape><Box/></Shape></Transform>
  <Transform translation="0 -0.05 0"><Shape><Box size="10 0.1 10"/></Shape></Transform>
  {extra}
</Scene></X3D>
"""
CORNERS = np.array([[x, y, z] for x in (-5, 5) for y in (-0.1, 2) for z in (-5, 5)], float)
DEGREE = '<unit category="angle" name="degree" conversionFactor="0.017453292519943295"/>'


def rodrigues(axis, angle) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def quaternion_matrix(x, y, z, w) -> np.ndarray:
    """The rotation of a unit quaternion, the textbook formula."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def assert_in_view(points, position, rotation, field_of_view):
    """Each point in front of the camera (its -Z) and within half the field
    of view of its axis, both across and up: inside the picture whatever its
    aspect, as the field of view is the picture's smaller angle."""
    local = (np.asarray(points) - position) @ rotation  # rows: R^T (p - c)
    depth = -local[:, 2]
    assert (depth > 0).all(), local
    limit = math.tan(field_of_view / 2)
    assert (np.abs(local[:, 0]) <= limit * depth).all(), local
    assert (np.abs(local[:, 1]) <= limit * depth).all(), local


def source(tmp_path, extra="", head="", version="4.0"):
    path = tmp_path / "in" / "scene.x3d"
    path.parent.mkdir(exist_ok=True)
    path.write_text(SCENE.format(version=version, head=head, extra=extra))
    return path


def converted(path):
    return sg.add_shadows(sg.load(path))


@pytest.mark.parametrize("suffix", [".x3d", ".x3dv", ".wrl", ".x3dj"])
def test_x3d_without_viewpoint_gets_one_that_frames_the_scene(tmp_path, suffix):
    scene = converted(source(tmp_path))
    out = tmp_path / "out" / f"scene{suffix}"
    out.parent.mkdir()
    sg.save(scene, out)
    assert any("no Viewpoint; added 'shadowgeo_overview'" in note for note in scene.warnings)
    back = sg.load(out)
    view = back.viewpoints[0]  # the first: the one a browser binds
    assert view.name == "shadowgeo_overview"
    assert len(back.viewpoints) == 1
    rotation = rodrigues(view.orientation[:3], view.orientation[3])
    assert_in_view(CORNERS, view.position, rotation, view.field_of_view)


def test_the_added_viewpoint_is_first_and_in_the_documents_angle_unit(tmp_path):
    scene = converted(source(tmp_path, head=DEGREE, extra="<Group/>"))
    out = tmp_path / "out.x3d"
    sg.save(scene, out)
    body = etree.parse(str(out)).getroot().find("Scene")
    first = body[0]
    assert first.tag == "Viewpoint" and first.get("class") == "shadowgeo-overview"
    # X3D's default field of view: unwritten, so no unit applies
    assert first.get("fieldOfView") is None
    # Read back (the reader takes degrees to radians): still framing the box.
    (view,) = sg.load(out).viewpoints
    assert view.field_of_view == 0.7854
    rotation = rodrigues(view.orientation[:3], view.orientation[3])
    assert_in_view(CORNERS, view.position, rotation, view.field_of_view)
    # Its crate moved 40 along x and converted again: framed anew, never two.
    moved = tmp_path / "moved.x3d"
    moved.write_text(out.read_text().replace('translation="0 1 0"', 'translation="40 1 0"'))
    again = tmp_path / "again.x3d"
    sg.save(converted(moved), again)
    (added,) = etree.parse(str(again)).getroot().findall(".//Viewpoint")
    assert added.get("DEF") == "shadowgeo_overview"
    (view,) = sg.load(again).viewpoints
    rotation = rodrigues(view.orientation[:3], view.orientation[3])
    assert_in_view([*CORNERS, (41, 2, 1), (41, 0, -1)], view.position, rotation, view.field_of_view)


def test_the_authors_viewpoint_is_kept_and_none_added(tmp_path):
    extra = '<Viewpoint DEF="mine" position="0 50 0" orientation="1 0 0 -1.5707963267948966"/>'
    scene = converted(source(tmp_path, extra=extra))
    out = tmp_path / "out.x3d"
    sg.save(scene, out)
    assert [v.get("DEF") for v in etree.parse(str(out)).getroot().iter("Viewpoint")] == ["mine"]
    assert not any("no Viewpoint" in note for note in scene.warnings)


def gltf_camera(path):
    """The camera of the default scene's first camera node: world position,
    rotation, yfov (the nodes it hangs under have no transform here)."""
    document = json.loads(path.read_text())
    nodes = document["nodes"]
    roots = document["scenes"][document["scene"]]["nodes"]
    (index,) = [i for i in roots if "camera" in nodes[i]][:1]
    node = nodes[index]
    camera = document["cameras"][node["camera"]]
    assert camera["type"] == "perspective"
    return (
        np.array(node["translation"]),
        quaternion_matrix(*node["rotation"]),
        camera["perspective"]["yfov"],
    )


def test_gltf_output_has_a_camera_framing_the_scene(tmp_path):
    scene = converted(source(tmp_path))
    out = tmp_path / "scene.gltf"
    sg.save(scene, out)
    assert gltf_problems(gltf_report(out)) == []
    position, rotation, yfov = gltf_camera(out)
    assert_in_view(CORNERS, position, rotation, yfov)


def test_gltf_camera_of_a_z_up_scene_in_centimetres(tmp_path):
    # A Z-up scene in cm: glTF gets (x, y, z) -> (x, z, -y) / 100, by hand.
    cube = sg.Shape([[0, 0, 0], [200, 0, 0], [0, 300, 0], [0, 0, 400]], [[0, 1, 2], [0, 1, 3]])
    scene = sg.Scene([cube], up_axis="Z", meters_per_unit=0.01)
    out = tmp_path / "scene.glb"
    sg.save(scene, out)
    assert gltf_problems(gltf_report(out)) == []
    corners = np.array([[x, z, -y] for x in (0, 2) for y in (0, 3) for z in (0, 4)], float)
    position, rotation, yfov = gltf_camera(_as_gltf(out, tmp_path))
    assert_in_view(corners, position, rotation, yfov)
    # The picture's up is the scene's up (+Z, glTF's +Y), tilted toward the view.
    assert (rotation @ [0, 1, 0])[1] > 0.5


def _as_gltf(glb, tmp_path):
    """The JSON chunk of a .glb as a .gltf file to read."""
    data = glb.read_bytes()
    length = int.from_bytes(data[12:16], "little")
    path = tmp_path / "chunk.gltf"
    path.write_bytes(data[20 : 20 + length])
    return path


def test_x3d_viewpoint_becomes_the_gltf_camera(tmp_path):
    # Looking along -X (a quarter turn about +Y) from (20, 1, 0), fov 0.6.
    extra = (
        '<Viewpoint DEF="side" description="From the side" position="20 1 0" '
        'orientation="0 1 0 1.5707963267948966" fieldOfView="0.6"/>'
    )
    out = tmp_path / "scene.gltf"
    sg.save(converted(source(tmp_path, extra=extra)), out)
    assert gltf_problems(gltf_report(out)) == []
    position, rotation, yfov = gltf_camera(out)
    np.testing.assert_allclose(position, [20, 1, 0], atol=1e-12)
    np.testing.assert_allclose(rotation @ [0, 0, -1], [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(rotation @ [0, 1, 0], [0, 1, 0], atol=1e-12)
    assert yfov == 0.6
    document = json.loads(out.read_text())
    assert document["cameras"][0]["name"] == "From the side"
    # and it reads back as the same viewpoint: a glTF's camera is kept
    (view,) = sg.load(out).viewpoints
    assert view.name == "side" and view.field_of_view == pytest.approx(0.6)
    again = tmp_path / "again.glb"
    sg.save(sg.load(out), again)
    position, rotation, yfov = gltf_camera(_as_gltf(again, tmp_path))
    np.testing.assert_allclose(position, [20, 1, 0], atol=1e-12)
    np.testing.assert_allclose(rotation @ [0, 0, -1], [-1, 0, 0], atol=1e-12)


def test_usd_output_has_a_camera_framing_the_scene(tmp_path):
    from pxr import Usd, UsdGeom
    from validators import usd_errors

    out = tmp_path / "scene.usda"
    sg.save(converted(source(tmp_path)), out)
    assert usd_errors(out, warnings=True) == []
    stage = Usd.Stage.Open(str(out))
    (camera,) = [UsdGeom.Camera(p) for p in stage.Traverse() if p.IsA(UsdGeom.Camera)]
    world = np.array(camera.ComputeLocalToWorldTransform(Usd.TimeCode.Default())).T
    focal = camera.GetFocalLengthAttr().Get()
    vertical = 2 * math.atan(camera.GetVerticalApertureAttr().Get() / (2 * focal))
    assert camera.GetHorizontalApertureAttr().Get() > camera.GetVerticalApertureAttr().Get()
    assert_in_view(CORNERS, world[:3, 3], world[:3, :3], vertical)
