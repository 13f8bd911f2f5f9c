"""GIS output of ``shadowgeo sun``: the day's sunlight levels (and shadows at
given times) as polygons in the input's CRS, read back by GeoPandas.

References: the areas of the library's own :class:`SunStudy` of the same
scene (the output must carry them through the CRS round trip unchanged), the
region's analytic area, and, for the hours at chosen points, a brute-force
count of the samples whose ray to the sun misses the building (a slab test
against its box, independent of the shadow polygons).
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pytest

import shadowgeo as sg
from cli.main import main
from cli.sun import local_zone
from shadowgeo.scene.sunlight import study_scene

gpd = pytest.importorskip("geopandas")
pyproj = pytest.importorskip("pyproj")
shapely = pytest.importorskip("shapely")

RD_NEW = "EPSG:28992"
DAY = dt.date(2026, 6, 21)
# A tall block (10 x 10 m, 20 m high) and a low one across the plot: the
# region studied is the buildings' plan, 0..40 m each way.
TALL = (0.0, 0.0, 10.0, 20.0)  # x, y (south-west corner), side, height
LOW = (38.0, 38.0, 2.0, 1.0)


def _square(x: float, y: float, side: float) -> list[list[float]]:
    return [[x, y], [x + side, y], [x + side, y + side], [x, y + side], [x, y]]


def _footprints(path: Path, origin: tuple[float, float], crs: str, to_file=None) -> Path:
    """The two blocks as GeoJSON footprints, offset by ``origin`` (metres) and
    mapped to the file's coordinates by ``to_file`` (none: metres as they are)."""
    features = []
    for x, y, side, height in (TALL, LOW):
        ring = np.asarray(_square(x + origin[0], y + origin[1], side))
        if to_file is not None:
            ring = np.column_stack(to_file(ring[:, 0], ring[:, 1]))
        features.append(
            {
                "type": "Feature",
                "properties": {"height": height},
                "geometry": {"type": "Polygon", "coordinates": [ring.tolist()]},
            }
        )
    document = {
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": crs}},
        "features": features,
    }
    path.write_text(json.dumps(document))
    return path


def _rd_new(tmp_path: Path) -> Path:
    return _footprints(tmp_path / "rd.geojson", (85000.0, 446000.0), RD_NEW)


def _crs84(tmp_path: Path) -> Path:
    """The blocks near Suzhou, given in longitude and latitude: a transverse
    Mercator at 31.3 N 120.6 E maps local metres to degrees."""
    local = pyproj.CRS.from_proj4("+proj=tmerc +lat_0=31.3 +lon_0=120.6 +k=1 +ellps=WGS84")
    to_degrees = pyproj.Transformer.from_crs(local, "OGC:CRS84", always_xy=True).transform
    return _footprints(tmp_path / "ll.geojson", (0.0, 0.0), "OGC:CRS84", to_degrees)


def _study(path: Path) -> tuple[sg.Scene, sg.SunStudy]:
    """The library's study of the file, as the command line runs it."""
    scene = sg.load(path)
    zone = local_zone(scene.site.longitude)
    start = dt.datetime(DAY.year, DAY.month, DAY.day, tzinfo=zone)
    times = sg.sun.hourly(start, start + dt.timedelta(days=1), dt.timedelta(hours=1))
    _, studies = study_scene(scene, times, step=dt.timedelta(hours=1), tz=zone)
    return scene, studies.days[DAY]


def _run(source: Path, target: Path, *options: str) -> None:
    assert main(["sun", str(source), str(target), "--date", DAY.isoformat(), *options]) == 0


def _ray_hours(scene: sg.Scene, study: sg.SunStudy, point: np.ndarray) -> float:
    """Hours of sun at a ground ``point`` (scene frame): the samples whose ray
    to the sun misses every block's box (slab test), one hour each."""
    site = scene.site
    _, lights = sg.sun.sun_lights(
        site.latitude, site.longitude, list(study.times), up="Z", north=site.north
    )
    boxes = [
        (shape.world_vertices.min(axis=0), shape.world_vertices.max(axis=0))
        for shape in scene.shapes
    ]
    lit = 0
    for light in lights:
        towards = -np.asarray(light.direction, dtype=np.float64)
        lit += not any(_hits(point, towards, low, high) for low, high in boxes)
    return float(lit)


def _hits(point: np.ndarray, towards: np.ndarray, low: np.ndarray, high: np.ndarray) -> bool:
    """Whether the ray from ``point`` along ``towards`` passes through the box."""
    with np.errstate(divide="ignore", invalid="ignore"):
        near = (low - point) / towards
        far = (high - point) / towards
    enter = np.nanmax(np.minimum(near, far))
    leave = np.nanmin(np.maximum(near, far))
    return bool(leave > max(enter, 0.0))


def _box_shadows(scene: sg.Scene, direction: np.ndarray) -> object:
    """The blocks' shadows on the ground z = 0 under a sun shining along
    ``direction``: each the convex hull of its footprint and its roof's
    outline moved along the light to the ground, unioned."""
    hulls = []
    for shape in scene.shapes:
        low, high = shape.world_vertices.min(axis=0), shape.world_vertices.max(axis=0)
        foot = np.array(shapely.box(low[0], low[1], high[0], high[1]).exterior.coords)
        moved = foot + high[2] * direction[:2] / -direction[2]
        hulls.append(shapely.MultiPoint(np.concatenate([foot, moved])).convex_hull)
    return shapely.union_all(hulls)


def _block_box(scene: sg.Scene) -> tuple[np.ndarray, np.ndarray]:
    tall = max(scene.shapes, key=lambda shape: np.ptp(shape.world_vertices[:, 2]))
    return tall.world_vertices.min(axis=0), tall.world_vertices.max(axis=0)


def _to_output(scene: sg.Scene, crs, points: np.ndarray) -> np.ndarray:
    """Scene-frame plan points in the output's ``crs`` (pyproj, not the writer)."""
    move = pyproj.Transformer.from_crs(scene.site.crs, crs, always_xy=True)
    return np.column_stack(move.transform(points[:, 0], points[:, 1]))


def _level_areas(study: sg.SunStudy) -> dict[float, float]:
    """Each level's area from the study's own polygons, by the shoelace
    formula about the region's first corner: ``SunStudy.level_areas`` sums
    products of raw coordinates, which at RD New's 446,000 m loses about
    1e-5 square metres (here 1e-6 of the smallest level) to rounding."""
    origin = study.region[0][0][0]
    return {
        study.hours(k): sum(
            float(sg.plane2d.signed_areas([loop - origin for loop in part]).sum()) for part in parts
        )
        for k, parts in study.levels.items()
    }


def _check_levels(path: Path, scene: sg.Scene, study: sg.SunStudy, crs) -> None:
    """The file's sunlight layer against the study: its CRS, each level's area
    (measured back in the scene's metric frame) and the hours at points."""
    frame = gpd.read_file(path, layer="sunlight") if path.suffix == ".gpkg" else None
    if frame is None:
        frame = gpd.read_file(path)
        frame = frame[frame["layer"] == "sunlight"]
    assert pyproj.CRS(frame.crs).equals(pyproj.CRS(crs), ignore_axis_order=True)
    metric = frame.to_crs(scene.site.crs)
    expected = _level_areas(study)
    got = dict(zip(frame["hours"], metric.area, strict=True))
    assert sorted(got) == sorted(expected)
    for hours, area in expected.items():
        assert got[hours] == pytest.approx(area, rel=1e-6, abs=1e-9 * study.area)
    assert sum(got.values()) == pytest.approx(40.0 * 40.0, rel=1e-6)
    meets = [bool(value) for value in frame["meets"]]
    assert meets == [hours >= 2.0 for hours in frame["hours"]]
    # just north of the tall block (in its noon shadow) and far from it
    low, high = _block_box(scene)
    points = np.array([[low[0] + 5.0, high[1] + 1.0], [low[0] + 30.0, low[1] + 5.0]])
    placed = shapely.points(_to_output(scene, frame.crs, points))
    for plan, point in zip(points, placed, strict=True):
        (row,) = np.flatnonzero(frame.geometry.contains(point).to_numpy())
        ray = _ray_hours(scene, study, np.array([plan[0], plan[1], low[2]]))
        assert frame["hours"].iloc[row] == ray
    shaded = np.flatnonzero(frame.geometry.contains(placed[0]).to_numpy())[0]
    assert frame["hours"].iloc[shaded] <= len(study.times) - 4  # noon hours in shadow


def test_geopackage_of_projected_input_keeps_its_crs_and_the_study_areas(tmp_path):
    source = _rd_new(tmp_path)
    scene, study = _study(source)
    target = tmp_path / "out.gpkg"
    _run(source, target)
    _check_levels(target, scene, study, RD_NEW)


def test_geopackage_and_geojson_of_lon_lat_input_are_in_crs84(tmp_path):
    source = _crs84(tmp_path)
    scene, study = _study(source)
    for name in ("out.gpkg", "out.geojson"):
        _run(source, tmp_path / name)
        _check_levels(tmp_path / name, scene, study, "OGC:CRS84")


def test_geojson_of_projected_input_is_reprojected_to_crs84(tmp_path):
    source = _rd_new(tmp_path)
    scene, study = _study(source)
    _run(source, tmp_path / "out.geojson")
    _check_levels(tmp_path / "out.geojson", scene, study, "OGC:CRS84")


def test_shadows_at_given_times_are_the_study_shadows(tmp_path):
    source = _rd_new(tmp_path)
    scene, study = _study(source)
    target = tmp_path / "out.gpkg"
    _run(source, target, "--shadows-at", "09:00,12:00,23:00")
    shadows = gpd.read_file(target, layer="shadows")
    assert pyproj.CRS(shadows.crs).equals(pyproj.CRS(RD_NEW))
    # 23:00 is night: left out
    assert [time[11:16] for time in shadows["time"]] == ["09:00", "12:00"]
    zone = local_zone(scene.site.longitude)
    site = scene.site
    region = shapely.box(*scene.bounds[0][:2], *scene.bounds[1][:2])
    for time, shadow in zip(shadows["time"], shadows.geometry, strict=True):
        when = dt.datetime.fromisoformat(time)
        assert when.utcoffset() == zone.utcoffset(None)
        _, (light,) = sg.sun.sun_lights(
            site.latitude, site.longitude, [when], up="Z", north=site.north
        )
        expected = _box_shadows(scene, np.asarray(light.direction)).intersection(region)
        assert shadow.area == pytest.approx(expected.area, rel=1e-9)
        assert shadow.symmetric_difference(expected).area < 1e-9 * expected.area
    # at noon the tall block's shadow reaches north of it (a 20 m block, sun at about 61 deg)
    low, high = _block_box(scene)
    noon = shadows.geometry.iloc[1]
    assert noon.contains(shapely.Point(low[0] + 5.0, high[1] + 5.0))
    assert not noon.contains(shapely.Point(low[0] + 5.0, low[1] - 5.0))


def test_geojson_of_input_without_crs_is_refused_and_gpkg_has_none(tmp_path, capsys):
    cityjson = tmp_path / "plain.city.json"
    cityjson.write_text(json.dumps(_plain_cityjson()))
    code = main(["sun", str(cityjson), str(tmp_path / "x.geojson"), "--at", "52,4.5"])
    assert code == 1
    assert "RFC 7946" in capsys.readouterr().err
    assert not (tmp_path / "x.geojson").exists()
    assert main(["sun", str(cityjson), str(tmp_path / "x.gpkg"), "--at", "52,4.5"]) == 0
    frame = gpd.read_file(tmp_path / "x.gpkg", layer="sunlight")
    assert frame.crs is None
    assert frame.area.sum() == pytest.approx(40.0 * 40.0, rel=1e-9)


def _plain_cityjson() -> dict:
    """The two blocks as a CityJSON with no CRS (metres, its own origin)."""
    vertices, boundaries = [], []
    for x, y, side, height in (TALL, LOW):
        base = len(vertices)
        for z in (0.0, height):
            vertices += [[x, y, z], [x + side, y, z], [x + side, y + side, z], [x, y + side, z]]
        bottom, top = [base + 3, base + 2, base + 1, base], [base + 4, base + 5, base + 6, base + 7]
        sides = [
            [base + i, base + (i + 1) % 4, base + 4 + (i + 1) % 4, base + 4 + i] for i in range(4)
        ]
        boundaries.append([[[bottom]] + [[top]] + [[side] for side in sides]])
    objects = {
        f"b{number}": {
            "type": "Building",
            "geometry": [{"type": "Solid", "lod": "1", "boundaries": shells[0:1]}],
        }
        for number, shells in enumerate(boundaries)
    }
    return {
        "type": "CityJSON",
        "version": "2.0",
        "transform": {"scale": [1.0, 1.0, 1.0], "translate": [0.0, 0.0, 0.0]},
        "CityObjects": objects,
        "vertices": [[int(c) for c in point] for point in vertices],
    }


def test_unknown_gis_suffix_and_shadows_at_without_gis_out_are_usage_errors(tmp_path):
    source = _rd_new(tmp_path)
    with pytest.raises(SystemExit) as raised:
        main(["sun", str(source), str(tmp_path / "o.x3d"), "--shadows-at", "12:00"])
    assert raised.value.code == 2
    with pytest.raises(SystemExit) as raised:
        main(["sun", str(source), str(tmp_path / "o.gpkg"), "--shadows-at", "25:00"])
    assert raised.value.code == 2


def test_a_target_under_a_file_is_one_line_naming_it_and_exit_1(tmp_path, capsys):
    source = _rd_new(tmp_path)
    blocker = tmp_path / "plain"
    blocker.write_text("not a folder")
    target = blocker / "out.gpkg"
    assert main(["sun", str(source), str(target), "--date", DAY.isoformat()]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) >= 1 and "out.gpkg" in err[-1] and "cannot write" in err[-1]
    assert sorted(path.name for path in tmp_path.iterdir()) == ["plain", "rd.geojson"]
