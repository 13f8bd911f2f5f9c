"""JSON mutants (X3D JSON, glTF): a key or item dropped, duplicated,
reordered, given another type or renamed to a node or field name."""

from __future__ import annotations

import json
import random

from .inputs import NODE_NAMES


def mutate_json(data: bytes, rng: random.Random):
    try:
        document = json.loads(data)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None
    containers = []

    def walk(value, depth=0):
        if depth > 200:
            return
        if isinstance(value, dict | list) and value:
            containers.append(value)
            for item in value.values() if isinstance(value, dict) else value:
                walk(item, depth + 1)

    walk(document)
    if not containers:
        return None
    node = rng.choice(containers)
    kind = rng.choice(("drop", "duplicate", "reorder", "retype", "rename"))
    keys = list(node) if isinstance(node, dict) else list(range(len(node)))
    key = rng.choice(keys)
    if kind == "drop":
        del node[key]
    elif kind == "duplicate" and isinstance(node, list):
        node.insert(key, json.loads(json.dumps(node[key])))
    elif kind == "reorder" and isinstance(node, list):
        rng.shuffle(node)
    elif kind == "retype":
        node[key] = rng.choice(([], {}, "", 0, -1, None, True, "x", [0, 0], {"@USE": "x"}))
    elif kind == "rename" and isinstance(node, dict):
        names = [n for n in NODE_NAMES] + ["@DEF", "@USE", "-children", "@point", "@coordIndex"]
        node[rng.choice(names)] = node.pop(key)
    else:
        return None
    return json.dumps(document).encode(), f"structure:json-{kind}"
