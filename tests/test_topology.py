import numpy as np
import pytest
import trimesh

from shadowgeo import GeometryError, as_caster


def test_closed_mesh_is_closed_and_open_mesh_is_not():
    sphere = trimesh.creation.icosphere(subdivisions=2)
    assert as_caster(sphere).is_closed
    open_mesh = (sphere.vertices, sphere.faces[1:])
    assert not as_caster(open_mesh).is_closed
    flipped = sphere.faces.copy()
    flipped[0] = flipped[0, ::-1]
    assert not as_caster((sphere.vertices, flipped)).is_closed


def test_topology_is_cached_on_the_mesh_and_dropped_when_it_changes():
    mesh = trimesh.creation.box()
    first = as_caster(mesh)
    assert as_caster(mesh) is first
    mesh.vertices = mesh.vertices * 2.0
    assert as_caster(mesh) is not first


def test_winding_number_inside_and_outside():
    caster = as_caster(trimesh.creation.box(extents=[2, 2, 2]))
    assert caster.winding_number([0.1, 0.2, 0.3]) == pytest.approx(1.0)
    assert caster.winding_number([3, 0, 0]) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    ("vertices", "faces", "message"),
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], "missing vertex"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, -1, 2]], "missing vertex"),
        ([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], "not finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2, 0]], r"\(m, 3\)"),
    ],
)
def test_bad_casters_are_refused(vertices, faces, message):
    with pytest.raises(GeometryError, match=message):
        as_caster((vertices, faces))
