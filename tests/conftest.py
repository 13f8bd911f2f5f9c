"""Shared fixtures: where the optional outside material lives.

``../shared`` (seeds, corpus, X3D schema) sits beside the repository on the
project's machines and CI, not in a user's clone; tests that need it skip with
a reason when it is absent. The node tools (glTF validator, X_ITE) are
installed by ``npm ci --prefix tests/node``; tests that need them skip when
they are not installed.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
NODE_TOOLS = ROOT / "tests" / "node" / "node_modules"


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """``../shared``, or skip."""
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent (it exists on the project's machines, not in a clone)")
    return SHARED


@pytest.fixture(scope="session")
def corpus_dir(shared_dir) -> Path:
    """The shared corpus of real X3D scenes, or skip."""
    corpus = shared_dir / "corpus" / "castle-demo-models"
    if not corpus.is_dir():
        pytest.skip(f"{corpus} is absent")
    return corpus


@pytest.fixture(scope="session")
def classic_corpus_dir(shared_dir) -> Path:
    """The shared corpus of ClassicVRML and VRML 97 scenes, or skip."""
    corpus = shared_dir / "corpus" / "castle-demo-models-classic"
    if not corpus.is_dir():
        pytest.skip(f"{corpus} is absent")
    return corpus


@pytest.fixture(scope="session")
def x3d_schema(shared_dir) -> Path:
    """The X3D 4.0 XML Schema file, or skip."""
    schema = shared_dir / "schemas" / "x3d" / "x3d-4.0.xsd"
    if not schema.is_file():
        pytest.skip(f"{schema} is absent")
    return schema


@pytest.fixture(scope="session")
def node_tools() -> Path:
    """tests/node/node_modules with node on PATH, or skip."""
    if shutil.which("node") is None:
        pytest.skip("node is not installed")
    if not NODE_TOOLS.is_dir():
        pytest.skip("node tools are not installed: run npm ci --prefix tests/node")
    return NODE_TOOLS
