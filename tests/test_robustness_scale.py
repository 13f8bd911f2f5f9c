"""Issue 12, second fuzzing campaign: findings of cost and geometry
(c8, c9, c10, c13, g2, g7), each pinned by a self-contained case."""

from __future__ import annotations

import math

import numpy as np

from cli.main import main
from shadowgeo.io import x3d_extrusion


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
