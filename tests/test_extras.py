"""Optional packages: whatever shadowgeo imports lazily is a dependency or an
extra, and a missing extra gives one line naming it."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from pathlib import Path

import pytest
import trimesh

import shadowgeo as sg

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
# Import name -> the distribution that provides it, where the two differ.
DISTRIBUTION = {"pxr": "usd-core", "vtk": "pyvista", "DracoPy": "DracoPy"}
# Extras for development only: the library must not need them.
DEVELOPMENT = {"test", "bench"}


def requirement_names(requirements: list[str]) -> set[str]:
    return {re.split(r"[\s<>=!~;\[]", requirement)[0].lower() for requirement in requirements}


def lazy_imports() -> dict[str, list[str]]:
    """Top-level module -> 'file:line' of every import inside a function of shadowgeo."""
    found: dict[str, list[str]] = {}
    for path in sorted((ROOT / "shadowgeo").rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for function in ast.walk(tree):
            if not isinstance(function, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            for node in ast.walk(function):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    top = name.split(".")[0]
                    place = f"{path.relative_to(ROOT)}:{node.lineno}"
                    found.setdefault(top, []).append(place)
    return found


def test_every_lazy_import_is_a_dependency_or_a_user_extra():
    dependencies = requirement_names(PROJECT["dependencies"])
    extras = {
        name: requirement_names(requirements)
        for name, requirements in PROJECT["optional-dependencies"].items()
        if name not in DEVELOPMENT
    }
    imports = lazy_imports()
    assert "shapely" in imports and "pyvista" in imports  # the scan sees function bodies
    for module, places in imports.items():
        if module in sys.stdlib_module_names or module == "shadowgeo":
            continue
        distribution = DISTRIBUTION.get(module, module).lower()
        declared = distribution in dependencies or any(
            distribution in names for names in extras.values()
        )
        assert declared, f"{module} (imported at {places}) is neither a dependency nor an extra"


def module_imports() -> dict[str, list[str]]:
    """Top-level module -> 'file:line' of every import at a module's top level
    (outside functions and ``if TYPE_CHECKING:``) in shadowgeo and cli."""
    found: dict[str, list[str]] = {}
    for path in sorted([*(ROOT / "shadowgeo").rglob("*.py"), *(ROOT / "cli").rglob("*.py")]):
        tree = ast.parse(path.read_text(), str(path))
        for node in tree.body:
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                found.setdefault(name.split(".")[0], []).append(f"{path.name}:{node.lineno}")
    return found


def test_every_module_level_import_is_a_dependency():
    # A plain `pip install shadowgeo` must be able to `import shadowgeo`.
    dependencies = requirement_names(PROJECT["dependencies"])
    imports = module_imports()
    assert "numpy" in imports and "shapely" in imports
    for module, places in imports.items():
        if module in sys.stdlib_module_names or module in ("shadowgeo", "cli", "__future__"):
            continue
        distribution = DISTRIBUTION.get(module, module).lower()
        assert distribution in dependencies, f"{module} (at {places}) is not a dependency"


def test_to_shapely_gives_the_region():
    shadow = sg.project_shadow(
        trimesh.creation.box(bounds=[[-0.5, 1, -0.5], [0.5, 2, 0.5]]),
        sg.PointLight([0.0, 5.0, 0.0]),
        sg.Plane([0.0, 1.0, 0.0], 0.0),
    )
    assert shadow.to_shapely().area == pytest.approx(shadow.area)


def test_the_extras_named_in_messages_exist():
    extras = PROJECT["optional-dependencies"]
    assert requirement_names(extras["sun"]) == {"astral"}
    assert requirement_names(extras["dask"]) == {"dask"}
    assert requirement_names(extras["draco"]) == {"dracopy"}
