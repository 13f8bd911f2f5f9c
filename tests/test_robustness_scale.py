"""Issue 12, second fuzzing campaign: findings of cost and geometry
(c8, c9, c10, c13, g2, g7), each pinned by a self-contained case."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

import shadowgeo as sg
from cli.main import main
from shadowgeo.io.x3d import extrusion as x3d_extrusion
from shadowgeo.scene import Shape, receivers
from shadowgeo.tolerance import Tolerance


def run(capsys, *args) -> tuple[int, str, str]:
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_c10_frames_of_a_zigzag_spine_match_the_spec():
    """ISO 19775-1 13.3.5: Y is the spine's tangent (next minus previous
    point), Z the bend normal (cross of the two legs), kept from flipping; X = Y x Z.
    A zigzag in the XY plane bends alternately left and right, so the raw
    normals alternate +-Z and the kept ones are all one sign."""
    n = 2001
    spine = np.column_stack([np.arange(n) % 2, np.arange(n), np.zeros(n)]).astype(float)
    axes = x3d_extrusion.frames(spine)
    assert axes.shape == (n, 3, 3)
    middle = spine[2:] - spine[:-2]
    expected_y = middle / np.linalg.norm(middle, axis=1, keepdims=True)
    assert np.allclose(axes[1:-1, :, 1], expected_y)
    assert np.allclose(axes[0, :, 1], (spine[1] - spine[0]) / math.sqrt(2))
    # first point's normal: (spine[2]-spine[1]) x (spine[0]-spine[1]) = (-1,1,0) x (-1,-1,0)
    z = np.cross(spine[2] - spine[1], spine[0] - spine[1])
    z /= np.linalg.norm(z)
    assert np.allclose(axes[:, :, 2], z)  # every Z the same: the flips undone
    assert np.allclose(axes[:, :, 0], np.cross(axes[:, :, 1], axes[:, :, 2]))
    rotations = np.einsum("nji,njk->nik", axes, axes)
    assert np.allclose(rotations, np.eye(3))


def test_c10_a_closed_spine_uses_the_wrap_around_tangent():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]], float)
    axes = x3d_extrusion.frames(square)
    # closed: the end points' tangent is spine[1] - spine[n-2] = (1,0,0) - (0,1,0)
    assert np.allclose(axes[0, :, 1], np.array([1, -1, 0]) / math.sqrt(2))
    assert np.allclose(axes[-1], axes[0])
    assert np.allclose(np.abs(axes[:, 2, 2]), 1.0)  # a planar spine bends about Z


def _plate_repeated(copies: int) -> tuple[np.ndarray, np.ndarray]:
    """A 2 x 3 plate on y = 0 (two triangles) whose vertices and faces are
    written ``copies`` times over, each copy's faces turned differently."""
    square = np.array([[0, 0, 0], [2, 0, 0], [2, 0, 3], [0, 0, 3]], float)
    faces = np.array([[0, 2, 1], [0, 3, 2]])
    vertices = np.tile(square, (copies, 1))
    turned = [np.roll(faces, k % 3, axis=1) + 4 * k for k in range(copies)]
    return vertices, np.concatenate(turned)


def test_c13_repeated_faces_are_one_by_coordinates():
    vertices, faces = _plate_repeated(1000)
    first, inverse, counts = receivers.repeated_faces(vertices, faces)
    assert len(first) == 2 and sorted(counts) == [1000, 1000]
    # every copy maps to the distinct face with the same corners
    corners = np.sort(vertices[faces].round().astype(int).reshape(len(faces), -1), axis=1)
    assert np.array_equal(corners, corners[first][inverse])
    # the other winding is another face
    flipped = np.concatenate([faces, faces[:1, ::-1]])
    assert len(receivers.repeated_faces(vertices, flipped)[0]) == 3


def test_c13_patches_of_a_face_written_1000_times_weigh_every_copy():
    vertices, faces = _plate_repeated(1000)
    shape = Shape(vertices, faces, np.eye(4))
    found = receivers.patches(shape, Tolerance())
    assert len(found) == 1
    plane, member, area = found[0]
    assert member.shape == (2000,) and member.all()
    assert math.isclose(area, 1000 * 6.0)
    # (0, 2, 1): (v2 - v0) x (v1 - v0) = (2, 0, 3) x (2, 0, 0) = (0, 6, 0): +y
    assert np.allclose(plane.normal, [0, 1, 0]) and abs(plane.offset) < 1e-12


# g7, shrunk by the fuzzer: 8 faces of an icosphere of size ~2 at 1.6e15, where
# float64's spacing is 0.25; a sun at 55 degrees gave an area of -2.06e7.
G7_VERTICES = [
    [-754504918379336.1, 1574836923801528.2, 314530175229224.25],
    [-754504918379336.6, 1574836923801527.0, 314530175229223.4],
    [-754504918379336.6, 1574836923801528.0, 314530175229223.4],
    [-754504918379337.5, 1574836923801527.5, 314530175229223.75],
    [-754504918379337.0, 1574836923801526.8, 314530175229224.75],
    [-754504918379337.0, 1574836923801526.8, 314530175229223.75],
    [-754504918379336.6, 1574836923801527.5, 314530175229223.25],
    [-754504918379335.9, 1574836923801528.0, 314530175229223.94],
    [-754504918379336.1, 1574836923801527.2, 314530175229223.44],
    [-754504918379336.1, 1574836923801527.8, 314530175229223.44],
    [-754504918379335.9, 1574836923801528.0, 314530175229224.56],
    [-754504918379335.6, 1574836923801527.5, 314530175229224.25],
    [-754504918379337.5, 1574836923801527.0, 314530175229223.94],
    [-754504918379337.1, 1574836923801527.2, 314530175229223.44],
    [-754504918379337.5, 1574836923801527.0, 314530175229224.56],
    [-754504918379337.1, 1574836923801527.2, 314530175229225.06],
]
G7_FACES = [[4, 15, 14], [1, 5, 13], [13, 12, 3], [5, 12, 13], [8, 1, 6], [9, 6, 2]]
G7_FACES += [[10, 7, 0], [11, 7, 10]]
G7_SUN = sg.DirectionalLight([0.5667685136841292, 0.803401797988215, -0.18253493606865123])


def test_g7_a_caster_below_resolution_never_has_a_negative_area():
    plane = sg.Plane(
        [-0.8209726300315444, 0.5693218935396711, -0.043318844346226126], -1502391942985547.0
    )
    area = sg.project_shadow((G7_VERTICES, G7_FACES), G7_SUN, plane).area
    assert area >= 0.0 and math.isfinite(area)


def test_g2_g7_a_volume_below_resolution_is_an_error_naming_the_caster():
    with pytest.raises(sg.GeometryError, match="below float64 resolution"):
        sg.shadow_volume((G7_VERTICES, G7_FACES), G7_SUN)
    # g2: one triangle 1.6e-6 across at 1e9 (float64's spacing there is 1.2e-7)
    triangle = [
        [-882007972.6267308, 372565350.14264107, 473053340.7483034],
        [-882007972.6267301, 372565350.1426403, 473053340.7483046],
        [-882007972.6267315, 372565350.1426413, 473053340.7483053],
    ]
    sun = sg.DirectionalLight([-0.9999973670663042, -5.660407150257637e-11, -0.0022947462733868456])
    with pytest.raises(sg.GeometryError, match="-882007972"):
        sg.shadow_volume((triangle, [[2, 0, 1]]), sun)


@pytest.mark.parametrize("scale", [1e9, 1e15])
def test_g2_control_the_same_caster_nearer_the_origin_has_a_positive_volume(scale):
    """The resolution check refuses only what rounding has flattened: a unit
    tetrahedron 1e4 units out at the same scales keeps its volume, closed and
    outward (a sweep of 1 unit, so the volume is at least the tetrahedron's)."""
    tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * scale / 1e6
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    volume = sg.shadow_volume((tetra + scale / 1e3, faces), sg.DirectionalLight([0, -1, 0]))
    assert volume.is_watertight and volume.volume > (scale / 1e6) ** 3 / 6 * 0.999


def test_c8_a_sphere_radius_past_the_range_is_named_not_tessellated(tmp_path, capsys):
    path = tmp_path / "sphere.x3d"
    path.write_text('<X3D><Scene><Shape><Sphere radius="1e155"/></Shape></Scene></X3D>')
    code, out, err = run(capsys, "info", path)
    assert code == 0 and "Traceback" not in err
    assert "radius" in out and "1e+155" in out


def test_c9_materials_the_writer_does_not_model_lose_their_non_finite_fields(tmp_path, capsys):
    path = tmp_path / "scene.x3d"
    path.write_text(
        "<X3D><Scene><Shape><Appearance>"
        '<Material diffuseColor="1 0 0"/><Material diffuseColor="nan 0 0"/>'
        '<PhysicalMaterial roughness="inf" baseColor="0.5 0.5 0.5"/>'
        '</Appearance><Box/></Shape><UnlitMaterial emissiveColor="1 -inf -1"/></Scene></X3D>'
    )
    out = tmp_path / "out.x3d"
    code, _, err = run(capsys, "convert", path, out, "--sun", "0.3,-1,0.2", "--plane", "0,1,0,2")
    assert code == 0 and "Traceback" not in err
    text = out.read_text().lower()
    assert "inf" not in text and "nan" not in text
    # the finite fields of the same nodes are kept
    assert 'baseColor="0.5 0.5 0.5"'.lower() in text and "<unlitmaterial" in text


def test_g2_faces_without_height_cast_no_volume():
    """A face with two corners at one point and one with its corners on a
    line (the midpoint, to rounding) enclose nothing: the volume is empty, not
    a closed mesh of zero volume. A real triangle beside them still casts."""
    a, b = np.array([-0.0848, 5.8865, 4.0723]), np.array([0.2976, 5.2228, 3.6563])
    p, q = np.array([-0.0200, 4.3073, 4.9963]), np.array([-0.0594, 4.1951, -0.0528])
    vertices = [a, b, a, p, (p + q) / 2, q]
    spot = sg.SpotLight([1.2894, 8.6925, 9.9643], [-0.4163, -0.4875, -1.1830], 0.2140)
    assert len(sg.shadow_volume((vertices, [[0, 1, 2], [3, 4, 5]]), spot).faces) == 0
    real = sg.shadow_volume((vertices, [[0, 1, 2], [3, 4, 5], [1, 3, 5]]), spot)
    assert real.is_watertight and real.volume > 0


@pytest.mark.parametrize("grazing", [6.8e-13, 5.1e-10])
def test_g2_a_grazing_sun_casts_the_prism_or_nothing(grazing):
    """A unit right triangle (area 1/2) on y = 3.2 under a sun whose
    direction is ``grazing`` below the horizontal. Within the angle tolerance
    (1e-12) it is edge-on: empty. Past it, the volume is the prism's,
    area * sweep * cos, however thin, and positive."""
    y = 3.2259775439249836
    triangle = [[-0.417, y, -0.243], [0.583, y, -0.243], [0.583, y, 0.757]]
    horizontal = np.array([-0.97, 0.0, -0.2426])
    direction = horizontal / np.linalg.norm(horizontal) * math.sqrt(1 - grazing**2)
    direction[1] = -grazing
    volume = sg.shadow_volume((triangle, [[0, 1, 2]]), sg.DirectionalLight(direction))
    if grazing < 1e-12:
        assert len(volume.faces) == 0
    else:
        sweep = volume.metadata["shadowgeo"]["sweep"]
        assert volume.is_watertight
        assert math.isclose(volume.volume, 0.5 * sweep * grazing, rel_tol=1e-3)


def _star(n: int = 8000) -> np.ndarray:
    """A flat star of ``n`` corners, radii 1 and 0.5 by turns."""
    k = np.arange(n)
    radius = np.where(k % 2 == 0, 1.0, 0.5)
    angle = 2 * np.pi * k / n
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])


def _comb(teeth: int = 2000) -> np.ndarray:
    """A comb: a spine along x and ``teeth`` teeth, their feet in line."""
    xs = np.linspace(-3.9, 3.9, 2 * teeth)
    corners = []
    for x0, x1 in zip(xs[0::2], xs[1::2], strict=True):
        corners += [(x0, 0.5), (x0, 3.0), (x1, 3.0), (x1, 0.5)]
    return np.array([(4.0, 0.0), (4.0, 0.5), *corners[::-1], (-4.0, 0.5), (-4.0, 0.0)]) - [0, 1.5]


@pytest.mark.parametrize("outline", [_star, _comb])
def test_a_polygon_of_many_reflex_corners_casts_its_exact_shadow_without_a_quadratic_sweep(
    tmp_path, monkeypatch, outline
):
    """A flat star of 8,000 corners and a comb of 2,000 teeth (each one
    non-convex X3D polygon) over a ground quad under a sun. Clipper2's
    sweep and manifold3d's ear clipping are quadratic in their reflex
    corners (50,000 spikes: 118 s to convert, now 1.7 s; 12,000 teeth: 85 s,
    now 6 s): the outline is certified simple (star-shaped, or by the
    sweep of shadowgeo.sweep), inside the receiver, and cut into triangles
    by shadowgeo itself, so neither sees more than a few corners. The
    shadow's area is the polygon's."""
    import shadowgeo.plane2d as plane2d

    flat = outline()
    n = len(flat)
    corners = np.column_stack([flat[:, 0], np.ones(n), flat[:, 1]])
    point = " ".join(repr(float(x)) for x in corners.ravel())
    index = " ".join(map(str, range(n)))
    path = tmp_path / "flat.x3d"
    path.write_text(
        '<X3D version="4.0"><Scene>'
        '<DirectionalLight direction="0.3 -1 0.2" shadows="true"/>'
        '<Shape DEF="ground"><IndexedFaceSet coordIndex="0 1 2 3 -1">'
        '<Coordinate point="-5 0 -5 -5 0 5 5 0 5 5 0 -5"/></IndexedFaceSet></Shape>'
        f'<Shape DEF="flat"><IndexedFaceSet convex="false" solid="false" coordIndex="{index}">'
        f'<Coordinate point="{point}"/></IndexedFaceSet></Shape></Scene></X3D>'
    )

    def few(function):
        def checked(loops, *args):
            assert sum(len(loop) for loop in loops) < 100, "a sweep over the whole outline"
            return function(loops, *args)

        return checked

    monkeypatch.setattr(plane2d.union, "_clipped", few(plane2d.union._clipped))
    monkeypatch.setattr(
        plane2d.triangulation, "triangulate", few(plane2d.triangulation.triangulate)
    )
    scene = sg.load(path)
    (shape,) = [shape for shape in scene.shapes if shape.name == "flat"]
    assert len(shape.faces) == n - 2
    result = sg.add_shadows(scene, surfaces=False)
    (shadow,) = result.shapes_with_role("shadow")
    triangles = shadow.world_vertices[shadow.faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    assert np.all(normals[:, 1] > 0)  # facing up, no triangle turned over
    area = 0.5 * float(normals[:, 1].sum())
    assert area == pytest.approx(abs(shapely.Polygon(flat).area), rel=1e-12)
