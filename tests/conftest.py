"""Shared fixtures for outside material, and the rule that CI runs every test.

``../shared`` (seeds, corpus) sits beside the repository on the project's
machines and CI, not in a user's clone. The node tools (glTF validator, X_ITE)
are installed by ``npm ci --prefix tests/node``. The X3D 4.0 schema is committed
under ``tests/data/x3d-schema``. What is absent skips only the test or
assertion that needs it (see ``needs.py``); with ``SHADOWGEO_REQUIRE_ALL=1``
(set by ``.ci/run``) it fails instead, and a run in which anything skipped
fails at the end, after printing how many tests ran.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import settings
from needs import REQUIRE_ALL, absent, need

# Property tests draw the same examples on every run and machine (a failure in
# CI is one anyone can reproduce), and keep no example database between runs.
settings.register_profile("shadowgeo", derandomize=True, database=None)
settings.load_profile("shadowgeo")

ROOT = Path(__file__).resolve().parents[1]
X3D_SCHEMA = ROOT / "tests" / "data" / "x3d-schema" / "x3d-4.0.xsd.gz"


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """``../shared``, or skip."""
    return need("shared")


@pytest.fixture(scope="session")
def corpus_dir() -> Path:
    """The shared corpus of real X3D scenes, or skip."""
    return need("corpus")


@pytest.fixture(scope="session")
def classic_corpus_dir(shared_dir) -> Path:
    """The shared corpus of ClassicVRML and VRML 97 scenes, or skip."""
    corpus = shared_dir / "corpus" / "castle-demo-models-classic"
    if not corpus.is_dir():
        absent(f"{corpus} is absent")
    return corpus


@pytest.fixture(scope="session")
def pairs_dir(shared_dir) -> Path:
    """The shared corpus of X3D JSON files, each beside its XML twin, or skip."""
    folder = shared_dir / "corpus" / "web3d-json-pairs"
    if not folder.is_dir():
        absent(f"{folder} is absent")
    return folder


@pytest.fixture(scope="session")
def x3d_schema() -> Path:
    """The X3D 4.0 XML Schema (committed, gzipped; lxml reads it as it is)."""
    return X3D_SCHEMA


@pytest.fixture(scope="session")
def node_tools() -> Path:
    """tests/node/node_modules with node on PATH, or skip."""
    return need("gltf-validator").parent


# -- every test ran ----------------------------------------------------------------------

_skipped: list[str] = []


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.skipped and not hasattr(report, "wasxfail"):
        _skipped.append(report.nodeid)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    if REQUIRE_ALL and _skipped and session.exitstatus == pytest.ExitCode.OK:
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_terminal_summary(terminalreporter, exitstatus, config) -> None:
    stats = terminalreporter.stats
    ran = sum(
        1
        for key in ("passed", "failed", "xfailed", "xpassed")
        for report in stats.get(key, [])
        if report.when == "call"
    )
    terminalreporter.write_line(f"shadowgeo: {ran} tests ran, {len(_skipped)} skipped")
    if REQUIRE_ALL and _skipped:
        terminalreporter.write_line(
            "SHADOWGEO_REQUIRE_ALL=1: a skipped test fails the run: " + ", ".join(_skipped[:20]),
            red=True,
        )
