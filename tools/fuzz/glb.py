"""The glb container: its JSON and binary chunks apart and together again
(the output check reads them too), and its mutants, which keep the
container whole so the reader gets past it."""

from __future__ import annotations

import random
import struct

from .mutate_bytes import mutate_bytes
from .mutate_meaning import mutate_meaning
from .mutate_structure import mutate_structure


def split_glb(data: bytes):
    """(json text, binary chunk) of a glb, or None."""
    if len(data) < 20 or data[:4] != b"glTF":
        return None
    length, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON":
        return None
    text = data[20 : 20 + length]
    rest = data[20 + length :]
    binary = b""
    if len(rest) >= 8:
        size = struct.unpack_from("<I", rest, 0)[0]
        binary = rest[8 : 8 + size]
    return text, binary


def join_glb(text: bytes, binary: bytes) -> bytes:
    text = text + b" " * (-len(text) % 4)
    binary = binary + b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if binary:
        chunks += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def mutate_glb(data: bytes, rng: random.Random):
    """Mutate the JSON chunk as text, or poke special values into the binary
    chunk, and repack with correct lengths so the container still parses."""
    parts = split_glb(data)
    if parts is None:
        return mutate_bytes(data, rng, [])
    text, binary = parts
    if binary and rng.random() < 0.4:
        buffer = bytearray(binary)
        for _ in range(rng.randint(1, 6)):
            at = rng.randrange(0, max(len(buffer) - 4, 1)) & ~3
            value = rng.choice(
                (float("nan"), float("inf"), 3.4e38, 1e-45, -0.0, 0.0, 2**31 - 1, 0xFFFFFFFF)
            )
            packed = (
                struct.pack("<I", value) if isinstance(value, int) else struct.pack("<f", value)
            )
            buffer[at : at + 4] = packed
        return join_glb(text, bytes(buffer)), ["glb:bin-special"]
    if rng.random() < 0.5:
        text, op = mutate_meaning(text, "gltf", rng)
    else:
        text, op = mutate_structure(text, "gltf", rng)
    return join_glb(text, binary), ["glb:json", op]
