"""Hours of sunlight per face as a .glb (:mod:`shadowgeo.io.sunlight_glb`),
read back byte by byte here (not by the writer's reader) and checked by the
Khronos glTF validator."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest
from test_gis_write import DAY, _level_areas, _rd_new, _study
from validators import gltf_problems, gltf_report

from cli.main import main
from shadowgeo.errors import SceneError
from shadowgeo.io.sunlight_glb import write_hours_glb
from shadowgeo.scene.sunlight import ramp_colour


def _read(path: Path) -> tuple[dict, dict[str, dict[str, np.ndarray]]]:
    """The JSON and, per node name, its attributes as arrays, in world
    coordinates (the node's translation added) back in Z up."""
    data = path.read_bytes()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert (magic, version, length) == (b"glTF", 2, len(data))
    size, _ = struct.unpack_from("<II", data, 12)
    document = json.loads(data[20 : 20 + size])
    binary = data[20 + size + 8 :]
    out = {}
    for node in document["nodes"]:
        (primitive,) = document["meshes"][node["mesh"]]["primitives"]
        arrays = {}
        for name, index in primitive["attributes"].items():
            accessor = document["accessors"][index]
            view = document["bufferViews"][accessor["bufferView"]]
            width = {"SCALAR": 1, "VEC3": 3}[accessor["type"]]
            raw = np.frombuffer(
                binary, np.float32, accessor["count"] * width, view["byteOffset"]
            ).reshape(accessor["count"], width)
            arrays[name] = raw.astype(np.float64)
        y_up = arrays["POSITION"] + node["translation"]
        arrays["world"] = np.column_stack([y_up[:, 0], -y_up[:, 2], y_up[:, 1]])
        out[node["name"]] = arrays
    return document, out


def test_two_faces_keep_their_hours_colours_and_coordinates(tmp_path):
    vertices = np.array(
        [[85000.0, 446000.0, 0.0], [85010.0, 446000.0, 0.0], [85000.0, 446010.0, 0.0],
         [85000.0, 446000.0, 5.0]]
    )  # fmt: skip
    faces = np.array([[0, 1, 2], [0, 1, 3]])
    target = tmp_path / "two.glb"
    write_hours_glb(
        target, vertices, faces, [3.0, np.nan], most_hours=12.0, groups=[0, 1],
        names=["ground", "wall"],
    )  # fmt: skip
    document, nodes = _read(target)
    assert document["extensionsUsed"] == ["KHR_materials_unlit"]
    ground, wall = nodes["ground"], nodes["wall"]
    # RD New's coordinates come back to the millimetre (float32 about the centre)
    assert np.abs(ground["world"] - vertices[[0, 1, 2]]).max() < 1e-3
    assert np.abs(wall["world"] - vertices[[0, 1, 3]]).max() < 1e-3
    assert ground["_SUNLIGHT_HOURS"].ravel().tolist() == [3.0] * 3
    assert wall["_SUNLIGHT_HOURS"].ravel().tolist() == [-1.0] * 3
    assert np.allclose(ground["COLOR_0"], ramp_colour(0.25), atol=1e-6)
    assert np.allclose(wall["COLOR_0"], 0.6, atol=1e-6)
    problems = gltf_problems(gltf_report(target))
    assert problems == []


def test_bad_arrays_are_refused_naming_the_file(tmp_path):
    target = tmp_path / "bad.glb"
    with pytest.raises(SceneError, match="bad.glb.*2 faces but 1 hours"):
        write_hours_glb(target, np.zeros((3, 3)), [[0, 1, 2], [0, 1, 2]], [1.0], most_hours=1)
    with pytest.raises(SceneError, match="outside the 3 vertices"):
        write_hours_glb(target, np.zeros((3, 3)), [[0, 1, 3]], [1.0], most_hours=1)
    assert not target.exists()


def test_cli_mesh_carries_the_study_hours_on_the_ground_faces(tmp_path):
    source = _rd_new(tmp_path)
    scene, study = _study(source)
    target = tmp_path / "hours.glb"
    # the ground only (walls and roofs: test_sun_surfaces_cli.py)
    args = ["sun", str(source), "--date", DAY.isoformat(), "--mesh", str(target)]
    assert main([*args, "--surfaces", "none"]) == 0
    _, nodes = _read(target)
    ground = nodes["ground"]
    corners = ground["world"].reshape(-1, 3, 3)
    areas = (
        np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        )
        / 2
    )
    hours = ground["_SUNLIGHT_HOURS"].reshape(-1, 3)
    assert np.all(hours == hours[:, :1])  # a face's three corners agree
    expected = _level_areas(study)
    for value, area in expected.items():
        got = areas[hours[:, 0] == value].sum()
        assert got == pytest.approx(area, rel=1e-5, abs=1e-6)
    buildings = [name for name in nodes if name != "ground"]
    assert len(buildings) == len(scene.shapes)
    assert all(np.all(nodes[name]["_SUNLIGHT_HOURS"] == -1.0) for name in buildings)
    assert gltf_problems(gltf_report(target)) == []
