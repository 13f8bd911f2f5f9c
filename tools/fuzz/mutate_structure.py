"""The structure level of the text encodings: X3D XML's elements and
attributes (:mod:`fuzz.mutate_xml`), JSON's keys and values
(:mod:`fuzz.mutate_json`), and for the others (ClassicVRML, VRML 97, USDA,
mesh text) tokens and ``Name { ... }`` blocks dropped, duplicated, swapped
or renamed."""

from __future__ import annotations

import random
import re

from .inputs import JSON_ENCODINGS, NODE_NAMES, XML_ENCODINGS
from .mutate_bytes import mutate_bytes
from .mutate_json import mutate_json
from .mutate_xml import mutate_xml

TOKEN = re.compile(rb'"(?:[^"\\\n]|\\.)*"|#[^\n]*|[A-Za-z_][\w.:-]*|[-+.\d][\w.+-]*|\S')


def mutate_structure(data: bytes, encoding: str, rng: random.Random):
    if encoding in XML_ENCODINGS:
        mutated = mutate_xml(data, rng)
        if mutated is not None:
            return mutated
    if encoding in JSON_ENCODINGS:
        mutated = mutate_json(data, rng)
        if mutated is not None:
            return mutated
    return mutate_tokens(data, rng)


def mutate_tokens(data: bytes, rng: random.Random):
    tokens = list(TOKEN.finditer(data))
    if not tokens:
        return mutate_bytes(data, rng, [])
    kind = rng.choice(("drop", "duplicate", "swap", "swap-name", "drop-block", "dup-block"))
    token = rng.choice(tokens)
    start, end = token.span()
    if kind == "drop":
        return data[:start] + data[end:], "structure:token-drop"
    if kind == "duplicate":
        return data[:end] + b" " + token.group() + data[end:], "structure:token-dup"
    if kind == "swap":
        other = rng.choice(tokens)
        (a, b), (c, d) = sorted([token.span(), other.span()])
        if b <= c:
            return data[:a] + data[c:d] + data[b:c] + data[a:b] + data[d:], "structure:token-swap"
    if kind == "swap-name":
        names = [t for t in tokens if t.group()[:1].isupper()]
        if names:
            name = rng.choice(names)
            new = rng.choice(NODE_NAMES + [n.group().decode("latin-1") for n in names])
            return (
                data[: name.start()] + new.encode("latin-1") + data[name.end() :],
                "structure:swap-name",
            )
    block = _brace_block(data, rng)
    if block is not None:
        a, b = block
        if kind == "dup-block":
            return data[:b] + b"\n" + data[a:b] + data[b:], "structure:block-dup"
        return data[:a] + data[b:], "structure:block-drop"
    return data[:start] + data[end:], "structure:token-drop"


def _brace_block(data: bytes, rng: random.Random):
    """(start, end) of a random ``Name { ... }`` block, braces balanced."""
    opens = [m.start() for m in re.finditer(rb"\{", data)]
    if not opens:
        return None
    at = rng.choice(opens)
    depth = 0
    for index in range(at, len(data)):
        if data[index] == ord("{"):
            depth += 1
        elif data[index] == ord("}"):
            depth -= 1
            if depth == 0:
                name = re.search(rb"[\w\"]+\s*$", data[max(0, at - 80) : at])
                start = at - (len(name.group()) if name else 0)
                return start, index + 1
    return None
