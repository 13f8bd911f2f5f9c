"""The public API is what ``shadowgeo.__all__`` says (issue 31): every module
marks what it exports (``__all__``, or a leading underscore for a private
module), modules import from one another only what those lists export, and
the package's list is the README's "Public API" table, name for name."""

from __future__ import annotations

import ast
import importlib
import re
import types
from collections.abc import Iterator
from pathlib import Path

import pytest
from needs import ROOT

import shadowgeo

PACKAGES = {"shadowgeo": ROOT / "shadowgeo", "cli": ROOT / "cli"}


def modules(folder: Path, package: str) -> Iterator[tuple[str, Path]]:
    """(dotted name, source) of every module under ``folder``."""
    for path in sorted(folder.rglob("*.py")):
        parts = [package, *path.relative_to(folder).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        yield ".".join(parts), path


def _declares_all(tree: ast.Module) -> bool:
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else []
        if isinstance(node, ast.AnnAssign):
            targets = [node.target]
        if any(isinstance(target, ast.Name) and target.id == "__all__" for target in targets):
            return True
    return False


LIBRARY = list(modules(PACKAGES["shadowgeo"], "shadowgeo"))


@pytest.mark.parametrize("name, path", LIBRARY, ids=[name for name, _ in LIBRARY])
def test_every_module_says_what_it_exports(name, path):
    private = any(part.startswith("_") for part in name.split(".")[1:])
    assert private or _declares_all(ast.parse(path.read_text(encoding="utf-8"))), (
        f"{path.relative_to(ROOT)}: give it __all__, or a name with a leading underscore"
    )
    module = importlib.import_module(name)
    exported = getattr(module, "__all__", [])
    assert len(set(exported)) == len(exported), f"{name}.__all__ lists a name twice"
    missing = [item for item in exported if not hasattr(module, item)]
    assert not missing, f"{name}.__all__ lists names it does not have: {missing}"


def _imported_names(module: str, path: Path) -> Iterator[tuple[int, str, str]]:
    """(line, module, name) of each ``from module import name`` in ``path``
    that names a module of ``shadowgeo`` (relative imports resolved)."""
    here = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = here[: len(here) - node.level + 1]
            target = ".".join(base + ([node.module] if node.module else []))
        else:
            target = node.module or ""
        if target.split(".")[0] == "shadowgeo":
            for alias in node.names:
                yield node.lineno, target, alias.name


def _is_module(name: str) -> bool:
    try:
        importlib.import_module(name)
    except ImportError:
        return False
    return True


def test_modules_import_from_one_another_only_what_is_exported():
    """An ``__all__`` means something only if it is kept: a name another
    module needs is in its list (or the import names a submodule)."""
    unlisted = []
    for package, folder in PACKAGES.items():
        for module, path in modules(folder, package):
            for line, target, name in _imported_names(module, path):
                exported = getattr(importlib.import_module(target), "__all__", None)
                if exported is None or name in exported or name.startswith("__"):
                    continue
                if not _is_module(f"{target}.{name}"):
                    unlisted.append(f"{path.relative_to(ROOT)}:{line}: {target}.{name}")
    assert not unlisted, "imported but not in the module's __all__:\n" + "\n".join(unlisted)


def test_the_package_exports_its_public_api_and_nothing_else():
    bound = {
        name
        for name, value in vars(shadowgeo).items()
        if not name.startswith("_")
        and not isinstance(value, types.ModuleType)
        and name != "annotations"  # from __future__
    }
    assert sorted(shadowgeo.__all__) == sorted(bound)
    for name in shadowgeo.__all__:
        scope: dict[str, object] = {}
        exec(f"from shadowgeo import {name}", scope)  # each importable by name
        assert scope[name] is getattr(shadowgeo, name)


def test_the_readme_lists_the_public_api_name_for_name():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("### Public API", 1)[1].split("\n#", 1)[0]
    table = "\n".join(line for line in section.splitlines() if line.startswith("|"))
    listed = re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)`", table)
    assert len(listed) == len(set(listed))
    assert sorted(listed) == sorted(shadowgeo.__all__)
