"""Validate X3D JSON files against the X3D 4.0 JSON schema with jsonschema.

The schema is draft 2020-12, where ``format`` is only an annotation unless
the validator asserts it; we assert its two formats, ``iri`` (the schema
location) and ``iri-reference`` (every url), with RFC 3987's characters:
jsonschema's own checker for them needs rfc3987 (GPL). The validator is built
once per schema file and kept for the session.
"""

from __future__ import annotations

import functools
import json
import re
from pathlib import Path

# Characters no IRI holds (RFC 3987: outside ucschar, iprivate and the ASCII it allows).
IRI_FORBIDDEN = re.compile(r'[\x00-\x20"<>\\^`{|}\x7f-\x9f]')
IRI_SCHEME = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*:")


def iri_reference(text) -> bool:
    """Whether ``text`` is an IRI reference (RFC 3987's characters, ``%XX`` escapes)."""
    if not isinstance(text, str):
        return True
    percent_ok = all(re.fullmatch(r"%[0-9A-Fa-f]{2}", m) for m in re.findall(r"%..?", text))
    return IRI_FORBIDDEN.search(text) is None and percent_ok


@functools.cache
def json_validator(schema_path: str):
    """A jsonschema validator of the schema at ``schema_path`` asserting ``iri``
    and ``iri-reference``."""
    import jsonschema

    schema = json.loads(Path(schema_path).read_text())
    validator = jsonschema.validators.validator_for(schema)
    validator.check_schema(schema)
    formats = jsonschema.FormatChecker()
    formats.checks("iri-reference")(iri_reference)
    formats.checks("iri")(lambda text: iri_reference(text) and IRI_SCHEME.match(text) is not None)
    return validator(schema, format_checker=formats)


def json_schema_errors(validator, path) -> list[str]:
    """Every schema error of the JSON file at ``path`` as ``"pointer: message"``
    (empty when the file is valid); ``validator`` from :func:`json_validator`."""
    errors = validator.iter_errors(json.loads(Path(path).read_text(encoding="utf-8")))
    return [f"{'/'.join(map(str, error.absolute_path))}: {error.message[:200]}" for error in errors]
