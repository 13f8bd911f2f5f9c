"""Validate X3D XML files against the X3D 4.0 XML Schema with lxml.

The schema takes about 2 s to parse, so it is parsed once per schema file and
kept for the session. Documents are parsed safely (no DTD loading, no entity
expansion, no network), ``.x3dz`` files are un-gzipped first.
"""

from __future__ import annotations

import functools
import gzip
import re
from collections import Counter
from pathlib import Path

from lxml import etree

_SAFE = dict(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False)


@functools.cache
def _schema(schema_path: str) -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(schema_path))


def x3d_schema_errors(path, schema_path) -> list[str]:
    """Every schema error of the X3D file at ``path``, as ``"line N: message"``
    (empty when the file is valid)."""
    data = Path(path).read_bytes()
    if data[:2] == b"\x1f\x8b":
        data = gzip.decompress(data)
    document = etree.fromstring(data, etree.XMLParser(**_SAFE)).getroottree()
    schema = _schema(str(schema_path))
    if schema.validate(document):
        return []
    return [f"line {error.line}: {error.message}" for error in schema.error_log]


def new_schema_errors(before: list[str], after: list[str]) -> list[str]:
    """Errors of ``after`` that ``before`` does not have, comparing messages
    without their line numbers and counting repeats."""

    def key(error: str) -> str:
        return re.sub(r"^line \d+: ", "", error)

    left = Counter(key(error) for error in before)
    new = []
    for error in after:
        if left[key(error)] > 0:
            left[key(error)] -= 1
        else:
            new.append(error)
    return new
