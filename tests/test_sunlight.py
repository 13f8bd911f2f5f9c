"""Sun studies of whole scenes: the floor, the casters and the map of sunlight
hours found from the scene (shadowgeo.scene.sunlight), and ``shadowgeo sun``."""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import subprocess
from pathlib import Path

import numpy as np
import pytest
import shapely
import trimesh
from needs import need
from x3d_schema import x3d_schema_errors

import shadowgeo as sg
from cli.main import main
from shadowgeo.scene import Scene, Shape
from shadowgeo.scene.sunlight import scene_study, study_scene, sunlight_shapes
from shadowgeo.sun import hourly, sun_lights

ROOT = Path(__file__).resolve().parents[1]
COURTYARD = ROOT / "examples" / "scenes" / "courtyard.x3d"
LONDON = dict(latitude=51.5, longitude=-0.12)
NOON = dt.datetime(2026, 3, 21, 12, 0, tzinfo=dt.UTC)


def in_process(capsys, *args):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out, err)


def slab_and_cube(z_up: bool = False) -> Scene:
    """A 20 x 20 slab 0.5 thick, its top at height 0, and a unit cube standing
    on it, off centre; Y up, or the same turned so that Z is up (Y-up's
    north, -Z, becomes +Y: the default north of a Z-up scene)."""
    slab = trimesh.creation.box([20.0, 0.5, 20.0])
    slab.apply_translation([0.0, -0.25, 0.0])
    cube = trimesh.creation.box([1.0, 1.0, 1.0])
    cube.apply_translation([2.0, 0.5, 1.0])
    shapes = []
    for name, mesh in (("slab", slab), ("cube", cube)):
        vertices = np.array(mesh.vertices)
        if z_up:  # (x, y, z) -> (x, -z, y): a rotation, the winding kept
            vertices = np.column_stack([vertices[:, 0], -vertices[:, 2], vertices[:, 1]])
        shapes.append(Shape(vertices, np.array(mesh.faces), name=name))
    return Scene(shapes=shapes, up_axis="Z" if z_up else "Y")


def exact_cube_shadow(direction: np.ndarray) -> float:
    """Area of the unit cube's shadow on y = 0 under a sun along ``direction``
    (Y up): the convex hull of its eight corners pushed along the light onto
    the ground, exact for a convex box standing on it."""
    corners = np.array([[x, y, z] for x in (1.5, 2.5) for y in (0.0, 1.0) for z in (0.5, 1.5)])
    ground = corners - (corners[:, 1] / direction[1])[:, None] * direction
    return float(shapely.MultiPoint(ground[:, [0, 2]]).convex_hull.area)


def test_the_floor_is_found_and_its_own_faces_cast_nothing():
    inputs = scene_study(sg.load(COURTYARD))
    assert inputs.floor == "the floor 'ground'" and inputs.up == "Y"
    assert np.allclose(inputs.plane.normal, [0, 1, 0])
    flat = inputs.plane.to_2d(inputs.region)
    assert shapely.Polygon(flat).area == pytest.approx(144.0, rel=1e-12)  # the 12 x 12 ground
    # of the faces lying in the floor's plane, none faces up: the floor's own
    # top casts nothing; the crate's and column's bottoms, resting on it,
    # still shade their footprints
    corners = inputs.caster.vertices[inputs.caster.faces]
    heights = np.abs(inputs.plane.signed_distance(corners.reshape(-1, 3))).reshape(-1, 3)
    lying = heights.max(axis=1) <= 1e-9
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert lying.any() and np.all(normals[lying] @ inputs.plane.normal < 0)


@pytest.mark.parametrize("z_up", [False, True])
def test_one_sample_leaves_the_cubes_exact_shadow_in_the_dark(z_up):
    """One sun sample: the region without sun is the cube's shadow (its
    footprint included), the rest has the sample's hour; the same for the
    scene turned Z-up, whose sun comes from the same side of the cube."""
    scene = slab_and_cube(z_up)
    inputs, studies = study_scene(scene, [NOON], **LONDON)
    (study,) = studies.days.values()
    assert inputs.floor == "the floor 'slab'" and inputs.up == ("Z" if z_up else "Y")
    (_,), (light,) = sun_lights(LONDON["latitude"], LONDON["longitude"], [NOON])
    shadow = exact_cube_shadow(light.direction)
    areas = study.level_areas()
    assert study.area == pytest.approx(400.0, rel=1e-12)
    assert areas[0.0] == pytest.approx(shadow, rel=1e-9)
    assert areas[1.0] == pytest.approx(400.0 - shadow, rel=1e-9)


def test_the_map_tiles_the_floor_in_colours_of_its_hours():
    scene = slab_and_cube()
    times = hourly(dt.datetime(2026, 6, 21, tzinfo=dt.UTC), dt.datetime(2026, 6, 22, tzinfo=dt.UTC))
    inputs, studies = study_scene(scene, times, **LONDON)
    (study,) = studies.days.values()
    shapes = sunlight_shapes(study, inputs.scale)
    assert [s.name for s in shapes] == [f"sunlight_{k}h" for k in sorted(study.levels)]
    assert {s.role for s in shapes} == {"shadow"} and {s.group for s in shapes} == {"sunlight"}
    total = 0.0
    for shape, (_, parts) in zip(shapes, sorted(study.levels.items()), strict=True):
        triangles = shape.vertices[shape.faces]
        normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        exact = sum(shapely.Polygon(part[0], part[1:]).area for part in parts)
        assert 0.5 * np.abs(normals[:, 1]).sum() == pytest.approx(exact, rel=1e-9, abs=1e-12)
        assert np.all(triangles[..., 1] > 0)  # lifted off the floor
        total += exact
    assert total == pytest.approx(400.0, rel=1e-9)
    colours = [np.array(s.material.emissive_color) for s in shapes]
    assert colours[0][2] > colours[0][0] and colours[-1][0] > colours[-1][2]  # purple to yellow
    assert all(s.material.diffuse_color == (0.0, 0.0, 0.0) for s in shapes)  # glows, unlit


def test_no_floor_studies_the_ground_plane_over_the_scene_plan():
    cube = trimesh.creation.box([2.0, 1.0, 4.0])
    cube.apply_translation([0.0, 0.5, 0.0])
    scene = Scene(shapes=[Shape(np.array(cube.vertices), np.array(cube.faces), name="box")])
    inputs = scene_study(scene)
    assert inputs.floor == "the ground plane"
    assert shapely.Polygon(inputs.plane.to_2d(inputs.region)).area == pytest.approx(8.0)
    assert any("no receiver found" in note for note in inputs.notes)
    with pytest.raises(sg.SceneError, match="vertical"):
        scene_study(scene, plane=sg.Plane([1, 0, 0], 0))
    # a floor and nothing on it, or only shapes that cast no shadow
    quad = np.array([[0.0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]])
    floor = Shape(quad, np.array([[0, 1, 2], [0, 2, 3]]))
    with pytest.raises(sg.SceneError, match="nothing in the scene casts"):
        scene_study(Scene(shapes=[floor]))
    # a floor that casts no shadow is still the floor
    plain = slab_and_cube()
    quiet = dataclasses.replace(plain.shapes[0], casts_shadow=False)
    inputs = scene_study(dataclasses.replace(plain, shapes=[quiet, plain.shapes[1]]))
    assert inputs.floor.startswith("the floor 'slab")
    assert len(inputs.caster.faces) == 12  # the cube's, all of them
    ghost = dataclasses.replace(scene.shapes[0], casts_shadow=False)
    with pytest.raises(sg.SceneError, match="nothing in the scene casts"):
        scene_study(Scene(shapes=[floor, ghost]))
    # a named floor may be any patch facing up (a roof terrace: the cube's top)...
    terrace = scene_study(slab_and_cube(), receivers=["cube"])
    assert terrace.floor.startswith("the floor 'cube")  # its top patch, as convert names it
    assert shapely.Polygon(terrace.plane.to_2d(terrace.region)).area == pytest.approx(1.0)
    # ... but a shape with none is refused
    quad = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    sign = Shape(quad, np.array([[0, 1, 2], [0, 2, 3]]), name="sign")
    scene = dataclasses.replace(slab_and_cube(), shapes=[*slab_and_cube().shapes, sign])
    with pytest.raises(sg.SceneError, match="faces up"):
        scene_study(scene, receivers=["sign"])


def test_shadowgeo_sun_prints_the_table_and_writes_the_map(capsys, tmp_path, x3d_schema):
    before = hashlib.sha256(COURTYARD.read_bytes()).hexdigest()
    out = tmp_path / "map.x3d"
    done = in_process(capsys, "sun", COURTYARD, out, "--at", "51.5,-0.12", "--date", "2026-03-21")
    assert done.returncode == 0, done.stderr
    assert "12 of 24 samples with the sun up on 2026-03-21" in done.stdout
    assert "| sunlight (h) | area | share of the region |" in done.stdout
    assert "of the region has at least 2 h of sun" in done.stdout
    assert "note: sun study: over the floor 'ground'" in done.stderr
    assert hashlib.sha256(COURTYARD.read_bytes()).hexdigest() == before  # never modified
    written = sg.load(out)
    maps = [s for s in written.shapes if s.role == "shadow"]
    assert maps and {s.group for s in maps} == {"sunlight"}
    area = 0.0
    for shape in maps:
        triangles = shape.world_vertices[shape.faces]
        area += 0.5 * np.abs(np.cross(triangles[:, 1] - triangles[:, 0],
                                      triangles[:, 2] - triangles[:, 0])[:, 1]).sum()  # fmt: skip
    assert area == pytest.approx(144.0, rel=1e-9)  # the map covers the ground once
    # the rows of the table are its durations, their shares adding up to the region
    rows = [
        line.split("|")
        for line in done.stdout.splitlines()
        if line.startswith("| ") and "%" in line
    ]
    assert sum(float(row[2]) for row in rows) == pytest.approx(144.0, rel=1e-5)
    # converting the map again replaces it as an earlier run's shadows
    again = sg.add_shadows(written)
    assert not [s for s in again.shapes if s.group == "sunlight"]
    assert x3d_schema_errors(out, x3d_schema) == []


def test_shadowgeo_sun_with_the_suns_disc_counts_fractions_of_hours(capsys, tmp_path):
    args = ["--at", "51.5,-0.12", "--date", "2026-03-21"]
    out = tmp_path / "map.x3d"
    done = in_process(
        capsys, "sun", COURTYARD, out, *args, "--sun-angle", "0.53", "--sun-samples", "4"
    )
    assert done.returncode == 0, done.stderr
    assert "the sun a 0.53 degree disc of 4 directions" in done.stdout
    rows = [line.split("|") for line in done.stdout.splitlines() if line.startswith("| ")]
    # the table bins the quarter hours into whole samples ("2 to 3"), one row
    # each, the whole day alone, and the bins still tile the region
    labels = [row[1].strip() for row in rows if "%" in row[3]]
    bins = [label.split(" to ") for label in labels]
    assert all(len(b) == 1 or float(b[1]) - float(b[0]) == 1.0 for b in bins), labels
    assert len(labels) == len(set(labels)) and len(labels) <= 13
    assert sum(float(row[2]) for row in rows if "%" in row[3]) == pytest.approx(144.0, rel=1e-5)
    point = in_process(capsys, "sun", COURTYARD, *args)
    assert "disc" not in point.stdout
    # the disc moves the share meeting 2 hours only by its thin penumbrae
    shares = [
        float(line.split("%")[0]) for run in (done, point) for line in run.stdout.splitlines()
        if "of the region has at least" in line
    ]  # fmt: skip
    assert shares[0] == pytest.approx(shares[1], abs=1.0)
    maps = [s for s in sg.load(out).shapes if s.role == "shadow"]
    assert any(s.name.endswith("_25h") or "_75h" in s.name for s in maps)


def test_shadowgeo_sun_over_days_is_the_same_on_dask(capsys):
    args = ["sun", COURTYARD, "--at", "51.5,-0.12", "--date", "2026-06-20", "--days", "2"]
    serial = in_process(capsys, *args, "--serial")
    assert serial.returncode == 0, serial.stderr
    assert "| 2026-06-20 |" in serial.stdout and "| 2026-06-21 |" in serial.stdout
    need("dask")
    parallel = in_process(capsys, *args, "--workers", "1", "--progress")
    assert parallel.returncode == 0, parallel.stderr
    assert parallel.stdout == serial.stdout
    assert "2 day(s) [" in parallel.stderr and "100%" in parallel.stderr


def test_shadowgeo_sun_usage(capsys, tmp_path):
    for args in (
        ["sun", str(COURTYARD)],  # no --at
        ["sun", str(COURTYARD), "--at", "95,0"],
        ["sun", str(COURTYARD), "--at", "51,0", "--date", "21 March"],
        ["sun", str(COURTYARD), "--at", "51,0", "--hours", "25"],
        ["sun", str(COURTYARD), str(tmp_path / "m.x3d"), "--at", "51,0", "--days", "2"],
        ["sun", str(COURTYARD), "--at", "51,0", "--serial", "--workers", "2"],
        ["sun", str(COURTYARD), "--at", "51,0", "--sun-angle", "-0.5"],
        ["sun", str(COURTYARD), "--at", "51,0", "--sun-angle", "90"],
        ["sun", str(COURTYARD), "--at", "51,0", "--sun-angle", "0.53", "--sun-samples", "0"],
    ):
        with pytest.raises(SystemExit) as exit_:
            main(args)
        assert exit_.value.code == 2, args
    capsys.readouterr()
    done = in_process(capsys, "sun", COURTYARD, "--at", "51,0", "--plane", "1,0,0,0")
    assert done.returncode == 1 and "vertical" in done.stderr
    done = in_process(capsys, "sun", tmp_path / "none.x3d", "--at", "51,0")
    assert done.returncode == 1 and "none.x3d" in done.stderr
    (tmp_path / "there.x3d").write_text("")  # OUT exists, SCENE does not: no traceback
    done = in_process(capsys, "sun", tmp_path / "none.x3d", tmp_path / "there.x3d", "--at", "51,0")
    assert done.returncode == 1 and "none.x3d" in done.stderr
    assert (tmp_path / "there.x3d").read_text() == ""


def test_a_scene_study_equals_the_hand_made_one():
    """The scene's study is sg.sun_study of the same caster, plane and region."""
    scene = slab_and_cube()
    times = hourly(dt.datetime(2026, 3, 21, tzinfo=dt.UTC), dt.datetime(2026, 3, 22, tzinfo=dt.UTC))
    inputs, studies = study_scene(scene, times, **LONDON)
    cube = dataclasses.replace(scene.shapes[1])
    by_hand = sg.sun_study(
        (cube.vertices, cube.faces), sg.Plane([0, 1, 0], 0), inputs.region, times, **LONDON
    )
    (study,) = studies.days.values()
    ours, theirs = study.level_areas(), by_hand.level_areas()
    assert sorted(ours) == sorted(theirs)
    for hours in ours:
        assert ours[hours] == pytest.approx(theirs[hours], rel=1e-9, abs=1e-12)


def test_a_basement_under_the_floor_leaves_the_study_as_it_was():
    """A box wholly under the slab (a basement reaching far below it, deeper
    than the buildings are tall): the slab is still the floor, and what lies
    under it shades nothing."""
    scene = slab_and_cube()
    basement = trimesh.creation.box([4.0, 2.0, 4.0])
    basement.apply_translation([-4.0, -3.0, -4.0])
    below = Shape(np.array(basement.vertices), np.array(basement.faces), name="basement")
    deep = dataclasses.replace(scene, shapes=[*scene.shapes, below])
    times = hourly(dt.datetime(2026, 3, 21, tzinfo=dt.UTC), dt.datetime(2026, 3, 22, tzinfo=dt.UTC))
    (plain,) = study_scene(scene, times, **LONDON)[1].days.values()
    inputs, studies = study_scene(deep, times, **LONDON)
    (study,) = studies.days.values()
    assert inputs.floor.startswith("the floor 'slab")
    assert study.area == pytest.approx(400.0, rel=1e-12)
    ours, theirs = study.level_areas(), plain.level_areas()
    assert sorted(ours) == sorted(theirs)
    for hours in ours:
        assert ours[hours] == pytest.approx(theirs[hours], rel=1e-9, abs=1e-9)


def test_a_region_in_plan_is_dropped_onto_the_floor_and_studied_alone(capsys):
    """--region: a 6 x 6 square in plan (x, z) over the courtyard; in the
    library, the same square over the slab is sg.sun_study's over it, and for
    the scene turned Z-up the square is in (x, y) and the levels the same."""
    done = in_process(
        capsys, "sun", COURTYARD, "--at", "51.5,-0.12", "--region=-3,-3,3,-3,3,3,-3,3"
    )
    assert done.returncode == 0, done.stderr
    assert "region 36 square units" in done.stdout
    assert "within the region given" in done.stderr
    square = [(-3.0, -3.0), (3.0, -3.0), (3.0, 3.0), (-3.0, 3.0)]
    times = hourly(dt.datetime(2026, 3, 21, tzinfo=dt.UTC), dt.datetime(2026, 3, 22, tzinfo=dt.UTC))
    areas = []
    for z_up in (False, True):
        inputs, studies = study_scene(slab_and_cube(z_up), times, region=square, **LONDON)
        (study,) = studies.days.values()
        up = 2 if z_up else 1
        across = [0, 1] if z_up else [0, 2]
        assert np.allclose(inputs.region[:, up], 0.0)  # on the slab's top
        assert np.allclose(inputs.region[:, across], square)
        assert study.area == pytest.approx(36.0, rel=1e-12)
        areas.append(study.level_areas())
    cube = slab_and_cube().shapes[1]
    corners = np.array([[x, 0.0, z] for x, z in square])
    by_hand = sg.sun_study(
        (cube.vertices, cube.faces), sg.Plane([0, 1, 0], 0), corners, times, **LONDON
    ).level_areas()
    for ours in areas:
        assert sorted(ours) == sorted(by_hand)
        for hours in ours:
            assert ours[hours] == pytest.approx(by_hand[hours], rel=1e-9, abs=1e-9)
    for args in (["--region", "1,2,3,4"], ["--region", "a,b,c,d,e,f"]):
        with pytest.raises(SystemExit) as exit_:
            main(["sun", str(COURTYARD), "--at", "51,0", *args])
        assert exit_.value.code == 2
    capsys.readouterr()
    with pytest.raises(sg.SceneError, match="no area"):
        scene_study(slab_and_cube(), region=[(0, 0), (1, 1), (2, 2)])
