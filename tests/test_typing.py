"""The library and its command line type-check: ``mypy --strict`` (the
configuration in pyproject.toml) finds nothing in ``shadowgeo/`` or ``cli/``.

Running it here puts the check under the README's one test command, so CI
fails on a type error as it fails on a wrong area.
"""

from __future__ import annotations

import subprocess
import sys

from needs import ROOT, need

# The library, and the command line over it: its calls into the library are
# checked against the library's hints.
PACKAGES = ("shadowgeo", "cli")


def test_mypy_strict_is_clean() -> None:
    need("mypy")
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-color-output", *PACKAGES],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, f"mypy {' '.join(PACKAGES)} failed:\n{output}"
    assert "Success: no issues found" in output, output
