"""Pictures: rendered off-screen, checked pixel by pixel against the geometry.

The shadow's expected place comes from an independent reference (the convex
hull of the box corners projected from the light by similar triangles), and
world points are taken to pixels with VTK's own world-to-display transform of
the renderer that drew the picture.
"""

from __future__ import annotations

import os
import re
import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from needs import absent
from reference import ray_plane
from scipy.spatial import ConvexHull, Delaunay

import shadowgeo as sg
from shadowgeo import viz

ROOT = Path(__file__).resolve().parents[1]

# One tiny off-screen render in a child process (a missing GL library can
# crash VTK outright): where it fails, these tests skip and say why (and fail
# under SHADOWGEO_REQUIRE_ALL=1, as in CI, which installs Mesa).
_PROBE = """
import numpy as np, trimesh, shadowgeo as sg
image = sg.plot([trimesh.creation.box()], off_screen=True, window_size=(16, 16))
assert image.shape == (16, 16, 3)
"""


@pytest.fixture(scope="module", autouse=True)
def can_render():
    result = subprocess.run(
        [sys.executable, "-c", _PROBE],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        check=False,
    )
    if result.returncode != 0:
        reason = (result.stderr.strip().splitlines() or ["no output"])[-1]
        absent(
            "VTK cannot render off-screen here (on Linux it needs Mesa's EGL and GL: "
            f"apt-get install libegl1 libgl1): {reason}"
        )


SIZE = (320, 240)
LIGHT = np.array([3.0, 6.0, 2.0])
BOX_LOW, BOX_HIGH = np.array([-0.5, 1.5, -0.5]), np.array([0.5, 2.5, 0.5])


def ground_shape(half=10.0, y=0.0):
    vertices = [[-half, y, -half], [half, y, -half], [half, y, half], [-half, y, half]]
    return sg.Shape(vertices, [[0, 2, 1], [0, 3, 2]], name="ground", receives_shadow=True)


def box_mesh():
    box = trimesh.creation.box(bounds=[BOX_LOW, BOX_HIGH])
    return box


def reference_shadow_xz():
    """(k, 2) hull of the box corners projected from LIGHT onto y = 0, in (x, z)."""
    corners = np.array(
        [[x, y, z] for x in (-0.5, 0.5) for y in (1.5, 2.5) for z in (-0.5, 0.5)], dtype=float
    )
    xz = ray_plane(corners, LIGHT, np.array([0.0, 1.0, 0.0]), 0.0)[:, [0, 2]]
    return xz[ConvexHull(xz).vertices]


def to_pixels(plotter, points):
    """World points -> (row, column) of the screenshot, via VTK's renderer."""
    renderer = plotter.renderer
    height = plotter.window_size[1]
    pixels = []
    for point in points:
        renderer.SetWorldPoint(*point, 1.0)
        renderer.WorldToDisplay()
        x, y, _ = renderer.GetDisplayPoint()
        pixels.append((int(round(height - 1 - y)), int(round(x))))
    return pixels


def brightness(image, pixel, radius=1):
    row, column = pixel
    patch = image[row - radius : row + radius + 1, column - radius : column + radius + 1]
    return float(patch[..., :3].astype(float).mean())


def render(*args, **kwargs):
    """Plotter and screenshot; the plotter keeps the camera used."""
    plotter = viz.scene_plotter(*args, off_screen=True, window_size=SIZE, **kwargs)
    image = np.asarray(plotter.screenshot(return_img=True))
    return plotter, image


def test_image_is_not_blank():
    scene = sg.Scene([ground_shape(), sg.Shape(box_mesh().vertices, box_mesh().faces)])
    shadow = sg.project_shadow(box_mesh(), sg.PointLight(LIGHT), sg.Plane([0, 1, 0], 0))
    image = sg.plot(scene, shadows=shadow, off_screen=True, window_size=SIZE)
    assert image.shape == (SIZE[1], SIZE[0], 3) and image.dtype == np.uint8
    colours = np.unique(image.reshape(-1, 3), axis=0)
    assert len(colours) > 20
    covered = np.any(image != 255, axis=2).mean()  # the background is white
    assert 0.05 < covered < 0.95


@pytest.mark.parametrize("view", ["top", (0.3, 1.0, 0.2)])
def test_shadow_is_darker_where_the_geometry_says(view):
    light = sg.PointLight(LIGHT)
    shadow = sg.project_shadow(box_mesh(), light, sg.Plane([0, 1, 0], 0), offset=1e-3)
    scene = sg.Scene([ground_shape(), sg.Shape(box_mesh().vertices, box_mesh().faces)])
    plotter, image = render(scene, shadows=shadow, view=view)
    try:
        outline = reference_shadow_xz()
        pairs = []
        for start, end in zip(outline, np.roll(outline, -1, axis=0), strict=True):
            middle, along = (start + end) / 2, end - start
            if np.linalg.norm(along) < 0.6:
                continue
            normal = np.array([along[1], -along[0]]) / np.linalg.norm(along)
            if np.dot(normal, middle - outline.mean(axis=0)) < 0:
                normal = -normal  # outward
            inside, outside = middle - 0.2 * normal, middle + 0.2 * normal
            # Keep points the box cannot hide from a camera above: far from its footprint.
            if min(np.abs(inside).max(), np.abs(outside).max()) < 1.3:
                continue
            pairs.append((inside, outside))
        assert len(pairs) >= 2
        points = [[p[0], 0.0, p[1]] for pair in pairs for p in pair]
        pixels = to_pixels(plotter, points)
        for index in range(len(pairs)):
            dark = brightness(image, pixels[2 * index])
            lit = brightness(image, pixels[2 * index + 1])
            assert dark < 0.5 * lit, (pairs[index], dark, lit)
        # And far from the shadow the ground is lit everywhere.
        far = to_pixels(plotter, [[8.0, 0.0, 8.0], [-8.0, 0.0, 8.0]])
        assert all(brightness(image, pixel) > 60 for pixel in far)
    finally:
        plotter.close()


def test_shadow_shapes_in_a_scene_are_drawn_dark():
    shadow = sg.project_shadow(
        box_mesh(), sg.PointLight(LIGHT), sg.Plane([0, 1, 0], 0), offset=0.01
    )
    baked = sg.Shape(shadow.mesh.vertices, shadow.mesh.faces, role="shadow")
    scene = sg.Scene([ground_shape(), baked], [sg.SceneLight(sg.PointLight(LIGHT))])
    plotter, image = render(scene, view="top")
    try:
        centre = reference_shadow_xz().mean(axis=0)  # inside: the hull is convex
        inside, outside = to_pixels(plotter, [[centre[0], 0, centre[1]], [6.0, 0.0, 6.0]])
        assert brightness(image, inside) < 0.5 * brightness(image, outside)
    finally:
        plotter.close()


@pytest.mark.parametrize(
    "light",
    [
        sg.PointLight([2.0, 4.0, 1.0]),
        sg.SpotLight([2.0, 4.0, 1.0], [-0.3, -1.0, -0.2], 0.6),
    ],
)
def test_positional_lights_are_marked_where_they_are(light):
    plotter, image = render([ground_shape()], lights=[light], view="top")
    try:
        (pixel,) = to_pixels(plotter, [light.position])
        red, green, blue = image[pixel].astype(int)
        assert red > 180 and green > 140 and blue < 90, image[pixel]
        # The ground's colour is grey: no yellow there.
        (ground,) = to_pixels(plotter, [[-7.0, 0.0, -7.0]])
        assert abs(int(image[ground][0]) - int(image[ground][2])) < 20
    finally:
        plotter.close()


def test_directional_light_is_an_arrow_along_its_rays_beside_the_geometry():
    light = sg.DirectionalLight([0.0, -1.0, 0.0])
    # Seen from the front, an arrow pointing down: a vertical yellow stroke
    # right of the ground (never in front of it), its head at the bottom.
    plotter, image = render([ground_shape()], lights=[light], view="front")
    try:
        yellow = (image[..., 0] > 180) & (image[..., 1] > 140) & (image[..., 2] < 90)
        rows, columns = np.nonzero(yellow)
        assert len(rows) > 20
        assert np.ptp(rows) > 2 * np.ptp(columns)
        (right_end,) = to_pixels(plotter, [[10.0, 0.0, 10.0]])  # the nearest right corner
        assert columns.min() > right_end[1]
        widths = np.bincount(rows - rows.min(), weights=np.ones(len(rows)))
        assert np.argmax(widths) > len(widths) / 2  # the head (widest) is below the middle
    finally:
        plotter.close()


@pytest.mark.parametrize("direction", [(0.3, -1.0, 0.2), (-1.0, -0.2, 0.0), (0.0, -0.3, -1.0)])
@pytest.mark.parametrize("view", ["iso", "top", (-1.0, 0.5, 0.3)])
def test_light_markers_never_hide_the_casters_and_far_lights_do_not_shrink_them(direction, view):
    box = box_mesh()
    scene = sg.Scene(
        [ground_shape(), sg.Shape(box.vertices, box.faces)],
        [sg.SceneLight(sg.DirectionalLight(direction)), sg.SceneLight(sg.PointLight([0, 900, 0]))],
    )
    plotter, image = render(scene, view=view)
    try:
        # Every yellow pixel lies outside the hull of the geometry's pixels.
        corners = [[x, y, z] for x in (-10, 10) for y in (0, 2.5) for z in (-10, 10)]
        pixels = np.array(to_pixels(plotter, corners), dtype=float)
        hull = Delaunay(pixels)
        yellow = (image[..., 0] > 180) & (image[..., 1] > 140) & (image[..., 2] < 90)
        assert yellow.sum() > 20  # the arrow is drawn
        assert np.all(hull.find_simplex(np.argwhere(yellow).astype(float)) < 0)
        # The far lamp is not framed: the geometry spans most of the picture.
        height, width = image.shape[:2]
        span = np.ptp(pixels, axis=0)
        assert span[0] > 0.5 * height or span[1] > 0.5 * width
    finally:
        plotter.close()


def test_volumes_are_semi_transparent():
    volume = trimesh.creation.box(
        bounds=[[5.0, 0.5, -2.0], [15.0, 1.5, 2.0]]
    )  # half off the ground
    plotter, image = render([ground_shape()], volumes=[volume], lights=False, view="top")
    try:
        over_ground, over_background, bare_ground = to_pixels(
            plotter, [[7.5, 1.5, 0.0], [12.5, 1.5, 0.0], [7.5, 0.0, 6.0]]
        )
        tinted = image[over_ground].astype(int)
        # The volume shows (the ground is tinted blue) ...
        assert tinted[2] - tinted[0] > 15
        assert np.abs(tinted - image[bare_ground].astype(int)).max() > 15
        # ... and the ground shows through it: what is behind changes the colour.
        assert np.abs(tinted - image[over_background].astype(int)).max() > 20
    finally:
        plotter.close()


def test_pbr_and_screenshot_file(tmp_path):
    from PIL import Image

    target = tmp_path / "picture.png"
    image = sg.plot(
        [ground_shape(), box_mesh()],
        lights=[sg.PointLight(LIGHT)],
        screenshot=target,
        window_size=SIZE,
        pbr=True,
    )
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 20
    written = np.asarray(Image.open(target).convert("RGB"))
    np.testing.assert_array_equal(written, image)
    assert [p.name for p in tmp_path.iterdir()] == ["picture.png"]  # no temporary left


def test_z_up_scene_top_view_looks_down_z():
    vertices = [[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]]
    ground = sg.Shape(vertices, [[0, 1, 2], [0, 2, 3]])
    marker = trimesh.creation.box(bounds=[[2, 2, 0], [4, 4, 0.5]])
    scene = sg.Scene([ground, sg.Shape(marker.vertices, marker.faces)], up_axis="Z")
    plotter, image = render(scene, view="top")
    try:
        camera = np.array(plotter.camera.position) - np.array(plotter.camera.focal_point)
        assert camera[2] > 0 and np.allclose(camera[:2], 0, atol=1e-9 * np.linalg.norm(camera))
    finally:
        plotter.close()


def test_bad_input_is_named():
    with pytest.raises(sg.GeometryError, match="cannot plot str"):
        sg.plot("scene.x3d", off_screen=True)
    with pytest.raises(sg.GeometryError, match="view must be one of"):
        sg.plot([box_mesh()], off_screen=True, view="sideways")
    with pytest.raises(sg.GeometryError, match="non-zero"):
        sg.plot([box_mesh()], off_screen=True, view=(0, 0, 0))


# -- the render and view commands -------------------------------------------------------------


@pytest.fixture
def scene_file(tmp_path):
    """A glTF scene: ground, box and a point light that casts shadows."""
    box = box_mesh()
    scene = sg.Scene(
        [ground_shape(), sg.Shape(box.vertices, box.faces, name="box")],
        [sg.SceneLight(sg.PointLight(LIGHT), name="lamp", shadows=True)],
    )
    path = tmp_path / "scene.glb"
    sg.save(scene, path)
    return path


def dark_fraction(image):
    return float((image.astype(float).mean(axis=2) < 50).mean())


def test_render_writes_a_png_with_the_shadow(scene_file, tmp_path, capsys):
    from PIL import Image

    from cli.main import main

    with_shadows, without = tmp_path / "with.png", tmp_path / "without.png"
    size = ["--size", "320x240", "--view", "top"]
    assert main(["render", str(scene_file), str(with_shadows), *size]) == 0
    assert "1 shadows" in capsys.readouterr().out
    assert main(["render", str(scene_file), str(without), *size, "--no-shadows"]) == 0
    shadowed = np.asarray(Image.open(with_shadows).convert("RGB"))
    plain = np.asarray(Image.open(without).convert("RGB"))
    assert shadowed.shape == plain.shape == (240, 320, 3)
    # Seen from above, the dark pixels added are the shadow: its area (hull of the
    # projected corners) over the ground's 20 x 20, times the ground's share of the image.
    hull = reference_shadow_xz()
    expected = ConvexHull(hull).volume / 400.0 * np.any(plain != 255, axis=2).mean()
    added = dark_fraction(shadowed) - dark_fraction(plain)
    assert 0.5 * expected < added < 1.5 * expected, (added, expected)


def test_render_usage_and_input_errors(scene_file, tmp_path, capsys):
    from cli.main import main

    assert main(["render", str(scene_file), str(tmp_path / "out.jpg")]) == 2
    assert ".png" in capsys.readouterr().err
    assert main(["render", str(tmp_path / "missing.glb"), str(tmp_path / "out.png")]) == 1
    assert "missing.glb" in capsys.readouterr().err
    for bad in (["--view", "sideways"], ["--view", "0,0,0"], ["--size", "big"]):
        with pytest.raises(SystemExit) as exit_:
            main(["render", str(scene_file), str(tmp_path / "out.png"), *bad])
        assert exit_.value.code == 2
    assert not list(tmp_path.glob("out*"))


def test_view_without_a_display_says_so(scene_file, monkeypatch, capsys):
    from cli.main import main

    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", str(scene_file)]) == 1
    error = capsys.readouterr().err
    assert "no display" in error and "shadowgeo render" in error
    with pytest.raises(RuntimeError, match="no display"):
        sg.plot([box_mesh()])


# -- the examples -----------------------------------------------------------------------------

EXAMPLES = ROOT / "examples"


@pytest.mark.parametrize(
    "script, picture",
    [
        ("tilted_plane.py", "picture.png"),
        ("shadow_volume.py", "picture.png"),
        ("converted_scene.py", "converted_scene.png"),
        ("sunlight_map.py", "picture.png"),
    ],
)
def test_examples_draw_their_pictures(script, picture, tmp_path, monkeypatch, capsys):
    from PIL import Image

    argument = tmp_path if script == "converted_scene.py" else tmp_path / picture
    monkeypatch.setattr(sys, "argv", [script, str(argument)])
    runpy.run_path(str(EXAMPLES / script), run_name="__main__")
    image = np.asarray(Image.open(tmp_path / picture).convert("RGB"))
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 20
    printed = capsys.readouterr().out
    if script == "sunlight_map.py":
        # the map's full sun (yellow) and its shaded hours (green to purple)
        red, green, blue = (image[..., k].astype(float) for k in range(3))
        assert ((red > 200) & (green > 180) & (blue < 90)).mean() > 0.2
        assert ((green > red + 30) & (green > blue)).mean() > 0.01
        share = float(re.search(r"([\d.]+)% of the ground has at least 2 hours", printed)[1])
        assert 0 < share < 100
        return
    if script == "converted_scene.py":
        # The courtyard's lamp shares the ground's light with a fill light and
        # the headlight: its shadow is drawn part-dark, as X_ITE draws it. Ground
        # (green over red over blue) darker than 140: 1.6 per mille of the
        # picture without the shadows, about 2 % with them.
        red, green, blue = (image[..., k].astype(float) for k in range(3))
        shaded = (green > red) & (red > blue) & (image.mean(axis=2) < 140)
        assert shaded.mean() > 0.01
    else:
        assert (image.mean(axis=2) < 90).mean() > 0.005  # a shadow is in the picture
    if script == "shadow_volume.py":
        # The volume sliced at the ground has the planar shadow's area
        # (manifold3d slices in float32: agreement to a few parts in 1e7).
        sliced, planar = (float(text) for text in re.findall(r"\b\d+\.\d{6}\b", printed))
        assert sliced == pytest.approx(planar, rel=2e-6)
    if script == "converted_scene.py":
        # glTF and USD keep the shapes' roles; X3D keeps the group the shadows went in.
        for name in ("courtyard_shadows.glb", "courtyard_shadows.usda"):
            assert sg.load(tmp_path / name).shapes_with_role("shadow"), name
        assert 'DEF="shadows_lamp"' in (tmp_path / "courtyard_shadows.x3d").read_text()


def test_a_light_given_twice_is_drawn_and_lit_once():
    light = sg.PointLight(LIGHT)
    shadow = sg.project_shadow(box_mesh(), light, sg.Plane([0, 1, 0], 0))
    scene = sg.Scene([ground_shape()], [sg.SceneLight(sg.PointLight(LIGHT), color=(1, 0, 0))])
    plotter = viz.scene_plotter(scene, shadows=[shadow, shadow], off_screen=True, window_size=SIZE)
    try:
        scene_lights = [light for light in plotter.renderer.lights if not light.is_headlight]
        assert len(scene_lights) == 1
        assert tuple(scene_lights[0].diffuse_color.float_rgb) == (1.0, 0.0, 0.0)  # the scene's
    finally:
        plotter.close()


def test_two_spots_at_one_place_aiming_apart_are_both_lit():
    spots = [sg.SpotLight(LIGHT, direction) for direction in ([0, -1, 0], [1, -1, 0])]
    plotter = viz.scene_plotter([ground_shape()], lights=spots, off_screen=True, window_size=SIZE)
    try:
        assert len([light for light in plotter.renderer.lights if not light.is_headlight]) == 2
    finally:
        plotter.close()


def test_a_scene_of_lights_alone_is_centred_on_its_positional_lights():
    lamp, sun = sg.PointLight([10.0, 10.0, 10.0]), sg.DirectionalLight([0, -1, 0])
    scene = sg.Scene([], [sg.SceneLight(lamp), sg.SceneLight(sun)])
    plotter = viz.scene_plotter(scene, off_screen=True, window_size=SIZE)
    try:
        lights = [light for light in plotter.renderer.lights if not light.is_headlight]
        (sunlight,) = [light for light in lights if not light.positional]
        np.testing.assert_allclose(sunlight.focal_point, lamp.position)  # lit towards the centre
    finally:
        plotter.close()


VIEWPOINTS = """<X3D version="4.0"><Scene>
<Shape DEF="ground"><IndexedFaceSet coordIndex="0 1 2 3 -1">
<Coordinate point="-10 0 -10 -10 0 10 10 0 10 10 0 -10"/></IndexedFaceSet></Shape>
<Transform translation="0 2 0"><Shape DEF="crate"><Box size="1 1 1"/></Shape></Transform>
<DirectionalLight direction="0.3 -1 0.2" shadows="true"/>
<Transform translation="10 0 0" rotation="0 1 0 1.5707963267948966" scale="2 2 2">
<Viewpoint DEF="side" position="1 2 3" orientation="1 0 0 -0.5" fieldOfView="0.6"/></Transform>
<Viewpoint DEF="front" description="From the front" position="0 3 20" fieldOfView="0.9"/>
</Scene></X3D>
"""


def camera_of(plotter):
    camera = plotter.camera
    position, focal = np.array(camera.position), np.array(camera.focal_point)
    direction = (focal - position) / np.linalg.norm(focal - position)
    return position, direction, np.array(camera.up), camera.view_angle


@pytest.mark.parametrize("size", [(320, 240), (240, 320)])
def test_render_camera_is_the_scenes_first_viewpoint(tmp_path, size):
    path = tmp_path / "views.x3d"
    path.write_text(VIEWPOINTS)
    scene = sg.add_shadows(sg.load(path))
    plotter = viz.scene_plotter(scene, off_screen=True, window_size=size)
    try:
        position, direction, up, angle = camera_of(plotter)
    finally:
        plotter.close()
    # By hand: a quarter turn about +y takes (x, y, z) to (z, y, -x). The
    # Viewpoint (1, 2, 3) scaled by 2 and moved by (10, 0, 0) is at (16, 4, -2);
    # about +x by -0.5, -z becomes (0, -sin .5, -cos .5) and +y (0, cos .5, -sin .5).
    np.testing.assert_allclose(position, [16, 4, -2], atol=1e-9)
    np.testing.assert_allclose(direction, [-np.cos(0.5), -np.sin(0.5), 0], atol=1e-9)
    np.testing.assert_allclose(up, [-np.sin(0.5), np.cos(0.5), 0], atol=1e-9)
    # fieldOfView is the smaller angle; VTK's view angle is the vertical one.
    width, height = size
    vertical = 0.6 if width >= height else 2 * np.arctan(np.tan(0.3) * height / width)
    assert angle == pytest.approx(np.degrees(vertical), rel=1e-12)


def test_render_viewpoint_option_and_view_override(tmp_path, capsys):
    from cli.main import build_parser, main
    from cli.render import camera

    path = tmp_path / "views.x3d"
    path.write_text(VIEWPOINTS)
    scene = sg.load(path)
    for name in ("front", "From the front"):
        args = build_parser().parse_args(["render", str(path), "o.png", "--viewpoint", name])
        plotter = viz.scene_plotter(
            scene, off_screen=True, window_size=SIZE, view=camera(args, scene)
        )
        try:
            position, direction, up, angle = camera_of(plotter)
        finally:
            plotter.close()
        np.testing.assert_allclose(position, [0, 3, 20], atol=1e-12)
        np.testing.assert_allclose(direction, [0, 0, -1], atol=1e-12)
        np.testing.assert_allclose(up, [0, 1, 0], atol=1e-12)
        assert angle == pytest.approx(np.degrees(0.9))
    args = build_parser().parse_args(["render", str(path), "o.png", "--view", "top"])
    assert camera(args, scene) == "top"  # --view overrides the Viewpoint
    out = tmp_path / "front.png"
    assert main(["render", str(path), str(out), "--viewpoint", "front", "--size", "64x48"]) == 0
    assert out.is_file()
    assert main(["render", str(path), str(out), "--viewpoint", "nope"]) == 1
    error = capsys.readouterr().err.strip().splitlines()
    assert error[-1].endswith("no Viewpoint named or described 'nope' (viewpoints: side, front)")


def test_a_shape_without_appearance_is_drawn_unlit_white(tmp_path):
    """X3D draws a Shape with no Appearance unlit, in white (the reader's
    Material: no diffuse, emissive 1 1 1): here with the light under the
    ground, which lights a grey ground's top not at all."""
    path = tmp_path / "bare.x3d"
    path.write_text(
        '<X3D version="4.0"><Scene><PointLight location="0 -5 0"/>'
        '<Shape DEF="bare"><IndexedFaceSet coordIndex="0 1 2 3 -1">'
        '<Coordinate point="-3 0 -3 -3 0 3 3 0 3 3 0 -3"/></IndexedFaceSet></Shape>'
        '<Shape DEF="grey"><Appearance><Material diffuseColor="0.8 0.8 0.8"/></Appearance>'
        '<IndexedFaceSet coordIndex="0 1 2 3 -1">'
        '<Coordinate point="4 0 -3 4 0 3 10 0 3 10 0 -3"/></IndexedFaceSet></Shape>'
        "</Scene></X3D>"
    )
    scene = sg.load(path)
    plotter, image = render(scene, view="top")
    try:
        bare, grey = to_pixels(plotter, [[0.0, 0.0, 0.0], [7.0, 0.0, 0.0]])
        assert brightness(image, bare) > 250
        assert brightness(image, grey) < 100
    finally:
        plotter.close()


def test_the_map_is_drawn_in_its_colours_and_shadows_stay_dark():
    """In a picture the map keeps its colours (emissive shadow-role shapes;
    black ones, baked shadows, are still drawn dark: the test above): half a
    day of sun next to a cube shows bluer than a whole day's yellow."""
    import dataclasses
    import datetime as dt

    from test_sunlight import LONDON, slab_and_cube

    from shadowgeo.scene.sunlight import study_scene, sunlight_shapes
    from shadowgeo.sun import hourly

    scene = slab_and_cube()
    times = hourly(dt.datetime(2026, 6, 21, tzinfo=dt.UTC), dt.datetime(2026, 6, 22, tzinfo=dt.UTC))
    inputs, studies = study_scene(scene, times, **LONDON)
    (study,) = studies.days.values()
    mapped = dataclasses.replace(scene, shapes=[*scene.shapes[1:], *sunlight_shapes(study, 20.0)])
    plotter, image = render(mapped, view="top")
    try:
        # just north of the cube (-z) 8 of 16 sunlit hours; the slab's corner all 16
        near, far = [[2.0, 0.0, 0.45]], [[-9.0, 0.0, 9.0]]
        hours = study.sunlit_hours(inputs.plane.to_2d(np.array(near + far)))
        assert hours.tolist() == [8.0, 16.0]
        shaded, sunny = to_pixels(plotter, near + far)
        shaded_rgb = image[shaded].astype(float)[:3]
        sunny_rgb = image[sunny].astype(float)[:3]
        assert sunny_rgb[0] > 200 and sunny_rgb[2] < 100  # yellow
        assert shaded_rgb[0] < sunny_rgb[0] - 40 and shaded_rgb[2] > sunny_rgb[2] + 20  # bluer
    finally:
        plotter.close()


def test_a_soft_shadow_is_drawn_graded_and_a_rect_light_as_itself():
    # a 2 x 2 x 2 box spanning heights 1 to 3 under a 1 x 1 square light at
    # height 6: umbra [-1.5, 1.5]^2, penumbra [-2.5, 2.5]^2 (hand-derived in
    # test_soft.py); along z = 0 the hidden fraction falls linearly from 1 at
    # x = 1.5 to 0 at x = 2.5, so the floor brightens step by step out there
    box = trimesh.creation.box([2, 2, 2])
    box.apply_translation([0, 2, 0])
    lamp = sg.RectLight([0, 6, 0], [0, -1, 0], 1, 1, up=[0, 0, 1])
    soft = sg.soft_shadow(box, lamp, sg.Plane([0, 1, 0], 0), offset=1e-3)
    plotter, image = render([ground_shape(), box], shadows=soft, view="top")
    try:
        xs = [1.3, 1.75, 2.0, 2.25, 3.0]  # umbra, 3/4, 1/2, 1/4 hidden, lit
        points = [[x, 0, 0] for x in xs]
        values = [brightness(image, pixel) for pixel in to_pixels(plotter, points)]
        assert all(a < b - 5 for a, b in zip(values, values[1:], strict=False)), values
    finally:
        plotter.close()
    # the panel itself (1 x 1, above the box's middle) in the light colour
    plotter, image = render([ground_shape(), box], shadows=soft, view=(0.3, 1.0, 0.2))
    try:
        ((row, column),) = to_pixels(plotter, [[0.0, 6.0, 0.0]])
        assert tuple(image[row, column, :3]) == tuple(round(255 * c) for c in viz.LIGHT_COLOR)
    finally:
        plotter.close()
