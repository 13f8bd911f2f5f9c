"""Issue 12, second fuzzing campaign: the readers' findings (c1-c7, c11, c12).

Each case is written here by hand, the smallest input of its class: bad input
gives an output or exit 1 with one line naming the file and what is wrong,
never a traceback and never a non-finite number in the output.
"""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import pytest

from cli.main import main
from shadowgeo.errors import SceneError
from shadowgeo.io import gltf_read, usd_read
from shadowgeo.io.gltf_layout import glb_container

# A unit square (two triangles) on y = 0, as a glTF with a data-URI buffer.
SQUARE = [(-1.0, 0.0, -1.0), (1.0, 0.0, -1.0), (1.0, 0.0, 1.0), (-1.0, 0.0, 1.0)]


def gltf(indices: list[int] | None = None) -> dict:
    """A glTF 2.0 document of SQUARE with the triangle ``indices``."""
    indices = indices if indices is not None else [0, 1, 2, 0, 2, 3]
    points = b"".join(struct.pack("<3f", *p) for p in SQUARE)
    index_bytes = struct.pack(f"<{len(indices)}H", *indices)
    index_bytes += b"\0" * (-len(index_bytes) % 4)
    data = points + index_bytes
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "ground", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 4,
                "type": "VEC3",
                "min": [-1, 0, -1],
                "max": [1, 0, 1],
            },
            {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(points)},
            {"buffer": 0, "byteOffset": len(points), "byteLength": len(indices) * 2},
        ],
        "buffers": [
            {
                "byteLength": len(data),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
            }
        ],
    }


def write_gltf(tmp_path: Path, document: dict, suffix: str = ".gltf") -> Path:
    path = tmp_path / f"scene{suffix}"
    text = json.dumps(document).encode()
    path.write_bytes(text if suffix == ".gltf" else glb_container(text, b""))
    return path


def run(capsys, *args) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def one_clear_error(code: int, err: str, *shown: str) -> None:
    """Exit 1 with one line (besides notes) that names each of ``shown``."""
    assert "Traceback" not in err
    assert code == 1, err
    lines = [line for line in err.splitlines() if not line.startswith("note:")]
    assert len(lines) == 1 and lines[0].startswith("shadowgeo "), err
    for text in shown:
        assert text in lines[0], err


def test_the_hand_written_gltf_reads(tmp_path):
    """The control: the unmutated document is a valid two-triangle square."""
    scene = gltf_read.read(write_gltf(tmp_path, gltf()))
    assert len(scene.shapes) == 1
    assert scene.shapes[0].name == "ground"
    assert scene.shapes[0].faces.shape == (2, 3)


def test_c1_a_corrupt_deflate_stream_is_one_clear_error(tmp_path, capsys):
    # gzip header, then a stored block whose LEN and NLEN disagree: zlib.error.
    path = tmp_path / "scene.x3dz"
    path.write_bytes(b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\xff\x00\x05\x00\x00\x00hello")
    code, _, err = run(capsys, "info", path)
    one_clear_error(code, err, "scene.x3dz", "cannot read")


def test_c2_a_usda_that_is_not_utf8_is_one_clear_error(tmp_path, capsys):
    path = tmp_path / "scene.usda"
    path.write_bytes(b"#usda 1.0\n\xff\n")
    code, _, err = run(capsys, "info", path)
    one_clear_error(code, err, "scene.usda")


def test_c3_an_unknown_xform_op_names_the_prim(tmp_path):
    path = tmp_path / "scene.usda"
    path.write_text(
        "#usda 1.0\n"
        'def Xform "box" {\n'
        "    double3 xformOp:trans = (0, 2, 0)\n"
        '    uniform token[] xformOpOrder = ["xformOp:trans"]\n'
        '    def Mesh "m" {\n'
        "        int[] faceVertexCounts = [3]\n"
        "        int[] faceVertexIndices = [0, 1, 2]\n"
        "        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n"
        "    }\n"
        "}\n"
    )
    with pytest.raises(SceneError, match="trans") as caught:
        usd_read.read(path)
    assert "/box/m" in str(caught.value)


def test_c12_a_light_colour_past_float32_is_refused(tmp_path):
    path = tmp_path / "scene.usda"
    path.write_text(
        '#usda 1.0\ndef SphereLight "lamp" {\n    color3f inputs:color = (1, 1e155, 1)\n}\n'
    )
    with pytest.raises(SceneError, match="color") as caught:
        usd_read.read(path)
    assert "/lamp" in str(caught.value)


@pytest.mark.parametrize("suffix", [".gltf", ".glb"])
def test_c4_a_face_index_out_of_range_names_the_node(tmp_path, suffix):
    path = write_gltf(tmp_path, gltf([0, 1, 1000, 0, 2, 3]), suffix)
    with pytest.raises(SceneError, match="vertex 1000 of 4") as caught:
        gltf_read.read(path)
    assert "ground" in str(caught.value)


def _set(document: dict, pointer: str, value) -> dict:
    *parents, last = pointer.strip("/").split("/")
    target = document
    for key in parents:
        target = target[int(key)] if isinstance(target, list) else target.setdefault(key, {})
    if isinstance(target, list):
        target[int(last)] = value
    else:
        target[last] = value
    return document


@pytest.mark.parametrize(
    "pointer, value",
    [
        ("/meshes/0/primitives/0", "x"),  # c5
        ("/meshes/0/primitives", True),  # c5b
        ("/images", 5),  # c7
        ("/buffers/0/uri", ["x"]),  # c7b
        ("/nodes/0/name", True),  # c6
        ("/nodes/0/name", {"a": 1}),  # c6b
        ("/nodes/0/extras/shadowgeo/group", {"a": 1}),  # c6c
        ("/nodes/0/extras/shadowgeo/castsShadow", "no"),
        ("/meshes/0/primitives/0/attributes/POSITION", 0.5),
        ("/nodes/0/translation", [0, 1e400, 0]),
    ],
)
@pytest.mark.parametrize("suffix", [".gltf", ".glb"])
def test_c5_c6_c7_a_json_value_of_the_wrong_type_names_its_pointer(
    tmp_path, capsys, suffix, pointer, value
):
    path = write_gltf(tmp_path, _set(gltf(), pointer, value), suffix)
    code, _, err = run(capsys, "convert", path, tmp_path / "out.usda", "--sun", "0.2,-1,-0.1")
    one_clear_error(code, err, path.name, pointer)
    assert not (tmp_path / "out.usda").exists()


def _light_document(attenuation: list) -> dict:
    document = gltf()
    document["extensions"] = {
        "KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 1, 1]}]}
    }
    document["nodes"].append(
        {
            "name": "lamp",
            "translation": [0, 5, 0],
            "extensions": {"KHR_lights_punctual": {"light": 0}},
            "extras": {"shadowgeo": {"attenuation": attenuation}},
        }
    )
    document["scenes"][0]["nodes"].append(1)
    return document


def test_c11_an_attenuation_of_four_values_is_refused(tmp_path, capsys):
    path = write_gltf(tmp_path, _light_document([1, 0, 0, 0]), ".glb")
    code, _, err = run(capsys, "convert", path, tmp_path / "out.usda")
    one_clear_error(code, err, "/nodes/1/extras/shadowgeo/attenuation", "an array of 3")


def test_c11_control_an_attenuation_of_three_values_is_kept(tmp_path):
    scene = gltf_read.read(write_gltf(tmp_path, _light_document([0.5, 0.25, 0]), ".glb"))
    assert scene.lights[0].attenuation == (0.5, 0.25, 0.0)


def test_c4b_faces_without_vertices_name_the_node(tmp_path, capsys):
    document = gltf()
    document["accessors"][0]["count"] = 0
    path = write_gltf(tmp_path, document)
    code, _, err = run(capsys, "info", path)
    one_clear_error(code, err, "ground", "of 0")
