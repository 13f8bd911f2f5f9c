"""A cast shadow reaching a smooth shape's terminator ends where the viewer's
shading ends (the smooth terminator), not in facet-wide stair steps.

The scene: an X3D Sphere (radius 1, at the origin) under an oblique sun, and a
wide slab above it that shades every point of the sphere with ``z`` above
about 0.1 (its edge, cast along the sun, lies near ``z = 0.07``). So on
the sphere, near its terminator, the truth is analytic: a point of the true
sphere with unit normal ``n`` is shaded by the sun where ``n . l > 0`` (``l``
towards the sun), and there the slab blocks it; where ``n . l <= 0`` the
viewer adds no sunlight, shadowed or not, and no shadow is to be drawn.
"""

from __future__ import annotations

import math
import re

import numpy as np
import trimesh
from needs import need
from test_browser import PIXELS, screenshot

import shadowgeo as sg
from cli.main import main
from shadowgeo.scene import primitives
from shadowgeo.scene.surfaces import receiving_faces
from shadowgeo.scene.terminator import clip_to_lit, corner_normals, lit_values

SUN = np.array([1.0, -1.0, 0.35]) / np.linalg.norm([1.0, -1.0, 0.35])  # travel direction
TOWARDS = -SUN
# The slab: 12 x 0.2 x 8, its lower face at y = 2.9, reaching down to z = -0.95:
# rays from the sphere towards the sun meet it where the sphere's z > about 0.07.
SLAB_CENTRE = np.array([-3.0, 3.0, 4.0 + 0.1 - 3.0 * 0.35])


def _text(vector: np.ndarray) -> str:
    return " ".join(f"{value:.17g}" for value in vector)


SCENE = f"""<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0">
  <Scene>
    <DirectionalLight DEF="sun" direction="{_text(SUN)}" shadows="true"/>
    <Shape DEF="ball"><Sphere radius="1"/></Shape>
    <Transform translation="{_text(SLAB_CENTRE)}">
      <Shape DEF="slab"><Box size="12 0.2 8"/></Shape>
    </Transform>
  </Scene>
</X3D>
"""


def blocked_by_slab(points: np.ndarray) -> np.ndarray:
    """(n,) bool: the ray from each point towards the sun meets the slab (by
    hand: where it crosses the slab's lower face)."""
    low, high = SLAB_CENTRE - [6.0, 0.1, 4.0], SLAB_CENTRE + [6.0, 0.1, 4.0]
    reach = (low[1] - points[:, 1]) / TOWARDS[1]
    landed = points + reach[:, None] * TOWARDS
    return (
        (reach > 0)
        & (landed[:, 0] >= low[0])
        & (landed[:, 0] <= high[0])
        & (landed[:, 2] >= low[2])
        & (landed[:, 2] <= high[2])
    )


def sphere_samples(count: int, seed: int = 3) -> np.ndarray:
    """(count, 3) unit vectors, uniform on the sphere."""
    points = np.random.default_rng(seed).normal(size=(count, 3))
    return points / np.linalg.norm(points, axis=1, keepdims=True)


def drawn_on_sphere(result: sg.Scene, directions: np.ndarray) -> np.ndarray:
    """(n,) bool: the ray from the sphere's centre along each direction meets a
    baked shadow triangle lying on the sphere (what a viewer would show dark there)."""
    triangles = []
    for shape in result.shapes_with_role("shadow"):
        corners = shape.world_vertices[shape.faces]
        on_ball = np.abs(np.linalg.norm(corners, axis=2) - 1.0).max(axis=1) < 0.05
        triangles.append(corners[on_ball])
    corners = np.concatenate(triangles)
    mesh = trimesh.Trimesh(corners.reshape(-1, 3), np.arange(len(corners) * 3).reshape(-1, 3))
    hit = mesh.ray.intersects_any(np.zeros_like(directions), directions)
    return np.asarray(hit)


def test_shadow_ends_at_the_smooth_terminator(tmp_path):
    path = tmp_path / "scene.x3d"
    path.write_text(SCENE)
    scene = sg.load(path, chord=3e-4)  # about 3 degrees a facet
    result = sg.add_shadows(scene)
    directions = sphere_samples(40_000)
    facing = directions @ TOWARDS
    truth = (facing > 0) & blocked_by_slab(directions)
    drawn = drawn_on_sphere(result, directions)

    # Well inside the slab's shadow and away from the terminator: all dark;
    # on the far side: nothing drawn.
    deep = (directions[:, 2] > 0.3) & (facing > 0.2) & truth
    assert deep.sum() > 1000 and drawn[deep].mean() > 0.995
    assert not drawn[facing < -0.2].any()
    # Within a band of the terminator (|n . l| < 0.08, about a facet and a
    # half either side) and inside the slab's shadow, what is drawn dark is
    # what the shading lights. Ending at the faceted terminator gets 16 % of
    # the band wrong (the stair steps); the smooth cut, under 2 % (its
    # interpolated normals against the true sphere's).
    # Every shadow point on the ball is lifted off it, outwards: its facets lie
    # within the chord tolerance (3e-4 of the scene's size) inside the unit
    # sphere, and the lift (1e-3 of it) is larger, so none is under the surface.
    for shape in result.shapes_with_role("shadow"):
        radius = np.linalg.norm(shape.world_vertices, axis=1)
        assert not ((radius > 0.9) & (radius < 1.0)).any()
    band = (np.abs(facing) < 0.08) & (directions[:, 2] > 0.3)
    assert band.sum() > 500
    wrong = np.mean(drawn[band] != truth[band])
    assert wrong < 0.05, wrong


def test_smoothed_normals_of_a_sphere_are_its_radii():
    """Crease angle above the facets' angle: each corner's normal is within a
    degree or two of the true sphere's (its position, normalised)."""
    vertices, faces = primitives.sphere(1.0, chord=0.01)
    groups = np.zeros(len(faces), dtype=np.int64)
    smooth = corner_normals(vertices, faces, groups, np.full(len(faces), 0.5))
    radial = vertices[faces]
    angle = np.degrees(np.arccos(np.clip(np.einsum("mkd,mkd->mk", smooth, radial), -1, 1)))
    assert angle.max() < 3.0
    # and 0 keeps each face's own normal at its three corners
    flat = corner_normals(vertices, faces, groups, np.zeros(len(faces)))
    corners = vertices[faces]
    own = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    own /= np.linalg.norm(own, axis=1, keepdims=True)
    assert np.allclose(flat, own[:, None, :])


def test_an_open_shape_turned_round_is_not_smoothed_with_itself():
    """An open shape receives on both sides: its faces go in twice, once each
    way round. X3D's creaseAngle 3.1416 (common in files: smooth everything)
    must not average a face with the turned copies: each side is shaded with
    the normals it has alone, the outside's those of crease 0.5, the
    inside's their opposites."""
    vertices, faces = primitives.sphere(1.0, chord=0.01)
    upper = faces[vertices[faces].mean(axis=1)[:, 1] > 0]  # an open dome
    groups = np.zeros(len(upper), dtype=np.int64)
    alone = corner_normals(vertices, upper, groups, np.full(len(upper), 0.5))
    tolerance = sg.Tolerance.for_points(vertices)
    for crease in (0.5, 3.1416):
        dome = sg.Shape(vertices, upper, solid=False, crease_angle=crease)
        surface = receiving_faces([dome], [], tolerance)
        assert len(surface.faces) == 2 * len(upper)
        outside = surface.vertices[surface.faces[: len(upper)]]
        assert np.array_equal(outside, vertices[upper])  # the faces as given first
        assert np.allclose(surface.normals[: len(upper)], alone, atol=1e-9), crease
        assert np.allclose(surface.normals[len(upper) :], -alone[:, ::-1], atol=1e-9), crease


def test_smoothing_stays_within_a_shape_and_its_crease():
    """Two unit squares folded 60 degrees along x = 0: one normal at the fold
    with a crease above 60 degrees, each face's own below; a second shape
    on the same corners is never averaged in."""
    fold = math.radians(60)
    vertices = np.array(
        [[0, 0, 0], [0, 0, 1], [1, 0, 0], [1, 0, 1], [-math.cos(fold), math.sin(fold), 0],
         [-math.cos(fold), math.sin(fold), 1]]
    )  # fmt: skip
    faces = np.array([[0, 1, 2], [2, 1, 3], [0, 4, 1], [1, 4, 5]])
    normals = corner_normals(vertices, faces, np.zeros(4, np.int64), np.full(4, math.radians(61)))
    # at the fold corner 0 of face 0: the mean of (0, 1, 0) weighted twice... by area:
    # face 0 (area 1/2, normal +y) and face 2 (area 1/2, normal turned 60 degrees)
    expected = np.array([0.0, 1.0, 0.0]) + np.array([math.sin(fold), math.cos(fold), 0.0])
    assert np.allclose(normals[0, 0], expected / np.linalg.norm(expected))
    assert np.allclose(normals[0, 2], [0, 1, 0])  # corner at x = 1: face 0 and 1 only
    apart = corner_normals(vertices, faces, np.zeros(4, np.int64), np.full(4, math.radians(59)))
    assert np.allclose(apart[0, 0], [0, 1, 0])
    shapes = np.array([0, 0, 1, 1])
    separate = corner_normals(vertices, faces, shapes, np.full(4, math.radians(61)))
    assert np.allclose(separate[0, 0], [0, 1, 0])


def test_clip_keeps_the_part_where_the_value_is_positive():
    """The unit right triangle with corner values (-1, 3, 1): the value is 0
    at (0.25, 0) and (0, 0.5); what is kept is the triangle less the corner
    triangle of area 1/16, as two triangles meeting the cut points exactly."""
    face = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    triangle, owner = np.array([[0, 1, 2]]), np.array([0])
    points, triangles, owners = clip_to_lit(
        face[0], triangle, owner, face, np.array([[-1.0, 3, 1]])
    )
    corners = points[triangles]
    twice = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert math.isclose(0.5 * np.linalg.norm(twice, axis=1).sum(), 0.5 - 1 / 16)
    assert (twice[:, 2] > 0).all()  # wound as the face
    assert owners.tolist() == [0, 0]
    assert {tuple(p) for p in points} == {(1, 0, 0), (0, 1, 0), (0.25, 0, 0), (0, 0.5, 0)}
    # one corner kept: the small triangle at it
    points, triangles, _ = clip_to_lit(face[0], triangle, owner, face, np.array([[1.0, -3, -1]]))
    assert {tuple(p) for p in points} == {(0, 0, 0), (0.25, 0, 0), (0, 0.5, 0)}
    # all corners negative: nothing; all positive: the triangle itself
    assert len(clip_to_lit(face[0], triangle, owner, face, -np.ones((1, 3)))[1]) == 0
    assert len(clip_to_lit(face[0], triangle, owner, face, np.ones((1, 3)))[1]) == 1


def test_lit_values_of_a_point_light():
    corners = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 0, 1]]])
    normals = np.tile([0.0, 1.0, 0.0], (1, 3, 1))
    values = lit_values(corners, normals, sg.PointLight([0, 1, 0]))
    assert np.allclose(values, [[1.0, 1 / math.sqrt(2), 1 / math.sqrt(2)]])


def test_a_face_is_not_shadowed_by_the_caster_named_for_it():
    """A unit square on the ground under a sun straight down: a closed box
    above its left half (outlined) and an open sheet above its right half
    (clipped triangle by triangle) each shade a half; naming either for a
    face takes that caster's shadow off that face only."""
    ground = ([[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]], [[0, 1, 2], [0, 2, 3]])
    box = trimesh.creation.box(bounds=[[-0.5, 1, -2], [0.5, 2, 1]])  # x < 0.5
    sheet = ([[0.5, 3, 1], [0.5, 3, -2], [2, 3, -2], [2, 3, 1]], [[0, 1, 2], [0, 2, 3]])
    sun = sg.DirectionalLight([0, -1, 0])
    casters = [box, sheet]
    # face 0 is the lower-right triangle (0,0)-(1,0)-(1,-1); face 1 the upper-left
    every = sg.shadow_on_surface(casters, sun, ground)
    assert np.allclose(every.fraction, [1.0, 1.0])
    no_box = sg.shadow_on_surface(casters, sun, ground, not_shadowed_by=[0, -1])
    # face 0 without the box: the sheet's part, x > 0.5 of (0,0)-(1,0)-(1,-1): 3/8 of 1/2
    assert np.allclose(no_box.fraction, [0.75, 1.0])
    no_sheet = sg.shadow_on_surface(casters, sun, ground, not_shadowed_by=[-1, 1])
    # face 1 without the sheet: the box's part, x < 0.5 of (0,0)-(1,-1)-(0,-1): 3/8 of 1/2
    assert np.allclose(no_sheet.fraction, [1.0, 0.75])


def test_x_ite_shows_the_shadow_ending_at_the_smooth_terminator(tmp_path):
    """The slab's shadow on the Sphere, converted and drawn by X_ITE (its own
    32-segment sphere, our shadow over it) from straight in front along -z,
    orthographic: near the terminator the black pixels are those the sun
    would light and the slab blocks, as on the true sphere."""
    half = 1.25  # the view shows x, y in [-1.25, 1.25]
    view = (
        '<NavigationInfo headlight="true" type=\'"NONE"\'/>'
        f'<OrthoViewpoint position="0 0 10" fieldOfView="{-half} {-half} {half} {half}"/>'
    )
    (tmp_path / "scene.x3d").write_text(SCENE.replace("<Scene>", "<Scene>" + view, 1))
    assert main(["convert", str(tmp_path / "scene.x3d"), str(tmp_path / "baked.x3d")]) == 0
    # the baked shadow alone: the sun's runtime shadow map off
    baked = (tmp_path / "baked.x3d").read_text().replace('shadows="true"', 'shadows="false"')
    # where the shadow lies is the question here, not how dark (the headlight
    # lights the ball too, so the baked shadow is part-transparent: .darkness)
    baked, count = re.subn(
        r'(<Material diffuseColor="0\.0 0\.0 0\.0") transparency="[^"]*"', r"\1", baked
    )
    assert count == 1
    (tmp_path / "converted.x3d").write_text(baked)
    need("x_ite")
    image = screenshot(tmp_path, str(need("chromium")))

    centres = (np.arange(PIXELS) + 0.5) / PIXELS * 2 * half - half
    x, y = np.meshgrid(centres, -centres)  # rows run down the screen, along -y
    inside = x**2 + y**2 < 0.95**2  # clear of the silhouette, where the spheres differ
    normals = np.stack([x, y, np.sqrt(np.clip(1 - x**2 - y**2, 0, 1))], axis=2)[inside]
    facing = normals @ TOWARDS
    truth = (facing > 0) & blocked_by_slab(normals)
    black = image.astype(float).mean(axis=2)[inside] < 12
    deep = (facing > 0.2) & (normals[:, 0] ** 2 + normals[:, 1] ** 2 < 0.8**2) & truth
    assert deep.sum() > 1000 and black[deep].mean() > 0.98, black[deep].mean()
    # Ending at the faceted terminator gets a third of this band wrong; the
    # smooth cut about 6 % (X_ITE's 32-segment sphere against the true one).
    band = (np.abs(facing) < 0.08) & (normals[:, 2] > 0.3)
    assert band.sum() > 1000
    wrong = np.mean(black[band] != truth[band])
    assert wrong < 0.12, wrong


def test_the_reader_gives_each_shape_the_crease_its_browser_shades_with(tmp_path):
    """Curved primitives smooth (across their facets, not their rims), Box
    flat, an IndexedFaceSet its own creaseAngle (default 0: flat)."""
    path = tmp_path / "shapes.x3d"
    path.write_text(
        """<X3D profile="Interchange" version="4.0"><Scene>
        <Shape DEF="ball"><Sphere/></Shape>
        <Shape DEF="can"><Cylinder/></Shape>
        <Shape DEF="hat"><Cone/></Shape>
        <Shape DEF="box"><Box/></Shape>
        <Shape DEF="flat"><IndexedFaceSet coordIndex="0 1 2 -1">
          <Coordinate point="0 0 0, 1 0 0, 0 1 0"/></IndexedFaceSet></Shape>
        <Shape DEF="creased"><IndexedFaceSet creaseAngle="1.2" coordIndex="0 1 2 -1">
          <Coordinate point="0 0 0, 1 0 0, 0 1 0"/></IndexedFaceSet></Shape>
        </Scene></X3D>"""
    )
    crease = {shape.name: shape.crease_angle for shape in sg.load(path).shapes}
    assert crease["box"] == crease["flat"] == 0.0
    assert crease["creased"] == 1.2
    for name in ("ball", "can", "hat"):
        assert math.radians(10) < crease[name] < math.radians(90)  # facets < rims


def test_clip_at_any_scale():
    """The same cut on a face 1e-80 and 1e80 across: the kept area scales
    with the square of the size (3/8 of the face's: values (-1, 3, 1))."""
    for size in (1e-80, 1e80):
        face = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]]) * size
        points, triangles, _ = clip_to_lit(
            face[0], np.array([[0, 1, 2]]), np.array([0]), face, np.array([[-1.0, 3, 1]])
        )
        corners = points[triangles] / size
        twice = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        assert math.isclose(0.5 * np.linalg.norm(twice, axis=1).sum(), 0.5 - 1 / 16)
