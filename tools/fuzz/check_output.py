"""The check that a written file holds no NaN or infinity: X3D field
values, USDA numbers, glTF's JSON and its float accessors."""

from __future__ import annotations

import contextlib
import json
import math
import mmap
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .glb import split_glb
from .inputs import gunzip

_SKIPPED_ATTRIBUTES = {"content", "description", "name", "DEF", "USE", "url", "title", "string"}
# A comment (skipped), or an attribute and its value (in double or single quotes).
_X3D_TOKENS = re.compile(
    rb"<!--.*?-->"
    rb"|(?P<name>[\w:.-]+)\s*=\s*(?:\"(?P<double>[^\"]*)\"|'(?P<single>[^']*)')",
    re.S,
)
# A string (skipped: its text is no number), a comment (skipped), or a NaN or
# infinity written as a value.
_USDA_TOKENS = re.compile(
    rb'"""(?:.|\n)*?"""|"(?:[^"\\]|\\.)*"|#[^\n]*'
    rb"|(?P<value>(?<![\w\"])[-+]?(?:nan|inf|infinity)(?![\w\"]))",
    re.IGNORECASE,
)


def _spelled_alone(text: bytes | mmap.mmap) -> bool:
    """Whether "nan" or "inf" (any case) stands somewhere as a word of its
    own ("infinity" too), not as the start of one ("info:id"): the text
    lowered a chunk at a time (chunks overlapping by a word), then searched."""
    size = len(text)
    for begin in range(0, max(size, 1), _CHUNK):
        start = max(begin - 1, 0)
        chunk = bytes(text[start : begin + _CHUNK + 9]).lower()
        for word in (b"nan", b"inf"):
            at = chunk.find(word, begin - start)
            while 0 <= at < begin - start + _CHUNK:
                end = at + 3
                if chunk[end : end + 5] == b"inity":
                    end += 5
                before = chunk[at - 1 : at] if start + at else b" "
                after = chunk[end : end + 1] if start + end < size else b" "
                if not (_WORDLIKE.match(before) or _WORDLIKE.match(after)):
                    return True
                at = chunk.find(word, at + 1)
    return False


_CHUNK = 1 << 24
_WORDLIKE = re.compile(rb'[\w"]')


def non_finite_in_output(path: Path) -> str | None:
    """A description of the first NaN or infinity the writer put in ``path``.

    The text is scanned in place, as bytes (a file mapped, or a gzip's
    bytes), with comments and strings skipped by one pattern, not copied
    out first: a 400 KB scene of 1,000 copies wrote a 546 MB USDA, which the
    copies took past the worker's memory budget."""
    suffix = path.suffix.lower()
    if suffix in (".x3d", ".x3dz"):
        with _text(path) as text:
            return _non_finite_attribute(text)
    if suffix == ".usda":
        with _text(path) as text:
            if not _spelled_alone(text):
                return None  # (found by memchr-fast searches; the tokens only if so)
            for match in _USDA_TOKENS.finditer(text):
                if match.lastgroup == "value":
                    start, end = max(0, match.start() - 60), match.end() + 20
                    return bytes(text[start:end]).decode("utf-8", "replace")
        return None
    if suffix in (".glb", ".gltf"):
        return non_finite_in_gltf(path.read_bytes(), path)
    return None


@contextlib.contextmanager
def _text(path: Path) -> Iterator[bytes | mmap.mmap]:
    """The file's bytes, gunzipped if they are a gzip, else mapped."""
    with path.open("rb") as stream:
        if stream.read(2) == b"\x1f\x8b" or path.stat().st_size == 0:
            stream.seek(0)
            yield gunzip(stream.read())
            return
        with mmap.mmap(stream.fileno(), 0, access=mmap.ACCESS_READ) as mapped:
            yield mapped


def _non_finite_attribute(text: bytes | mmap.mmap) -> str | None:
    for match in _X3D_TOKENS.finditer(text):
        if match.group("name") is None:  # a comment: its text is no field value
            continue
        name = match.group("name").decode("utf-8", "replace")
        value = (match.group("double") or match.group("single") or b"").decode("utf-8", "replace")
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
