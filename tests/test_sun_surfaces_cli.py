"""``shadowgeo sun`` giving a city's walls and roofs their hours of sun
(issue 33): ``--mesh`` (a .glb of the ground's levels and the buildings'
faces, read back byte by byte and checked by the Khronos validator) and
``--cityjson`` (the input with hours on its semantic surfaces, read back as
plain JSON), on real files of the shared corpus cut to a few buildings.

References, independent of the code: the samples with the sun up come from
NOAA's low-accuracy solar position formula written out here (the days and
steps are chosen so that no sample lies within 1.5 degrees of the horizon,
where it and the library's refraction could disagree); a roof with nothing
higher anywhere is sunlit at every one of them, whole; on 21 June at 52 N
the sun rises in the north-east and sets in the north-west, so north walls
get a few early and late hours and south walls most of the day.
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pytest
from needs import SHARED, absent
from noaa_sun import elevation
from test_sunlight_glb import _read
from validators import gltf_problems, gltf_report

from cli.main import main
from shadowgeo.io.sunlight_glb import UNKNOWN_HOURS

GIS = SHARED / "corpus" / "gis"
DAY = dt.date(2026, 6, 21)
EVERY = 90  # minutes: no sample within 1.5 degrees of the horizon (see the module notes)
# Delft: five LoD1 blocks side by side, the road they stand on and a plot of
# land use lower than 1 m (the ground, studied as such, neither cast nor given hours)
DELFT_BUILDINGS = [
    "b11267a1d-00ba-11e6-b420-2bdcc4ab5d7f",
    "b1126a169-00ba-11e6-b420-2bdcc4ab5d7f",
    "b1126c87e-00ba-11e6-b420-2bdcc4ab5d7f",
    "b112715ef-00ba-11e6-b420-2bdcc4ab5d7f",
    "b112715f4-00ba-11e6-b420-2bdcc4ab5d7f",
]
DELFT_GROUND = ["b984231ca-00c9-11e6-b420-2bdcc4ab5d7f", "b492910e5-00b4-11e6-b420-2bdcc4ab5d7f"]
# a tree (PlantCover, a 2 m block 10.8 m high) 2 m south-west of a 2.8 m block
DELFT_TREE = "b8e4fa919-00b3-11e6-b420-2bdcc4ab5d7f"
DELFT_SHADED = "b31be49f5-00ba-11e6-b420-2bdcc4ab5d7f"


def _gis(name: str) -> Path:
    path = GIS / name
    if not path.is_file():
        absent(f"{path} is absent (it exists on the project's machines and CI, not in a clone)")
    return path


def _elevation(latitude: float, longitude: float, time: dt.datetime) -> float:
    """The sun's elevation in degrees, by NOAA's general solar position
    formulas (:mod:`noaa_sun`)."""
    return elevation(latitude, longitude, time)


def _sun_up_hours(latitude: float, longitude: float, zone_hours: int, every: int = EVERY) -> float:
    """Hours of the samples with the sun up on DAY (local mean time, as the
    command samples it: the middle of each step), checking that none is
    near the horizon."""
    start = dt.datetime(
        DAY.year, DAY.month, DAY.day, tzinfo=dt.timezone(dt.timedelta(hours=zone_hours))
    )
    elevations = [
        _elevation(latitude, longitude, start + dt.timedelta(minutes=every * (k + 0.5)))
        for k in range(24 * 60 // every)
    ]
    assert min(abs(value) for value in elevations) > 1.5  # the test's precondition
    return sum(value > 0 for value in elevations) * every / 60.0


def _subset_cityjson(source: Path, target: Path, keep: list[str]) -> Path:
    """``source`` with only the city objects ``keep`` (vertices, transform and
    metadata as they are)."""
    document = json.loads(source.read_text())
    document["CityObjects"] = {name: document["CityObjects"][name] for name in keep}
    target.write_text(json.dumps(document))
    return target


def _faces(nodes: dict) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per node, (f, 3, 3) triangles in the world (Z up) and (f,) hours."""
    return {
        name: (arrays["world"].reshape(-1, 3, 3), arrays["_SUNLIGHT_HOURS"].reshape(-1, 3)[:, 0])
        for name, arrays in nodes.items()
    }


def _normals(triangles: np.ndarray) -> np.ndarray:
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return cross / np.linalg.norm(cross, axis=1, keepdims=True)


def _areas(triangles: np.ndarray) -> np.ndarray:
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return 0.5 * np.linalg.norm(cross, axis=1)


def _run(args: list[str], capsys) -> tuple[int, str, str]:
    """The exit code (a usage error's too), stdout and stderr."""
    try:
        code = main(args)
    except SystemExit as stopped:
        code = stopped.code
    out, err = capsys.readouterr()
    return code, out, err


def test_delft_glb_has_hours_on_walls_and_roofs(tmp_path, capsys):
    """Delft's LoD1 blocks (no semantic surfaces: kinds by facing)."""
    source = _subset_cityjson(
        _gis("delft_lod1.city.json"), tmp_path / "delft.city.json", DELFT_BUILDINGS + DELFT_GROUND
    )
    target = tmp_path / "delft.glb"
    args = ["sun", str(source), "--date", DAY.isoformat(), "--every", str(EVERY)]
    code, out, err = _run([*args, "--mesh", str(target), "--progress"], capsys)
    assert code == 0, err
    assert "walls and roofs [" in err  # its progress bar
    assert "walls: " in out and "roofs: " in out
    assert gltf_problems(gltf_report(target)) == []
    faces = _faces(_read(target)[1])
    most = _sun_up_hours(52.0132, 4.3661, 0)
    for name in DELFT_BUILDINGS:
        triangles, hours = faces[name]
        up = _normals(triangles)[:, 2]
        studied = up > -0.866  # floors are not studied
        assert np.all(hours[~studied] == UNKNOWN_HOURS)
        assert np.all((hours[studied] >= 0) & (hours[studied] <= most + 1e-9))
    for name in DELFT_GROUND:  # the ground: neither walls nor roofs
        assert np.all(faces[name][1] == UNKNOWN_HOURS)
    # the tallest block's roof has nothing higher near it: the sun whenever it is up
    tops = {name: faces[name][0][:, :, 2].max() for name in DELFT_BUILDINGS}
    tallest = max(tops, key=tops.get)
    triangles, hours = faces[tallest]
    roof = (_normals(triangles)[:, 2] > 0.99) & np.isclose(
        triangles[:, :, 2].min(axis=1), tops[tallest]
    )
    assert roof.any()
    assert hours[roof] == pytest.approx(np.full(roof.sum(), most), abs=1e-9)
    # walls facing north against walls facing south (RD New's grid north is
    # within 2 degrees of true north)
    walls = {"north": [], "south": []}
    for name in DELFT_BUILDINGS:
        triangles, hours = faces[name]
        normals = _normals(triangles)
        for side, sign in (("north", 1), ("south", -1)):
            chosen = sign * normals[:, 1] > 0.7  # within 45 degrees of north (south)
            walls[side].append((hours[chosen], _areas(triangles[chosen])))
    mean = {
        side: np.average(
            np.concatenate([h for h, _ in found]), weights=np.concatenate([a for _, a in found])
        )
        for side, found in walls.items()
    }
    assert mean["north"] < mean["south"]
    # Delft's blocks have no semantic surfaces to carry hours in a CityJSON
    code, _, err = _run([*args, "--cityjson", str(tmp_path / "x.city.json")], capsys)
    assert code == 2 and "semantic surface" in err
    assert not (tmp_path / "x.city.json").exists()


def _polygons(document: dict) -> list[tuple[str, dict | None, np.ndarray]]:
    """(object id, semantic surface or None, outer ring in file coordinates)
    of every polygon of every geometry, read from the file's JSON here."""
    scale = np.asarray(document["transform"]["scale"])
    translate = np.asarray(document["transform"]["translate"])
    points = np.asarray(document["vertices"], dtype=np.float64) * scale + translate
    depth = {
        "MultiSurface": 0,
        "CompositeSurface": 0,
        "Solid": 1,
        "MultiSolid": 2,
        "CompositeSolid": 2,
    }
    found = []

    def walk(boundaries, values, level, name, surfaces):
        for index, item in enumerate(boundaries):
            value = None if values is None else values[index]
            if level:
                walk(item, value, level - 1, name, surfaces)
            else:
                found.append((name, None if value is None else surfaces[value], points[item[0]]))

    for name, body in document["CityObjects"].items():
        for geometry in body.get("geometry", []):
            semantics = geometry.get("semantics") or {}
            walk(
                geometry["boundaries"],
                semantics.get("values"),
                depth[geometry["type"]],
                name,
                semantics.get("surfaces", []),
            )
    return found


def _ring_area(ring: np.ndarray) -> float:
    return 0.5 * float(np.linalg.norm(np.cross(ring, np.roll(ring, -1, axis=0)).sum(axis=0)))


def test_rotterdam_cityjson_and_glb_carry_each_surface_s_hours(tmp_path, capsys):
    """Rotterdam's LoD2 buildings (semantic surfaces; no CRS: --at)."""
    import shadowgeo as sg

    source = _gis("rotterdam_subset.city.json")
    mesh, city = tmp_path / "r.glb", tmp_path / "r.city.json"
    args = ["sun", str(source), "--at", "51.92,4.48", "--date", DAY.isoformat()]
    args += ["--every", str(EVERY), "--mesh", str(mesh), "--cityjson", str(city)]
    code, out, err = _run(args, capsys)
    assert code == 0, err
    assert f"wrote {city}" in out
    assert gltf_problems(gltf_report(mesh)) == []
    most = _sun_up_hours(51.92, 4.48, 0)
    before = sg.load(source)
    after = sg.load(city)  # loads back with our reader, the same geometry
    assert [shape.name for shape in after.shapes] == [shape.name for shape in before.shapes]
    for old, new in zip(before.shapes, after.shapes, strict=True):
        assert np.array_equal(old.world_vertices, new.world_vertices)
    polygons = _polygons(json.loads(city.read_text()))
    assert len(polygons) == len(_polygons(json.loads(source.read_text())))
    given = {}
    for name, surface, ring in polygons:
        if surface is None or surface["type"] not in ("RoofSurface", "WallSurface"):
            assert surface is None or "sunlight_hours" not in surface
            continue
        if _ring_area(ring) == 0:  # a wall with no area (the file has a dozen): no faces
            continue
        hours = surface["sunlight_hours"]
        assert 0 <= hours <= most + 1e-9
        given[(name, tuple(map(tuple, ring)))] = (surface["type"], hours)
    assert len(given) > 200
    # the highest roof of the file, flat: nothing can shade it
    top = max(ring[:, 2].max() for _, _, ring in polygons)
    highest = [
        hours for (_, ring), (kind, hours) in given.items()
        if kind == "RoofSurface" and min(z for _, _, z in ring) == top
    ]  # fmt: skip
    assert highest == [pytest.approx(most, abs=1e-9)]
    # a wall facing north gets less sun than one facing south, over the file
    sides = {"north": [], "south": []}
    for (_, ring), (kind, hours) in given.items():
        normal = np.cross(np.asarray(ring), np.roll(np.asarray(ring), -1, axis=0)).sum(axis=0)
        normal /= np.linalg.norm(normal)
        if kind == "WallSurface" and abs(normal[1]) > 0.9:
            sides["north" if normal[1] > 0 else "south"].append(hours)
    assert max(map(np.mean, sides.values())) == np.mean(sides["south"])
    assert np.mean(sides["north"]) < 0.5 * np.mean(sides["south"])


def test_rotterdam_cityjson_over_two_days_sums_them(tmp_path, capsys):
    source = _subset_cityjson(
        _gis("rotterdam_subset.city.json"),
        tmp_path / "two.city.json",
        list(json.loads(_gis("rotterdam_subset.city.json").read_text())["CityObjects"])[:3],
    )
    city = tmp_path / "hours.city.json"
    args = ["sun", str(source), "--at", "51.92,4.48", "--date", DAY.isoformat(), "--days", "2"]
    code, out, err = _run(
        [*args, "--every", str(EVERY), "--serial", "--cityjson", str(city)], capsys
    )
    assert code == 0, err
    assert "over the 2 day(s)" in out
    polygons = _polygons(json.loads(city.read_text()))
    top = max(ring[:, 2].max() for _, _, ring in polygons)
    roofs = [
        surface["sunlight_hours"]
        for _, surface, ring in polygons
        if surface and surface["type"] == "RoofSurface" and ring[:, 2].min() == top
    ]
    # 21 and 22 June have the same samples with the sun up (to the hour)
    assert roofs == [pytest.approx(2 * _sun_up_hours(51.92, 4.48, 0), abs=1e-9)]


def _subset_footprints(source: Path, target: Path, around: int, reach: float) -> Path:
    """The footprints within ``reach`` degrees of footprint ``around``."""
    document = json.loads(source.read_text())

    def centre(feature):
        return np.asarray(feature["geometry"]["coordinates"][0], dtype=np.float64).mean(axis=0)

    middle = centre(document["features"][around])
    document["features"] = [
        feature
        for feature in document["features"]
        if feature["geometry"]["type"] == "Polygon"
        and np.abs(centre(feature) - middle).max() < reach
    ]
    target.write_text(json.dumps(document))
    return target


def test_suzhou_footprints_glb_and_no_cityjson(tmp_path, capsys):
    """Footprints with heights (CRS84): extruded walls and flat roofs."""
    full = _gis("suzhou_buildings.geojson")
    heights = [item["properties"]["height"] for item in json.loads(full.read_text())["features"]]
    source = _subset_footprints(full, tmp_path / "few.geojson", int(np.argmax(heights)), 0.0006)
    features = json.loads(source.read_text())["features"]
    assert 5 <= len(features) <= 20
    target = tmp_path / "few.glb"
    args = ["sun", str(source), "--date", DAY.isoformat(), "--every", str(EVERY)]
    code, out, err = _run([*args, "--mesh", str(target)], capsys)
    assert code == 0, err
    assert gltf_problems(gltf_report(target)) == []
    faces = _faces(_read(target)[1])
    most = _sun_up_hours(31.30, 120.607, 8)
    tallest = max(item["properties"]["height"] for item in features)
    roofs = 0
    for name, (triangles, hours) in faces.items():
        if name == "ground":
            continue
        up = _normals(triangles)[:, 2]
        studied = hours != UNKNOWN_HOURS
        assert np.array_equal(studied, up > -0.866)  # walls and roofs, not floors
        assert np.all((hours[studied] >= 0) & (hours[studied] <= most + 1e-9))
        top = (up > 0.99) & np.isclose(triangles[:, :, 2].min(axis=1), tallest)
        assert hours[top] == pytest.approx(np.full(top.sum(), most), abs=1e-9)
        roofs += int(top.any())
    assert roofs >= 1
    # footprints have no CityJSON file of their own to carry hours
    code, _, err = _run([*args, "--cityjson", str(tmp_path / "x.city.json")], capsys)
    assert code == 2 and "footprints" in err


def test_surfaces_usage_errors(tmp_path, capsys):
    source = _gis("rotterdam_subset.city.json")
    args = ["sun", str(source), "--at", "51.92,4.48"]
    for extra, message in (
        (["--surfaces", "doors"], "expected walls, roofs"),
        (
            ["--surfaces", "none", "--cityjson", str(tmp_path / "a.city.json")],
            "not with --surfaces none",
        ),
        (["--cityjson", str(tmp_path / "a.gpkg")], "writes CityJSON"),
        (
            [
                "--cityjson",
                str(tmp_path / "a.city.json"),
                "--days",
                "2",
                "--mesh",
                str(tmp_path / "a.glb"),
            ],
            "--days 1",
        ),
    ):
        with pytest.raises(SystemExit) as stopped:
            main([*args, *extra])
        assert stopped.value.code == 2
        assert message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("option, name", [("--mesh", "a.glb"), ("--cityjson", "a.city.json")])
def test_an_output_that_cannot_be_written_is_refused_before_the_study(
    tmp_path, capsys, option, name
):
    blocker = tmp_path / "plain"
    blocker.write_text("a file, not a folder")
    target = blocker / name
    args = ["sun", str(_gis("rotterdam_subset.city.json")), "--at", "51.92,4.48"]
    code, out, err = _run([*args, option, str(target)], capsys)
    assert code == 1
    assert str(target) in err and "not a folder" in err
    assert out == ""  # no study ran


def test_delft_geopackage_gets_a_layer_of_wall_and_roof_faces_in_3d(tmp_path, capsys):
    gpd = pytest.importorskip("geopandas")
    source = _subset_cityjson(
        _gis("delft_lod1.city.json"), tmp_path / "delft.city.json", DELFT_BUILDINGS + DELFT_GROUND
    )
    target = tmp_path / "delft.gpkg"
    args = ["sun", str(source), str(target), "--date", DAY.isoformat(), "--every", str(EVERY)]
    code, out, err = _run([*args, "--surfaces", "walls,roofs"], capsys)
    assert code == 0, err
    frame = gpd.read_file(target, layer="surfaces")
    assert frame.crs.equals("EPSG:7415", ignore_axis_order=True)  # the file's own, RD New + NAP
    assert frame.has_z.all()
    assert set(frame["object"]) == set(DELFT_BUILDINGS)  # the ground is not given hours
    assert set(frame["kind"]) == {"WallSurface", "RoofSurface"}
    most = _sun_up_hours(52.0132, 4.3661, 0)
    assert frame["hours"].between(0, most + 1e-9).all()
    corners = np.array([np.asarray(item.geoms[0].exterior.coords)[:3] for item in frame.geometry])
    # the tallest block's roof, as in the glb
    top = corners[:, :, 2].max()
    roof = (frame["kind"] == "RoofSurface").to_numpy() & np.isclose(
        corners[:, :, 2].min(axis=1), top
    )
    assert roof.any()
    assert frame["hours"][roof].to_numpy() == pytest.approx(np.full(roof.sum(), most), abs=1e-9)
    # each kind's area adds up to what the command printed
    areas = _areas(corners)
    for word, kind in (("walls", "WallSurface"), ("roofs", "RoofSurface")):
        line = next(row for row in out.splitlines() if row.startswith(f"{word}: "))
        printed = float(line.split(", ")[1].split()[0])
        assert areas[(frame["kind"] == kind).to_numpy()].sum() == pytest.approx(printed, rel=1e-5)


def test_a_tree_casts_on_the_walls_but_gets_no_hours_of_its_own(tmp_path, capsys):
    """Only a CityJSON file's Building and BuildingPart objects receive."""
    building = DELFT_SHADED
    args = ["sun", "--date", DAY.isoformat(), "--every", str(EVERY), "--mesh"]
    found = {}
    for label, keep in (("alone", [building]), ("tree", [building, DELFT_TREE])):
        source = _subset_cityjson(
            _gis("delft_lod1.city.json"), tmp_path / f"{label}.city.json", keep
        )
        target = tmp_path / f"{label}.glb"
        code, _, err = _run([*args, str(target), str(source)], capsys)
        assert code == 0, err
        found[label] = _faces(_read(target)[1])
    assert "1 Building and BuildingPart object(s) are studied" in err
    assert np.all(found["tree"][DELFT_TREE][1] == UNKNOWN_HOURS)
    alone, shaded = found["alone"][building][1], found["tree"][building][1]
    studied = alone != UNKNOWN_HOURS
    assert np.array_equal(studied, shaded != UNKNOWN_HOURS)
    # the tree only takes sun away (float32 hours; the site moves a little with the box)
    assert np.all(shaded[studied] <= alone[studied] + 1e-3)
    assert shaded[studied].sum() < alone[studied].sum() - 0.1  # and some it does take
