"""A DEM gives the terrain (issue 33 item 1): ``shadowgeo.io.dem`` reads a
GeoTIFF through rasterio into a mesh in the city data's frame, and
``shadowgeo sun CITY --dem TIF`` lets it receive and cast.

The GeoTIFFs are written here by rasterio. References, independent of the
code: a tilted plane's faces get sun exactly when the sun is above the
plane's horizon (``dot(normal, sun) > 0``), the sun from NOAA's general
solar position formulas written out here (no sample near the horizon or
the plane's horizon, so the library's refraction and rounding cannot tip
one); shadows of a ridge and of a building against rays cast back to the
sun through every triangle (a brute-force Moller-Trumbore test here).
"""

from __future__ import annotations

import datetime as dt
import json
import math
from pathlib import Path

import numpy as np
import pytest

rasterio = pytest.importorskip("rasterio")  # the test extra installs it; CI fails a skip
pyproj = pytest.importorskip("pyproj")
from noaa_sun import sun_vector  # noqa: E402
from rasterio.transform import from_origin  # noqa: E402
from test_sun_surfaces_cli import _faces, _normals, _run  # noqa: E402

import shadowgeo  # noqa: E402
from shadowgeo.errors import SceneError  # noqa: E402
from shadowgeo.io.dem import read_terrain, stand_on  # noqa: E402
from shadowgeo.io.sunlight_glb import UNKNOWN_HOURS  # noqa: E402
from shadowgeo.sunlight_surfaces import surface_sunlight  # noqa: E402

# Amersfoort, the origin of RD New (EPSG:28992): grid north is true north there.
RD_X, RD_Y = 155_000.0, 463_000.0
DAY = dt.date(2026, 6, 21)
EVERY = 40  # minutes (see test_tilted_plane...: no sample near either horizon)


def _write_dem(
    path: Path,
    heights: np.ndarray,
    corner: tuple[float, float],
    cell: tuple[float, float],
    crs: str | None,
    nodata: float | None = None,
) -> Path:
    """A one-band float64 GeoTIFF, north up, its top-left corner at ``corner``."""
    rows, cols = heights.shape
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=cols,
        height=rows,
        count=1,
        dtype="float64",
        crs=crs,
        transform=from_origin(corner[0], corner[1], cell[0], cell[1]),
        nodata=nodata,
    ) as dataset:
        dataset.write(heights, 1)
    return path


def _centres(corner: tuple[float, float], cell: tuple[float, float], rows: int, cols: int):
    """(rows, cols) x and y of the cell centres."""
    col, row = np.meshgrid(np.arange(cols) + 0.5, np.arange(rows) + 0.5)
    return corner[0] + col * cell[0], corner[1] - row * cell[1]


def _footprints(path: Path, squares: list[tuple[float, float, float, float]]) -> Path:
    """GeoJSON footprints in RD New: squares (x, y of the centre, side, height)."""
    features = []
    for number, (x, y, side, height) in enumerate(squares):
        half = side / 2
        ring = [[x - half, y - half], [x + half, y - half], [x + half, y + half]]
        ring += [[x - half, y + half], [x - half, y - half]]
        features.append(
            {
                "type": "Feature",
                "id": number,
                "properties": {"height": height},
                "geometry": {"type": "Polygon", "coordinates": [ring]},
            }
        )
    document = {
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}},
        "features": features,
    }
    path.write_text(json.dumps(document))
    return path


def _sun(latitude: float, longitude: float, time: dt.datetime) -> np.ndarray:
    """(3,) unit vector towards the sun, x east, y north, z up, by NOAA's
    general solar position formulas (:mod:`noaa_sun`)."""
    return sun_vector(latitude, longitude, time)


def _samples(latitude: float, longitude: float) -> list[np.ndarray]:
    """The sun at the middle of each --every step of DAY (local mean time:
    UTC at Amersfoort's 5.39 E)."""
    start = dt.datetime(DAY.year, DAY.month, DAY.day, tzinfo=dt.UTC)
    return [
        _sun(latitude, longitude, start + dt.timedelta(minutes=EVERY * (k + 0.5)))
        for k in range(24 * 60 // EVERY)
    ]


def _rd_to_degrees(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    moved = pyproj.Transformer.from_crs("EPSG:28992", "EPSG:4326", always_xy=True)
    return moved.transform(x, y)


def _degrees_to_rd(lon: np.ndarray, lat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    moved = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:28992", always_xy=True)
    return moved.transform(lon, lat)


# A plane through (RD_X, RD_Y, 0) falling 40 degrees to the west: its normal
# points west and up, so the morning sun in the east is below its horizon.
SLOPE = math.tan(math.radians(40.0))
NORMAL = np.array([-math.sin(math.radians(40.0)), 0.0, math.cos(math.radians(40.0))])


def _plane(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return SLOPE * (np.asarray(x) - RD_X) + 0.0 * np.asarray(y)


def _sunlit_hours(normal: np.ndarray) -> float:
    """Hours of the samples with the sun up and above the plane's horizon."""
    latitude, longitude = _site()
    suns = _samples(latitude, longitude)
    assert min(abs(sun[2]) for sun in suns) > math.sin(math.radians(1.5))  # precondition
    assert min(abs(float(sun @ normal)) for sun in suns) > 0.02  # precondition
    return sum(sun[2] > 0 and float(sun @ normal) > 0 for sun in suns) * EVERY / 60.0


def _site() -> tuple[float, float]:
    lon, lat = _rd_to_degrees(np.array([RD_X]), np.array([RD_Y]))
    return float(lat[0]), float(lon[0])


def _sun_run(tmp_path, city: Path, dem: Path, capsys, *extra: str):
    glb, gpkg = tmp_path / "hours.glb", tmp_path / "levels.gpkg"
    args = ["sun", str(city), str(gpkg), "--date", DAY.isoformat(), "--every", str(EVERY)]
    code, out, err = _run([*args, "--dem", str(dem), "--mesh", str(glb), *extra], capsys)
    return code, out, err, glb, gpkg


def _check_plane_hours(glb: Path, gpkg: Path, building: tuple[float, float]) -> None:
    """Every terrain face away from the building has the plane's hours, in
    the .glb and in the GIS 'surfaces' layer."""
    expected = _sunlit_hours(NORMAL)
    assert 0 < expected < 16  # the slope loses the morning: a real test
    triangles, hours = _faces(shadowgeo_glb(glb))["terrain"]
    assert np.all(hours != UNKNOWN_HOURS)
    assert np.allclose(_normals(triangles), NORMAL, atol=1e-5)  # float32 corners
    centres = triangles.mean(axis=1)
    far = np.hypot(centres[:, 0] - building[0], centres[:, 1] - building[1]) > 150.0
    assert far.sum() > 100
    assert hours[far] == pytest.approx(np.full(far.sum(), expected), abs=1e-6)  # float32
    import geopandas

    layer = geopandas.read_file(gpkg, layer="surfaces")
    terrain = layer[layer["kind"] == "TerrainSurface"]
    assert len(terrain) == len(triangles)
    assert set(terrain["object"]) == {"terrain"}
    middle = terrain.geometry.centroid
    away = np.hypot(middle.x - building[0], middle.y - building[1]).to_numpy() > 150.0
    assert away.sum() == far.sum()
    given = terrain["hours"].to_numpy()[away]
    assert given == pytest.approx(np.full(away.sum(), expected), abs=1e-9)


def shadowgeo_glb(path: Path) -> dict:
    from test_sunlight_glb import _read

    return _read(path)[1]


def test_tilted_plane_in_rd_gets_the_hours_of_its_horizon(tmp_path, capsys):
    """A 40-degree slope in RD New under one footprint building: each face's
    hours are the samples with the sun above the plane; the building stands
    on the slope at its centroid's height."""
    corner, cell = (RD_X - 400.0, RD_Y + 400.0), (25.0, 25.0)
    x, y = _centres(corner, cell, 32, 32)
    dem = _write_dem(tmp_path / "slope.tif", _plane(x, y), corner, cell, "EPSG:28992")
    building = (RD_X + 10.0, RD_Y - 20.0)
    city = _footprints(tmp_path / "one.geojson", [(*building, 4.0, 6.0)])
    code, _, err, glb, gpkg = _sun_run(tmp_path, city, dem, capsys, "--dem-margin", "390")
    assert code == 0, err
    assert "stand on the DEM's height at their footprint's centroid" in err
    _check_plane_hours(glb, gpkg, building)
    walls, _ = _faces(shadowgeo_glb(glb))["_0"]
    base = float(_plane(building[0], building[1]))  # the plane is straight under the centroid
    assert walls[:, :, 2].min() == pytest.approx(base, abs=1e-5)  # float32
    assert walls[:, :, 2].max() == pytest.approx(base + 6.0, abs=1e-5)


def test_tilted_plane_in_longitude_and_latitude(tmp_path, capsys):
    """The same slope in a DEM in EPSG:4326 (heights set at each cell
    centre's RD position) under RD footprints: the terrain's points land
    on the plane in RD, and its faces get the plane's hours."""
    lon, lat = _rd_to_degrees(np.array([RD_X - 400.0]), np.array([RD_Y + 400.0]))
    corner, cell = (float(lon[0]), float(lat[0])), (0.0004, 0.00025)
    x, y = _centres(corner, cell, 32, 36)
    rd_x, rd_y = _degrees_to_rd(x, y)
    dem = _write_dem(tmp_path / "slope4326.tif", _plane(rd_x, rd_y), corner, cell, "EPSG:4326")
    building = (RD_X + 10.0, RD_Y - 20.0)
    city = _footprints(tmp_path / "one.geojson", [(*building, 4.0, 6.0)])
    code, _, err, glb, gpkg = _sun_run(tmp_path, city, dem, capsys, "--dem-margin", "300")
    assert code == 0, err
    scene = shadowgeo.load(city)
    terrain = read_terrain(dem, scene, np.array(building), np.array(building), margin=300.0)
    corners = terrain.vertices[np.unique(terrain.faces)]
    assert corners[:, 2] == pytest.approx(_plane(corners[:, 0], corners[:, 1]), abs=1e-6)
    assert corners[:, 0].min() < RD_X - 250 and corners[:, 0].max() > RD_X + 250
    assert corners[:, 1].min() < RD_Y - 250 and corners[:, 1].max() > RD_Y + 250
    _check_plane_hours(glb, gpkg, building)


def _blocked(origins: np.ndarray, toward: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(k,) whether a ray from each origin towards ``toward`` hits any of the
    (t, 3, 3) triangles (Moller-Trumbore, both sides), past a small start."""
    hit = np.zeros(len(origins), dtype=bool)
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    edge1, edge2 = b - a, c - a
    p = np.cross(toward, edge2)
    det = np.einsum("ij,ij->i", edge1, p)
    usable = np.abs(det) > 1e-12
    edge1, edge2, a, p, det = edge1[usable], edge2[usable], a[usable], p[usable], det[usable]
    for start in range(0, len(origins), 256):
        chunk = origins[start : start + 256]
        s = chunk[:, None, :] - a[None]
        u = np.einsum("kij,ij->ki", s, p) / det
        q = np.cross(s, edge1[None])
        v = np.einsum("kij,j->ki", q, toward) / det
        t = np.einsum("kij,ij->ki", q, edge2) / det
        inside = (u > 0) & (v > 0) & (u + v < 1) & (t > 1e-6)
        hit[start : start + 256] = inside.any(axis=1)
    return hit


def _face_points(receiver: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(m * 15, 3) points on a barycentric grid inside each triangle and
    (m * 15,) the triangle of each."""
    steps = [(i, j) for i in range(1, 6) for j in range(1, 6) if i + j < 7]
    weights = np.array([[1 - (i + j) / 7, i / 7, j / 7] for i, j in steps])
    points = np.einsum("pk,mkj->mpj", weights, receiver)
    return points.reshape(-1, 3), np.repeat(np.arange(len(receiver)), len(steps))


def _rd_scene(path: Path) -> shadowgeo.Scene:
    """A scene in RD New with no geometry of its own (the terrain's frame)."""
    return shadowgeo.load(_footprints(path, [(RD_X, RD_Y, 1.0, 1.0)]))


def _compare(sunlight, receiver: np.ndarray, casters: np.ndarray, toward: np.ndarray) -> None:
    """Whether each point of a grid on every receiving face is in the sun,
    exactly, against a ray cast back to the sun through every caster
    triangle (and the face turned to the sun)."""
    points, faces = _face_points(receiver)
    exact = sunlight.sunlit(points, faces)[0]
    normals = np.cross(receiver[:, 1] - receiver[:, 0], receiver[:, 2] - receiver[:, 0])
    rays = ~_blocked(points, toward, casters) & (normals[faces] @ toward > 0)
    assert rays.sum() > 200 and (~rays).sum() > 200  # sun and shadow both tested
    assert np.array_equal(exact, rays)


def test_a_ridge_shadows_the_valley_floor_at_low_sun(tmp_path):
    """A north-south ridge 30 m high west of a flat valley floor, the sun 8
    degrees up in the west: the ridge's shadow on the floor (and the ridge's
    own lee side) against rays cast back to the sun."""
    corner, cell = (RD_X - 150.0, RD_Y + 100.0), (10.0, 10.0)
    x, _ = _centres(corner, cell, 20, 30)
    heights = np.clip(30.0 - np.abs(x - (RD_X - 90.0)) * 0.6, 0.0, None)
    dem = _write_dem(tmp_path / "ridge.tif", heights, corner, cell, "EPSG:28992")
    scene = _rd_scene(tmp_path / "site.geojson")
    terrain = read_terrain(
        dem, scene, np.array([RD_X - 150, RD_Y - 100]), np.array([RD_X + 150, RD_Y + 100]), margin=0
    )
    elevation = math.radians(8.0)
    toward = np.array([-math.cos(elevation), 0.1, math.sin(elevation)])
    toward /= np.linalg.norm(toward)
    mesh = (terrain.vertices, terrain.faces)
    sunlight = surface_sunlight([mesh], mesh, -toward[None], levels=False)
    triangles = terrain.vertices[terrain.faces]
    _compare(sunlight, triangles, triangles, toward)
    # the floor from the ridge's foot (x = -40 m) to x = 40 m is in its shadow
    # (30 m high: a shadow 30 / tan 8 deg = 213 m long on the floor), but
    # where the rays pass the ridge's north end (y > 50 m: 0.1 north per 1 west)
    plan = triangles[:, :, :2]
    east = (plan[:, :, 0].min(axis=1) > RD_X - 40) & (plan[:, :, 0].max(axis=1) < RD_X + 40)
    floor = (triangles[:, :, 2].max(axis=1) == 0) & east & (plan[:, :, 1].max(axis=1) < RD_Y + 50)
    assert floor.sum() > 50 and np.all(sunlight.sunlit_fraction()[0][floor] == 0.0)


def test_a_building_on_the_dem_shadows_the_slope(tmp_path):
    """A 20 m footprint tower stood on an east-facing slope at its centroid's
    height, the sun 20 degrees up in the east: its shadow on the slope
    against rays, and its base on the plane (hand-derived)."""
    corner, cell = (RD_X - 120.0, RD_Y + 120.0), (8.0, 8.0)
    x, y = _centres(corner, cell, 30, 30)
    slope = 0.3  # falling to the east
    dem = _write_dem(tmp_path / "east.tif", -slope * (x - RD_X), corner, cell, "EPSG:28992")
    city = _footprints(tmp_path / "tower.geojson", [(RD_X + 3.0, RD_Y - 2.0, 12.0, 20.0)])
    scene = shadowgeo.load(city)
    terrain = read_terrain(
        dem, scene, np.array([RD_X - 100, RD_Y - 100]), np.array([RD_X + 100, RD_Y + 100]), margin=0
    )
    standing, note = stand_on(scene, terrain)
    assert "1 of 1" in note
    (tower,) = standing.shapes
    world = tower.world_vertices
    assert world[:, 2].min() == pytest.approx(-slope * 3.0, abs=1e-9)  # the centroid's height
    elevation = math.radians(20.0)
    toward = np.array([math.cos(elevation), 0.2, math.sin(elevation)])
    toward /= np.linalg.norm(toward)
    mesh = (terrain.vertices, terrain.faces)
    building = (world, tower.faces)
    sunlight = surface_sunlight([building, mesh], mesh, -toward[None], levels=False)
    receiver = terrain.vertices[terrain.faces]
    casters = np.concatenate([world[tower.faces], receiver])
    _compare(sunlight, receiver, casters, toward)


def test_nodata_cells_leave_holes(tmp_path):
    """A 10 x 12 raster with a 2 x 3 block and one corner cell of nodata:
    the squares touching them are left out, and no face has a point there."""
    corner, cell = (RD_X - 60.0, RD_Y + 50.0), (10.0, 10.0)
    heights = np.full((10, 12), 5.0)
    heights[3:5, 4:7] = -9999.0
    heights[0, 0] = -9999.0
    dem = _write_dem(tmp_path / "holes.tif", heights, corner, cell, "EPSG:28992", -9999.0)
    scene = _rd_scene(tmp_path / "site.geojson")
    terrain = read_terrain(
        dem, scene, np.array([RD_X - 60, RD_Y - 50]), np.array([RD_X + 60, RD_Y + 50]), margin=0
    )
    # 9 x 11 squares; the block is a corner of 3 x 4 of them, the cell of 1
    assert len(terrain.faces) == 2 * (9 * 11 - 12 - 1)
    x, y = _centres(corner, cell, 10, 12)
    missing = np.column_stack([x[heights < 0], y[heights < 0]])
    used = terrain.vertices[np.unique(terrain.faces)][:, :2]
    gaps = np.linalg.norm(used[:, None] - missing[None], axis=2)
    assert gaps.min() > 1.0
    assert np.all(terrain.vertices[np.unique(terrain.faces), 2] == 5.0)
    assert any("7 cell(s) without a height" in note for note in terrain.notes)


def test_a_dem_without_crs_under_city_data_with_one_is_refused(tmp_path, capsys):
    dem = _write_dem(tmp_path / "nocrs.tif", np.zeros((4, 4)), (0.0, 4.0), (1.0, 1.0), None)
    scene = _rd_scene(tmp_path / "site.geojson")
    with pytest.raises(SceneError, match="no coordinate reference system") as raised:
        read_terrain(dem, scene, np.array([0.0, 0.0]), np.array([4.0, 4.0]))
    assert "nocrs.tif" in str(raised.value)
    code, _, err = _run(
        ["sun", str(tmp_path / "site.geojson"), "--dem", str(dem), "--every", "120"], capsys
    )
    assert code == 1 and "nocrs.tif" in err and "no coordinate reference system" in err


def test_an_oversized_raster_is_refused_before_its_pixels_are_read(tmp_path, monkeypatch):
    """40,000 x 30,000 cells (1.2e9, over the budget) in a sparse file of a
    few kilobytes: refused from the header; reading a pixel would fail."""
    path = tmp_path / "huge.tif"
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=40_000,
        height=30_000,
        count=1,
        dtype="float32",
        crs="EPSG:28992",
        transform=from_origin(RD_X, RD_Y, 1.0, 1.0),
        tiled=True,
        sparse_ok=True,
    ):
        pass
    assert path.stat().st_size < 10_000_000

    def no_read(*args, **kwargs):
        raise AssertionError("a pixel was read")

    monkeypatch.setattr(rasterio.io.DatasetReader, "read", no_read)
    scene = _rd_scene(tmp_path / "site.geojson")
    with pytest.raises(SceneError, match="1,200,000,000|40,000 x 30,000") as raised:
        read_terrain(path, scene, np.array([RD_X, RD_Y - 10]), np.array([RD_X + 10, RD_Y]))
    assert "huge.tif" in str(raised.value)


def test_a_file_that_is_not_a_raster_is_refused(tmp_path):
    path = tmp_path / "notes.tif"
    path.write_text("not a raster at all\n")
    scene = _rd_scene(tmp_path / "site.geojson")
    with pytest.raises(SceneError, match="cannot read as a raster") as raised:
        read_terrain(path, scene, np.array([0.0, 0.0]), np.array([1.0, 1.0]))
    assert "notes.tif" in str(raised.value)


def _cityjson_box(path: Path, centre: tuple[float, float], side: float, low: float, high: float):
    """A CityJSON 2.0 file in EPSG:7415 (RD New + NAP heights) with one LoD1
    Building, a box from ``low`` to ``high`` (absolute heights)."""
    half = side / 2
    x0, x1, y0, y1 = centre[0] - half, centre[0] + half, centre[1] - half, centre[1] + half
    points = [[x, y, z] for z in (low, high) for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))]
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    document = {
        "type": "CityJSON",
        "version": "2.0",
        "transform": {"scale": [0.001, 0.001, 0.001], "translate": [0.0, 0.0, 0.0]},
        "metadata": {"referenceSystem": "https://www.opengis.net/def/crs/EPSG/0/7415"},
        "CityObjects": {
            "tower": {
                "type": "Building",
                "geometry": [
                    {"type": "Solid", "lod": "1", "boundaries": [[[face] for face in faces]]}
                ],
            }
        },
        "vertices": [[round(v * 1000) for v in point] for point in points],
    }
    path.write_text(json.dumps(document))
    return path


def test_cityjson_buildings_keep_their_heights_and_the_terrain_gets_hours(tmp_path, capsys):
    """A CityJSON Building (absolute heights, its walls and roofs studied by
    name) on the slope: the terrain is studied beside it, and the building
    stays at the heights the file gives."""
    corner, cell = (RD_X - 400.0, RD_Y + 400.0), (25.0, 25.0)
    x, y = _centres(corner, cell, 32, 32)
    dem = _write_dem(tmp_path / "slope.tif", _plane(x, y), corner, cell, "EPSG:28992")
    building = (RD_X + 10.0, RD_Y - 20.0)
    city = _cityjson_box(tmp_path / "tower.city.json", building, 4.0, 3.0, 9.0)
    code, out, err, glb, gpkg = _sun_run(tmp_path, city, dem, capsys, "--dem-margin", "390")
    assert code == 0, err
    assert "stand on the DEM" not in err
    assert "terrain: 1922 faces" in out
    _check_plane_hours(glb, gpkg, building)
    walls, _ = _faces(shadowgeo_glb(glb))["tower"]
    assert walls[:, :, 2].min() == pytest.approx(3.0, abs=1e-5)
    assert walls[:, :, 2].max() == pytest.approx(9.0, abs=1e-5)


def test_the_command_shadows_the_valley_with_the_ridge(tmp_path, capsys):
    """``sun --dem``: a ridge 100 m high (slopes of 1 in 2: no face steep
    enough to be a wall, so the terrain must not be taken for ground cover)
    west of a flat valley floor. Each floor face of a strip across the
    valley against rays cast from 15 points of it to the sun at every
    sample (the library's sun positions, tested on their own in
    test_sun_position.py, at the site the command reads)."""
    corner, cell = (RD_X - 420.0, RD_Y + 200.0), (20.0, 20.0)
    x, _ = _centres(corner, cell, 20, 42)
    heights = np.clip(100.0 - 0.5 * np.abs(x - (RD_X - 200.0)), 0.0, None)
    dem = _write_dem(tmp_path / "ridge.tif", heights, corner, cell, "EPSG:28992")
    building = (RD_X + 350.0, RD_Y - 150.0)  # far from the strip
    city = _footprints(tmp_path / "hut.geojson", [(*building, 2.0, 2.0)])
    code, out, err, glb, _ = _sun_run(tmp_path, city, dem, capsys, "--dem-margin", "400")
    assert code == 0, err
    triangles, hours = _faces(shadowgeo_glb(glb))["terrain"]
    site = shadowgeo.load(city).site
    start = dt.datetime(DAY.year, DAY.month, DAY.day, tzinfo=dt.UTC)
    times = shadowgeo.sun.hourly(start, start + dt.timedelta(days=1), dt.timedelta(minutes=EVERY))
    suns = [
        shadowgeo.sun_direction(site.latitude, site.longitude, when, up="Z", north=site.north)
        for when in times
    ]
    toward = [-np.asarray(sun) for sun in suns if sun is not None]
    plan = triangles[:, :, :2].mean(axis=1)
    strip = (np.abs(plan[:, 1] - (RD_Y + 10.0)) < 10.0) & (triangles[:, :, 2].max(axis=1) == 0)
    receiver = triangles[strip].astype(np.float64)
    points, faces = _face_points(receiver)
    lit = np.zeros(len(points))
    for direction in toward:
        lit += ~_blocked(points, direction, triangles.astype(np.float64))
    lit = lit.reshape(len(receiver), -1) * EVERY / 60.0
    agreed = np.all(lit == lit[:, :1], axis=1)
    assert agreed.sum() >= 0.8 * len(receiver) and len(receiver) >= 30
    expected = lit[agreed, 0]
    assert expected.min() < len(toward) * EVERY / 60.0 - 1  # the ridge takes evening hours
    # a face whose 15 points agree can still have a shadow edge cross a
    # corner of it at a sample or two: part of one sample, never more
    found = hours[strip][agreed]
    assert np.all(np.abs(found - expected) < EVERY / 60.0)
    assert np.mean(np.abs(found - expected) < 1e-5) >= 0.75  # float32


def test_a_big_window_is_averaged_to_the_cell_budget(tmp_path):
    """30 x 41 cells of a plane read with a budget of 100: averaged in whole
    blocks of 4 x 4 (the raster has no more cells to grow to 32 x 44, so 28 x
    40 are read: 7 x 10 cells); the mean of a block of a plane's cells is
    the plane at the block's centre, so every point stays on it
    (hand-derived: the coarse centres lie 20 m apart, 10 m in from the
    raster's corner)."""
    corner, cell = (RD_X - 205.0, RD_Y + 150.0), (5.0, 5.0)
    x, y = _centres(corner, cell, 30, 41)
    dem = _write_dem(
        tmp_path / "fine.tif", 0.2 * (x - RD_X) - 0.1 * (y - RD_Y), corner, cell, "EPSG:28992"
    )
    scene = _rd_scene(tmp_path / "site.geojson")
    terrain = read_terrain(
        dem,
        scene,
        np.array([RD_X - 500, RD_Y - 500]),
        np.array([RD_X + 500, RD_Y + 500]),
        cells=100,
    )
    assert terrain.grid.heights.shape == (7, 10)
    assert len(terrain.faces) == 2 * 6 * 9
    points = terrain.vertices
    assert points[:, 2] == pytest.approx(
        0.2 * (points[:, 0] - RD_X) - 0.1 * (points[:, 1] - RD_Y), abs=1e-9
    )
    assert points[0, :2] == pytest.approx([corner[0] + 10.0, corner[1] - 10.0], abs=1e-9)
    assert np.diff(np.unique(points[:, 0]))[:9] == pytest.approx(np.full(9, 20.0))
    assert any("averaged to 7 x 10" in note for note in terrain.notes)


def test_a_truncated_geotiff_is_refused_naming_it(tmp_path):
    """A DEM cut short after its header: its heights cannot be read."""
    corner, cell = (RD_X - 100.0, RD_Y + 100.0), (1.0, 1.0)
    full = _write_dem(
        tmp_path / "full.tif", np.arange(200 * 200.0).reshape(200, 200), corner, cell, "EPSG:28992"
    )
    cut = tmp_path / "cut.tif"
    cut.write_bytes(full.read_bytes()[:4000])
    scene = _rd_scene(tmp_path / "site.geojson")
    with pytest.raises(SceneError, match="cannot read") as raised:
        read_terrain(cut, scene, np.array([RD_X - 50, RD_Y - 50]), np.array([RD_X + 50, RD_Y + 50]))
    assert "cut.tif" in str(raised.value)
