"""City data in (issue 33): building footprints extruded from GeoJSON,
GeoPackage and Shapefile, CityJSON and CityJSONSeq, and their coordinate
reference systems. References are hand-derived (a prism's volume, a cube's
corners), pyproj's geodesic areas, or the file's own polygons measured here."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from needs import SHARED, absent

import shadowgeo as sg
from shadowgeo.io import json_format

pyproj = pytest.importorskip("pyproj")
pytest.importorskip("pyogrio")

GIS = SHARED / "corpus" / "gis"
RD_NEW = "EPSG:28992"


def _gis(name: str) -> Path:
    path = GIS / name
    if not path.is_file():
        absent(f"{path} is absent (it exists on the project's machines and CI, not in a clone)")
    return path


def _mesh(shape: sg.Shape) -> trimesh.Trimesh:
    return trimesh.Trimesh(shape.world_vertices, shape.faces, process=False)


def _areas(shape: sg.Shape) -> np.ndarray:
    corners = shape.world_vertices[shape.faces]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return np.linalg.norm(cross, axis=1) / 2


def _kind_area(shape: sg.Shape, kind: str) -> float:
    return float(_areas(shape)[shape.semantics.faces(kind)].sum())


def _closed_outward(shape: sg.Shape) -> bool:
    """Every edge met once each way (closed), and a positive volume (outward)."""
    faces = shape.faces
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    forward = {tuple(edge) for edge in edges.tolist()}
    closed = len(forward) == len(edges) and all((b, a) in forward for a, b in forward)
    return closed and _mesh(shape).volume > 0


def _feature(rings, **properties) -> dict:
    return {
        "type": "Feature",
        "properties": properties,
        "geometry": {"type": "Polygon", "coordinates": rings},
    }


def _geojson(path: Path, features: list[dict], crs: str | None = RD_NEW) -> Path:
    document = {"type": "FeatureCollection", "features": features}
    if crs is not None:  # GeoJSON 2008's crs member; without one GDAL takes CRS84
        document["crs"] = {"type": "name", "properties": {"name": crs}}
    path.write_text(json.dumps(document))
    return path


def _square(x: float, y: float, side: float) -> list[list[float]]:
    return [[x, y], [x + side, y], [x + side, y + side], [x, y + side], [x, y]]


# -- footprints ---------------------------------------------------------------------------


def test_unit_square_of_height_3_is_a_closed_prism_of_volume_3(tmp_path):
    path = _geojson(tmp_path / "one.geojson", [_feature([_square(90000, 435000, 1)], height=3)])
    scene = sg.load(path)
    (shape,) = scene.shapes
    assert scene.up_axis == "Z"
    assert shape.solid and _closed_outward(shape)
    assert _mesh(shape).volume == pytest.approx(3.0, rel=1e-12)
    assert _kind_area(shape, "RoofSurface") == pytest.approx(1.0, rel=1e-12)
    assert _kind_area(shape, "GroundSurface") == pytest.approx(1.0, rel=1e-12)
    assert _kind_area(shape, "WallSurface") == pytest.approx(12.0, rel=1e-12)
    roof = shape.world_vertices[shape.faces[shape.semantics.faces("RoofSurface")]]
    assert np.all(roof[..., 2] == 3.0)
    normals = np.cross(roof[:, 1] - roof[:, 0], roof[:, 2] - roof[:, 0])
    assert np.all(normals[:, 2] > 0)  # the roof faces up, out of the prism
    low, high = scene.bounds
    assert low.tolist() == [90000.0, 435000.0, 0.0] and high.tolist() == [90001.0, 435001.0, 3.0]
    # the vertices are kept near zero, placed by the transform (float32 outputs)
    assert np.abs(shape.vertices).max() <= 3.0


def test_holes_multipolygons_floors_and_base(tmp_path):
    ring, hole = _square(0, 0, 4), _square(1, 1, 2)[::-1]
    two = {
        "type": "Feature",
        "properties": {"Floor": 2},
        "geometry": {
            "type": "MultiPolygon",
            "coordinates": [[_square(10, 0, 1)], [_square(20, 0, 2)]],
        },
    }
    features = [_feature([ring, hole], height=2, base=5), two, _feature([_square(30, 0, 1)])]
    path = _geojson(tmp_path / "many.geojson", features)
    scene = sg.load(path, floors="Floor", base="base")
    courtyard, pair = scene.shapes
    assert _closed_outward(courtyard) and _closed_outward(pair)
    assert _mesh(courtyard).volume == pytest.approx((16 - 4) * 2, rel=1e-12)
    assert _kind_area(courtyard, "RoofSurface") == pytest.approx(12.0, rel=1e-12)
    heights = courtyard.world_vertices[:, 2]
    assert heights.min() == 5.0 and heights.max() == 7.0
    assert _mesh(pair).volume == pytest.approx((1 + 4) * 2 * 3.0, rel=1e-12)  # 2 floors x 3 m
    assert any("no height" in note and "features 2" in note for note in scene.warnings)
    tall = sg.load(path, floors="Floor", storey_height=4.0, base="base")
    assert _mesh(tall.shapes[1]).volume == pytest.approx((1 + 4) * 2 * 4.0, rel=1e-12)


def test_geopackage_and_shapefile_read_as_geojson_does(tmp_path):
    import pyogrio.raw
    import shapely

    geometry = shapely.Polygon(_square(90000, 435000, 2)[:-1])
    for name in ("prism.gpkg", "prism.shp"):
        path = tmp_path / name
        pyogrio.raw.write(  # pyogrio's own writer: no GeoDataFrame
            path,
            np.array([shapely.to_wkb(geometry)], dtype=object),
            [np.array([7.5])],
            fields=["hoogte"],
            geometry_type="Polygon",
            crs=RD_NEW,
        )
        scene = sg.load(path, height="hoogte")
        (shape,) = scene.shapes
        assert _mesh(shape).volume == pytest.approx(4 * 7.5, rel=1e-12)
        assert scene.site is not None and scene.site.latitude == pytest.approx(51.9, abs=0.1)
    with pytest.raises(sg.SceneError, match=r"prism\.shp: no height attribute 'height'.*hoogte"):
        sg.load(tmp_path / "prism.shp")


def test_crs84_footprint_projects_to_its_geodesic_area(tmp_path):
    """0.001 degree square at 52 N: about 68 m by 111 m. In degrees it would
    be 1e-6 'square metres'; projected, its area is the ellipsoid's."""
    lon, lat, side = 4.4, 52.0, 0.001
    path = _geojson(
        tmp_path / "crs84.geojson",
        [_feature([_square(lon, lat, side)], height=10)],
        crs="urn:ogc:def:crs:OGC:1.3:CRS84",
    )
    scene = sg.load(path)
    (shape,) = scene.shapes
    geodesic, _ = pyproj.Geod(ellps="WGS84").polygon_area_perimeter(
        [lon, lon + side, lon + side, lon], [lat, lat, lat + side, lat + side]
    )
    assert _kind_area(shape, "RoofSurface") == pytest.approx(abs(geodesic), rel=1e-6)
    assert _mesh(shape).volume == pytest.approx(abs(geodesic) * 10, rel=1e-6)
    site = scene.site
    assert site.latitude == pytest.approx(lat + side / 2, abs=1e-12)
    assert site.longitude == pytest.approx(lon + side / 2, abs=1e-12)
    assert site.source_crs == "EPSG:4326"  # GDAL's name for CRS84's lon/lat
    assert pyproj.CRS(site.crs).is_projected
    assert np.allclose(site.north, (0, 1, 0), atol=1e-9)  # on the central meridian
    low, high = scene.bounds[:, :2]
    assert np.abs(low + high).max() < 0.1  # centred on the data
    assert (high - low).tolist() == pytest.approx([68.6, 111.3], abs=0.1)  # metres, not degrees


def test_metres_under_a_geographic_crs_are_refused_not_read_as_degrees(tmp_path):
    """A GeoJSON without a crs member is CRS84 (RFC 7946): RD New metres
    written into one are latitudes of 435,000 degrees, an error, never a
    city 40,000 km across."""
    path = _geojson(
        tmp_path / "rd.geojson", [_feature([_square(90000, 435000, 1)], height=3)], None
    )
    with pytest.raises(sg.SceneError, match=r"rd\.geojson: longitudes 90000 .* are not those"):
        sg.load(path)


def test_suzhou_footprints_are_metres_at_31_3_n_120_6_e():
    path = _gis("suzhou_buildings.geojson")
    scene = sg.load(path)
    assert scene.site.latitude == pytest.approx(31.3, abs=0.02)
    assert scene.site.longitude == pytest.approx(120.6, abs=0.02)
    assert len(scene.shapes) == 3076
    assert all(shape.solid and _closed_outward(shape) for shape in scene.shapes[::97])
    # Every footprint's area is its geodesic area on the ellipsoid (a km off
    # the projection's centre its scale is off by about 1e-8); pyproj's
    # geodesic area itself is only good to about 1e-5 m2 (on a 1.5 m2 shed
    # it is 3e-6 off the area a transverse Mercator centred on the shed
    # gives, which the reader's matches to 1e-8), hence the absolute term.
    import pyogrio.raw
    import shapely

    _, _, wkb, fields = pyogrio.raw.read(path)
    geod = pyproj.Geod(ellps="WGS84")
    heights = fields[2]
    for index in range(3076):
        footprint = shapely.from_wkb(wkb[index])
        expected = abs(geod.geometry_area_perimeter(footprint)[0])
        shape = scene.shapes[index]
        assert _kind_area(shape, "RoofSurface") == pytest.approx(expected, rel=1e-6, abs=1e-4)
        assert np.ptp(shape.world_vertices[:, 2]) == heights[index]


# -- CityJSON -----------------------------------------------------------------------------

# A cube of side 2 as a Solid: its eight corners as integers (millimetres)
# under a transform; ground, roof and four walls, each counter-clockwise seen
# from outside.
CUBE_VERTICES = [
    [0, 0, 0],
    [2000, 0, 0],
    [2000, 2000, 0],
    [0, 2000, 0],
    [0, 0, 2000],
    [2000, 0, 2000],
    [2000, 2000, 2000],
    [0, 2000, 2000],
]
CUBE_FACES = [
    [[0, 3, 2, 1]],
    [[4, 5, 6, 7]],
    [[0, 1, 5, 4]],
    [[1, 2, 6, 5]],
    [[2, 3, 7, 6]],
    [[3, 0, 4, 7]],
]
TRANSLATE = [85000.5, 447000.25, -1.5]


def _cityjson(path: Path, objects: dict, **extra) -> Path:
    document = {
        "type": "CityJSON",
        "version": "2.0",
        "transform": {"scale": [0.001, 0.001, 0.001], "translate": TRANSLATE},
        "CityObjects": objects,
        "vertices": CUBE_VERTICES,
        **extra,
    }
    path.write_text(json.dumps(document))
    return path


def _cube(lod: str = "2") -> dict:
    return {
        "type": "Solid",
        "lod": lod,
        "boundaries": [CUBE_FACES],
        "semantics": {
            "surfaces": [
                {"type": "GroundSurface"},
                {"type": "RoofSurface"},
                {"type": "WallSurface", "slope": 90},
            ],
            "values": [[0, 1, 2, 2, 2, None]],
        },
    }


def test_cityjson_cube_with_transform_has_the_right_coordinates(tmp_path):
    path = _cityjson(
        tmp_path / "cube.city.json", {"house": {"type": "Building", "geometry": [_cube()]}}
    )
    scene = sg.load(path)
    (shape,) = scene.shapes
    expected = np.array(CUBE_VERTICES) * 0.001 + TRANSLATE
    found = shape.world_vertices
    assert sorted(map(tuple, found.tolist())) == sorted(map(tuple, expected.tolist()))
    assert shape.name == "house" and shape.solid and _closed_outward(shape)
    assert _mesh(shape).volume == pytest.approx(8.0, rel=1e-9)
    assert shape.semantics.counts() == {"GroundSurface": 2, "RoofSurface": 2, "WallSurface": 6}
    assert int((shape.semantics.face_kind == -1).sum()) == 2  # the wall with no kind
    roof = shape.world_vertices[shape.faces[shape.semantics.faces("RoofSurface")]]
    assert np.all(roof[..., 2] == 0.5)
    assert scene.site is None and scene.up_axis == "Z"


def test_json_named_cityjson_is_read_as_cityjson_and_x3d_json_is_not(tmp_path):
    city = _cityjson(tmp_path / "cube.json", {"a": {"type": "Building", "geometry": [_cube()]}})
    assert json_format(city) == "cityjson"
    assert sg.load(city).shapes[0].name == "a"
    x3d = tmp_path / "box.json"
    x3d.write_text('{"X3D": {"Scene": {"-children": [{"Shape": {"-geometry": {"Box": {}}}}]}}}')
    assert json_format(x3d) == "x3d.read"
    assert sg.load(x3d).shapes[0].n_faces == 12


def test_batch_conversion_gives_a_cityjson_json_no_x3d_chord(tmp_path):
    """--tolerance is X3D's chord for curved primitives: batch conversion
    passes it to the reader the file goes to, found by content for .json."""
    from shadowgeo.batch import ConvertOptions, shadowed

    city = _cityjson(tmp_path / "cube.json", {"a": {"type": "Building", "geometry": [_cube()]}})
    scene, result = shadowed(city, ConvertOptions(tolerance=1e-3))
    assert scene.shapes[0].name == "a" and result.shapes_with_role("shadow")


def test_cityjson_highest_lod_by_default_and_lod_option(tmp_path):
    low = _cube("1")
    low["boundaries"] = [[face for face in CUBE_FACES[:5]]]  # one wall less
    low["semantics"]["values"] = [[0, 1, 2, 2, 2]]
    path = _cityjson(
        tmp_path / "lods.city.json", {"b": {"type": "Building", "geometry": [low, _cube("2.2")]}}
    )
    assert sg.load(path).shapes[0].n_faces == 12
    assert sg.load(path, lod="1").shapes[0].n_faces == 10
    assert sg.load(path, lod="2").shapes[0].n_faces == 12


def test_cityjson_lod_missing_everywhere_is_an_error(tmp_path):
    path = _cityjson(
        tmp_path / "lods.city.json", {"b": {"type": "Building", "geometry": [_cube()]}}
    )
    with pytest.raises(sg.SceneError, match="no city object with faces"):
        sg.load(path, lod="3")


# The window as the specification has it (against its wall's outer ring) and
# as some files write it (the same way round): the same hole either way.
@pytest.mark.parametrize("window_ring", [[8, 9, 10, 11], [11, 10, 9, 8]])
def test_cityjson_multisurface_with_hole_and_geometry_template(tmp_path, window_ring):
    wall = [[[0, 1, 5, 4], window_ring]]  # a 2 x 2 wall with a 1 x 1 window
    window = [[500, 0, 500], [500, 0, 1500], [1500, 0, 1500], [1500, 0, 500]]
    tree = {
        "type": "GeometryInstance",
        "template": 0,
        "boundaries": [12],
        "transformationMatrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1],
    }
    template = {
        "type": "MultiSurface",
        "lod": "1",
        "boundaries": [[[0, 1, 2]]],
        "semantics": {"surfaces": [{"type": "+Crown"}], "values": [0]},
    }
    document = {
        "type": "CityJSON",
        "version": "1.1",
        "transform": {"scale": [0.001, 0.001, 0.001], "translate": TRANSLATE},
        "CityObjects": {
            "facade": {
                "type": "Building",
                "geometry": [{"type": "MultiSurface", "lod": "2", "boundaries": wall}],
            },
            "tree": {"type": "SolitaryVegetationObject", "geometry": [tree]},
        },
        "vertices": [*CUBE_VERTICES, *window, [10000, 0, 0]],
        "geometry-templates": {
            "templates": [template],
            "vertices-templates": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
        },
    }
    path = tmp_path / "parts.city.json"
    path.write_text(json.dumps(document))
    facade, tree_shape = sg.load(path).shapes
    assert float(_areas(facade).sum()) == pytest.approx(4 - 1, rel=1e-9)
    assert not facade.solid  # an open surface with no semantics receives on both sides
    assert facade.semantics.counts() == {}
    reference = np.array([10.0, 0.0, 0.0]) + TRANSLATE
    expected = reference + 2 * np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert tree_shape.world_vertices[tree_shape.faces[0]] == pytest.approx(expected, abs=1e-9)
    assert tree_shape.semantics.counts() == {"+Crown": 1}
    only = sg.load(path, types={"Building"})
    assert [shape.name for shape in only.shapes] == ["facade"]


@pytest.mark.parametrize(("ground", "one_sided"), [([0, 3, 2, 1], True), ([0, 1, 2, 3], False)])
def test_an_open_surface_is_one_sided_when_its_semantics_say_outward(tmp_path, ground, one_sided):
    """A roof and a floor, no walls: open. Its floor turned down (outward)
    makes it one-sided; turned up (into the building), two-sided."""
    geometry = {
        "type": "MultiSurface",
        "lod": "2",
        "boundaries": [[ground], [[4, 5, 6, 7]]],
        "semantics": {
            "surfaces": [{"type": "GroundSurface"}, {"type": "RoofSurface"}],
            "values": [0, 1],
        },
    }
    path = _cityjson(
        tmp_path / "open.city.json", {"o": {"type": "Building", "geometry": [geometry]}}
    )
    (shape,) = sg.load(path).shapes
    assert shape.solid is one_sided


def test_cityjsonseq_reads_each_feature_with_its_own_vertices(tmp_path):
    header = {
        "type": "CityJSON",
        "version": "2.0",
        "transform": {"scale": [0.001, 0.001, 0.001], "translate": TRANSLATE},
        "CityObjects": {},
        "vertices": [],
        "metadata": {"referenceSystem": "https://www.opengis.net/def/crs/EPSG/0/7415"},
    }
    lines = [json.dumps(header)]
    for number, shift in enumerate((0, 5000)):
        feature = {
            "type": "CityJSONFeature",
            "id": f"b{number}",
            "CityObjects": {f"b{number}": {"type": "Building", "geometry": [_cube()]}},
            "vertices": [[x + shift, y, z] for x, y, z in CUBE_VERTICES],
        }
        lines.append(json.dumps(feature))
    path = tmp_path / "two.city.jsonl"
    path.write_text("\n".join(lines) + "\n")
    scene = sg.load(path)
    assert [shape.name for shape in scene.shapes] == ["b0", "b1"]
    assert scene.shapes[1].world_vertices[:, 0].min() == pytest.approx(TRANSLATE[0] + 5.0)
    assert scene.site.latitude == pytest.approx(52.0, abs=0.1)
    assert scene.site.longitude == pytest.approx(4.36, abs=0.1)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(version="3.0"), "CityJSON version '3.0' is not read"),
        (
            lambda d: d["CityObjects"]["house"]["geometry"][0]["boundaries"][0][0].__setitem__(
                0, [0, 3, 2, 99]
            ),
            r"CityObject 'house': vertex index 99 is out of range \(8 vertices\)",
        ),
        (
            lambda d: d["CityObjects"]["house"].update(
                geometry=[{"type": "Solid", "lod": "2", "boundaries": CUBE_FACES}]
            ),
            "CityObject 'house': a surface must be a list of rings",
        ),
        (
            lambda d: d["CityObjects"]["house"]["geometry"][0]["semantics"].update(
                values=[[0, 1, 7, 2, 2, None]]
            ),
            "CityObject 'house': semantics value 7",
        ),
        (lambda d: d.update(metadata={"referenceSystem": "EPSG:999999"}), "unknown coordinate"),
        (lambda d: d["transform"].update(scale=[1, 1]), "transform scale must be 3"),
        (  # 1e300 mm: past the range shadowgeo carries
            lambda d: d["vertices"].__setitem__(5, [1e300, 0, 0]),
            "CityObject 'house': the object's point 5 has coordinate 1e\\+297, outside",
        ),
    ],
)
def test_bad_cityjson_is_a_scene_error_naming_the_file_and_object(tmp_path, edit, message):
    path = _cityjson(
        tmp_path / "bad.city.json", {"house": {"type": "Building", "geometry": [_cube()]}}
    )
    document = json.loads(path.read_text())
    edit(document)
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match=r"bad\.city\.json.*" + message):
        sg.load(path)


def _faulty_cube(faults: dict[int, tuple[list, object]]) -> dict:
    """The cube with, per face number, its ring and its semantics value replaced."""
    cube = json.loads(json.dumps(_cube()))  # its own lists, not CUBE_FACES
    for face, (ring, value) in faults.items():
        if ring is not None:
            cube["boundaries"][0][face] = [ring]
        if value is not None:
            cube["semantics"]["values"][0][face] = value
    return cube


# Faults in two faces (or two in one face): the message names the one a
# reader going face by face, each face's rings before its semantics, meets first.
@pytest.mark.parametrize(
    ("faults", "message"),
    [
        ({0: (None, 7), 3: ([1, 2, 6, 99], None)}, "semantics value 7 is not one"),
        ({0: ([0, 3, 2, 99], None), 3: (None, 7)}, r"vertex index 99 is out of range"),
        ({1: ([4, 5, 6, -3], 9)}, r"vertex index -3 is out of range"),
        ({2: ([0, True, 5, 4], None), 4: ([2, 3, 7, 60], None)}, "a ring must be a list of"),
        ({2: ([0, 1, 5, 4.0], None), 4: ([2, 3, 7, 60], None)}, "a ring must be a list of"),
        ({4: ([2, 3, 7, 60], None), 5: ([3, 0, "4", 7], None)}, r"vertex index 60 is out of"),
        # past int64 (the fuzz campaign's cityjson mutant 273 at seed 36 raised
        # OverflowError): named, and shortened to a bounded message
        ({1: ([4, 5, 6, 10**40], None)}, r"vertex index 100000000000\.\.\. \(41 digits\) is out"),
        ({1: ([4, 5, 6, -(2**63) - 1], None)}, r"vertex index -92233720368547758\d* is out"),
    ],
)
def test_the_first_fault_in_the_files_order_is_the_one_named(tmp_path, faults, message):
    path = _cityjson(tmp_path / "bad.city.json", {"house": {"type": "Building"}})
    document = json.loads(path.read_text())
    document["CityObjects"]["house"]["geometry"] = [_faulty_cube(faults)]
    path.write_text(json.dumps(document))
    with pytest.raises(sg.SceneError, match=r"bad\.city\.json.*CityObject 'house': " + message):
        sg.load(path)


def test_repeated_and_closing_indices_and_degenerate_rings_are_dropped(tmp_path):
    # A 2 x 2 m square with a 1 x 1 m hole, both rings written with a corner
    # repeated in a row and the first corner again at the end; a second
    # polygon whose outer ring is one index twice (no area, dropped), and a
    # two-corner hole in the first polygon (dropped): 4 - 1 = 3 m2 in all.
    vertices = [[0, 0, 0], [2000, 0, 0], [2000, 2000, 0], [0, 2000, 0]]
    vertices += [[500, 500, 0], [1500, 500, 0], [1500, 1500, 0], [500, 1500, 0]]
    square = [0, 1, 1, 2, 3, 0]
    hole = [4, 7, 7, 6, 5, 4]
    surface = {
        "type": "MultiSurface",
        "lod": "1",
        "boundaries": [[square, hole, [5, 6]], [[2, 2]], [[3]]],
    }
    path = _cityjson(
        tmp_path / "holed.city.json",
        {"slab": {"type": "Building", "geometry": [surface]}},
        vertices=vertices,
    )
    (shape,) = sg.load(path).shapes
    assert _areas(shape).sum() == pytest.approx(3.0, rel=1e-12)
    assert len(shape.faces) == 8  # a square with a square hole: 8 triangles
    assert len(shape.world_vertices) == 8


def test_template_bomb_and_deep_nesting_are_refused(tmp_path, monkeypatch):
    from shadowgeo.io import cityjson

    monkeypatch.setattr(cityjson, "MAX_TEMPLATE_POINTS", 20)
    instance = {
        "type": "GeometryInstance",
        "template": 0,
        "boundaries": [0],
        "transformationMatrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
    }
    templates = {
        "templates": [{"type": "MultiSurface", "lod": "1", "boundaries": [[[0, 1, 2]]]}],
        "vertices-templates": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
    }
    objects = {
        f"tree{k}": {"type": "SolitaryVegetationObject", "geometry": [instance]} for k in range(7)
    }
    path = _cityjson(tmp_path / "bomb.city.json", objects, **{"geometry-templates": templates})
    with pytest.raises(sg.SceneError, match=r"bomb\.city\.json, CityObject 'tree6': .*templates"):
        sg.load(path)
    monkeypatch.setattr(cityjson, "MAX_TEMPLATE_POINTS", 21)
    assert len(sg.load(path).shapes) == 7  # 7 x 3 points: at the budget, read
    deep = tmp_path / "deep.city.json"
    deep.write_text('{"type": "CityJSON", "version": "2.0", "vertices": ' + "[" * 100_000)
    with pytest.raises(sg.SceneError, match=r"deep\.city\.json.*malformed JSON"):
        sg.load(deep)


def test_malformed_json_and_nan_are_refused(tmp_path):
    path = tmp_path / "cut.city.json"
    path.write_text('{"type": "CityJSON", "version": "2.0",\n "vertices": [[0, 0, ')
    with pytest.raises(sg.SceneError, match=r"cut\.city\.json line 2: malformed JSON"):
        sg.load(path)
    path.write_text('{"type": "CityJSON", "version": "2.0", "vertices": [[NaN, 0, 0]]}')
    with pytest.raises(sg.SceneError, match=r"cut\.city\.json: malformed JSON: NaN"):
        sg.load(path)
    cube = _cityjson(
        tmp_path / "inf.city.json", {"house": {"type": "Building", "geometry": [_cube()]}}
    )
    cube.write_text(cube.read_text().replace("[0, 0, 0]", "[1e400, 0, 0]", 1))  # json: inf
    with pytest.raises(sg.SceneError, match=r"inf\.city\.json, CityObject 'house': .*not finite"):
        sg.load(cube)
    bad = _geojson(tmp_path / "bad.geojson", [])
    bad.write_text("{not json")
    with pytest.raises(sg.SceneError, match=r"bad\.geojson"):
        sg.load(bad)


# -- the real files -----------------------------------------------------------------------


def _file_kind_areas(path: Path) -> dict[str, dict[str, float]]:
    """Per city object, the area of each semantic kind, from the file's own
    polygons (Newell's normal of each ring, holes subtracted): independent of
    the reader's triangulation."""
    document = json.loads(path.read_text())
    scale = np.array(document["transform"]["scale"])
    points = np.array(document["vertices"], dtype=np.float64) * scale
    result = {}
    for name, body in document["CityObjects"].items():
        totals: dict[str, float] = {}
        for geometry in body.get("geometry", []):
            surfaces = geometry["boundaries"]
            values = (geometry.get("semantics") or {}).get("values")
            listed = (geometry.get("semantics") or {}).get("surfaces", [])
            if geometry["type"] == "Solid":
                surfaces = [surface for shell in surfaces for surface in shell]
                values = None if values is None else [v for shell in values for v in shell]
            for number, surface in enumerate(surfaces):
                area = 0.0
                for ring_number, ring in enumerate(surface):
                    corners = points[ring]
                    newell = np.cross(corners, np.roll(corners, -1, axis=0)).sum(axis=0)
                    area += (1 if ring_number == 0 else -1) * np.linalg.norm(newell) / 2
                value = None if values is None else values[number]
                kind = "none" if value is None else listed[value]["type"]
                totals[kind] = totals.get(kind, 0.0) + area
        if totals:
            result[name] = totals
    return result


@pytest.mark.parametrize(
    ("name", "relative"),
    # A polygon out of its plane has a Newell area a little off its
    # triangles': Den Haag's roof quads stand up to 9 mm out of it (a few
    # parts in 1e5), Rotterdam's a fraction of a millimetre (a few in 1e8).
    [("rotterdam_subset.city.json", 1e-6), ("denhaag_subset.city.json", 1e-4)],
)
def test_semantic_areas_per_building_match_the_file(name, relative):
    path = _gis(name)
    scene = sg.load(path)
    expected = _file_kind_areas(path)
    assert scene.site is None  # neither file names a CRS: the caller gives the place
    assert {shape.name for shape in scene.shapes} == set(expected)
    for shape in scene.shapes:
        found = {kind: _kind_area(shape, kind) for kind in shape.semantics.kinds}
        unnamed = float(_areas(shape)[shape.semantics.face_kind == -1].sum())
        if unnamed:
            found["none"] = unnamed
        assert found.keys() == expected[shape.name].keys(), shape.name
        for kind, area in expected[shape.name].items():
            assert found[kind] == pytest.approx(area, rel=relative), (shape.name, kind)


def test_denhaag_solids_are_closed_and_rotterdam_counts():
    denhaag = sg.load(_gis("denhaag_subset.city.json"))
    assert len(denhaag.shapes) == 9 and all(shape.solid for shape in denhaag.shapes)
    rotterdam = sg.load(_gis("rotterdam_subset.city.json"))
    assert len(rotterdam.shapes) == 16
    # open (T-junctions where walls meet roofs) but wound outward: one-sided
    assert all(shape.solid for shape in rotterdam.shapes)
    assert not any(_closed_outward(shape) for shape in rotterdam.shapes)
    assert all(
        set(shape.semantics.kinds) == {"RoofSurface", "WallSurface", "GroundSurface"}
        for shape in rotterdam.shapes
    )


def test_delft_keeps_rd_new_and_finds_its_place():
    path = _gis("delft_lod1.city.json")
    scene = sg.load(path)
    assert len(scene.shapes) == 570
    extent = json.loads(path.read_text())["metadata"]["geographicalExtent"]
    assert scene.bounds.ravel().tolist() == pytest.approx(extent, abs=1e-6)  # metres, kept
    assert scene.site.latitude == pytest.approx(52.01, abs=0.01)
    assert scene.site.longitude == pytest.approx(4.37, abs=0.01)
    assert pyproj.CRS(scene.site.crs).equals(pyproj.CRS("EPSG:7415"))
    # RD New's grid north turns from true north by about 0.8 degrees here
    convergence = math.degrees(math.atan2(scene.site.north[0], scene.site.north[1]))
    assert 0.5 < convergence < 1.0
    buildings = sg.load(path, types={"Building"})
    assert len(buildings.shapes) == 160 and all(shape.solid for shape in buildings.shapes)


# -- shadows ------------------------------------------------------------------------------


def test_a_prism_casts_its_exact_shadow_and_saves(tmp_path):
    """A 1 x 1 x 3 prism on z = 0 under light travelling along (1, 0, -1):
    the ground it hides is the square swept 3 m along x, a 4 x 1 rectangle."""
    path = _geojson(tmp_path / "one.geojson", [_feature([_square(90000, 435000, 1)], height=3)])
    scene = sg.load(path)
    scene.lights.append(sg.SceneLight(sg.DirectionalLight([1.0, 0.0, -1.0]), name="sun"))
    shadowed = sg.add_shadows(scene, plane=[0.0, 0.0, 1.0, 0.0])
    shadows = shadowed.shapes_with_role("shadow")
    assert shadows
    area = sum(float(_areas(shape).sum()) for shape in shadows)
    assert area == pytest.approx(4.0, rel=1e-9)
    sg.save(shadowed, tmp_path / "out.glb")
    again = sg.load(tmp_path / "out.glb")
    assert len(again.shapes) == len(shadowed.shapes)


def test_rotterdam_takes_shadows_and_saves_to_the_millimetre(tmp_path):
    """RD New puts Rotterdam 435 km from the origin, where float32 (glTF's
    positions) steps by 3 cm: each shape's vertices sit near its own corner."""
    scene = sg.load(_gis("rotterdam_subset.city.json"))
    shadowed = sg.add_shadows(scene)
    # the street takes the shadows (a ground is added), not the buildings' floors
    assert shadowed.shapes_with_role("ground")
    assert any(shape.name == "shadow_sun_ground" for shape in shadowed.shapes)
    sg.save(shadowed, tmp_path / "rotterdam.glb")
    again = {shape.name: shape for shape in sg.load(tmp_path / "rotterdam.glb").shapes}
    for shape in scene.shapes:
        y_up = again[shape.name].world_vertices  # glTF is Y up: (x, z, -y)
        back = np.column_stack([y_up[:, 0], -y_up[:, 2], y_up[:, 1]])
        assert np.abs(back - shape.world_vertices).max() < 1e-3, shape.name


def test_a_sun_study_takes_the_place_and_true_north_from_the_site(tmp_path):
    """RD New far west of its central meridian (about 3.4 E): true north turns
    from grid north by about 1.5 degrees, which moves a wall's shadow."""
    import datetime as dt

    from shadowgeo.scene.sunlight import study_scene
    from shadowgeo.sunstudy import sun_study_by_day

    wall = [[20000, 400000], [20002, 400000], [20002, 400040], [20000, 400040], [20000, 400000]]
    scene = sg.load(_geojson(tmp_path / "wall.geojson", [_feature([wall], height=30)]))
    site = scene.site
    convergence = math.degrees(math.atan2(site.north[0], site.north[1]))
    assert 1.0 < abs(convergence) < 2.0
    times = [dt.datetime(2026, 6, 21, 12, tzinfo=dt.UTC)]
    region = [[19900, 399900], [20100, 399900], [20100, 400140], [19900, 400140]]
    inputs, studies = study_scene(scene, times, region=region)  # no latitude, longitude
    (study,) = studies.days.values()

    def shade(north):
        (day,) = sun_study_by_day(
            inputs.caster,
            inputs.plane,
            inputs.region,
            times,
            latitude=site.latitude,
            longitude=site.longitude,
            up="Z",
            north=north,
        ).days.values()
        return day.level_areas()[0.0]

    assert study.level_areas()[0.0] == pytest.approx(shade(site.north), rel=1e-12)
    assert abs(study.level_areas()[0.0] - shade(None)) > 1e-3 * shade(None)  # grid north
    with pytest.raises(sg.SceneError, match="give the latitude and longitude"):
        study_scene(sg.load(_gis("rotterdam_subset.city.json")), times)


@settings(max_examples=60, deadline=None)
@given(
    corners=st.lists(st.tuples(st.floats(0.0, 1.0), st.floats(0.3, 2.0)), min_size=3, max_size=14),
    height=st.floats(0.1, 80.0),
    far=st.sampled_from([0.0, 4.35e5]),
)
def test_any_star_shaped_footprint_extrudes_to_a_closed_prism(corners, height, far):
    """Extrusion's promise on any simple footprint (star-shaped about its
    centre: convex or not, thin spikes included), near the origin or 435 km
    from it: closed, wound outward, volume = footprint area x height, roof
    and ground each the footprint's area."""
    import shapely

    from shadowgeo.io.city_surfaces import CityObject, Surfaces, city_shapes
    from shadowgeo.io.footprints import prism

    chosen = dict(sorted((round(turn * 2 * math.pi, 9), radius) for turn, radius in corners))
    if len(chosen) < 3:
        return
    corners_xy = [[far + r * math.cos(a), far + r * math.sin(a)] for a, r in chosen.items()]
    footprint = shapely.Polygon(corners_xy)
    if not footprint.is_valid or footprint.area < 1e-3:
        return
    # counter-clockwise, as the reader has shapely make it before extruding
    ring = np.asarray(shapely.orient_polygons(footprint).exterior.coords)[:-1]
    surfaces = Surfaces()
    points = prism([ring], 0.0, height, surfaces, 0)
    (shape,) = city_shapes([CityObject("b", points, surfaces, True)], path=Path("p"), kind="f")
    assert _closed_outward(shape)
    assert _mesh(shape).volume == pytest.approx(footprint.area * height, rel=1e-6)
    assert _kind_area(shape, "RoofSurface") == pytest.approx(footprint.area, rel=1e-6)
    assert _kind_area(shape, "GroundSurface") == pytest.approx(footprint.area, rel=1e-6)


def _square_feature(lon: float, lat: float, side: float, height: float) -> dict:
    ring = [[lon, lat], [lon + side, lat], [lon + side, lat + side], [lon, lat + side], [lon, lat]]
    return {
        "type": "Feature",
        "properties": {"height": height},
        "geometry": {"type": "Polygon", "coordinates": [ring]},
    }


def test_sun_cli_takes_the_site_from_the_files_crs(capsys, tmp_path):
    # CRS84 footprints at 51.5 N, 0.1 W: no --at; a file with no CRS needs one
    from cli.main import main

    path = tmp_path / "block.geojson"
    features = [
        _square_feature(-0.1, 51.5, 2e-4, 20.0),
        _square_feature(-0.1 + 4e-4, 51.5, 2e-4, 8.0),
    ]
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    assert main(["sun", str(path), "--date", "2026-03-21"]) == 0
    out = capsys.readouterr().out
    assert "at 51.5001, -0.0997" in out or "at 51.5" in out
    local = tmp_path / "local.city.json"  # a CityJSON with no CRS: where is it?
    cube = [[[[0, 1, 2, 3]], [[4, 7, 6, 5]], [[0, 4, 5, 1]], [[1, 5, 6, 2]], [[2, 6, 7, 3]],
             [[3, 7, 4, 0]]]]  # fmt: skip
    local.write_text(
        json.dumps(
            {
                "type": "CityJSON",
                "version": "2.0",
                "transform": {"scale": [1, 1, 1], "translate": [0, 0, 0]},
                "vertices": [
                    [0, 0, 0],
                    [0, 9, 0],
                    [9, 9, 0],
                    [9, 0, 0],
                    [0, 0, 9],
                    [0, 9, 9],
                    [9, 9, 9],
                    [9, 0, 9],
                ],  # fmt: skip
                "CityObjects": {
                    "b": {
                        "type": "Building",
                        "geometry": [{"type": "Solid", "lod": "1", "boundaries": cube}],
                    }
                },
            }
        )
    )
    with pytest.raises(SystemExit) as exit_:  # a usage error, as a missing option is
        main(["sun", str(local), "--date", "2026-03-21"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "--at LAT,LON" in err and "local.city.json" in err
    assert main(["sun", str(local), "--date", "2026-03-21", "--at", "52,4.3"]) == 0
