"""glTF's fast path (shadowgeo.io.gltf_native): plain files decoded with numpy
read exactly as trimesh reads them, and anything else still goes to trimesh."""

from __future__ import annotations

import base64
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest
from validators import one_triangle_gltf

import shadowgeo as sg
from shadowgeo.io import gltf_native, gltf_read

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "courtyard.x3d"


def _read_both_ways(path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[sg.Scene, sg.Scene]:
    """The scene read by the fast path, and by trimesh (the fast path off)."""
    document, binary = gltf_read._gltf_document(path)
    assert gltf_native.plain_meshes(document, binary, path) is not None, "not read natively"
    native = sg.load(path)
    with monkeypatch.context() as patch:
        patch.setattr(gltf_read, "plain_meshes", lambda *args: None)
        through_trimesh = sg.load(path)
    return native, through_trimesh


def _assert_same_scene(native: sg.Scene, reference: sg.Scene) -> None:
    assert [s.name for s in native.shapes] == [s.name for s in reference.shapes]
    for mine, theirs in zip(native.shapes, reference.shapes, strict=True):
        assert mine.vertices.dtype == np.float64 and mine.faces.dtype == np.int64
        np.testing.assert_array_equal(mine.vertices, theirs.vertices)
        np.testing.assert_array_equal(mine.faces, theirs.faces)
        np.testing.assert_allclose(mine.transform, theirs.transform, rtol=0, atol=1e-12)
        assert (mine.material, mine.solid, mine.role, mine.source) == (
            theirs.material,
            theirs.solid,
            theirs.role,
            theirs.source,
        )
    assert [repr(light) for light in native.lights] == [repr(light) for light in reference.lights]
    assert native.warnings == reference.warnings


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_a_converted_scene_reads_natively_as_trimesh_reads_it(tmp_path, monkeypatch, suffix):
    scene = sg.add_shadows(sg.load(EXAMPLE))
    path = tmp_path / f"courtyard{suffix}"
    sg.save(scene, path)
    native, reference = _read_both_ways(path, monkeypatch)
    assert len(native.shapes) == len(scene.shapes) and native.lights
    _assert_same_scene(native, reference)


def _plain_document(folder: Path) -> dict:
    """Nested nodes (TRS parent, matrix child), a mesh used twice, positions
    interleaved with normals (byteStride), uint8 and uint16 indices and an
    unindexed mesh, in an external buffer and a data URI."""
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], dtype="<f4")
    interleaved = np.hstack([square, np.tile([[0, 1, 0]], (4, 1)).astype("<f4")]).tobytes()
    small = np.array([0, 2, 1, 0, 3, 2], dtype="<u1").tobytes() + b"\0\0"
    wide = np.array([0, 1, 2], dtype="<u2").tobytes() + b"\0\0"
    loose = np.array([[0, 0, 0], [0, 1, 0], [0, 0, 1]], dtype="<f4").tobytes()
    external = interleaved + small + wide
    (folder / "parts.bin").write_bytes(external)
    embedded = "data:application/octet-stream;base64," + base64.b64encode(loose).decode()
    half = math.sqrt(0.5)
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3]}],
        "nodes": [
            {
                "name": "parent",
                "translation": [1, 2, 3],
                "rotation": [0, half, 0, half],  # a quarter turn about +y
                "scale": [2, 2, 2],
                "mesh": 0,
                "children": [1, 2],
            },
            {"name": "child", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1]},  # noqa: E501
            {"name": "triangle", "mesh": 1},
            {"name": "loose", "mesh": 2, "translation": [0, 0, -4]},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 3, "mode": 4}]},
            {"primitives": [{"attributes": {"POSITION": 4}}]},
        ],
        "buffers": [
            {"byteLength": len(external), "uri": "parts.bin"},
            {"byteLength": len(loose), "uri": embedded},
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": len(interleaved), "byteStride": 24},
            {"buffer": 0, "byteOffset": len(interleaved), "byteLength": 6},
            {"buffer": 0, "byteOffset": len(interleaved) + 8, "byteLength": 6},
            {"buffer": 1, "byteLength": len(loose)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 0, 1]},
            {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "count": 6, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [0, 1, 1]},
        ],
    }  # fmt: skip


def test_strided_indexed_nested_and_shared_meshes_read_natively_as_trimesh_reads_them(
    tmp_path, monkeypatch
):
    path = tmp_path / "plain.gltf"
    path.write_text(json.dumps(_plain_document(tmp_path)))
    native, reference = _read_both_ways(path, monkeypatch)
    _assert_same_scene(native, reference)
    parent, child, triangle, loose = native.shapes
    assert [s.name for s in native.shapes] == ["parent", "child", "triangle", "loose"]
    # The parent turns +x to -z, doubles and moves by (1, 2, 3); the child adds 5 along
    # its parent's x: the corner (1, 0, 0) lands at (1, 2, 1) and (1, 2, -9).
    assert np.allclose(parent.world_vertices[1], [1, 2, 1], atol=1e-12)
    assert np.allclose(child.world_vertices[1], [1, 2, -9], atol=1e-12)
    assert parent.faces.tolist() == [[0, 2, 1], [0, 3, 2]] and triangle.faces.tolist() == [
        [0, 1, 2]
    ]
    assert loose.faces.tolist() == [[0, 1, 2]]  # unindexed: the vertices in threes
    assert np.shares_memory(parent.vertices, child.vertices)  # one mesh, decoded once


@pytest.mark.parametrize(
    "change",
    [
        "vertex colours",
        "sparse positions",
        "lines",
        "lines beside triangles",
        "Draco extension",
        "node reached twice",
        "matrix and translation",
    ],
)
def test_files_outside_the_fast_path_still_go_to_trimesh(tmp_path, change):
    document = _plain_document(tmp_path)
    mesh = document["meshes"][0]["primitives"]
    if change == "vertex colours":
        mesh[0]["attributes"]["COLOR_0"] = 1
    elif change == "sparse positions":
        document["accessors"][0]["sparse"] = {"count": 0}
    elif change == "lines":
        document["meshes"][1]["primitives"][0]["mode"] = 1
    elif change == "lines beside triangles":
        mesh.append({**mesh[0], "mode": 1})
    elif change == "Draco extension":
        mesh[0]["extensions"] = {"KHR_draco_mesh_compression": {}}
    elif change == "node reached twice":
        document["scenes"][0]["nodes"].append(2)
    else:
        document["nodes"][1]["translation"] = [0, 1, 0]
    path = tmp_path / "other.gltf"
    path.write_text(json.dumps(document))
    parsed, binary = gltf_read._gltf_document(path)
    assert gltf_native.plain_meshes(parsed, binary, path) is None


def test_an_accessor_past_its_buffer_is_left_to_trimesh_and_refused(tmp_path):
    path = tmp_path / "long.gltf"
    path.write_text(json.dumps(one_triangle_gltf(accessor_count=4)))
    document, binary = gltf_read._gltf_document(path)
    assert gltf_native.plain_meshes(document, binary, path) is None
    with pytest.raises(sg.SceneError, match="long.gltf"):
        sg.load(path)
    # the same file, in bounds, is read natively
    path.write_text(json.dumps(one_triangle_gltf()))
    document, binary = gltf_read._gltf_document(path)
    assert gltf_native.plain_meshes(document, binary, path) is not None
    (shape,) = sg.load(path).shapes
    assert shape.name == "tri" and shape.n_faces == 1


def test_quaternion_matrix_is_a_rotation_with_exact_quarter_turns():
    half = math.sqrt(0.5)
    turn = gltf_native.quaternion_matrix([-half, 0, 0, half])  # -90 degrees about x
    assert turn.tolist() == [[1, 0, 0], [0, 0, 1], [0, -1, 0]]
    rng = np.random.default_rng(3)
    for xyzw in rng.normal(size=(20, 4)):
        rotation = gltf_native.quaternion_matrix(list(xyzw))  # any length: normalised
        np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-14)
        assert np.linalg.det(rotation) == pytest.approx(1.0, abs=1e-14)
    assert gltf_native.quaternion_matrix([0, 0, 0, 0]).tolist() == np.eye(3).tolist()


def test_a_glb_buffer_shorter_than_declared_is_not_read_natively(tmp_path):
    path = tmp_path / "tri.glb"
    sg.save(sg.Scene(shapes=[sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])]), path)
    data = bytearray(path.read_bytes())
    json_length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(bytes(data[20 : 20 + json_length]))
    document["buffers"][0]["byteLength"] += 4  # claims more than the chunk holds
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + json_length :]
    head = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + len(rest))
    path.write_bytes(head + struct.pack("<I4s", len(text), b"JSON") + text + rest)
    parsed, binary = gltf_read._gltf_document(path)
    assert gltf_native.plain_meshes(parsed, binary, path) is None


def test_a_broken_mesh_no_node_shows_does_not_stop_the_scene(tmp_path):
    document = _plain_document(tmp_path)
    document["meshes"].append({"primitives": [{"attributes": {"POSITION": 5}}]})
    document["accessors"].append(
        {"bufferView": 3, "componentType": 5126, "count": 400, "type": "VEC3"}  # past its view
    )
    path = tmp_path / "unused.gltf"
    path.write_text(json.dumps(document))
    assert [shape.name for shape in sg.load(path).shapes] == [
        "parent",
        "child",
        "triangle",
        "loose",
    ]
    document["nodes"][3]["mesh"] = 3  # now a node shows it: trimesh reads, and refuses, the file
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match="unused.gltf"):
        sg.load(path)


def test_a_mesh_of_several_primitives_reads_natively_one_shape_each_with_exact_colours(
    tmp_path, monkeypatch
):
    # Two primitives of one mesh sharing its positions, each with its own
    # material, on the two nodes that use the mesh: the same shapes as
    # trimesh reads, in the same order, with the colours as the file gives them
    document = _plain_document(tmp_path)
    primitives = document["meshes"][0]["primitives"]
    primitives[0]["material"] = 0
    primitives.append({"attributes": {"POSITION": 0}, "indices": 3, "material": 1})
    document["materials"] = [
        {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1]}},
        {
            "name": "blue",
            "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.95, 1]},
            "doubleSided": True,
        },
    ]
    path = tmp_path / "parts.gltf"
    path.write_text(json.dumps(document))
    parsed, binary = gltf_read._gltf_document(path)
    assert gltf_native.plain_meshes(parsed, binary, path) is not None
    native = sg.load(path)
    with monkeypatch.context() as patch:
        patch.setattr(gltf_read, "plain_meshes", lambda *args: None)
        reference = sg.load(path)
    names = ["parent", "parent", "child", "child", "triangle", "loose"]
    assert [s.name for s in native.shapes] == [s.name for s in reference.shapes] == names
    # each node's primitives in the file's order (trimesh orders them by its frame names)
    assert [s.material.name for s in native.shapes[:4]] == ["red", "blue", "red", "blue"]
    colours = [None, "red", "blue"]
    key = lambda shape: (names.index(shape.name), colours.index(shape.material.name))  # noqa: E731
    for mine, theirs in zip(native.shapes, sorted(reference.shapes, key=key), strict=True):
        np.testing.assert_array_equal(mine.vertices, theirs.vertices)
        np.testing.assert_array_equal(mine.faces, theirs.faces)
        np.testing.assert_allclose(mine.transform, theirs.transform, rtol=0, atol=1e-12)
        assert mine.solid == theirs.solid and mine.material.name == theirs.material.name
        # trimesh keeps 8-bit colours: within half a step of the exact ones
        np.testing.assert_allclose(
            mine.material.diffuse_color, theirs.material.diffuse_color, atol=0.5 / 255 + 1e-12
        )
    red, blue = native.shapes[0].material, native.shapes[1].material
    assert red.diffuse_color == (0.9, 0.1, 0.1) and blue.diffuse_color == (0.1, 0.2, 0.95)
    assert (native.shapes[0].solid, native.shapes[1].solid) == (True, False)
    assert np.shares_memory(native.shapes[0].vertices, native.shapes[1].vertices)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), float("-inf")])
def test_a_position_that_is_not_finite_is_refused_naming_the_node(tmp_path, value):
    document = one_triangle_gltf()
    corners = np.array([0, 0, 0, 1, 0, 0, value, 1, 0], dtype="<f4")
    uri = "data:application/octet-stream;base64," + base64.b64encode(corners.tobytes()).decode()
    document["buffers"][0]["uri"] = uri
    path = tmp_path / "bad.gltf"
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match=r"bad.gltf.*node 'tri'.*point 2"):
        sg.load(path)
