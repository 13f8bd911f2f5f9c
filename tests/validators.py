"""Independent validators the tests run on written files.

Import from any test::

    from validators import gltf_problems, gltf_report, gltf_reports, usd_errors

``gltf_report(path)`` runs the Khronos glTF validator (npm ``gltf-validator``,
through node and ``tests/node/validate_gltf.mjs``) and returns its report;
``gltf_reports(paths)`` does many files in one run of node;
``gltf_problems(report)`` lists its errors (and warnings, if asked) as lines.
``one_triangle_gltf()`` is a minimal valid glTF document written by hand
from the spec, for tests that validate, read or break it.
``usd_errors(path)`` runs every validator usd-core registers
(``pxr.UsdValidation``; ``UsdUtils.ComplianceChecker`` on usd-core older than
24.11) and returns the errors as lines. The glTF validator skips the calling
test at that point when it is not installed (``needs.need``: a failure under
SHADOWGEO_REQUIRE_ALL=1), never passes silently; usd-core is a dependency.
"""

from __future__ import annotations

import base64
import json
import struct
import subprocess
from pathlib import Path

from needs import need

NODE_DIR = Path(__file__).resolve().parent / "node"
GLTF_SCRIPT = NODE_DIR / "validate_gltf.mjs"


def one_triangle_gltf(accessor_count: int = 3) -> dict:
    """A valid glTF with one triangle on node 0 (named ``tri``) and the
    buffer embedded; an ``accessor_count`` other than 3 makes the POSITION
    accessor read past its buffer view, which the validator must report."""
    positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    uri = "data:application/octet-stream;base64," + base64.b64encode(positions).decode()
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tri", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": len(positions), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": len(positions), "target": 34962}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": accessor_count,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            }
        ],
    }


# Severities in the Khronos validator's report.
GLTF_ERROR, GLTF_WARNING, GLTF_INFO, GLTF_HINT = 0, 1, 2, 3


def gltf_report(path) -> dict:
    """The Khronos glTF validator's report on a .gltf or .glb file.

    External buffers of a .gltf are loaded from the file's folder.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    dict
        The validator's JSON report: ``report["issues"]`` has ``numErrors``,
        ``numWarnings``, ``numInfos``, ``numHints`` and ``messages`` (each with
        ``code``, ``message``, ``severity`` 0-3 and ``pointer``);
        ``report["info"]`` summarises the asset.

    Raises
    ------
    RuntimeError
        The validator could not run at all (the file is not glTF or GLB).
    """
    __tracebackhide__ = True  # an absent validator is reported at the test's line
    return gltf_reports([path])[0]


def gltf_reports(paths) -> list[dict]:
    """:func:`gltf_report` for many files in one run of node (it takes about
    half a second to start), in the order given."""
    __tracebackhide__ = True
    need("gltf-validator")
    node = str(need("node"))
    paths = [str(Path(path).resolve()) for path in paths]
    completed = subprocess.run(
        [node, str(GLTF_SCRIPT), *paths],
        capture_output=True,
        text=True,
        timeout=120 + 10 * len(paths),
        cwd=NODE_DIR,
    )
    if completed.returncode != 0:
        raise RuntimeError(f"gltf-validator failed: {completed.stderr.strip()}")
    reports = [json.loads(line) for line in completed.stdout.splitlines() if line.strip()]
    if len(reports) != len(paths):
        raise RuntimeError(f"gltf-validator gave {len(reports)} reports for {len(paths)} files")
    return reports


def gltf_problems(report: dict, *, warnings: bool = True) -> list[str]:
    """The report's errors (and warnings unless ``warnings=False``) as
    ``"CODE at /pointer: message"`` lines; empty for a clean file."""
    worst = GLTF_WARNING if warnings else GLTF_ERROR
    return [
        f"{message['code']} at {message.get('pointer', '')}: {message['message']}"
        for message in report["issues"]["messages"]
        if message["severity"] <= worst
    ]


def usd_errors(path, *, warnings: bool = False) -> list[str]:
    """Errors (and warnings if asked) that usd-core's own validators find in a
    USD file, as ``"Name at </prim>: message"`` lines; empty for a clean file.

    Uses ``pxr.UsdValidation`` (a ``ValidationContext`` over every validator in
    the registry); on usd-core without it, ``UsdUtils.ComplianceChecker``.
    """
    from pxr import Usd

    try:
        from pxr import UsdValidation
    except ImportError:
        return _compliance_errors(path, warnings=warnings)

    stage = Usd.Stage.Open(str(path))
    if stage is None:
        return [f"usd-core cannot open {path}"]
    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    kinds = {UsdValidation.ValidationErrorType.Error}
    if warnings:
        kinds.add(UsdValidation.ValidationErrorType.Warn)
    lines = []
    for error in context.Validate(stage):
        if error.GetType() not in kinds:
            continue
        sites = ", ".join(str(site.GetPrim().GetPath()) for site in error.GetSites())
        lines.append(f"{error.GetName()} at <{sites}>: {error.GetMessage()}")
    return lines


def _compliance_errors(path, *, warnings: bool) -> list[str]:
    from pxr import UsdUtils

    if not hasattr(UsdUtils, "ComplianceChecker"):
        raise RuntimeError("this usd-core has neither UsdValidation nor UsdUtils.ComplianceChecker")
    checker = UsdUtils.ComplianceChecker()
    checker.CheckCompliance(str(path))
    lines = list(checker.GetErrors()) + list(checker.GetFailedChecks())
    if warnings:
        lines += list(checker.GetWarnings())
    return [str(line) for line in lines]
