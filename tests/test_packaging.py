"""The wheel holds every package of the source tree.

``pyproject.toml`` lists the packages by name, so a new subpackage left out
of the list installs without its modules: an editable install and the tests
run from the tree would not notice, a user's ``pip install .`` would fail on
import (``shadowgeo.plane2d`` did once, caught only by the entry-point test
in a fresh virtual environment).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _listed() -> set[str]:
    settings = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    return set(settings["packages"])


def _in_tree() -> set[str]:
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for init in (ROOT / "shadowgeo").rglob("__init__.py")
        if "__pycache__" not in init.parts
    }
    if (ROOT / "cli" / "__init__.py").is_file():
        found.add("shadowgeo_cli")  # cli/ installs as shadowgeo_cli (package-dir)
    return found


def test_every_package_of_the_tree_is_in_the_wheel():
    missing = _in_tree() - _listed()
    assert not missing, f"pyproject.toml [tool.setuptools] packages lacks {sorted(missing)}"


def test_every_listed_package_exists():
    extra = _listed() - _in_tree()
    assert not extra, f"pyproject.toml lists packages the tree does not have: {sorted(extra)}"
