"""USD reader and writer: validated by usd-core's own validators."""

from __future__ import annotations

import pytest
from validators import usd_errors

pxr = pytest.importorskip("pxr")
from pxr import Usd, UsdGeom  # noqa: E402


def test_validator_flags_missing_stage_metadata(tmp_path):
    path = tmp_path / "bare.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Xform.Define(stage, "/World")
    stage.Save()
    errors = usd_errors(path)
    assert any("defaultPrim" in e for e in errors)
    assert any("upAxis" in e for e in errors)
    assert any("metersPerUnit" in e for e in errors)

    stage.SetDefaultPrim(stage.GetPrimAtPath("/World"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.Save()
    assert usd_errors(path) == []
