"""The X3D ``shadowgeo convert`` writes shows its baked shadow in a real X3D browser,
as dark as X_ITE draws its own.

X_ITE (the npm package ``x_ite``) runs in headless Debian Chromium with
software WebGL (SwiftShader), served from 127.0.0.1 and screenshotted once it
has loaded the scene and drawn a few frames (``xite.py``).

The check: looking straight down with an OrthoViewpoint whose field of view we
set (in the input scene; the converter keeps it), the pixels inside the shadow
polygon are dark and those around it are lit. The polygon is an independent
reference: the convex hull of the box's corners projected from the light by
similar triangles.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import shapely
from needs import need
from reference import ray_plane
from xite import Canvas, render

LIGHT = np.array([3.0, 6.0, 2.0])
BOX = np.array([[-0.5, 1.5, -0.5], [0.5, 2.5, 0.5]])
HALF_VIEW = 10.0  # the OrthoViewpoint shows x, z in [-10, 10]
PIXELS = 400
LOAD_TIMEOUT = 45.0  # seconds for X_ITE to load and draw, in software

# The input scene: ground, a red box (an X3D Box, tessellated by the reader), a lamp.
# shadows="false": X_ITE must show the shadow shadowgeo baked, not one of its own.
# No headlight: the lamp alone lights the ground, so its shadow is black.
SCENE = f"""<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0">
  <Scene>
    <NavigationInfo headlight="false" type='"NONE"'/>
    <OrthoViewpoint position="0 50 0" orientation="1 0 0 -1.5707963267948966"
                    fieldOfView="{-HALF_VIEW} {-HALF_VIEW} {HALF_VIEW} {HALF_VIEW}"/>
    <PointLight DEF="lamp" location="{LIGHT[0]} {LIGHT[1]} {LIGHT[2]}" shadows="false"/>
    <Shape DEF="ground">
      <Appearance><Material diffuseColor="0.8 0.8 0.8"/></Appearance>
      <IndexedFaceSet coordIndex="0 1 2 3 -1" solid="false">
        <Coordinate point="-15 0 -15, -15 0 15, 15 0 15, 15 0 -15"/>
      </IndexedFaceSet>
    </Shape>
    <Transform translation="{BOX.mean(axis=0)[0]} {BOX.mean(axis=0)[1]} {BOX.mean(axis=0)[2]}">
      <Shape DEF="box">
        <Appearance><Material diffuseColor="0.8 0.1 0.1"/></Appearance>
        <Box size="{BOX[1, 0] - BOX[0, 0]} {BOX[1, 1] - BOX[0, 1]} {BOX[1, 2] - BOX[0, 2]}"/>
      </Shape>
    </Transform>
  </Scene>
</X3D>
"""

# VRML 97 has no OrthoViewpoint: a Viewpoint straight above shows the ground plane
# (square to the view) as linearly as the orthographic one, with the same field
PERSPECTIVE_SCENE = re.sub(
    r"<OrthoViewpoint[^>]*/>",
    '<Viewpoint position="0 50 0" orientation="1 0 0 -1.5707963267948966" '
    f'fieldOfView="{2 * math.atan(HALF_VIEW / 50)!r}"/>',
    SCENE,
)
assert PERSPECTIVE_SCENE != SCENE


def reference_shadow():
    """shapely Polygon of the box's shadow on y = 0, in (x, z)."""
    corners = np.array([[x, y, z] for x in BOX[:, 0] for y in BOX[:, 1] for z in BOX[:, 2]])
    landed = ray_plane(corners, LIGHT, np.array([0.0, 1.0, 0.0]), 0.0)
    return shapely.MultiPoint(landed[:, [0, 2]]).convex_hull


def convert(folder: Path, suffix: str = ".x3d") -> Path:
    """``shadowgeo convert`` the input scene to ``converted<suffix>``."""
    from cli.main import main

    source, target = folder / "scene.x3d", folder / f"converted{suffix}"
    source.write_text(PERSPECTIVE_SCENE if suffix == ".wrl" else SCENE)
    assert main(["convert", str(source), str(target)]) == 0
    return target


def screenshot(folder: Path, browser: Path, scene: str = "converted.x3d") -> np.ndarray:
    """X_ITE's picture of ``folder / scene``, the lights as the file says."""
    (shot,) = render(folder, [Canvas(scene)], PIXELS, browser, LOAD_TIMEOUT)
    assert shot.status == "ok", shot.status
    return shot.image


# every X3D encoding shadowgeo writes: XML, ClassicVRML, VRML 97
@pytest.mark.parametrize("suffix", [".x3d", ".x3dv", ".wrl"])
def test_x_ite_shows_the_baked_shadow(tmp_path, suffix):
    convert(tmp_path, suffix)
    need("x_ite")
    image = screenshot(tmp_path, need("chromium"), f"converted{suffix}")
    assert image.shape[:2] == (PIXELS, PIXELS)

    # Pixel centres -> world (x, z): looking down -y with screen-up = -z.
    centres = (np.arange(PIXELS) + 0.5) / PIXELS * 2 * HALF_VIEW - HALF_VIEW
    x, z = np.meshgrid(centres, centres)  # rows run along +z, columns along +x
    points = shapely.points(x.ravel(), z.ravel())
    shadow = reference_shadow()
    box = shapely.box(*BOX[0, [0, 2]], *BOX[1, [0, 2]])
    margin = 2.5 * 2 * HALF_VIEW / PIXELS  # a few pixels of antialiasing
    inside = shapely.contains(shadow.buffer(-margin).difference(box.buffer(margin)), points)
    outside = ~shapely.intersects(shadow.union(box).buffer(margin), points)
    brightness = image.astype(float).mean(axis=2).ravel()

    assert inside.sum() > 1000
    assert np.mean(brightness[inside] < 40) > 0.99, np.percentile(brightness[inside], 99)
    # lit by the lamp alone: the far corners of the ground, at a grazing angle, get 66
    assert np.mean(brightness[outside] > 55) > 0.99, np.percentile(brightness[outside], 1)
    # The dark region has the reference's area (in pixels), to within its outline's width.
    dark = (brightness < 40).sum() * (2 * HALF_VIEW / PIXELS) ** 2
    expected = shadow.difference(box).area
    assert abs(dark - expected) < shadow.length * 3 * margin, (dark, expected)


def test_x_ite_opens_a_converted_gltf_looking_at_its_shadow(tmp_path):
    """A glTF with no light of its own, converted with no flags: X_ITE opens
    the X3D at the Viewpoint shadowgeo wrote, and the default sun's shadow is
    dark where that camera, projected here by hand, puts it."""
    import trimesh

    import shadowgeo as sg
    from cli.main import main

    ground = sg.Shape(
        [[-6, 0, -6], [6, 0, -6], [6, 0, 6], [-6, 0, 6]],
        [[0, 2, 1], [0, 3, 2]],
        material=sg.Material(diffuse_color=(0.8, 0.8, 0.8)),
        name="ground",
    )
    box = trimesh.creation.box(bounds=BOX)
    red = sg.Material(diffuse_color=(0.8, 0.1, 0.1))
    scene = sg.Scene([ground, sg.Shape(box.vertices, box.faces, material=red, name="box")])
    sg.save(scene, tmp_path / "scene.glb")
    assert main(["convert", str(tmp_path / "scene.glb"), str(tmp_path / "converted.x3d")]) == 0
    (view,) = sg.load(tmp_path / "converted.x3d").viewpoints
    need("x_ite")
    image = screenshot(tmp_path, need("chromium"))

    # The default sun travels along (0.3, -1, 0.2): the box's corners land on y = 0.
    corners = np.array([[x, y, z] for x in BOX[:, 0] for y in BOX[:, 1] for z in BOX[:, 2]])
    sun = np.array([0.3, -1.0, 0.2])
    landed = corners - np.outer(corners[:, 1] / sun[1], sun)
    shadow = shapely.MultiPoint(landed[:, [0, 2]]).convex_hull

    # The camera by hand: the Viewpoint's orientation turns -z (forward) and +y (up).
    axis, angle = np.array(view.orientation[:3]), view.orientation[3]
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
    right, up, back = turn[:, 0], turn[:, 1], turn[:, 2]
    tangent = np.tan(view.field_of_view / 2)  # a square canvas: both angles are the field of view
    eye = np.array(view.position)

    def pixel_to_ground(rows, columns):
        """Where the ray through each pixel centre meets y = 0, as (x, y, z)."""
        ndc_x = (columns + 0.5) / PIXELS * 2 - 1
        ndc_y = 1 - (rows + 0.5) / PIXELS * 2
        rays = -back + np.outer(ndc_x * tangent, right) + np.outer(ndc_y * tangent, up)
        reach = -eye[1] / rays[:, 1]
        return eye + rays * reach[:, None]

    rows, columns = np.mgrid[0:PIXELS, 0:PIXELS]
    on_ground = pixel_to_ground(rows.ravel().astype(float), columns.ravel().astype(float))
    points = shapely.points(on_ground[:, 0], on_ground[:, 2])
    margin = 0.15  # about two pixels on the ground at this distance
    # Only the ground the box does not hide from the camera is checked: what
    # hides it is the hull of the box's corners cast from the camera onto y = 0.
    behind = eye + (corners - eye) * (eye[1] / (eye[1] - corners[:, 1]))[:, None]
    hidden = shapely.MultiPoint(np.vstack([behind, corners])[:, [0, 2]]).convex_hull
    inside = shapely.contains(shadow.buffer(-margin).difference(hidden.buffer(margin)), points)
    near_ground = shapely.box(-5.5, -5.5, 5.5, 5.5)
    outside = shapely.contains(near_ground.difference(shadow.union(hidden).buffer(margin)), points)
    brightness = image.astype(float).mean(axis=2).ravel()
    assert inside.sum() > 100, inside.sum()  # the shadow is in the picture, not edge-on
    assert np.mean(brightness[inside] < 40) > 0.95, np.percentile(brightness[inside], 95)
    assert outside.sum() > 10_000  # most of the ground is in the picture too
    assert np.mean(brightness[outside] > 60) > 0.95, np.percentile(brightness[outside], 5)


# Two more lights that cast no shadow, one with ambient light, over a green-grey
# ground: the lamp's shadow is lit by them (and by the headlight when on).
OTHER_LIGHTS = (
    '<DirectionalLight direction="-0.3 -1 0.2" intensity="0.4" color="1 0.8 0.6"/>\n'
    '    <PointLight location="-4 3 -4" intensity="0.5" ambientIntensity="0.3" '
    'attenuation="0.5 0.1 0"/>\n    '
)


@pytest.mark.parametrize("headlight", ["false", "true"])
def test_the_baked_shadow_is_as_dark_as_x_ites_own(tmp_path, headlight):
    """X_ITE draws the lamp's shadow itself (shadows="true") in one picture and
    shows shadowgeo's baked one in the other: inside the shadow, the two
    pictures have the same luminance (to 3 levels of 255), though the other
    lights and the headlight light it: not a black hole."""
    from cli.main import main

    need("x_ite")
    browser = str(need("chromium"))
    scene = (
        SCENE.replace('headlight="false"', f'headlight="{headlight}"')
        .replace('diffuseColor="0.8 0.8 0.8"', 'diffuseColor="0.3 0.4 0.3"')
        .replace('<PointLight DEF="lamp"', OTHER_LIGHTS + '<PointLight DEF="lamp"')
        .replace('shadows="false"', 'shadows="true"')
    )
    pictures = {}
    for kind in ("runtime", "baked"):
        folder = tmp_path / kind
        folder.mkdir()
        (folder / "scene.x3d").write_text(scene)
        if kind == "runtime":
            (folder / "converted.x3d").write_text(scene)
        else:
            assert main(["convert", str(folder / "scene.x3d"), str(folder / "converted.x3d")]) == 0
            assert 'shadows="false"' in (folder / "converted.x3d").read_text()
        pictures[kind] = screenshot(folder, browser)

    centres = (np.arange(PIXELS) + 0.5) / PIXELS * 2 * HALF_VIEW - HALF_VIEW
    x, z = np.meshgrid(centres, centres)
    points = shapely.points(x.ravel(), z.ravel())
    box = shapely.box(*BOX[0, [0, 2]], *BOX[1, [0, 2]])
    inside = shapely.contains(reference_shadow().buffer(-0.3).difference(box.buffer(0.3)), points)
    weights = np.array([0.2126, 0.7152, 0.0722])
    luminance = {
        kind: float((image.reshape(-1, 3)[inside].astype(float) @ weights).mean())
        for kind, image in pictures.items()
    }
    assert inside.sum() > 500
    assert luminance["runtime"] > 40  # the shadow is lit by the other lights
    assert abs(luminance["baked"] - luminance["runtime"]) < 3, luminance
