"""Every epsilon is named in one of two places (issue 31): scene-scaled ones in
``shadowgeo/tolerance.py``, fixed numeric guards in ``shadowgeo/limits.py``,
each with a comment saying what it guards. Elsewhere in ``shadowgeo/`` a
number literal below 1e-6 is a bare epsilon, and this test names where.

Numbers are read as Python's tokenizer sees them, so ``1e-9`` in a docstring
or a comment (prose, doctest output) is not one; ``1.0e-9``, ``0.0000001``
and ``1E-9`` in code are.
"""

from __future__ import annotations

import ast
import io
import tokenize

from needs import ROOT

PACKAGE = ROOT / "shadowgeo"
# Where epsilons are named, and tables generated from the X3D schemas (their
# numbers are the schema's, not thresholds).
NAMED = {PACKAGE / "tolerance.py", PACKAGE / "limits.py"}
GENERATED = {PACKAGE / "io" / "x3d" / "tables.py"}
SMALLEST_PLAIN = 1e-6


def small_literals(source: str) -> list[tuple[int, str]]:
    """(line, text) of every number literal in ``source`` that is > 0 and
    below :data:`SMALLEST_PLAIN` (strings and comments are not numbers)."""
    found = []
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type != tokenize.NUMBER:
            continue
        text = token.string.replace("_", "").lower()
        if text.endswith("j") or text.startswith(("0x", "0o", "0b")):
            continue
        value = float(text)
        if 0.0 < value < SMALLEST_PLAIN:
            found.append((token.start[0], token.string))
    return found


def test_the_scan_sees_numbers_not_prose():
    source = (
        '"""A doctest prints 1e-9."""\n'
        "x = 1e-3  # a comment says 1e-12\n"
        "y = 1.0E-10 + 0.0000001 - 2e-300\n"
        "z = '1e-9' + f'{1e-7}'\n"
        "w = 1e-6 + 0x1 + 3j\n"
    )
    found = small_literals(source)
    assert [text for _, text in found[:3]] == ["1.0E-10", "0.0000001", "2e-300"]
    # an f-string's expression is code: tokenized as a number on 3.12+, inside
    # the string token before
    assert [text for _, text in found[3:]] in ([], ["1e-7"])


def test_no_bare_epsilon_outside_tolerance_and_limits():
    bare = [
        f"{path.relative_to(ROOT)}:{line}: {text}"
        for path in sorted(PACKAGE.rglob("*.py"))
        if path not in NAMED | GENERATED
        for line, text in small_literals(path.read_text(encoding="utf-8"))
    ]
    assert not bare, "name these in shadowgeo/limits.py or tolerance.py:\n" + "\n".join(bare)


def test_each_guard_in_limits_says_what_it_guards():
    """A module-level constant of limits.py below 1e-6 has a comment just
    above it (or is described in the module docstring)."""
    path = PACKAGE / "limits.py"
    source = path.read_text(encoding="utf-8")
    lines = source.splitlines()
    module = ast.parse(source)
    docstring = ast.get_docstring(module) or ""
    guards = []
    for node in module.body:
        if not (isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant)):
            continue
        value = node.value.value
        if isinstance(value, float) and 0.0 < value < SMALLEST_PLAIN:
            names = [target.id for target in node.targets if isinstance(target, ast.Name)]
            guards.append(names[0])
            above = lines[node.lineno - 2].lstrip()
            assert above.startswith("#") or f"``{names[0]}" in docstring, names[0]
    assert {"TINY", "RELATIVE_ROUNDING", "PRODUCT_ROUNDING"} <= set(guards)
