"""Issue 12, second fuzzing campaign: findings of cost and geometry
(c8, c9, c10, c13, g2, g7), each pinned by a self-contained case."""

from __future__ import annotations

import math

import numpy as np

from cli.main import main
from shadowgeo.io import x3d_extrusion
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
