"""The skip rule itself: an absent tool skips only where it is needed, and under
SHADOWGEO_REQUIRE_ALL=1 (CI) it fails, as does a run in which anything skipped.

Each case runs pytest in a child process on a small suite that uses this
directory's real ``conftest.py`` and ``needs.py``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

SUITE = """
import pytest
import needs
from needs import need

needs.TOOLS["nothing"] = (lambda: None, "nothing is installed: apt-get install nothing")
checked = []


def test_passes():
    assert True


def test_behaviour_then_a_missing_tool():
    checked.append("behaviour")
    assert 1 + 1 == 2
    need("nothing")
    raise AssertionError("need() returned for an absent tool")


def test_the_behaviour_before_the_tool_ran():
    assert checked == ["behaviour"]


def test_a_plain_skip():
    pytest.skip("skipped without need()")
"""


def run_suite(
    tmp_path: Path, require_all: bool, suite: str = SUITE
) -> subprocess.CompletedProcess[str]:
    for name in ("conftest.py", "needs.py"):
        shutil.copy(HERE / name, tmp_path / name)
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "test_suite.py").write_text(suite)
    env = {k: v for k, v in os.environ.items() if k != "SHADOWGEO_REQUIRE_ALL"}
    if require_all:
        env["SHADOWGEO_REQUIRE_ALL"] = "1"
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", "test_suite.py"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_an_absent_tool_skips_at_the_assertion_with_its_reason(tmp_path):
    done = run_suite(tmp_path, require_all=False)
    assert done.returncode == 0, done.stdout
    assert "2 passed, 2 skipped" in done.stdout
    assert "nothing is installed: apt-get install nothing" in done.stdout
    assert "shadowgeo: 2 tests ran, 2 skipped" in done.stdout


def test_in_ci_an_absent_tool_fails_and_any_skip_fails_the_run(tmp_path):
    done = run_suite(tmp_path, require_all=True)
    assert done.returncode == 1, done.stdout
    assert "1 failed, 2 passed, 1 skipped" in done.stdout
    assert "nothing is installed" in done.stdout and "SHADOWGEO_REQUIRE_ALL=1" in done.stdout
    assert "shadowgeo: 3 tests ran, 1 skipped" in done.stdout
    assert "a skipped test fails the run: test_suite.py::test_a_plain_skip" in done.stdout


def test_in_ci_a_run_with_nothing_skipped_passes(tmp_path):
    done = run_suite(tmp_path, require_all=True, suite="def test_passes():\n    assert True\n")
    assert done.returncode == 0, done.stdout
    assert "shadowgeo: 1 tests ran, 0 skipped" in done.stdout
