"""The golden record (tests/data/golden/manifest.json, written by tools/golden.py
before issue 31's rewrite) still holds for a subset of its geometry cases: the
pyramid, each kind of light on a small mesh through every call, the many-lights
path, a shadow on a surface with self-shadowing. The same area repr and the same
bytes of every array, or the test fails naming what changed: a change to these
results must be explained and the manifest recorded again. Conversion bytes are
left to ``python tools/golden.py compare`` (other work may change them)."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
import shapely

ROOT = Path(__file__).resolve().parents[1]
MANIFEST = ROOT / "tests" / "data" / "golden" / "manifest.json"

SUBSET = [
    "shadow/pyramid/point/project_shadow",
    *(
        f"shadow/icosphere/{light}/{call}"
        for light in ("point", "spot", "directional")
        for call in ("project_shadow", "shadow_on_surface", "shadow_volume", "silhouette")
    ),
    "shadow/icosphere/all/project_shadow",
    "shadow/torus/spot/self_shadow",
    "shadow/terrain/directional/shadow_on_surface",
    "shadow/terrain-open/point/project_shadow",
]


def tool(name: str) -> ModuleType:
    """A module of tools/golden/ (tools/ is not a package)."""
    folder = str(ROOT / "tools")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module(f"golden.{name}")


@pytest.fixture(scope="module")
def manifest() -> dict:
    return json.loads(MANIFEST.read_text())


@pytest.fixture(scope="module")
def geometry_cases() -> dict:
    return {case.id: case for case in tool("geometry").cases()}


def test_manifest_is_of_a_clean_commit(manifest):
    assert not manifest["commit"]["dirty"]
    assert len(manifest["commit"]["head"]) == 40
    assert manifest["nondeterministic"] == []


@pytest.mark.parametrize("case_id", SUBSET)
def test_geometry_case_as_recorded(case_id, manifest, geometry_cases, tmp_path):
    recorded = manifest["cases"][case_id]
    result = geometry_cases[case_id].run(tmp_path)
    assert "error" not in result.record, result.record["error"]
    now = {"what": recorded["what"], **result.record}
    compare = tool("manifest")
    assert compare.same(recorded, now), compare.difference(recorded, now)


def test_pyramid_record_is_the_hull_of_the_hand_derived_corners(manifest, geometry_cases, tmp_path):
    # examples/pyramid.py: the shadow is the hull of these corners on y = 0
    corners = [(-7, -6.5), (-1, -6.5), (-4, -2), (-10, -12.5)]  # (x, z)
    hull = shapely.convex_hull(shapely.MultiPoint(corners))
    recorded = float(manifest["cases"]["shadow/pyramid/point/project_shadow"]["area"])
    assert recorded == pytest.approx(hull.area, rel=1e-12)
    result = geometry_cases["shadow/pyramid/point/project_shadow"].run(tmp_path)
    points = result.arrays["polygons.points"]  # plane 2-D on y = 0: (x, -z)
    outline = sorted((round(u, 9) + 0.0, round(-v, 9) + 0.0) for u, v in points.tolist())
    assert outline == sorted(corners)


def test_a_change_of_one_bit_is_a_difference(manifest):
    compare = tool("manifest")
    recorded = manifest["cases"]["shadow/icosphere/point/project_shadow"]
    nudged = {**recorded, "area": repr(float(np.nextafter(float(recorded["area"]), np.inf)))}
    status, detail = compare.verdict(recorded, nudged)
    assert status == "different" and "area" in detail and "rel" in detail
    assert compare.verdict(recorded, None)[0] == "not run"
    assert compare.verdict(recorded, dict(recorded))[0] == "identical"


def test_corpus_cases_name_the_corpus_files_recorded(manifest, shared_dir):
    # the conversions of the corpus scenes apply while the corpus holds the same bytes
    digest, conversions = tool("digest"), tool("conversions")
    corpus = shared_dir / "corpus"
    for name in conversions.CORPUS:
        record = manifest["cases"][f"convert/corpus/{name}"]
        assert digest.sha256((corpus / name).read_bytes()) == record["input_sha256"], name
        assert "error" not in record, (name, record.get("error"))
