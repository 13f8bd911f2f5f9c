"""The public API's shape: one name for the caster, the old name still working
with a warning, the types a user annotates with exported, hints shipped."""

from __future__ import annotations

import inspect
import typing
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import shadowgeo as sg

ROOT = Path(__file__).resolve().parents[1]
BOX = trimesh.creation.box(bounds=[[-0.5, 1.0, -0.5], [0.5, 2.0, 0.5]])
LIGHT = sg.PointLight([0.3, 5.0, 0.2])


@pytest.mark.parametrize("function", [sg.project_shadow, sg.silhouette, sg.shadow_volume])
def test_every_geometry_function_calls_its_first_argument_caster(function):
    first = next(iter(inspect.signature(function).parameters.values()))
    assert first.name == "caster"
    assert "MeshLike" in str(first.annotation)


@pytest.mark.parametrize("function", [sg.silhouette, sg.shadow_volume])
def test_the_old_keyword_mesh_still_works_with_a_deprecation_warning(function):
    expected = function(caster=BOX, light=LIGHT)
    with pytest.warns(DeprecationWarning, match=r"mesh=.*caster"):
        old = function(mesh=BOX, light=LIGHT)
    if function is sg.silhouette:
        assert np.array_equal(old.edges, expected.edges)
        assert np.array_equal(old.front, expected.front)
    else:
        assert old.volume == pytest.approx(expected.volume, rel=1e-12)
        assert old.is_watertight
    with pytest.raises(TypeError, match="mesh="):
        function(BOX, mesh=BOX, light=LIGHT)


def test_the_new_keyword_gives_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sg.silhouette(caster=BOX, light=LIGHT)
        sg.shadow_volume(BOX, LIGHT)


def test_light_and_meshlike_are_exported_and_mean_what_they_say():
    assert {"Light", "MeshLike"} <= set(sg.__all__)
    assert set(typing.get_args(sg.Light)) == {sg.PointLight, sg.DirectionalLight, sg.SpotLight}
    # Each form MeshLike names is accepted, and gives the same shadow.
    areas = [
        sg.project_shadow(caster, LIGHT, sg.Plane([0, 1, 0], 0)).area
        for caster in (BOX, (BOX.vertices, BOX.faces), sg.as_caster(BOX))
    ]
    assert areas[0] > 0 and areas[1] == areas[0] and areas[2] == areas[0]


def test_py_typed_is_in_the_package_and_declared_as_package_data():
    assert (ROOT / "shadowgeo" / "py.typed").is_file()
    assert Path(sg.__file__).with_name("py.typed").is_file()
    assert '"py.typed"' in (ROOT / "pyproject.toml").read_text()


def test_string_options_are_literals():
    method = inspect.signature(sg.project_shadow).parameters["method"].annotation
    assert method.replace("'", '"') == 'Literal["auto", "triangles"]'
    method = inspect.signature(sg.add_shadows).parameters["method"].annotation
    assert method.replace("'", '"') == 'Literal["planar", "volume"]'
