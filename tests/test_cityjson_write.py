"""Hours of sunlight on CityJSON's semantic surfaces
(:mod:`shadowgeo.io.cityjson_write`): each polygon given hours gets a
surface of its own carrying them, the rest of the file unchanged, and the
file still reads as before."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_city import CUBE_VERTICES, TRANSLATE, _cityjson, _cube

import shadowgeo as sg
from shadowgeo.errors import SceneError
from shadowgeo.io.cityjson_write import surface_polygons, write_surface_hours


def test_cube_polygons_each_get_their_hours_and_the_file_reads_the_same(tmp_path):
    source = _cityjson(
        tmp_path / "cube.city.json", {"b": {"type": "Building", "geometry": [_cube()]}}
    )
    polygons = surface_polygons(source)
    # ground, roof, three walls sharing one surface, one wall with none (the file's order)
    kinds = [polygon.kind for polygon in polygons]
    assert kinds == ["GroundSurface", "RoofSurface", *["WallSurface"] * 3, None]
    scale = np.array([0.001] * 3)
    corners = np.asarray(CUBE_VERTICES) * scale + TRANSLATE
    assert np.allclose(polygons[1].outer, corners[[4, 5, 6, 7]])
    hours = [0.0, 12.0, 3.0, 4.5, None, 7.0]
    target = tmp_path / "hours.city.json"
    assert write_surface_hours(source, target, hours) == 1  # the untyped wall
    geometry = json.loads(target.read_text())["CityObjects"]["b"]["geometry"][0]
    surfaces, values = geometry["semantics"]["surfaces"], geometry["semantics"]["values"][0]
    given = [surfaces[v].get("sunlight_hours") if v is not None else None for v in values]
    assert given == [0.0, 12.0, 3.0, 4.5, None, None]
    assert [surfaces[v]["type"] if v is not None else None for v in values] == kinds
    # the shared wall surface is kept for the wall given no hours, slope and all
    assert surfaces[values[4]] == {"type": "WallSurface", "slope": 90}
    assert surfaces[values[2]] == {"type": "WallSurface", "slope": 90, "sunlight_hours": 3.0}
    before, after = sg.load(source).shapes[0], sg.load(target).shapes[0]
    assert np.array_equal(before.world_vertices, after.world_vertices)
    assert before.semantics.counts() == after.semantics.counts()
    for kind in before.semantics.kinds:
        assert np.array_equal(before.semantics.faces(kind), after.semantics.faces(kind))


def test_hours_not_one_per_polygon_or_not_finite_are_refused(tmp_path):
    source = _cityjson(
        tmp_path / "cube.city.json", {"b": {"type": "Building", "geometry": [_cube()]}}
    )
    with pytest.raises(SceneError, match="2 hours for 6 polygons"):
        write_surface_hours(source, tmp_path / "x.city.json", [1.0, 2.0])
    with pytest.raises(SceneError, match="not finite"):
        write_surface_hours(source, tmp_path / "x.city.json", [float("nan")] + [None] * 5)
    assert not (tmp_path / "x.city.json").exists()


def test_each_face_knows_the_file_polygon_it_was_cut_from(tmp_path):
    """Semantics.polygon against the file: every triangle's corners are
    corners of its polygon's outer ring (the cube's six quads, two
    objects, so numbers restart per object)."""
    body = {"type": "Building", "geometry": [_cube()]}
    source = _cityjson(tmp_path / "two.city.json", {"a": body, "b": body})
    polygons = surface_polygons(source)
    for shape in sg.load(source).shapes:
        rings = [polygon.outer for polygon in polygons if polygon.object_id == shape.name]
        numbers = shape.semantics.polygon
        assert sorted(set(numbers.tolist())) == list(range(6))
        for corners, number in zip(shape.world_vertices[shape.faces], numbers, strict=True):
            ring = rings[number]
            assert all(np.abs(ring - corner).max(axis=1).min() < 1e-9 for corner in corners)
