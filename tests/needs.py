"""Outside tools and files some assertions need, and what happens without them.

Import from any test::

    from needs import absent, need

``need(tool)`` returns the tool's path; when the tool is absent it skips the
calling test *at that point*, with a reason saying how to install it. Call it
just before the one assertion that needs the tool, after the behaviour has been
checked, so a missing validator never hides a broken writer.

With ``SHADOWGEO_REQUIRE_ALL=1`` (``.ci/run`` sets it) an absent tool fails the
test instead, and ``conftest.py`` fails the run if anything skipped at all: a
green CI run means every test ran.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
NODE_MODULES = ROOT / "tests" / "node" / "node_modules"
REQUIRE_ALL = os.environ.get("SHADOWGEO_REQUIRE_ALL", "") == "1"


def absent(reason: str) -> NoReturn:
    """Skip the calling test here with ``reason``; fail it under SHADOWGEO_REQUIRE_ALL=1."""
    __tracebackhide__ = True  # report the test's line, not this one
    if REQUIRE_ALL:
        pytest.fail(f"{reason} (SHADOWGEO_REQUIRE_ALL=1: every test must run)", pytrace=False)
    pytest.skip(reason)


def _executable(*names: str) -> Callable[[], Path | None]:
    def find() -> Path | None:
        for name in names:
            found = shutil.which(name)
            if found:
                return Path(found)
        return None

    return find


def _module(name: str) -> Callable[[], Path | None]:
    def find() -> Path | None:
        spec = importlib.util.find_spec(name)
        return Path(spec.origin) if spec is not None and spec.origin else None

    return find


def _existing(path: Path) -> Callable[[], Path | None]:
    return lambda: path if path.exists() else None


def _node_package(name: str) -> Callable[[], Path | None]:
    def find() -> Path | None:
        if shutil.which("node") is None:
            return None
        package = NODE_MODULES / name
        return package if package.is_dir() else None

    return find


NPM = "run npm ci --prefix tests/node (needs node and npm)"

# tool -> (finder, how to get it)
TOOLS: dict[str, tuple[Callable[[], Path | None], str]] = {
    "shared": (
        _existing(SHARED),
        f"{SHARED} is absent (it exists on the project's machines and CI, not in a clone)",
    ),
    "corpus": (
        _existing(SHARED / "corpus" / "castle-demo-models"),
        f"the corpus {SHARED / 'corpus' / 'castle-demo-models'} is absent "
        "(it exists on the project's machines and CI, not in a clone)",
    ),
    "node": (_executable("node"), "node is not installed (apt-get install nodejs)"),
    "gltf-validator": (_node_package("gltf-validator"), f"gltf-validator is not installed: {NPM}"),
    "x_ite": (_node_package("x_ite"), f"X_ITE is not installed: {NPM}"),
    "chromium": (
        _executable("chromium", "chromium-browser"),
        "Chromium is not installed (apt-get install chromium; .ci/run does)",
    ),
    "mypy": (_module("mypy"), 'mypy is not installed: pip install ".[test]"'),
    "radon": (_module("radon"), 'radon is not installed: pip install ".[test]"'),
    "dask": (_module("distributed"), 'Dask is not installed: pip install ".[dask]"'),
    "shadowgeo-script": (
        _executable("shadowgeo"),
        'the shadowgeo console script is not on PATH: pip install ".[test]"',
    ),
}


def need(tool: str) -> Path:
    """The path of ``tool`` (a key of :data:`TOOLS`), or :func:`absent`."""
    __tracebackhide__ = True
    find, how = TOOLS[tool]
    found = find()
    if found is None:
        absent(how)
    return found
