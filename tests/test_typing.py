"""The library type-checks: ``mypy --strict`` (the configuration in
pyproject.toml) finds nothing in ``shadowgeo/``.

Running it here puts the check under the README's one test command, so CI
fails on a type error as it fails on a wrong area.
"""

from __future__ import annotations

import subprocess
import sys

from needs import ROOT, need


def test_mypy_strict_is_clean() -> None:
    need("mypy")
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-color-output", "shadowgeo"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, f"mypy shadowgeo failed:\n{output}"
    assert "Success: no issues found" in output, output
