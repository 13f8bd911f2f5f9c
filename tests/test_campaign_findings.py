"""Regression tests for what the fuzz campaign at seed 38 found (issue 34).

* CityJSON mutant 1597: one vertex at 3e35 beside houses of 10 m. float64's
  rounding of that coordinate is wider than the receiver, so a face sorted as
  projecting inside the shadow's window landed at 8e24 local units and
  Clipper2 refused the union with a bare RuntimeError. The projection now
  checks its loops against the window it sorted by and names the cause.
* glTF mutant 2433: a light's intensity of -1e308 (finite in JSON) became
  ``-inf`` in a USD float attribute. USD float attributes are now held inside
  float32's range.
* x3dv mutant 1692: one face retracing its corners 10,000 times (40,006
  corners) kept the ear clipper over 30 s. One polygon's corners now have a
  budget, ``limits.MAX_POLYGON_CORNERS``, checked before the triangulation.
* x3dz mutant 1899: 10,000 shapes of one name written to USD took 27 s: each
  name walked past every suffix taken before it, and each mesh defined
  through the stage recomposed its parent's 10,000 children. Names now
  resume from their last suffix, and the prims are declared in one change
  block first (the golden USD outputs are byte for byte the same).
"""

from __future__ import annotations

import contextlib
import importlib
import io
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import shadowgeo as sg
from cli.main import main as cli_main
from shadowgeo import limits, plane2d
from shadowgeo.errors import BudgetError

DATA = Path(__file__).parent / "data"
EXAMPLES = Path(__file__).parents[1] / "examples" / "scenes"


def run_cli(*argv: str) -> tuple[int, str]:
    error = io.StringIO()
    with contextlib.redirect_stderr(error), contextlib.redirect_stdout(io.StringIO()):
        code = cli_main(list(argv))
    return code, error.getvalue()


def test_a_city_vertex_far_past_the_receiver_is_one_clear_line_and_no_output(tmp_path):
    target = tmp_path / "out.x3d"
    source = DATA / "findings" / "far_vertex.city.json"
    code, message = run_cli("sun", str(source), str(target), "--at", "52.0,4.36", "--serial",
                            "--every", "240")
    assert code == 1
    lines = [line for line in message.splitlines() if line.strip()]
    assert len(lines) == 1, message
    assert "too large" in lines[0] and "3e+35" in lines[0] and source.name in lines[0]
    assert "RuntimeError" not in message and "Traceback" not in message
    assert not target.exists()


def test_usd_float_attributes_stay_finite_for_numbers_past_float32(tmp_path):
    scene = sg.load(EXAMPLES / "courtyard.x3d")
    lights = [replace(light, intensity=-1e308, color=(1e308, 0.5, -1e300)) for light in scene.lights]
    target = tmp_path / "out.usda"
    sg.save(replace(scene, lights=lights), target)
    text = target.read_text()
    assert "inf" not in text.replace("info:", "")  # (info:id is a token, not a number)
    back = sg.load(target)
    assert all(math.isfinite(light.intensity) for light in back.lights)
    assert len(back.lights) == len(lights)


def test_a_polygon_past_the_corner_budget_is_refused_before_triangulating():
    square = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    retraced = np.tile(square, (limits.MAX_POLYGON_CORNERS // 4 + 1, 1))
    with pytest.raises(BudgetError, match="MAX_POLYGON_CORNERS"):
        plane2d.polygon_triangles(retraced)
    # at the budget it is triangulated (a retraced square of 4,000 corners: fast)
    assert len(plane2d.polygon_triangles(np.tile(square, (1000, 1)))) == 3998


def test_an_x3d_face_retracing_its_corners_is_skipped_with_a_note(tmp_path):
    corners = " ".join(["0 1 2 3"] * (limits.MAX_POLYGON_CORNERS // 4 + 1))
    source = tmp_path / "retraced.x3dv"
    source.write_text(
        "#X3D V3.0 utf8\nPROFILE Interchange\n"
        "Shape { geometry IndexedFaceSet { convex FALSE solid FALSE\n"
        "  coord Coordinate { point [0 1 0, 1 1 0, 1 2 0.5, 0 2 0] }\n"
        f"  coordIndex [{corners}] }} }}\n"
        "Shape { geometry Box { } }\n"
    )
    target = tmp_path / "out.x3d"
    code, message = run_cli("convert", str(source), str(target), "--sun=-0.5,-1,0.3")
    assert code == 0, message
    assert "MAX_POLYGON_CORNERS" in message and "the Shape is skipped" in message
    assert target.exists()


def test_many_shapes_of_one_name_get_unique_usd_names_in_order(tmp_path):
    scene = sg.load(EXAMPLES / "courtyard.x3d")
    shape = next(s for s in scene.shapes if s.name)
    shapes = [replace(shape, name="tent") for _ in range(300)]
    target = tmp_path / "out.usda"
    sg.save(replace(scene, shapes=shapes), target)
    text = target.read_text()
    names = [line.split('"')[1] for line in text.splitlines() if line.strip().startswith("def Mesh")]
    assert names == ["tent", *[f"tent_{k}" for k in range(1, 300)]]
    assert text.index('def Mesh "tent"') < text.index('def Scope "Looks"') < text.index(
        'def Mesh "tent_1"'
    )
    back = sg.load(target)
    assert len(back.shapes) == 300


def area_check():
    folder = str(Path(__file__).resolve().parents[1] / "tools")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module("fuzz.check_area")


BOX_ON_GROUND = """<X3D profile="Interchange" version="4.0"><Scene>
  <Transform translation="0 2 0"><Shape>
    <Appearance><Material transparency="{transparency}"/></Appearance>
    <Box size="2 2 2"/></Shape></Transform>
  <Transform translation="3 1 0"><Shape><Box size="1 1 1"/></Shape></Transform>
</Scene></X3D>"""
ARGV = ["convert", "IN", "OUT.glb", "--sun", "0.3,-1,0.2", "--plane", "0,1,0,0"]


def test_the_campaigns_area_check_takes_casters_by_their_opacity(tmp_path):
    # x3d mutants 4645 and 5151 at seed 38: transparency="10" and "3e38" are
    # clamped to 1 (as browsers do), so the box casts nothing; the check took
    # it for an opaque caster and reported the converter's area as wrong
    check = area_check()
    source = tmp_path / "scene.x3d"
    for transparency in ("10", "3e38", "1"):
        source.write_text(BOX_ON_GROUND.format(transparency=transparency))
        assert check.reference_area_problem(source, ARGV) is None, transparency
    source.write_text(BOX_ON_GROUND.format(transparency="0.5"))  # translucent: no reference
    assert check.reference_area_problem(source, ARGV) is None
    # an opaque scene is still compared: a shadow area off by a little is caught
    source.write_text(BOX_ON_GROUND.format(transparency="0"))
    assert check.reference_area_problem(source, ARGV) is None
    original = check.triangles_area
    try:
        check.triangles_area = lambda triangles: 1.001 * original(triangles)
        assert "textbook union" in (check.reference_area_problem(source, ARGV) or "")
    finally:
        check.triangles_area = original
