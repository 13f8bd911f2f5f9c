"""Translucent casters in sun studies count by their opacity (issue 33 item 2):
at a sample a point gets ``(1 - a) * step`` of sun, ``a`` the largest opacity
among the casters hiding it, as the converter's rule (shadowgeo.scene.opacity).

References: the shadows of boxes standing on the ground are the convex hulls
of their corners pushed along the sun onto it (hand-derived, shapely's hull);
random points are checked against a Möller-Trumbore ray test written here
that takes, per sample, the largest opacity among the faces it hits."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
import shapely
import trimesh

import shadowgeo as sg
from shadowgeo.scene import Material, Scene, Shape
from shadowgeo.scene.sunlight import scene_study, study_scene
from shadowgeo.sun import sun_lights
from shadowgeo.sunstudy import sun_study

LONDON = dict(latitude=51.5, longitude=-0.12)
NOON = dt.datetime(2026, 3, 21, 12, 0, tzinfo=dt.UTC)
DAY = [dt.datetime(2026, 6, 21, hour, 30, tzinfo=dt.UTC) for hour in range(6, 19, 2)]
FLOOR = [[-10, 0, 10], [10, 0, 10], [10, 0, -10], [-10, 0, -10]]


def box(size, centre) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(size)
    mesh.apply_translation(centre)
    return mesh


def slab_scene(casters: list[tuple[trimesh.Trimesh, float]]) -> Scene:
    """A 20 x 20 slab, its top at y = 0, and ``casters`` (mesh, transparency) on it."""
    shapes = [Shape(np.array(box([20, 0.5, 20], [0, -0.25, 0]).vertices),
                    np.array(box([20, 0.5, 20], [0, -0.25, 0]).faces), name="slab")]  # fmt: skip
    for index, (mesh, transparency) in enumerate(casters):
        shapes.append(
            Shape(
                np.array(mesh.vertices),
                np.array(mesh.faces),
                name=f"caster{index}",
                material=Material(transparency=transparency),
            )
        )
    return Scene(shapes=shapes, up_axis="Y")


def sun_direction(time: dt.datetime) -> np.ndarray:
    _, lights = sun_lights(LONDON["latitude"], LONDON["longitude"], [time], up="Y")
    return np.asarray(lights[0].direction, dtype=np.float64)


def hull_shadow(mesh: trimesh.Trimesh, direction: np.ndarray) -> shapely.Polygon:
    """A convex caster's shadow on y = 0, in (x, z): its corners pushed
    along the light onto the ground, their convex hull."""
    corners = np.asarray(mesh.vertices)
    ground = corners - (corners[:, 1] / direction[1])[:, None] * direction
    return shapely.MultiPoint(ground[:, [0, 2]]).convex_hull


def plan_areas(study, inputs) -> dict[float, float]:
    return {hours: area for hours, area in study.level_areas().items() if area > 1e-12}


def test_a_box_of_transparency_075_leaves_three_quarters_of_the_sun(tmp_path):
    # read from X3D: the Material's transparency is what the study weighs
    scene_file = tmp_path / "glass.x3d"
    scene_file.write_text(
        """<X3D profile="Interchange" version="4.0"><Scene>
        <Transform translation="0 -0.25 0">
          <Shape DEF="slab"><Box size="20 0.5 20"/></Shape>
        </Transform>
        <Transform translation="2 1 1"><Shape DEF="glass">
          <Appearance><Material transparency="0.75"/></Appearance><Box size="1 2 1"/>
        </Shape></Transform></Scene></X3D>"""
    )
    inputs, studies = study_scene(sg.load(scene_file), [NOON], **LONDON)
    (study,) = studies.days.values()
    shadow = hull_shadow(box([1, 2, 1], [2, 1, 1]), sun_direction(NOON))
    areas = plan_areas(study, inputs)
    # hand-derived: the shadow gets (1 - 0.25) of the hour, the rest all of it
    assert sorted(areas) == [0.75, 1.0]
    assert areas[0.75] == pytest.approx(shadow.area, rel=1e-9)
    assert areas[1.0] == pytest.approx(400.0 - shadow.area, rel=1e-9)
    # a day's summary (the levels' areas alone) weighs it the same
    (summary,) = study_scene(sg.load(scene_file), [NOON], **LONDON, summaries=True)[1].values()
    assert summary.level_areas == pytest.approx({0.75: shadow.area, 1.0: 400.0 - shadow.area})
    inside = np.asarray(shadow.representative_point().coords)[0]
    uv = inputs.plane.to_2d(np.array([[inside[0], 0.0, inside[1]], [-9.0, 0.0, -9.0]]))
    assert study.sunlit_hours(uv).tolist() == [0.75, 1.0]


@pytest.mark.parametrize("translucent", [0.5, 0.75])
def test_two_overlapping_casters_count_the_most_opaque_one(translucent):
    direction = sun_direction(NOON)
    low = box([2, 1, 2], [0, 0.5, 0])
    # a tall opaque post just south of it (the sun's side): its long shadow
    # falls across the low box's
    post = box([0.6, 4, 0.6], [0.5, 2, 1.8])
    scene = slab_scene([(low, 1.0 - translucent), (post, 0.0)])
    inputs, studies = study_scene(scene, [NOON], **LONDON)
    (study,) = studies.days.values()
    low_shadow, post_shadow = hull_shadow(low, direction), hull_shadow(post, direction)
    overlap = low_shadow.intersection(post_shadow).area
    assert overlap > 0.5  # the case is the overlap
    areas = plan_areas(study, inputs)
    # under the post: its 0, whatever the translucent box over it lets through
    assert areas[0.0] == pytest.approx(post_shadow.area, rel=1e-9)
    assert areas[1.0 - translucent] == pytest.approx(low_shadow.area - overlap, rel=1e-9)
    assert sum(areas.values()) == pytest.approx(400.0, rel=1e-12)
    assert len(areas) == 3


def hit_opacity(points, direction, triangles, opacity) -> np.ndarray:
    """(n,) the largest opacity among ``triangles`` (t, 3, 3) the ray from
    each point towards the sun (against ``direction``) crosses (Möller-
    Trumbore, every pair at once); 0 where none."""
    towards = -direction / np.linalg.norm(direction)
    edge1 = triangles[:, 1] - triangles[:, 0]
    edge2 = triangles[:, 2] - triangles[:, 0]
    pvec = np.cross(towards, edge2)  # (t, 3)
    det = np.einsum("tk,tk->t", edge1, pvec)
    usable = np.abs(det) > 1e-14
    inverse = np.where(usable, 1.0 / np.where(usable, det, 1.0), 0.0)
    tvec = points[:, None, :] - triangles[None, :, 0]  # (n, t, 3)
    u = np.einsum("ntk,tk->nt", tvec, pvec) * inverse
    qvec = np.cross(tvec, edge1[None])
    v = np.einsum("ntk,k->nt", qvec, towards) * inverse
    distance = np.einsum("ntk,tk->nt", qvec, edge2) * inverse
    hit = usable & (u >= 0) & (v >= 0) & (u + v <= 1) & (distance > 1e-9)
    return np.max(np.where(hit, opacity[None, :], 0.0), axis=1)


def test_random_points_get_the_sun_the_most_opaque_hit_caster_lets_through():
    # floating boxes (their shadows do not touch their footprints) and a
    # standing one, of opacities 1/4, 1/2, 3/4 and 1, shadows crossing over the day
    casters = [
        (box([2, 1, 2], [-1, 2.5, 0]), 0.75),
        (box([1, 3, 1], [1, 1.5, 1]), 0.5),
        (box([3, 0.4, 1], [0, 1.2, -1]), 0.25),
        (box([0.5, 2.5, 0.5], [-2, 1.25, 2]), 0.0),
    ]
    scene = slab_scene(casters)
    inputs, studies = study_scene(scene, DAY, **LONDON)
    (study,) = studies.days.values()
    assert study.opacity_units == 4
    rng = np.random.default_rng(33)
    uv = inputs.plane.to_2d(np.array([[x, 0.0, z] for x, z in rng.uniform(-7, 7, (2000, 2))]))
    points = inputs.plane.to_3d(uv)
    triangles = np.concatenate([np.asarray(mesh.vertices)[mesh.faces] for mesh, _ in casters])
    opacity = np.concatenate([np.full(len(mesh.faces), 1 - t) for mesh, t in casters])
    expected = np.zeros(len(points))
    for time in study.times:
        expected += 1.0 - hit_opacity(points, sun_direction(time), triangles, opacity)
    # the level polygons, read with shapely: each point's level is its hours
    from_levels = np.full(len(points), np.nan)
    edges = shapely.MultiLineString(
        [loop for parts in study.levels.values() for part in parts for loop in part]
    )
    for k, parts in study.levels.items():
        region = shapely.MultiPolygon([shapely.Polygon(part[0], part[1:]) for part in parts])
        from_levels[shapely.contains_xy(region, uv[:, 0], uv[:, 1])] = study.hours(k)
    clear = shapely.distance(edges, shapely.points(uv)) > 1e-7
    assert clear.sum() > 1900
    assert np.abs(from_levels - expected)[clear].max() < 1e-12
    assert np.abs(study.sunlit_hours(uv) - expected)[clear].max() < 1e-12
    assert set(np.round(expected * 4) % 4) >= {1, 2, 3}  # the translucent levels were met


def test_an_opaque_scene_is_the_opaque_study_bit_for_bit():
    cube = box([1, 1, 1], [2, 0.5, 1])
    # an opaque scene hands no opacity on: the study is today's road
    assert scene_study(slab_scene([(cube, 0.0)])).opacity is None
    given = sun_study(
        cube, sg.Plane([0, 1, 0]), FLOOR, DAY, **LONDON, opacity=np.ones(len(cube.faces))
    )
    alone = sun_study(cube, sg.Plane([0, 1, 0]), FLOOR, DAY, **LONDON)
    assert given.opacity_units == alone.opacity_units == 1
    assert sorted(given.levels) == sorted(alone.levels)
    for k in alone.levels:
        for mine, theirs in zip(given.levels[k], alone.levels[k], strict=True):
            assert all(np.array_equal(a, b) for a, b in zip(mine, theirs, strict=True))
    assert given.level_areas() == alone.level_areas()
    assert all(
        np.array_equal(a, b)
        for mine, theirs in zip(given.shadows, alone.shadows, strict=True)
        for part_a, part_b in zip(mine, theirs, strict=True)
        for a, b in zip(part_a, part_b, strict=True)
    )


def test_a_nearly_clear_caster_casts_nothing_and_bad_opacity_is_refused():
    cube = box([1, 1, 1], [2, 0.5, 1])
    # opacity 0.01 rounds to 0: the cube casts nothing, the slab under the floor alone is left
    inputs, studies = study_scene(slab_scene([(cube, 0.99)]), [NOON], **LONDON)
    assert inputs.opacity is None and len(inputs.caster.faces) == 10
    assert plan_areas(next(iter(studies.days.values())), inputs) == pytest.approx({1.0: 400.0})
    with pytest.raises(sg.GeometryError, match="3 values for 12 caster faces"):
        sun_study(cube, sg.Plane([0, 1, 0]), FLOOR, DAY, **LONDON, opacity=[1, 1, 1])


# Walls and roofs (shadowgeo.sunlight_surfaces): a 4 x 4 wall in y = 0 facing +y.
WALL = (
    np.array([[0, 0, 0], [4, 0, 0], [4, 0, 4], [0, 0, 4]], dtype=float),
    np.array([[0, 2, 1], [0, 3, 2]]),
)


@pytest.mark.parametrize("opacity", [0.25, 0.75])
def test_a_wall_behind_a_translucent_pane_keeps_the_sun_it_lets_through(opacity):
    pane = box([2, 0.1, 2], [2, 2, 2])  # its shadow: the square [1, 3] x [1, 3] of the wall
    # the second sun is behind the wall: its front is dark, whatever the pane lets through
    suns = [[0, -1, 0], [0, 1, 0]]
    result = sg.surface_sunlight(pane, WALL, suns, opacity=np.full(12, opacity))
    through = 1.0 - opacity
    # hand-derived: each half of the wall (area 8) has 2 in the pane's shadow
    assert result.opacity_units == 4
    assert result.mean_hours() == pytest.approx([(6 + 2 * through) / 8] * 2, abs=1e-12)
    for face in (0, 1):
        areas = result.level_areas(face)
        assert areas == pytest.approx({through: 2.0, 1.0: 6.0}, abs=1e-9)
    points = np.array([[2, 0, 2.5], [0.5, 0, 3.5]])
    assert result.sunlit_hours(points, [1, 1]).tolist() == [through, 1.0]
    assert result.fraction_meeting(0.8).tolist() == pytest.approx([0.75, 0.75])


def test_random_wall_points_get_the_sun_the_most_opaque_hit_caster_lets_through():
    casters = [
        (box([1.5, 0.3, 1.5], [1.5, 1.5, 2.0]), 0.25),
        (box([0.5, 0.5, 3.0], [2.5, 2.5, 2.2]), 1.0),
        (box([2.0, 0.4, 1.0], [2.2, 1.0, 1.2]), 0.5),
        (box([1.0, 1.0, 1.0], [1.0, 3.0, 3.0]), 0.75),
    ]
    meshes = [(np.asarray(mesh.vertices), np.asarray(mesh.faces)) for mesh, _ in casters]
    opacity = np.concatenate([np.full(len(mesh.faces), value) for mesh, value in casters])
    directions = np.array([[0.3, -1, -0.4], [-0.2, -1, -0.6], [0.1, -1, 0.2], [0, 1, -1]])
    result = sg.surface_sunlight(meshes, WALL, directions, opacity=opacity)
    rng = np.random.default_rng(34)
    plan = rng.uniform(0, 4, (3000, 2))
    points = np.column_stack([plan[:, 0], np.zeros(len(plan)), plan[:, 1]])
    face = np.where(plan[:, 0] >= plan[:, 1], 0, 1)  # the diagonal splits the wall
    triangles = np.concatenate([np.asarray(mesh.vertices)[mesh.faces] for mesh, _ in casters])
    expected = np.zeros(len(points))
    for direction in directions[:3]:  # the last lights the wall's back: no sun on its front
        expected += 1.0 - hit_opacity(points, direction, triangles, opacity)
    # each point's level polygon, read with shapely in its face's frame
    relative = points - result.origin[face]
    uv = np.column_stack([np.einsum("ij,ij->i", relative, result.u[face]),
                          np.einsum("ij,ij->i", relative, result.v[face])])  # fmt: skip
    from_levels = np.full(len(points), np.nan)
    near_edge = np.zeros(len(points), dtype=bool)
    for index in (0, 1):
        mine = face == index
        dots = shapely.points(uv[mine])
        loops = [loop for parts in result.levels[index].values() for p in parts for loop in p]
        near_edge[mine] = shapely.distance(shapely.MultiLineString(loops), dots) < 1e-7
        for k, parts in result.levels[index].items():
            region = shapely.MultiPolygon([shapely.Polygon(p[0], p[1:]) for p in parts])
            inside = np.flatnonzero(mine)[shapely.contains_xy(region, uv[mine, 0], uv[mine, 1])]
            from_levels[inside] = k * result.hours_per_unit
    clear = ~near_edge
    assert clear.sum() > 2900
    assert np.abs(from_levels - expected)[clear].max() < 1e-12
    assert np.abs(result.sunlit_hours(points, face) - expected)[clear].max() < 1e-12
    assert set(np.round(expected * 4) % 4) >= {1, 2, 3}  # the translucent levels were met
    # the faces' mean hours: the points' mean, to the sampling's error
    for index in (0, 1):
        assert result.mean_hours()[index] == pytest.approx(expected[face == index].mean(), abs=0.06)


def test_facade_hours_weigh_a_translucent_canopy_over_a_roof():
    from shadowgeo.scene.facade_hours import ROOFS, facade_hours

    cube = box([10, 10, 10], [0, 0, 5])
    canopy = box([200, 200, 0.2], [0, 0, 20])  # over the roof at every sample below
    scene = Scene(
        [
            Shape(np.asarray(cube.vertices), np.asarray(cube.faces), name="box"),
            Shape(np.asarray(canopy.vertices), np.asarray(canopy.faces), name="canopy",
                  material=Material(transparency=0.5)),
        ],
        up_axis="Z",
    )  # fmt: skip
    midday = [dt.datetime(2026, 6, 21, hour, 0, tzinfo=dt.UTC) for hour in range(10, 15)]
    found = facade_hours(scene, midday, latitude=52.0, longitude=0.0, receivers=["box"])
    roof = found.hours[found.kind == found.kinds.index(ROOFS)]
    # hand-derived: five samples, each through the canopy's half
    assert roof == pytest.approx(np.full(len(roof), 2.5), abs=1e-12)


def test_shadowgeo_sun_notes_the_translucent_casters_and_bins_their_levels(capsys, tmp_path):
    from cli.main import main

    scene_file = tmp_path / "glass.x3d"
    scene_file.write_text(
        """<X3D profile="Interchange" version="4.0"><Scene>
        <Transform translation="0 -0.25 0">
          <Shape DEF="slab"><Box size="20 0.5 20"/></Shape>
        </Transform>
        <Transform translation="2 1 1"><Shape DEF="glass">
          <Appearance><Material transparency="0.75"/></Appearance><Box size="1 2 1"/>
        </Shape></Transform></Scene></X3D>"""
    )
    code = main(["sun", str(scene_file), "--at", "51.5,-0.12", "--date", "2026-03-21"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "1 translucent caster(s) let part of the sun through (opacity 0.25" in err
    rows = [line.split("|") for line in out.splitlines() if line.startswith("| ") and "%" in line]
    # a quarter-step level sits in its whole sample's bin, and the bins tile the slab
    assert any(" to " in row[1] for row in rows)
    assert sum(float(row[2]) for row in rows) == pytest.approx(400.0, rel=1e-5)
