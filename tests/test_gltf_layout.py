"""What the glTF reader and writer share: GLB chunks parsed with length
checks (for files and X3D Inlines alike), the extras layout, and the one
containment rule for the files a scene names."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest

import shadowgeo as sg
from shadowgeo.io import outside_reason
from shadowgeo.io.gltf_layout import BIN_CHUNK, JSON_CHUNK, glb_chunks, glb_container

TEXT = json.dumps({"asset": {"version": "2.0"}}).encode()


def _glb(json_length: int, chunk: bytes, tail: bytes = b"") -> bytes:
    """A GLB by hand: header, a JSON chunk header claiming ``json_length``, ``chunk``."""
    body = struct.pack("<II", json_length, JSON_CHUNK) + chunk + tail
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def test_chunks_come_back_as_written():
    binary = bytes(range(10))
    text, back = glb_chunks(glb_container(TEXT, binary), Path("x.glb"))
    # The container pads JSON with spaces and BIN with zeros to 4 bytes.
    assert text.rstrip(b" ") == TEXT and back == binary + b"\0\0"
    assert glb_chunks(glb_container(TEXT, b""), Path("x.glb"))[1] == b""


@pytest.mark.parametrize(
    "data, message",
    [
        (b"glTF\x02\x00\x00\x00", "truncated GLB header"),
        (_glb(len(TEXT) + 1, TEXT), "not a complete JSON chunk"),
        (_glb(2**31, TEXT), "not a complete JSON chunk"),
        (_glb(len(TEXT), TEXT).replace(struct.pack("<I", JSON_CHUNK), b"BIN\0"), "JSON chunk"),
    ],
)
def test_lying_lengths_are_refused(data, message):
    with pytest.raises(sg.SceneError, match=message) as caught:
        glb_chunks(data, Path("liar.glb"))
    assert "liar.glb" in str(caught.value)


def test_a_bin_chunk_longer_than_the_file_gives_what_is_there():
    tail = struct.pack("<II", 1000, BIN_CHUNK) + b"\1\2\3\4"
    assert glb_chunks(_glb(len(TEXT), TEXT, tail), Path("x.glb"))[1] == b"\1\2\3\4"


def test_an_inlined_glb_with_a_lying_length_is_skipped_with_its_reason(tmp_path):
    (tmp_path / "part.glb").write_bytes(_glb(len(TEXT) + 400, TEXT))
    scene = tmp_path / "scene.x3d"
    scene.write_text(
        '<X3D version="4.0"><Scene><Inline url=\'"part.glb"\'/></Scene></X3D>', encoding="utf-8"
    )
    loaded = sg.load(scene)
    assert loaded.shapes == []
    (warning,) = loaded.warnings
    assert "Inline skipped" in warning and "part.glb" in warning
    assert "not a complete JSON chunk" in warning


@pytest.mark.parametrize(
    "reference, target, reason",
    [
        ("a/b.bin", "scene/a/b.bin", None),
        ("../b.bin", "b.bin", "it leaves the file's folder"),
        ("/etc/passwd", "/etc/passwd", "not a relative path"),
        ("\\\\server\\share", "scene/x", "not a relative path"),
        ("http://example.com/b.bin", "scene/x", "not a relative path"),
        ("C:/b.bin", "scene/x", "not a relative path"),
        ("link.bin", "elsewhere/b.bin", "it leaves the file's folder"),
    ],
)
def test_containment_rule(tmp_path, reference, target, reason):
    folder = tmp_path / "scene"
    assert outside_reason(reference, tmp_path / target, folder) == reason


def test_empty_shapes_keep_their_shadow_flags_through_gltf(tmp_path):
    empty = sg.Shape(
        np.zeros((0, 3)), np.zeros((0, 3)), name="e", casts_shadow=False, receives_shadow=True
    )
    triangle = sg.Shape([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="t")
    path = tmp_path / "flags.gltf"
    sg.save(sg.Scene(shapes=[empty, triangle]), path)
    node = json.loads(path.read_text())["nodes"][0]
    assert node["extras"]["shadowgeo"]["castsShadow"] is False
    back = sg.load(path).shapes
    assert [(s.name, s.casts_shadow, s.receives_shadow) for s in back] == [
        ("e", False, True),
        ("t", True, False),
    ]


@pytest.mark.parametrize(
    ("document", "pointer", "wanted"),
    [
        ({"nodes": [{}, {}, {}, {"name": 7}]}, "/nodes/3/name", "a string"),
        ({"nodes": [{"children": [1, True]}]}, "/nodes/0/children/1", "an integer"),
        ({"meshes": [{"primitives": [{}, []]}]}, "/meshes/0/primitives/1", "an object"),
        ({"scene": "zero"}, "/scene", "an integer"),
    ],
)
def test_a_member_of_the_wrong_type_is_named_by_its_json_pointer(document, pointer, wanted):
    from shadowgeo.io.gltf_layout import check_types

    with pytest.raises(sg.SceneError, match=f"malformed glTF: {pointer} is .*, not {wanted}"):
        check_types({"asset": {"version": "2.0"}, **document}, Path("scene.gltf"))


@pytest.mark.parametrize(
    ("document", "pointer", "wanted"),
    [
        ({"nodes": [{"translation": [0.5, float("nan"), 1.0]}]}, "/nodes/0/translation/1", "a"),
        ({"nodes": [{"scale": [1.0, 1.0, "2"]}]}, "/nodes/0/scale/2", "a finite number"),
        ({"nodes": [{"rotation": [0.0, 0.0, 0.0, True]}]}, "/nodes/0/rotation/3", "a finite"),
        ({"nodes": [{"matrix": [1.0] * 15}]}, "/nodes/0/matrix", "an array of 16"),
    ],
)
def test_number_arrays_are_checked_member_by_member(document, pointer, wanted):
    from shadowgeo.io.gltf_layout import check_types

    with pytest.raises(sg.SceneError, match=f"malformed glTF: {pointer} is .*, not {wanted}"):
        check_types({"asset": {"version": "2.0"}, **document}, Path("scene.gltf"))
    fine = {"nodes": [{"translation": [0.5, -2.0, 1e300], "scale": [1, 2.0, 3]}]}
    check_types({"asset": {"version": "2.0"}, **fine}, Path("scene.gltf"))  # no error


@pytest.mark.parametrize(
    "text",
    [
        b'{"asset": {"version": "2.0"}, "nodes": [{"translation": [0.1, 1e-310, -0.0]}]}',
        b'{"asset": {"version": "2.0"}, "nodes": [{"name": "a", "name": "b"}]}',  # the last wins
        b'{"asset": {"version": "2.0"}, "nodes": [{"translation": [NaN, 0, 0]}]}',
        b'\xef\xbb\xbf{"asset": {"version": "2.0"}}',  # a byte-order mark
        '{"asset": {"version": "2.0"}}'.encode("utf-16"),
        b'{"asset": {"version": "2.0"}, "nodes": [{"name": "caf\xc3\xa9"}]}',
    ],
)
def test_json_is_read_the_same_with_or_without_orjson(tmp_path, monkeypatch, text):
    from shadowgeo.io import gltf_layout

    path = tmp_path / "scene.gltf"
    path.write_bytes(text)

    def read():
        try:
            document, _ = gltf_layout.json_document(path)
        except sg.SceneError as error:
            return "refused", str(error)
        return "read", json.dumps(document, sort_keys=True)  # (NaN and -0.0 spelled out)

    fast = read()
    monkeypatch.setattr(gltf_layout, "orjson", None)
    assert read() == fast


def test_an_integer_beyond_64_bits_is_read_either_way(tmp_path, monkeypatch):
    # (orjson reads it as a float, json as an int: nowhere shadowgeo reads
    # can such a number be valid, and check_types refuses it there either way)
    from shadowgeo.io import gltf_layout

    path = tmp_path / "scene.gltf"
    path.write_text('{"asset": {"version": "2.0"}, "extras": {"big": 1234567890123456789012345}}')
    for module in (gltf_layout.orjson, None):
        monkeypatch.setattr(gltf_layout, "orjson", module)
        document, _ = gltf_layout.json_document(path)
        assert document["extras"]["big"] == pytest.approx(1234567890123456789012345)
