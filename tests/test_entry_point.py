"""The installed ``shadowgeo`` console script, run as a user runs it.

The other CLI tests call ``python -m cli`` from the source tree; these run the
script ``pip install .`` puts on PATH, so a broken ``[project.scripts]`` entry or
a package left out of the wheel fails here. Without the script the tests skip
(fail under SHADOWGEO_REQUIRE_ALL=1, as in CI, which installs it).
"""

from __future__ import annotations

import importlib.metadata
import subprocess
from pathlib import Path

import numpy as np
from lxml import etree
from needs import need
from reference import ray_plane

LAMP = np.array([1.0, 6.0, 0.5])
BOX = np.array([[-0.5, 1.0, -0.5], [0.5, 2.0, 0.5]])  # min and max corners

SCENE = f"""<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0">
  <Scene>
    <PointLight DEF="lamp" location="{LAMP[0]} {LAMP[1]} {LAMP[2]}" shadows="true"/>
    <Shape DEF="ground">
      <IndexedFaceSet coordIndex="0 1 2 3 -1" solid="false">
        <Coordinate point="-20 0 -20, -20 0 20, 20 0 20, 20 0 -20"/>
      </IndexedFaceSet>
    </Shape>
    <Transform translation="0 1.5 0"><Shape DEF="box"><Box size="1 1 1"/></Shape></Transform>
  </Scene>
</X3D>
"""


def run(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    script = need("shadowgeo-script")
    return subprocess.run(
        [str(script), *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=300
    )


def test_help_and_version_come_from_the_installed_package(tmp_path):
    done = run("--help", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: shadowgeo")
    assert "convert" in done.stdout and "info" in done.stdout
    version = run("--version", cwd=tmp_path)
    assert version.returncode == 0, version.stderr
    assert importlib.metadata.version("shadowgeo") in version.stdout


def test_convert_bakes_the_shadow_a_hand_projection_predicts(tmp_path):
    source, target = tmp_path / "box.x3d", tmp_path / "out" / "box.x3d"
    source.write_text(SCENE)
    target.parent.mkdir()
    done = run("convert", source, target, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "wrote" in done.stdout and "Traceback" not in done.stderr
    root = etree.parse(str(target), etree.XMLParser(resolve_entities=False)).getroot()
    shadows = root.findall("Scene/Group[@class='shadowgeo-shadows']/Shape")
    assert len(shadows) == 1
    point = shadows[0].find(".//Coordinate").get("point")
    points = np.array(point.replace(",", " ").split(), dtype=float).reshape(-1, 3)
    # Reference: the box's corners projected from the lamp onto y = 0 by similar
    # triangles; the shadow is their convex hull, so its extent is theirs.
    corners = np.array([[x, y, z] for x in BOX[:, 0] for y in BOX[:, 1] for z in BOX[:, 2]])
    landed = ray_plane(corners, LAMP, np.array([0.0, 1.0, 0.0]), 0.0)
    # On the ground, lifted by one small scene-scaled offset against z-fighting.
    assert np.ptp(points[:, 1]) == 0 and 0 <= points[0, 1] < 0.01 * 40
    np.testing.assert_allclose(points[:, [0, 2]].min(axis=0), landed[:, [0, 2]].min(axis=0))
    np.testing.assert_allclose(points[:, [0, 2]].max(axis=0), landed[:, [0, 2]].max(axis=0))


def test_a_missing_input_is_one_line_and_a_failure_code(tmp_path):
    done = run("convert", tmp_path / "nowhere.x3d", tmp_path / "out.x3d", cwd=tmp_path)
    assert done.returncode != 0
    assert "Traceback" not in done.stderr
    assert "nowhere.x3d" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert not (tmp_path / "out.x3d").exists()
