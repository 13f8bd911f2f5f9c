"""glTF writer: validated by the Khronos validator, read back through trimesh."""

from __future__ import annotations

import base64
import json

import numpy as np
import pytest
from validators import gltf_problems, gltf_report


def _minimal_gltf(accessor_count: int) -> dict:
    """A one-triangle glTF with an embedded buffer; ``accessor_count`` other
    than 3 makes the POSITION accessor read past its buffer view."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype="<f4").tobytes()
    uri = "data:application/octet-stream;base64," + base64.b64encode(positions).decode()
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": len(positions), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": len(positions), "target": 34962}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": accessor_count,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            }
        ],
    }


def test_validator_passes_a_clean_file_and_catches_a_broken_one(tmp_path, node_tools):
    clean = tmp_path / "clean.gltf"
    clean.write_text(json.dumps(_minimal_gltf(3)))
    assert gltf_problems(gltf_report(clean)) == []

    broken = tmp_path / "broken.gltf"
    broken.write_text(json.dumps(_minimal_gltf(30)))
    problems = gltf_problems(gltf_report(broken), warnings=False)
    assert any(p.startswith("ACCESSOR_TOO_LONG at /accessors/0") for p in problems)


def test_validator_refuses_a_file_that_is_not_gltf(tmp_path, node_tools):
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"\x00\x01not a gltf at all")
    with pytest.raises(RuntimeError, match="junk.glb"):
        gltf_report(junk)
