"""Soft shadows baked by the converter (shadowgeo.scene.softbake), and the
bundled example examples/scenes/soft_lights.usda (issue 32's done-when check):
a USD scene with a DistantLight of angle 0.53 degrees and a RectLight
converts to X3D, glTF and USD with graded shadows that pass the three
validators.

References: the validators (the X3D 4.0 schema, the Khronos glTF validator,
usd-core's), the hard shadow's darkness from the same scene with the lights'
sizes set to zero, and an independent ray test of the rectangle light.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from validators import gltf_problems, gltf_report, usd_errors
from x3d_schema import x3d_schema_errors

import shadowgeo as sg
from cli.main import main

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "soft_lights.usda"
LEVEL = re.compile(r"^shadow_(?P<light>[A-Za-z]+)_(?P<on>\w+?)_soft(?P<percent>\d+)$")


@pytest.fixture(scope="module")
def baked():
    return sg.add_shadows(sg.load(EXAMPLE))


def levels_of(scene):
    """{(light, receiver): [(percent, darkness), ...] sorted by percent}."""
    found: dict[tuple[str, str], list[tuple[int, float]]] = {}
    for shape in scene.shapes:
        match = LEVEL.match(shape.name or "")
        if match:
            key = (match["light"], match["on"])
            darkness = 1.0 - shape.material.transparency
            found.setdefault(key, []).append((int(match["percent"]), darkness))
    return {key: sorted(values) for key, values in found.items()}


def test_the_example_has_a_sun_of_053_degrees_and_a_rect_light():
    scene = sg.load(EXAMPLE)
    lights = {light.name: light for light in scene.lights}
    assert lights["Sun"].light.angle == pytest.approx(math.radians(0.53), rel=1e-6)
    panel = lights["Panel"].area
    assert isinstance(panel, sg.RectLight) and (panel.width, panel.height) == (2.0, 1.0)
    assert np.allclose(panel.direction, [0, -1, 0])


@pytest.mark.parametrize("suffix", [".x3d", ".glb", ".usda"])
def test_the_example_converts_with_graded_shadows_the_validators_pass(
    baked, tmp_path, suffix, x3d_schema
):
    out = tmp_path / f"soft_lights{suffix}"
    sg.save(baked, out)
    if suffix == ".x3d":
        assert x3d_schema_errors(out, x3d_schema) == []
    elif suffix == ".glb":
        assert gltf_problems(gltf_report(out), warnings=False) == []
    else:
        assert usd_errors(out) == []
    levels = levels_of(sg.load(out))
    # both lights bake graded layers on the floor, the sun's on the box too
    assert ("Sun", "Floor") in levels and ("Panel", "Floor") in levels
    assert any(light == "Sun" and on != "Floor" for light, on in levels)
    for values in levels.values():
        percents = [percent for percent, _ in values]
        darkness = [dark for _, dark in values]
        # k / 8 of the light hidden, each level darker than the one before
        assert set(percents) <= {round(100 * k / 8) for k in range(1, 9)}
        assert all(a < b for a, b in zip(darkness, darkness[1:], strict=False)), values
    for light in ("Sun", "Panel"):  # several levels, up to the umbra
        values = levels[(light, "Floor")]
        assert len(values) >= 6 and values[-1][0] == 100


@pytest.mark.parametrize("name", ["Sun", "Panel"])
def test_each_level_is_its_fraction_of_the_hard_shadows_darkness(name):
    # one light at a time (its share of the lighting is then all of it): with
    # its size dropped it bakes a hard shadow; a level k / 8 is k / 8 as dark
    scene = sg.load(EXAMPLE)
    (light,) = [light for light in scene.lights if light.name == name]
    if name == "Sun":
        hard_light = dataclasses.replace(light, light=sg.DirectionalLight(light.light.direction))
    else:
        hard_light = dataclasses.replace(light, area=None)
    soft = sg.add_shadows(dataclasses.replace(scene, lights=[light]))
    hard = sg.add_shadows(dataclasses.replace(scene, lights=[hard_light]))
    dark = {s.name: 1.0 - s.material.transparency for s in hard.shapes_with_role("shadow")}
    assert f"shadow_{name}_Floor" in dark and not any("_soft" in each for each in dark)
    checked = 0
    for values in levels_of(soft).values():
        for percent, darkness in values:
            fraction = {round(100 * k / 8): k / 8 for k in range(1, 9)}[percent]
            assert darkness == pytest.approx(fraction * dark[f"shadow_{name}_Floor"], abs=1e-9)
            checked += 1
    assert checked >= 6


def test_lights_with_no_size_bake_no_graded_layers():
    floor = sg.Shape([[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]], [[0, 2, 1], [0, 3, 2]])
    floor.name = "floor"
    box = sg.Shape([[0, 1, 0], [1, 1, 0], [1, 1, 1]], [[0, 1, 2]], name="roof")
    for light in (sg.DirectionalLight([0.2, -1, 0], angle=0.0), sg.PointLight([0, 4, 0])):
        out = sg.add_shadows(sg.Scene([floor, box], [sg.SceneLight(light, name="l")]))
        names = [s.name for s in out.shapes_with_role("shadow")]
        assert names == ["shadow_l_floor"]


def test_convert_sun_angle_and_light_size_options(tmp_path, capsys):
    scene = tmp_path / "lamp.x3d"
    scene.write_text(
        """<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0"><Scene>
<PointLight DEF="lamp" location="0 4 0" shadows="true"/>
<DirectionalLight DEF="sun" direction="0.3 -1 0.2" shadows="true"/>
<Shape DEF="floor"><IndexedFaceSet coordIndex="0 1 2 3 -1" solid="false">
<Coordinate point="-5 0 -5 -5 0 5 5 0 5 5 0 -5"/></IndexedFaceSet></Shape>
<Transform translation="0 1 0"><Shape DEF="box"><Box size="1 1 1"/></Shape></Transform>
</Scene></X3D>"""
    )
    out = tmp_path / "out.x3d"
    code = main(
        ["convert", str(scene), str(out), "--sun-angle", "2", "--light-size", "lamp=0.3",
         "--soft-levels", "4", "--soft-samples", "32"]
    )  # fmt: skip
    assert code == 0, capsys.readouterr().err
    levels = levels_of(sg.load(out))
    assert {percent for percent, _ in levels[("lamp", "floor")]} <= {25, 50, 75, 100}
    assert len(levels[("lamp", "floor")]) >= 3 and ("sun", "floor") in levels
    # an unknown light is a usage error naming it
    with pytest.raises(SystemExit) as stopped:
        main(["convert", str(scene), str(tmp_path / "x.x3d"), "--light-size", "lampe=0.3"])
    assert stopped.value.code == 2
    err = capsys.readouterr().err
    assert "lampe" in err and "lamp" in err
    assert not (tmp_path / "x.x3d").exists()
    for bad in ("lamp", "lamp=-1", "=0.3"):
        with pytest.raises(SystemExit) as stopped:
            main(["convert", str(scene), str(tmp_path / "x.x3d"), "--light-size", bad])
        assert stopped.value.code == 2


def test_info_lists_the_lights_with_their_sizes(capsys):
    assert main(["info", str(EXAMPLE)]) == 0
    out = capsys.readouterr().out
    assert "RectLight" in out and "2 x 1" in out and "angle 0.53 deg" in out


@pytest.mark.parametrize("options", [{"soft_levels": 0}, {"soft_samples": 10_000}])
def test_bad_soft_settings_are_refused_at_once(options):
    with pytest.raises(sg.GeometryError, match="levels|samples"):
        sg.add_shadows(sg.load(EXAMPLE), **options)
