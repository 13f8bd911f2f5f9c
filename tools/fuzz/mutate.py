"""One mutant of a seed: the encoding's own mutators (the gzip layer of
x3dz, the chunks of glb), else one to three operations at the bytes,
structure or meaning level (text encodings; the others at the bytes level)."""

from __future__ import annotations

import gzip
import random

from .glb import mutate_glb
from .inputs import MAX_MUTANT, TEXT_ENCODINGS, gunzip
from .mutate_bytes import mutate_bytes
from .mutate_meaning import mutate_meaning
from .mutate_structure import mutate_structure


def mutate(data: bytes, encoding: str, rng: random.Random, others: list[bytes]):
    """One mutant of ``data``: (bytes, list of the operations applied)."""
    if encoding == "x3dz" and rng.random() < 0.85:
        inner, ops = mutate(gunzip(data), "x3d", rng, [gunzip(o) for o in others[:3]])
        return gzip.compress(inner, mtime=0), ["gunzip", *ops]
    if encoding == "glb" and rng.random() < 0.7:
        return mutate_glb(data, rng)
    ops = []
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        level = rng.choices(("bytes", "structure", "meaning"), (3, 3, 4))[0]
        if level == "bytes" or encoding not in TEXT_ENCODINGS:
            data, op = mutate_bytes(data, rng, others)
        elif level == "structure":
            data, op = mutate_structure(data, encoding, rng)
        else:
            data, op = mutate_meaning(data, encoding, rng)
        ops.append(op)
    return data[:MAX_MUTANT], ops
