"""The bytes level, for any encoding: bit flips, truncation, splices of two
seeds, repeated or deleted chunks, inserted bytes."""

from __future__ import annotations

import random


def mutate_bytes(data: bytes, rng: random.Random, others: list[bytes]):
    size = max(len(data), 1)
    at = rng.randrange(size)
    kind = rng.choice(("flip", "set", "truncate", "splice", "repeat", "delete", "insert"))
    if kind == "flip":
        buffer = bytearray(data)
        for _ in range(rng.randint(1, 8)):
            if buffer:
                buffer[rng.randrange(len(buffer))] ^= 1 << rng.randrange(8)
        return bytes(buffer), "bytes:flip"
    if kind == "set":
        buffer = bytearray(data)
        if buffer:
            buffer[at % len(buffer)] = rng.choice((0, 0xFF, 0x7F, 0x80, ord("<"), ord("{")))
        return bytes(buffer), "bytes:set"
    if kind == "truncate":
        return data[:at], f"bytes:truncate@{at}"
    if kind == "splice" and others:
        other = rng.choice(others)
        return data[:at] + other[rng.randrange(max(len(other), 1)) :], "bytes:splice"
    if kind == "repeat":
        chunk = data[at : at + rng.randint(1, 200)]
        return data[:at] + chunk * rng.randint(2, 60) + data[at:], "bytes:repeat"
    if kind == "delete":
        return data[:at] + data[at + rng.randint(1, 400) :], "bytes:delete"
    junk = rng.choice(
        (b"<", b"&", b"\x00", b"\xff\xfe", b"]]>", b"{", b'"', b"&#0;", b"\xc3", b"[", b"}")
    )
    return data[:at] + junk * rng.randint(1, 4) + data[at:], "bytes:insert"
