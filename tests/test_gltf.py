"""glTF writer: validated by the Khronos validator, read back through trimesh."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest
import trimesh
from validators import gltf_problems, gltf_report, one_triangle_gltf

import shadowgeo as sg
from shadowgeo.io import look_rotation
from shadowgeo.io.gltf_layout import quaternion_xyzw
from shadowgeo.io.gltf_write import is_trs


def test_validator_passes_a_clean_file_and_catches_a_broken_one(tmp_path, node_tools):
    clean = tmp_path / "clean.gltf"
    clean.write_text(json.dumps(one_triangle_gltf(3)))
    assert gltf_problems(gltf_report(clean)) == []

    broken = tmp_path / "broken.gltf"
    broken.write_text(json.dumps(one_triangle_gltf(30)))
    problems = gltf_problems(gltf_report(broken), warnings=False)
    assert any(p.startswith("ACCESSOR_TOO_LONG at /accessors/0") for p in problems)


def test_validator_refuses_a_file_that_is_not_gltf(tmp_path, node_tools):
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"\x00\x01not a gltf at all")
    with pytest.raises(RuntimeError, match="junk.glb"):
        gltf_report(junk)


# --- the writer -------------------------------------------------------------------------------


def _quaternion_rotate(q, vector):
    """Rotate ``vector`` by the unit quaternion ``q = [x, y, z, w]`` (v' = q v q*)."""
    u, w = np.asarray(q[:3], dtype=float), float(q[3])
    vector = np.asarray(vector, dtype=float)
    return vector + 2.0 * np.cross(u, np.cross(u, vector) + w * vector)


def _read_glb(path):
    """The JSON and binary chunks of a GLB, parsed by hand from the spec."""
    data = path.read_bytes()
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert (magic, version, length) == (0x46546C67, 2, len(data))
    json_length, json_type = struct.unpack_from("<II", data, 12)
    assert json_type == 0x4E4F534A
    document = json.loads(data[20 : 20 + json_length])
    offset = 20 + json_length
    binary = b""
    if offset < len(data):
        bin_length, bin_type = struct.unpack_from("<II", data, offset)
        assert bin_type == 0x004E4942
        binary = data[offset + 8 : offset + 8 + bin_length]
    return document, binary


def _accessor(document, binary, index):
    accessor = document["accessors"][index]
    view = document["bufferViews"][accessor["bufferView"]]
    dtype = {5126: "<f4", 5125: "<u4"}[accessor["componentType"]]
    width = {"VEC3": 3, "SCALAR": 1}[accessor["type"]]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    values = np.frombuffer(binary, dtype=dtype, count=accessor["count"] * width, offset=start)
    return values.reshape(-1, width) if width > 1 else values


def _scene(**shape_options):
    box = trimesh.creation.box(extents=[2.0, 1.0, 0.5])
    moved = np.eye(4)
    moved[:3, 3] = [10.0, 2.0, -3.0]
    turned = np.eye(4)
    turned[:3, :3] = trimesh.transformations.rotation_matrix(0.3, [0, 1, 0])[:3, :3] * 2.0
    return sg.Scene(
        shapes=[
            sg.Shape(box.vertices, box.faces, moved, name="crate", **shape_options),
            sg.Shape(
                box.vertices,
                box.faces,
                turned,
                name="glass",
                material=sg.Material((0.2, 0.4, 0.6), transparency=0.25),
                solid=False,
            ),
            sg.Shape([[0, 0, 0], [1, 0, 0], [0, 0, -1]], [[0, 1, 2]], role="shadow", group="sun"),
        ],
        lights=[
            sg.SceneLight(sg.PointLight([0, 5, 0], radius=10), name="bulb", intensity=0.7),
            sg.SceneLight(sg.DirectionalLight([1, -1, 0]), name="sun", shadows=True),
            sg.SceneLight(
                sg.SpotLight([0, 5, 0], [0, 0, 1], cut_off_angle=0.5), name="spot", beam_width=0.3
            ),
        ],
    )


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_written_file_has_no_validator_errors_or_warnings(tmp_path, node_tools, suffix):
    path = tmp_path / f"scene{suffix}"
    sg.save(_scene(), path)
    report = gltf_report(path)
    assert report["issues"]["numErrors"] == 0
    assert gltf_problems(report) == []
    assert report["info"]["drawCallCount"] == 3
    assert "KHR_lights_punctual" in report["info"]["extensionsUsed"]


def test_glb_positions_materials_and_nodes_as_the_spec_lays_them_out(tmp_path):
    path = tmp_path / "scene.glb"
    scene = _scene()
    sg.save(scene, path)
    document, binary = _read_glb(path)
    nodes = {node.get("name"): node for node in document["nodes"]}

    crate = nodes["crate"]
    matrix = np.array(crate["matrix"]).reshape(4, 4).T  # glTF is column-major
    np.testing.assert_array_equal(matrix, scene.shapes[0].transform)
    primitive = document["meshes"][crate["mesh"]]["primitives"][0]
    positions = _accessor(document, binary, primitive["attributes"]["POSITION"])
    indices = _accessor(document, binary, primitive["indices"]).reshape(-1, 3)
    expected = scene.shapes[0].vertices[scene.shapes[0].faces]
    np.testing.assert_allclose(positions[indices], expected, rtol=0, atol=1e-7)

    glass = document["materials"][
        document["meshes"][nodes["glass"]["mesh"]]["primitives"][0]["material"]
    ]
    assert glass["alphaMode"] == "BLEND"
    assert glass["doubleSided"] is True
    np.testing.assert_allclose(
        glass["pbrMetallicRoughness"]["baseColorFactor"], [0.2, 0.4, 0.6, 0.75]
    )
    opaque = document["materials"][document["meshes"][crate["mesh"]]["primitives"][0]["material"]]
    assert "alphaMode" not in opaque and opaque["doubleSided"] is False

    # The shadow sits under a node named after its light group, not at the top.
    top = [document["nodes"][i].get("name") for i in document["scenes"][0]["nodes"]]
    assert "sun" in top and "crate" in top
    group = next(n for n in document["nodes"] if n.get("children") and n.get("name") == "sun")
    children = [document["nodes"][i] for i in group["children"]]
    assert [c["extras"]["shadowgeo"]["role"] for c in children] == ["shadow"]


def test_lights_point_their_node_minus_z_along_the_light(tmp_path):
    path = tmp_path / "scene.glb"
    sg.save(_scene(), path)
    document, _ = _read_glb(path)
    lights = document["extensions"]["KHR_lights_punctual"]["lights"]
    by_name = {}
    for node in document["nodes"]:
        if "extensions" in node:
            by_name[node["name"]] = (
                node,
                lights[node["extensions"]["KHR_lights_punctual"]["light"]],
            )

    node, light = by_name["bulb"]
    assert light["type"] == "point" and light["range"] == 10 and light["intensity"] == 0.7
    assert node["translation"] == [0, 5, 0] and "rotation" not in node

    node, light = by_name["sun"]
    assert light["type"] == "directional" and "range" not in light
    direction = _quaternion_rotate(node["rotation"], [0, 0, -1])
    np.testing.assert_allclose(direction, np.array([1, -1, 0]) / np.sqrt(2), atol=1e-12)

    node, light = by_name["spot"]
    # +Z is the one direction the shortest arc from -Z cannot take: half a turn.
    np.testing.assert_allclose(
        _quaternion_rotate(node["rotation"], [0, 0, -1]), [0, 0, 1], atol=1e-12
    )
    assert light["spot"] == {"innerConeAngle": 0.3, "outerConeAngle": 0.5}


def test_spot_inner_cone_stays_below_the_outer_cone(tmp_path):
    # X3D's default beamWidth equals its default cutOffAngle; glTF needs inner < outer.
    light = sg.SceneLight(sg.SpotLight([0, 1, 0], [0, -1, 0], cut_off_angle=math.pi / 4))
    path = tmp_path / "spot.gltf"
    sg.save(sg.Scene(lights=[light]), path)
    spot = json.loads(path.read_text())["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"]
    assert spot["innerConeAngle"] < spot["outerConeAngle"] == math.pi / 4
    assert spot["outerConeAngle"] - spot["innerConeAngle"] < 1e-12
    assert gltf_problems(gltf_report(path)) == []


@pytest.mark.parametrize("direction", [[0, 0, -1], [0, 0, 1], [1, 0, 0], [0, -1, 0], [1, 2, -3]])
def test_look_rotation_is_a_rotation_taking_minus_z_to_the_direction(direction):
    rotation = look_rotation(direction)
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    unit = np.array(direction, dtype=float) / np.linalg.norm(direction)
    np.testing.assert_allclose(rotation @ [0, 0, -1], unit, atol=1e-14)
    np.testing.assert_allclose(
        _quaternion_rotate(quaternion_xyzw(rotation), [0, 0, -1]), unit, atol=1e-12
    )


def test_sheared_transform_is_baked_into_the_vertices(tmp_path):
    shear = np.eye(4)
    shear[0, 1] = 0.5  # x += 0.5 y: not translation x rotation x scale
    shear[:3, 3] = [1, 2, 3]
    assert not is_trs(shear)
    box = trimesh.creation.box()
    path = tmp_path / "shear.glb"
    sg.save(sg.Scene(shapes=[sg.Shape(box.vertices, box.faces, shear, name="sheared")]), path)
    document, binary = _read_glb(path)
    node = document["nodes"][0]
    assert "matrix" not in node
    primitive = document["meshes"][node["mesh"]]["primitives"][0]
    positions = _accessor(document, binary, primitive["attributes"]["POSITION"])
    indices = _accessor(document, binary, primitive["indices"]).reshape(-1, 3)
    world = box.vertices @ shear[:3, :3].T + shear[:3, 3]
    np.testing.assert_allclose(positions[indices], world[box.faces], atol=1e-6)
    assert gltf_problems(gltf_report(path)) == []


def test_z_up_scene_in_centimetres_is_rotated_and_scaled_to_y_up_metres(tmp_path):
    triangle = sg.Shape([[0, 0, 0], [100, 0, 0], [0, 0, 200]], [[0, 1, 2]], name="t")
    light = sg.SceneLight(sg.SpotLight([0, 0, 300], [0, 0, -1]), name="down")
    path = tmp_path / "z.glb"
    scene = sg.Scene(shapes=[triangle], lights=[light], up_axis="Z", meters_per_unit=0.01)
    sg.save(scene, path)
    document, _ = _read_glb(path)
    root = document["nodes"][document["scenes"][0]["nodes"][0]]
    matrix = np.array(root["matrix"]).reshape(4, 4).T
    # Z-up (x, y, z) in cm is (x, z, -y) / 100 in Y-up metres: up stays up.
    np.testing.assert_allclose(matrix @ [0, 0, 200, 1], [0, 2, 0, 1], atol=1e-15)
    np.testing.assert_allclose(matrix @ [0, 100, 0, 1], [0, 0, -1, 1], atol=1e-15)
    assert gltf_problems(gltf_report(path)) == []


def test_writer_rejects_bad_input_with_the_file_named(tmp_path):
    bad = sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    bad.faces = np.array([[0, 1, 7]])
    with pytest.raises(sg.SceneError, match=r"bad\.glb.*vertex 7 of 3"):
        sg.save(sg.Scene(shapes=[bad]), tmp_path / "bad.glb")
    assert not (tmp_path / "bad.glb").exists()
    with pytest.raises(sg.SceneError, match="up axis"):
        sg.save(sg.Scene(up_axis="X"), tmp_path / "x.glb")
    assert list(tmp_path.iterdir()) == []


def test_failed_write_leaves_the_existing_file_untouched(tmp_path, monkeypatch):
    path = tmp_path / "scene.glb"
    path.write_bytes(b"previous contents")
    real_write_bytes = Path.write_bytes

    def write_half_then_fail(self, data):
        real_write_bytes(self, data[: len(data) // 2])
        raise OSError("disk full")

    monkeypatch.setattr(Path, "write_bytes", write_half_then_fail)
    with pytest.raises(sg.SceneError, match="scene.glb: cannot write: disk full"):
        sg.save(_scene(), path)
    monkeypatch.undo()
    assert path.read_bytes() == b"previous contents"
    assert [p.name for p in tmp_path.iterdir()] == ["scene.glb"]
    with pytest.raises(sg.SceneError, match="new.glb: cannot write: disk full"):
        monkeypatch.setattr(Path, "write_bytes", write_half_then_fail)
        sg.save(_scene(), tmp_path / "new.glb")
    monkeypatch.undo()
    assert [p.name for p in tmp_path.iterdir()] == ["scene.glb"]


def test_random_trs_mirrored_and_far_transforms_validate(tmp_path):
    # Non-uniform scales, mirrors (negative determinant), translations of 1e7,
    # repeated and degenerate faces: glTF takes all of them as node matrices.
    rng = np.random.default_rng(1)
    shapes = []
    for index in range(40):
        rotation = trimesh.transformations.random_rotation_matrix(rng.random(3))
        scale = rng.uniform(0.01, 100, 3) * rng.choice([-1, 1], 3)
        transform = rotation @ np.diag([*scale, 1.0])
        transform[:3, 3] = rng.uniform(-1e7, 1e7, 3)
        vertices = rng.uniform(-1e4, 1e4, (6, 3))
        faces = rng.integers(0, 6, (5, 3))
        shapes.append(sg.Shape(vertices, faces, transform, name=f"s{index}"))
    path = tmp_path / "random.glb"
    sg.save(sg.Scene(shapes=shapes), path)
    document, _ = _read_glb(path)
    assert sum("matrix" in node for node in document["nodes"]) == 40
    report = gltf_report(path)
    assert gltf_problems(report) == []
    # Degenerate triangles are only informational for the validator.
    codes = {m["code"] for m in report["issues"]["messages"]}
    assert codes <= {"ACCESSOR_INDEX_TRIANGLE_DEGENERATE"}


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_an_empty_scene_is_a_valid_file(tmp_path, suffix):
    # Real X3D files with no geometry (metadata only) convert to this.
    path = tmp_path / f"empty{suffix}"
    sg.save(sg.Scene(), path)
    back = sg.load(path)
    assert back.shapes == [] and back.lights == []
    assert gltf_problems(gltf_report(path)) == []


def test_out_of_range_looks_and_intensities_are_clamped_to_what_gltf_allows(tmp_path):
    odd = sg.Material((1.5, -0.2, 0.5), (2.0, 0.0, 0.0), shininess=3.0, transparency=-0.5)
    shape = sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], material=odd)
    light = sg.SceneLight(sg.PointLight([0, 1, 0]), color=(2, 1, -1), intensity=-3.0)
    path = tmp_path / "odd.glb"
    sg.save(sg.Scene(shapes=[shape], lights=[light]), path)
    document, _ = _read_glb(path)
    material = document["materials"][0]
    assert material["pbrMetallicRoughness"]["baseColorFactor"] == [1.0, 0.0, 0.5, 1.0]
    assert material["emissiveFactor"] == [1.0, 0.0, 0.0]
    assert material["pbrMetallicRoughness"]["roughnessFactor"] == 0.0
    entry = document["extensions"]["KHR_lights_punctual"]["lights"][0]
    assert entry["color"] == [1.0, 1.0, 0.0] and entry["intensity"] == 0.0
    assert gltf_problems(gltf_report(path)) == []


def test_shapes_differing_only_in_shininess_keep_their_own_roughness(tmp_path):
    triangle = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    scene = sg.Scene(
        shapes=[
            sg.Shape(triangle, [[0, 1, 2]], name="dull", material=sg.Material(shininess=0.25)),
            sg.Shape(triangle, [[0, 1, 2]], name="shiny", material=sg.Material(shininess=0.75)),
        ]
    )
    sg.save(scene, tmp_path / "two.glb")
    back = sg.load(tmp_path / "two.glb")
    assert [shape.material.shininess for shape in back.shapes] == [0.25, 0.75]


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, -1]], "vertex -1 of 3"),
        (np.zeros((0, 3)), [[0, 1, 2]], "vertex 0 of 0"),  # not silently dropped
    ],
)
@pytest.mark.parametrize("suffix", [".glb", ".usda"])
def test_writers_name_the_face_index_that_has_no_vertex(tmp_path, vertices, faces, message, suffix):
    shape = sg.Shape(vertices, faces, name="bad")
    with pytest.raises(sg.SceneError, match=rf"'bad'.*{message}"):
        sg.save(sg.Scene(shapes=[shape]), tmp_path / f"bad{suffix}")
    assert list(tmp_path.iterdir()) == []


def test_is_trs_takes_rotation_scale_translation_and_refuses_the_rest():
    turn = np.eye(4)
    c, s = np.cos(0.7), np.sin(0.7)
    turn[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.diag([2.0, 3.0, 0.5])
    turn[:3, 3] = [1e6, -4, 2]
    assert is_trs(turn) and is_trs(np.eye(4))
    for row, column, value in [
        (0, 1, 0.25),  # a shear
        (3, 0, 0.1),  # projective
        (1, 1, float("nan")),
        (2, 3, float("inf")),
        (0, 0, float("nan")),
    ]:
        broken = turn.copy()
        broken[row, column] += value
        assert not is_trs(broken), (row, column, value)
    flat = turn.copy()
    flat[:3, 2] = 0.0  # a zero scale: no rotation to give glTF
    assert not is_trs(flat)
