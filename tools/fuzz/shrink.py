"""Shrinking a failure by delta debugging: an input by lines, tags, words
and bytes; a geometry case by faces."""

from __future__ import annotations

import gzip
import re
from typing import TYPE_CHECKING

from .inputs import XML_ENCODINGS, gunzip

if TYPE_CHECKING:
    from .pool import Pool


def ddmin(items: list, reproduces, budget: list[int]) -> list:
    """Delta debugging: a smaller list of ``items`` for which ``reproduces``
    (called on a batch of candidates, returning the index of the first that
    reproduces or None) still holds; ``budget[0]`` runs at most."""
    granularity = 2
    while len(items) >= 2 and budget[0] > 0:
        size = max(1, len(items) // granularity)
        chunks = [items[i : i + size] for i in range(0, len(items), size)]
        complements = [
            [x for j, chunk in enumerate(chunks) if j != i for x in chunk]
            for i in range(len(chunks))
        ]
        # Two chunks: each is the other's complement; more: complements first.
        candidates = (chunks if len(chunks) <= 2 else complements)[: budget[0]]
        budget[0] -= len(candidates)
        found = reproduces(candidates)
        if found is not None:
            items = candidates[found]
            granularity = max(granularity - 1, 2) if len(chunks) > 2 else 2
            continue
        if granularity >= len(items):
            break
        granularity = min(len(items), granularity * 2)
    return items


def shrink_input(pool: Pool, task: dict, signature: str, tries: int) -> bytes:
    """The smallest input found that still fails with ``signature``."""
    encoding = task["encoding"]
    wrap = (lambda b: gzip.compress(b, mtime=0)) if encoding == "x3dz" else (lambda b: b)
    inner = gunzip(task["data"]) if encoding == "x3dz" else task["data"]
    if encoding == "x3dz" and not _same(pool, task, wrap(inner), signature):
        inner, wrap = task["data"], (lambda b: b)
    budget = [tries]

    def reproduces(candidates) -> int | None:
        tasks = [dict(task, data=wrap(b"".join(c))) for c in candidates]
        for index, result in enumerate(pool.map(tasks)):
            if result.get("signature") == signature:
                return index
        return None

    pieces = re.split(rb"(?<=\n)", inner)
    inner = b"".join(ddmin([p for p in pieces if p], reproduces, budget))
    if encoding in XML_ENCODINGS or encoding == "x3dz":
        inner = b"".join(ddmin(re.split(rb"(?=<)", inner), reproduces, budget))
    inner = b"".join(ddmin([t for t in re.split(rb"(\s+)", inner) if t], reproduces, budget))
    inner = b"".join(ddmin([bytes([b]) for b in inner], reproduces, [min(budget[0], 200)]))
    return wrap(inner)


def _same(pool: Pool, task: dict, data: bytes, signature: str) -> bool:
    return pool.map([dict(task, data=data)])[0].get("signature") == signature


def shrink_case(pool: Pool, case: dict, signature: str, tries: int) -> dict:
    """Fewest faces (then fewest vertices) for which the case still fails."""
    budget = [tries]

    def reproduces(candidates) -> int | None:
        tasks = [{"kind": "geometry", "case": dict(case, faces=c)} for c in candidates]
        for index, result in enumerate(pool.map(tasks)):
            if result.get("signature") == signature:
                return index
        return None

    faces = ddmin(list(case["faces"]), reproduces, budget)
    used = sorted({i for face in faces for i in face})
    remap = {old: new for new, old in enumerate(used)}
    smaller = dict(
        case,
        faces=[[remap[i] for i in face] for face in faces],
        vertices=[case["vertices"][i] for i in used],
    )
    result = pool.map([{"kind": "geometry", "case": smaller}])[0]
    return smaller if result.get("signature") == signature else dict(case, faces=faces)
