"""The meaning level of the text encodings: numbers turned into 0, -0,
1e308, 1e-320, nan, inf, huge counts or negative indices, fields emptied,
deep nesting, DEF/USE cycles (each in the encoding's own syntax), and X3D
XML's modelled fields set to hostile values (:mod:`fuzz.mutate_xml`); for
city data, mostly its own (:mod:`fuzz.mutate_city`)."""

from __future__ import annotations

import json
import random
import re

from .inputs import (
    CITY_ENCODINGS,
    JSON_ENCODINGS,
    MAX_MUTANT,
    SPECIAL_FLOATS,
    SPECIAL_INTS,
    XML_ENCODINGS,
)
from .mutate_bytes import mutate_bytes
from .mutate_city import mutate_city
from .mutate_xml import mutate_x3d_fields

NUMBER = re.compile(rb"(?<![\w.#])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")


def mutate_meaning(data: bytes, encoding: str, rng: random.Random):
    if encoding in CITY_ENCODINGS and rng.random() < 0.7:
        mutated = mutate_city(data, encoding, rng)
        if mutated is not None:
            return mutated
    kinds = ["number", "number", "field", "count", "empty", "nest", "cycle"]
    if encoding in XML_ENCODINGS:
        kinds += ["set-field", "set-field", "add-node", "add-node"]
    kind = rng.choice(kinds)
    if kind in ("set-field", "add-node"):
        mutated = mutate_x3d_fields(data, rng, add=kind == "add-node")
        if mutated is not None:
            return mutated, f"meaning:{kind}"
        kind = "number"
    if kind == "nest":
        return deep_nesting(data, encoding, rng), "meaning:deep-nesting"
    if kind == "cycle":
        return def_use_cycle(data, encoding, rng), "meaning:def-use-cycle"
    if kind == "empty":
        return empty_field(data, encoding, rng), "meaning:empty-field"
    numbers = list(NUMBER.finditer(data))
    if not numbers:
        return mutate_bytes(data, rng, [])
    if kind == "number":
        match = rng.choice(numbers)
        is_int = re.fullmatch(rb"[-+]?\d+", match.group()) is not None
        value = rng.choice(SPECIAL_INTS if is_int and rng.random() < 0.6 else SPECIAL_FLOATS)
        return data[: match.start()] + value.encode() + data[match.end() :], f"meaning:{value}"
    if kind == "field":  # every number of one run (a field's values) becomes the same special
        first = rng.randrange(len(numbers))
        value = rng.choice(SPECIAL_FLOATS + SPECIAL_INTS).encode()
        run = [numbers[first]]
        for match in numbers[first + 1 :]:
            if re.fullmatch(rb"[\s,]*", data[run[-1].end() : match.start()]) is None:
                break
            run.append(match)
        # one join, not one copy of the whole file per number: after a count
        # mutation a run can hold a million numbers
        pieces, done = [], 0
        for match in run:
            pieces += [data[done : match.start()], value]
            done = match.end()
        return b"".join([*pieces, data[done:]]), f"meaning:field={value.decode()}"
    # count: a run of numbers repeated many times (a huge index or point list)
    match = rng.choice(numbers)
    end = min(len(data), match.end() + rng.randint(10, 400))
    stop = max((m.end() for m in numbers if match.start() <= m.end() <= end), default=match.end())
    chunk = data[match.start() : stop] + b" "
    times = rng.choice((100, 1000, 10000))
    if len(chunk) * times > MAX_MUTANT:
        times = max(2, MAX_MUTANT // max(len(chunk), 1))
    return data[:stop] + b" " + chunk * times + data[stop:], f"meaning:count*{times}"


def empty_field(data: bytes, encoding: str, rng: random.Random) -> bytes:
    if encoding in XML_ENCODINGS:
        spans = list(re.finditer(rb'(\w+)=("[^"]*"|\'[^\']*\')', data))
        if spans:
            match = rng.choice(spans)
            return data[: match.start(2)] + b'""' + data[match.end(2) :]
    spans = list(re.finditer(rb"\[[^\[\]]*\]", data))
    if spans:
        match = rng.choice(spans)
        return data[: match.start()] + b"[]" + data[match.end() :]
    return data


def deep_nesting(data: bytes, encoding: str, rng: random.Random) -> bytes:
    depth = rng.choice((50, 500, 5000))
    if encoding in XML_ENCODINGS:
        match = re.search(rb"<Scene[^>]*>", data)
        if match:
            head, tail = b"<Transform>" * depth, b"</Transform>" * depth
            close = data.rfind(b"</Scene>")
            if close > match.end():
                inner = data[match.end() : close]
                return data[: match.end()] + head + inner + tail + data[close:]
    if encoding in JSON_ENCODINGS:
        try:
            document = json.loads(data)
        except (ValueError, UnicodeDecodeError):
            return data
        nested = document
        for _ in range(min(depth, 250)):  # json.dumps recurses
            nested = {"Transform": {"-children": [nested]}} if encoding != "gltf" else [nested]
        return json.dumps({"X3D": nested} if encoding != "gltf" else nested).encode()
    if encoding == "usda":
        head, tail = b'def Xform "n" {\n' * depth, b"}\n" * depth
        return data + b"\n" + head + tail
    return (
        data
        + b"\n"
        + b"Group { children [ " * depth
        + b"Shape { geometry Box {} } "
        + (b"] } " * depth)
    )


def def_use_cycle(data: bytes, encoding: str, rng: random.Random) -> bytes:
    if encoding in XML_ENCODINGS:
        defs = list(re.finditer(rb'<(\w+)([^>]*?)DEF=(["\'])([^"\']*)\3([^>]*?)(?<!/)>', data))
        if defs:
            match = rng.choice(defs)
            name = match.group(4)
            return data[: match.end()] + b'<Group USE="' + name + b'"/>' + data[match.end() :]
        match = re.search(rb"<(Transform|Group)(\s[^>]*)?(?<!/)>", data)
        if match:
            insert = b' DEF="cyc"'
            at = match.start() + 1 + len(match.group(1))
            body = data[:at] + insert + data[at : match.end()] + b'<Transform USE="cyc"/>'
            return body + data[match.end() :]
        return data
    if encoding in JSON_ENCODINGS:
        text = data.decode("utf-8", "replace")
        match = re.search(r'"@DEF"\s*:\s*"([^"]*)"', text)
        name = match.group(1) if match else "cyc"
        spot = text.find('"-children"')
        if spot < 0:
            return data
        bracket = text.find("[", spot)
        use = '{"Group": {"@USE": "' + name + '"}},'
        if not match:
            use = '{"Transform": {"@DEF": "cyc", "-children": [{"Group": {"@USE": "cyc"}}]}},'
        return (text[: bracket + 1] + use + text[bracket + 1 :]).encode()
    if encoding == "usda":
        return data + b'\nover "cyc" (references = </cyc>) {}\n'
    defs = list(re.finditer(rb"DEF\s+([\w-]+)\s+(\w+)\s*\{", data))
    if defs:
        match = rng.choice(defs)
        children = data.find(b"children", match.end())
        bracket = data.find(b"[", children) if children >= 0 else -1
        if bracket >= 0:
            return data[: bracket + 1] + b" USE " + match.group(1) + b" " + data[bracket + 1 :]
    return data + b"\nDEF cyc Group { children [ USE cyc ] }\n"
