"""The check that a written file holds no NaN or infinity: X3D field
values, USDA numbers, glTF's JSON and its float accessors."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from .glb import split_glb
from .inputs import gunzip

_SKIPPED_ATTRIBUTES = {"content", "description", "name", "DEF", "USE", "url", "title", "string"}
_ATTRIBUTE = re.compile(r'([\w:.-]+)\s*=\s*("([^"]*)"|\'([^\']*)\')')
_NONFINITE = re.compile(r"(?<![\w\"])[-+]?(nan|inf|infinity)(?![\w\"])", re.IGNORECASE)


def non_finite_in_output(path: Path) -> str | None:
    """A description of the first NaN or infinity the writer put in ``path``."""
    suffix = path.suffix.lower()
    data = path.read_bytes()
    if suffix in (".x3d", ".x3dz"):
        text = gunzip(data).decode("utf-8", "replace")
        # A comment's text is no field value (a commented-out node may say "nan").
        text = re.sub(r"<!--.*?-->", "", text, flags=re.S)
        for match in _ATTRIBUTE.finditer(text):
            name, value = match.group(1), match.group(3) or match.group(4) or ""
            if name in _SKIPPED_ATTRIBUTES:
                continue
            words = [w for w in re.split(r"[\s,]+", value) if w]
            if (
                words
                and all(_is_number(w) for w in words)
                and not all(math.isfinite(float(w)) for w in words)
            ):
                return f'{name}="{value[:80]}"'
        return None
    if suffix == ".usda":
        text = data.decode("utf-8", "replace")
        text = re.sub(r'"(?:[^"\\]|\\.)*"', '""', text)
        text = re.sub(r"#[^\n]*", "", text)
        match = _NONFINITE.search(text)
        return None if match is None else text[max(0, match.start() - 60) : match.end() + 20]
    if suffix in (".glb", ".gltf"):
        return non_finite_in_gltf(data, path)
    return None


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def non_finite_in_gltf(data: bytes, path: Path) -> str | None:
    if path.suffix.lower() == ".glb":
        parts = split_glb(data)
        if parts is None:
            return "not a glb"
        text, binary = parts
    else:
        text, binary = data, b""

    def refuse(constant):
        raise ValueError(f"JSON constant {constant}")

    try:
        document = json.loads(text, parse_constant=refuse)
    except ValueError as error:
        return str(error)
    buffers = []
    for index, buffer in enumerate(document.get("buffers", [])):
        uri = buffer.get("uri")
        if uri is None:
            buffers.append(binary if index == 0 else b"")
        elif uri.startswith("data:"):
            import base64

            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            external = path.parent / uri
            buffers.append(external.read_bytes() if external.is_file() else b"")
    views = document.get("bufferViews", [])
    for index, accessor in enumerate(document.get("accessors", [])):
        if accessor.get("componentType") != 5126 or "bufferView" not in accessor:
            continue
        view = views[accessor["bufferView"]]
        raw = buffers[view.get("buffer", 0)]
        start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}.get(
            accessor.get("type"), 1
        )
        stride = view.get("byteStride") or 4 * width
        count = accessor.get("count", 0)
        try:
            if stride == 4 * width:
                rows = np.frombuffer(raw, "<f4", count * width, start)
            else:
                rows = np.array(
                    [np.frombuffer(raw, "<f4", width, start + i * stride) for i in range(count)]
                )
        except ValueError as error:
            return f"accessor {index} unreadable: {error}"
        if rows.size and not np.all(np.isfinite(rows)):
            return f"accessor {index} has NaN or inf"
    return None
