"""No import cycles: the modules of ``shadowgeo`` and ``cli`` (and of the
fuzzer, ``tools/fuzz/``) form a graph without loops, read from the source.

A cycle means two modules each need the other to be read first: which one
Python finishes depends on who is imported first, and a name used at import
time turns up missing (issue 31 found ``polygons`` with ``sweep`` and
``seams``, and ``cli/convert.py`` with ``cli/batch.py``). The graph counts
every ``import`` and ``from ... import``, relative ones resolved, at any depth
(inside functions too: a deferred import still ties the two modules in one
knot, only a later one), except under ``if TYPE_CHECKING:``, which never runs.

``from package import name`` is an edge to ``package.name`` when that is a
module, else to ``package`` (its ``__init__``). A module's own package
``__init__`` runs before it whatever it imports, so that implied edge is not
drawn; an explicit ``import shadowgeo`` or ``from shadowgeo import X`` from
inside the package is, and closes a loop with the re-exports there.
Imports by computed name (``importlib.import_module``, as ``cli/main.py``
loads the commands) are not seen.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest
from needs import ROOT

# Import name -> source folder, for the names its modules go by in the source
# (``cli`` is installed as ``shadowgeo_cli``, but imports inside it are
# relative); and the fuzzer's package, which tools/fuzz.py imports as ``fuzz``.
PACKAGES = {"shadowgeo": ROOT / "shadowgeo", "cli": ROOT / "cli", "fuzz": ROOT / "tools" / "fuzz"}


def module_files(packages: Mapping[str, Path]) -> dict[str, Path]:
    """Dotted module name -> source file, for every ``.py`` under each package."""
    modules: dict[str, Path] = {}
    for name, folder in packages.items():
        for path in sorted(folder.rglob("*.py")):
            parts = [name, *path.relative_to(folder).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts.pop()
            modules[".".join(parts)] = path
    return modules


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _import_nodes(node: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement under ``node`` that can run: ``if TYPE_CHECKING:``
    bodies left out (their ``else:`` kept)."""
    if isinstance(node, ast.Import | ast.ImportFrom):
        yield node
        return
    if isinstance(node, ast.If) and _is_type_checking(node.test):
        children: list[ast.AST] = list(node.orelse)
    else:
        children = list(ast.iter_child_nodes(node))
    for child in children:
        yield from _import_nodes(child)


def _within(name: str, modules: Mapping[str, Path]) -> str | None:
    """``name`` or its nearest enclosing module that is one of ``modules``."""
    parts = name.split(".")
    while parts:
        candidate = ".".join(parts)
        if candidate in modules:
            return candidate
        parts.pop()
    return None


def imported_modules(module: str, path: Path, modules: Mapping[str, Path]) -> set[str]:
    """The modules of ``modules`` that ``module`` (source ``path``) imports."""
    is_package = path.name == "__init__.py"
    found: set[str] = set()
    for node in _import_nodes(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        else:
            if node.level:
                # The package a relative import starts from: the module's own
                # package for level 1, one up for each further dot.
                base = module.split(".")
                drop = node.level - 1 if is_package else node.level
                if drop > len(base) - 1:
                    raise ValueError(f"{path}: relative import beyond the top package")
                base = base[: len(base) - drop]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            # ``a.b``: the module ``b`` of package ``a``, or else (a name
            # defined in ``a``, or ``*``) ``a`` itself, as _within finds.
            targets = [f"{source}.{alias.name}" for alias in node.names]
        for target in targets:
            resolved = _within(target, modules)
            if resolved is not None:
                found.add(resolved)
    return found


def import_graph(packages: Mapping[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules it imports, over every module under ``packages``."""
    modules = module_files(packages)
    return {name: imported_modules(name, path, modules) for name, path in modules.items()}


def knots(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module, each sorted:
    every module in one can reach every other, so each is in a cycle."""
    index: dict[str, int] = {}
    lowlink: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def connect(start: str) -> None:
        # Tarjan's algorithm, iterative: the graph's depth is not Python's limit.
        work: list[tuple[str, Iterator[str]]] = [(start, iter(sorted(graph.get(start, ()))))]
        index[start] = lowlink[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, successors = work[-1]
            advanced = False
            for successor in successors:
                if successor not in index:
                    index[successor] = lowlink[successor] = len(index)
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(sorted(graph.get(successor, ())))))
                    advanced = True
                    break
                if successor in on_stack:
                    lowlink[node] = min(lowlink[node], index[successor])
            if advanced:
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                lowlink[parent] = min(lowlink[parent], lowlink[node])
            if lowlink[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    components.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            connect(node)
    return sorted(components)


def loop_in(component: list[str], graph: Mapping[str, set[str]]) -> list[str]:
    """The shortest loop through the component's first module (breadth first)."""
    members = set(component)
    start = component[0]
    came_from: dict[str, str] = {}
    frontier = [start]
    while frontier:
        following: list[str] = []
        for node in frontier:
            for successor in sorted(graph[node] & members):
                if successor == start:
                    path = [node]
                    while path[-1] != start:
                        path.append(came_from[path[-1]])
                    return [*reversed(path), start]
                if successor not in came_from:
                    came_from[successor] = node
                    following.append(successor)
        frontier = following
    raise AssertionError(f"no loop through {start} in {component}")  # cannot happen


# -- the graph reader on packages written here --------------------------------------------


def _write(root: Path, files: Mapping[str, str]) -> None:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def test_reader_resolves_each_kind_of_import(tmp_path: Path) -> None:
    _write(
        tmp_path,
        {
            "pkg/__init__.py": "from .a import thing\n",
            "pkg/a.py": "import pkg.sub.c\nfrom pkg import b\n",
            "pkg/b.py": "from .sub import c\nfrom . import a as alias\nfrom .sub import *\n",
            "pkg/sub/__init__.py": "",
            "pkg/sub/c.py": "from ..b import name\nfrom .. import thing\nimport os\n",
            "pkg/sub/d.py": "def late():\n    from . import c\n",
        },
    )
    graph = import_graph({"pkg": tmp_path / "pkg"})
    assert graph == {
        "pkg": {"pkg.a"},
        "pkg.a": {"pkg.sub.c", "pkg.b"},
        "pkg.b": {"pkg.sub.c", "pkg.a", "pkg.sub"},
        "pkg.sub": set(),
        "pkg.sub.c": {"pkg.b", "pkg"},
        "pkg.sub.d": {"pkg.sub.c"},
    }


def test_reader_refuses_a_relative_import_above_the_package(tmp_path: Path) -> None:
    _write(tmp_path, {"pkg/__init__.py": "", "pkg/a.py": "from .. import other\n"})
    with pytest.raises(ValueError, match="beyond the top package"):
        import_graph({"pkg": tmp_path / "pkg"})


def test_reader_leaves_out_type_checking_imports(tmp_path: Path) -> None:
    _write(
        tmp_path,
        {
            "pkg/__init__.py": "",
            "pkg/a.py": "from typing import TYPE_CHECKING\n"
            "if TYPE_CHECKING:\n    from .b import B\nelse:\n    from .c import C\n",
            "pkg/b.py": "import typing\nif typing.TYPE_CHECKING:\n    from . import a\n",
            "pkg/c.py": "",
        },
    )
    assert import_graph({"pkg": tmp_path / "pkg"})["pkg.a"] == {"pkg.c"}
    assert import_graph({"pkg": tmp_path / "pkg"})["pkg.b"] == set()


def test_cycles_reports_each_knot_once_as_a_loop() -> None:
    graph = {
        "a": {"b"},
        "b": {"c"},
        "c": {"a", "d"},
        "d": set(),
        "e": {"f"},
        "f": {"e"},
        "g": {"a"},
    }
    assert knots(graph) == [["a", "b", "c"], ["e", "f"]]
    assert [loop_in(knot, graph) for knot in knots(graph)] == [
        ["a", "b", "c", "a"],
        ["e", "f", "e"],
    ]
    # Two loops through one module make one knot; the shortest loop is shown.
    graph = {"p": {"s", "w"}, "s": {"p"}, "w": {"s"}}
    assert knots(graph) == [["p", "s", "w"]]
    assert loop_in(["p", "s", "w"], graph) == ["p", "s", "p"]
    assert knots({"a": {"b"}, "b": {"c"}, "c": set()}) == []


# -- the project ---------------------------------------------------------------------------


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_package_has_modules(package: str) -> None:
    # The check below passes vacuously on an empty graph; make sure it is not one.
    modules = [name for name in module_files(PACKAGES) if name.split(".")[0] == package]
    assert len(modules) > 5, modules


def test_no_import_cycles() -> None:
    graph = import_graph(PACKAGES)
    report = []
    for knot in knots(graph):
        report.append(f"cycle {' -> '.join(loop_in(knot, graph))}; the whole knot:")
        members = set(knot)
        report += [
            f"  {module} imports {', '.join(sorted(graph[module] & members))}" for module in knot
        ]
    assert not report, "import cycles:\n" + "\n".join(report)
