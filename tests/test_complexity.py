"""No function in ``shadowgeo/`` or ``cli/`` is too tangled or too long to
read in one sitting (issue 31): radon's cyclomatic complexity at most
:data:`MAX_COMPLEXITY` for every function and method, and at most
:data:`MAX_LINES` lines of body (from its first statement after the
docstring to its last line, comments and blank lines counted) for every
function, nested ones included. The generated X3D tables are aside.

:data:`KNOWN` lists the functions still over when this test was written,
each with its figure then; the test fails when one outside it goes over,
and when one in it is fixed, so that the list only shrinks (an entry whose
figure falls but stays over is still allowed).
"""

from __future__ import annotations

import ast

import pytest
from needs import ROOT, need

MAX_COMPLEXITY = 15
MAX_LINES = 80
PACKAGES = ("shadowgeo", "cli")
GENERATED = {"shadowgeo/io/x3d/tables.py"}

# (file, function, "complexity" or "lines") -> its figure when this test was
# written; fixed ones are taken out, never new ones put in.
KNOWN: dict[tuple[str, str, str], int] = {}


def modules() -> list[tuple[str, str]]:
    """(path from the repository root, source) of every module checked."""
    found = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            name = path.relative_to(ROOT).as_posix()
            if name not in GENERATED:
                found.append((name, path.read_text(encoding="utf-8")))
    return found


def complexities(source: str) -> dict[str, int]:
    """radon's complexity of every function, method (``Class.method``) and
    nested function (``outer.inner``: radon counts it apart from the one
    holding it) in ``source``."""
    need("radon")
    from radon.complexity import cc_visit
    from radon.visitors import Class

    figures = {}
    waiting = []
    for block in cc_visit(source):
        methods = block.methods if isinstance(block, Class) else [block]
        waiting.extend((method.fullname, method) for method in methods)
    while waiting:
        name, function = waiting.pop()
        figures[name] = max(figures.get(name, 0), function.complexity)
        waiting.extend((f"{name}.{inner.name}", inner) for inner in function.closures)
    return figures


def body_lines(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines from the first statement after the docstring to the end."""
    body = function.body
    first = body[0]
    if (
        isinstance(first, ast.Expr)
        and isinstance(first.value, ast.Constant)
        and isinstance(first.value.value, str)
    ):
        body = body[1:]
    if not body:
        return 0
    return int(function.end_lineno or function.lineno) - body[0].lineno + 1


def lengths(source: str) -> dict[str, int]:
    """The body's lines of every function (``Class.method``,
    ``outer.inner``) in ``source``; of two of one name, the longer."""
    figures: dict[str, int] = {}

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef):
                name = prefix + child.name
                figures[name] = max(figures.get(name, 0), body_lines(child))
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)

    visit(ast.parse(source), "")
    return figures


def over_limits() -> dict[tuple[str, str, str], int]:
    """(file, function, measure) -> figure of every function over a limit."""
    over = {}
    for name, source in modules():
        for function, figure in complexities(source).items():
            if figure > MAX_COMPLEXITY:
                over[(name, function, "complexity")] = figure
        for function, figure in lengths(source).items():
            if figure > MAX_LINES:
                over[(name, function, "lines")] = figure
    return over


@pytest.fixture(scope="module")
def over() -> dict[tuple[str, str, str], int]:
    return over_limits()


def test_no_new_function_over_the_limits(over: dict[tuple[str, str, str], int]) -> None:
    new = {key: figure for key, figure in over.items() if key not in KNOWN}
    assert not new, (
        f"over complexity {MAX_COMPLEXITY} or {MAX_LINES} lines of body; split them into "
        f"named steps: {new}"
    )


def test_known_ones_are_still_over(over: dict[tuple[str, str, str], int]) -> None:
    fixed = sorted(key for key in KNOWN if key not in over)
    assert not fixed, f"within the limits now: take them out of KNOWN: {fixed}"


def test_the_measures_see_what_they_should() -> None:
    source = (
        "class Box:\n"
        "    def method(self, a):\n"
        '        """Doc\n\n        string."""\n'
        "        if a:\n"
        "            return 1\n"
        "        # a comment\n"
        "        return 2\n"
        "def outer(a, b):\n"
        "    def inner():\n"
        "        return a or b\n"
        "    return inner() if a else 0\n"
    )
    assert complexities(source) == {"Box.method": 2, "outer": 2, "outer.inner": 2}
    assert lengths(source) == {"Box.method": 4, "outer": 3, "outer.inner": 1}
