"""How dark baked shadows are drawn, the ground added under the scene, and
the runtime shadows of the lights whose shadows are baked.

The reference darkness is computed by hand from X3D's lighting equation (as
X_ITE's shader evaluates it): a shadow takes away its light's diffuse term,
the other lights, the headlight, ambient and emissive light stay, and the
display clamps each channel at 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import trimesh
from lxml import etree

import shadowgeo as sg
from shadowgeo.scene.darkness import shadow_darkness

QUAD = [[0, 2, 1], [0, 3, 2]]


def ground(half=5.0, diffuse=(0.5, 0.5, 0.5), emissive=(0.0, 0.0, 0.0)):
    corners = [[-half, 0, -half], [half, 0, -half], [half, 0, half], [-half, 0, half]]
    look = sg.Material(diffuse_color=diffuse, emissive_color=emissive)
    return sg.Shape(corners, QUAD, material=look, name="ground")


def cube(name="cube", low=(-0.5, 1.0, -0.5), high=(0.5, 2.0, 0.5)):
    mesh = trimesh.creation.box(bounds=[low, high])
    return sg.Shape(mesh.vertices, mesh.faces, name=name)


def sun(direction, name, intensity, **fields):
    return sg.SceneLight(
        sg.DirectionalLight(direction), name=name, intensity=intensity, shadows=True, **fields
    )


# Two suns over a flat ground: "top" straight down (n . l = 1), "slant" at
# (0.6, -0.8, 0) (n . l = 0.8), intensities 0.3 and 0.5: diffuse terms 0.3 and 0.4.
TOP, SLANT = (0.0, -1.0, 0.0), (0.6, -0.8, 0.0)


def opacities(scene, **options):
    """{light name: opacity} of the shadows on the ground."""
    result = sg.add_shadows(scene, receivers=["ground"], **options)
    found = {}
    for shape in result.shapes_with_role("shadow"):
        name = shape.group.removeprefix("shadows_")
        found[name] = 1.0 - shape.material.transparency
    return found


def two_suns(headlight=False, viewpoints=(), **fields):
    lights = [sun(TOP, "top", 0.3, **fields), sun(SLANT, "slant", 0.5)]
    return sg.Scene([ground(), cube()], lights, headlight=headlight, viewpoints=list(viewpoints))


def test_two_lights_share_the_ground_headlight_off():
    # lit 0.5 (0.3 + 0.4) = 0.35, no clamp; each shadow takes its light's share
    found = opacities(two_suns())
    assert found["top"] == pytest.approx(0.3 / 0.7, abs=1e-12)
    assert found["slant"] == pytest.approx(0.4 / 0.7, abs=1e-12)


def test_the_headlight_counts_along_the_first_viewpoint():
    # The camera turned -30 degrees about x looks along (0, -0.5, -0.866):
    # the headlight adds |n . v| = 0.5 to the diffuse terms 0.3 and 0.4.
    view = sg.Viewpoint((0, 5, 9), (1, 0, 0, -math.pi / 6))
    found = opacities(two_suns(headlight=True, viewpoints=[view]))
    assert found["top"] == pytest.approx(0.3 / 1.2, abs=1e-12)
    assert found["slant"] == pytest.approx(0.4 / 1.2, abs=1e-12)
    # No Viewpoint: the headlight shines straight onto the receiver (1).
    found = opacities(two_suns(headlight=True))
    assert found["top"] == pytest.approx(0.3 / 1.7, abs=1e-12)


def test_ambient_and_emissive_light_stay_in_the_shadow():
    # top's ambientIntensity 0.5 times the material's 0.2: 0.1 more that no
    # shadow takes away
    found = opacities(two_suns(ambient_intensity=0.5))
    assert found["slant"] == pytest.approx(0.4 / 0.8, abs=1e-12)
    # an emissive 0.1 on a diffuse 0.5: lit 0.1 + 0.5 * 0.7 = 0.45
    scene = two_suns()
    scene.shapes[0] = ground(emissive=(0.1, 0.1, 0.1))
    found = opacities(scene)
    assert found["top"] == pytest.approx(0.5 * 0.3 / 0.45, abs=1e-12)


def test_one_light_alone_keeps_its_shadow_intensity():
    for intensity in (1.0, 0.7):
        lamp = sg.SceneLight(
            sg.PointLight([0, 4, 0]), name="lamp", intensity=0.4, shadow_intensity=intensity
        )
        found = opacities(sg.Scene([ground(), cube()], [lamp]))
        assert found == {"lamp": pytest.approx(intensity, abs=1e-12)}


def test_a_light_lit_past_white_leaves_the_display_clamp():
    # diffuse 0.8 under one light (0.8) and the headlight (0.8): 1.6 shows as
    # 1; the light's shadow leaves 0.8: opacity 0.2 (X_ITE draws 204 of 255)
    lamp = sun(TOP, "top", 1.0)
    scene = sg.Scene([ground(diffuse=(0.8, 0.8, 0.8)), cube()], [lamp], headlight=True)
    assert opacities(scene)["top"] == pytest.approx(0.2, abs=1e-12)


def test_attenuation_and_the_spot_cone_weigh_a_light():
    # a small triangle at (2, 0, 0) facing up; the point light at (2, 2, 0)
    # with attenuation 1 / d^2 gives 1/4; the spot light at (0, 2, 0) looking
    # down sees it 45 degrees off its axis, half-way from its beam (30) to
    # its cut-off (60): 1/2, times n . l = cos 45
    tile = np.array([[2.0, 0, 0], [2.01, 0, 0], [2.0, 0, -0.01]]), np.array([[0, 1, 2]])
    point = sg.SceneLight(sg.PointLight([2, 2, 0]), attenuation=(0.0, 0.0, 1.0))
    spot = sg.SceneLight(
        sg.SpotLight([0, 2, 0], [0, -1, 0], math.radians(60)), beam_width=math.radians(30)
    )
    dim = sg.Material(diffuse_color=(0.5, 0.5, 0.5))
    spot_term = 0.5 * math.cos(math.pi / 4)
    expected = 0.25 / (0.25 + spot_term)
    got = shadow_darkness(point, *tile, [point, spot], material=dim)
    assert got == pytest.approx(expected, abs=2e-3)  # the triangle's centroid, not (2, 0, 0)
    # out of the spot's cone, or past the point light's radius: the other alone
    far = sg.SceneLight(sg.PointLight([2, 2, 0], radius=1.0))
    assert shadow_darkness(spot, *tile, [far, spot], material=dim) == pytest.approx(1.0)


def test_a_light_the_scene_does_not_hold_keeps_its_shadow_intensity():
    # the default sun is not drawn by the browser: its share cannot be known
    lamp = sg.SceneLight(sg.PointLight([0, 4, 0]), name="lamp", shadows=False, on=False)
    result = sg.add_shadows(sg.Scene([ground(), cube()], [lamp], headlight=True))
    (shadow,) = result.shapes_with_role("shadow")
    assert shadow.material.transparency == 0.0


# -- the ground ---------------------------------------------------------------------------


def test_the_ground_plane_that_receives_is_drawn_under_every_shadow():
    low, high = cube("a"), cube("b", (2.0, 0.5, 1.0), (3.0, 3.0, 2.0))
    lamps = [
        sg.SceneLight(sg.PointLight([0, 6, 0]), name="lamp", shadows=True),
        sg.SceneLight(sg.DirectionalLight([-0.5, -1, 0.3]), name="sun", shadows=True),
    ]
    result = sg.add_shadows(sg.Scene([low, high], lamps))
    (floor,) = result.shapes_with_role("ground")
    assert floor.role != "shadow" and not floor.casts_shadow
    assert floor.material.transparency == 0.0 and floor.material.diffuse_color == (0.7, 0.7, 0.7)
    # in the plane under the scene's lowest point (y = 0.5), facing up
    assert np.all(floor.world_vertices[:, 1] == 0.5)
    corners = floor.world_vertices[floor.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert np.all(normals[:, 1] > 0)
    region = shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in corners])
    shadows = result.shapes_with_role("shadow")
    assert len(shadows) == 2
    for shadow in shadows:
        points = shadow.world_vertices
        assert np.all(points[:, 1] > 0.5)  # above the ground, lifted towards the light
        assert region.contains(shapely.MultiPoint(points[:, [0, 2]]).convex_hull)
    # and it covers the scene's footprint too, with a margin
    assert region.contains(shapely.box(-0.5, -0.5, 3.0, 2.0).buffer(0.2))
    # added again: one ground, the same
    again = sg.add_shadows(result)
    (second,) = again.shapes_with_role("ground")
    assert np.array_equal(second.world_vertices, floor.world_vertices)


def test_no_ground_is_added_when_the_scene_has_its_own():
    lamp = sg.SceneLight(sg.PointLight([0, 4, 0]), name="lamp", shadows=True)
    result = sg.add_shadows(sg.Scene([ground(), cube()], [lamp]))
    assert result.shapes_with_role("ground") == []


# -- runtime shadows ----------------------------------------------------------------------

SCENE = """<X3D profile="Interchange" version="4.0"><Scene>
  <NavigationInfo headlight="false"/>
  <PointLight DEF="lamp" location="0 6 0" shadows="true"/>
  <PointLight DEF="fill" location="4 6 0" intensity="0.2"/>
  <Shape DEF="ground"><IndexedFaceSet coordIndex="0 1 2 3 -1">
    <Coordinate point="-5 0 -5, -5 0 5, 5 0 5, 5 0 -5"/></IndexedFaceSet></Shape>
  <Transform translation="0 1.5 0"><Shape><Box/></Shape></Transform>
</Scene></X3D>"""


def lights_written(path):
    root = etree.parse(str(path)).getroot()
    return {light.get("DEF"): light for light in root.iter("PointLight")}


def test_a_baked_light_draws_no_runtime_shadows_in_the_x3d_output(tmp_path):
    from cli.main import main

    (tmp_path / "scene.x3d").write_text(SCENE)
    assert main(["convert", str(tmp_path / "scene.x3d"), str(tmp_path / "out.x3d")]) == 0
    written = lights_written(tmp_path / "out.x3d")
    assert written["lamp"].get("shadows") == "false"
    assert written["lamp"].get("class") == "shadowgeo-shadows-baked"
    comment = written["lamp"].getprevious()
    assert isinstance(comment, etree._Comment) and "baked" in comment.text
    assert written["fill"].get("shadows") is None  # not baked: as the author wrote it
    back = sg.load(tmp_path / "out.x3d")
    assert [(light.name, light.shadows, light.baked) for light in back.lights] == [
        ("lamp", True, True),
        ("fill", False, False),
    ]
    # converted again: the same light casts, one mark and one comment
    assert main(["convert", str(tmp_path / "out.x3d"), str(tmp_path / "again.x3d")]) == 0
    text = (tmp_path / "again.x3d").read_text()
    assert text.count("shadowgeo-shadows-baked") == 1 and text.count("<!-- shadowgeo:") == 1
    assert lights_written(tmp_path / "again.x3d")["lamp"].get("shadows") == "false"


def test_keep_runtime_shadows_leaves_them_on(tmp_path, capsys):
    from cli.main import main

    (tmp_path / "scene.x3d").write_text(SCENE)
    target = tmp_path / "out.x3d"
    assert (
        main(["convert", str(tmp_path / "scene.x3d"), str(target), "--keep-runtime-shadows"]) == 0
    )
    assert "runtime shadows still drawn by light lamp" in capsys.readouterr().err
    lamp = lights_written(target)["lamp"]
    assert lamp.get("shadows") == "true" and lamp.get("class") is None


def test_baked_lights_reach_every_writer(tmp_path):
    lamp = sg.SceneLight(sg.PointLight([0, 6, 0]), name="lamp", shadows=True)
    result = sg.add_shadows(sg.Scene([cube()], [lamp]))
    assert result.lights[0].baked and not result.lights[0].runtime_shadows
    for suffix in (".x3d", ".glb", ".usda", ".x3dv"):
        sg.save(result, tmp_path / f"out{suffix}")
        (back,) = sg.load(tmp_path / f"out{suffix}").lights
        assert (back.shadows, back.baked) == (True, True), suffix
        roles = [shape.role for shape in sg.load(tmp_path / f"out{suffix}").shapes]
        assert roles == ["geometry", "ground", "shadow"], suffix
    x3d = lights_written(tmp_path / "out.x3d")["lamp"]
    assert x3d.get("shadows") == "false"


def test_the_x3d_reader_keeps_the_headlight(tmp_path):
    cases = {
        "": True,
        '<NavigationInfo headlight="false"/>': False,
        '<NavigationInfo/><NavigationInfo headlight="false"/>': True,  # the first is bound
    }
    for navigation, headlight in cases.items():
        (tmp_path / "scene.x3d").write_text(
            f'<X3D version="4.0"><Scene>{navigation}<Shape><Box/></Shape></Scene></X3D>'
        )
        assert sg.load(tmp_path / "scene.x3d").headlight is headlight, navigation


def test_info_says_which_lights_are_baked(tmp_path, capsys):
    from cli.main import main

    (tmp_path / "scene.x3d").write_text(SCENE)
    assert main(["convert", str(tmp_path / "scene.x3d"), str(tmp_path / "out.x3d")]) == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "out.x3d")]) == 0
    rows = {line.split()[0]: line for line in capsys.readouterr().out.splitlines() if line}
    assert "baked (1)" in rows["lamp"] and "PointLight  on  no " in rows["fill"]
