"""City data mutants (CityJSON, GeoJSON footprints) at the meaning level:
the numbers, indices, transforms, templates and properties that the city
readers take on trust; and small seeds cut from the big corpus files."""

from __future__ import annotations

import json
import random

HOSTILE_NUMBERS = [0, -0.0, 1e308, -1e308, 1e-320, 2**63, -(2**31), 1e155, 3e38, -1]
HOSTILE_TEXT = ["", "nan", "inf", "-inf", "1e999", "x", "NaN"]


def mutate_city(data: bytes, encoding: str, rng: random.Random):
    """One meaning-level mutant of a CityJSON or GeoJSON document: (bytes, op),
    or None when ``data`` is not a JSON object."""
    try:
        document = json.loads(data)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return None
    if not isinstance(document, dict):
        return None
    if encoding == "cityjson":
        operations = (_transform, _vertex, _boundary_index, _template_bomb, _geometry_type)
        operations += (_lod, _reference_system, _deep_boundaries)
    else:
        operations = (_coordinate, _ring, _height, _geometry_type_geojson, _copies)
        operations += (_crs, _deep_boundaries)
    operation = rng.choice(operations)
    name = operation(document, rng)
    if name is None:
        return None
    return json.dumps(document, allow_nan=True).encode(), f"meaning:city-{name}"


def _hostile(rng: random.Random):
    return rng.choice(HOSTILE_NUMBERS + HOSTILE_TEXT + [None, [], {}])


def _objects(document: dict) -> list[dict]:
    objects = document.get("CityObjects")
    return [o for o in objects.values() if isinstance(o, dict)] if isinstance(objects, dict) else []


def _geometries(document: dict) -> list[dict]:
    return [
        g
        for o in _objects(document)
        for g in (o.get("geometry") or [])
        if isinstance(g, dict) and isinstance(o.get("geometry"), list)
    ]


def _transform(document: dict, rng: random.Random) -> str | None:
    transform = document.setdefault("transform", {"scale": [1, 1, 1], "translate": [0, 0, 0]})
    if not isinstance(transform, dict):
        return None
    key = rng.choice(("scale", "translate"))
    values = transform.get(key)
    values = list(values) if isinstance(values, list) else [1, 1, 1]
    if values and rng.random() < 0.8:
        values[rng.randrange(len(values))] = _hostile(rng)
    else:
        values = _hostile(rng)
    transform[key] = values
    return f"transform-{key}"


def _vertex(document: dict, rng: random.Random) -> str | None:
    vertices = document.get("vertices")
    if not isinstance(vertices, list) or not vertices:
        return None
    index = rng.randrange(len(vertices))
    vertex = vertices[index]
    if isinstance(vertex, list) and vertex and rng.random() < 0.8:
        vertex[rng.randrange(len(vertex))] = _hostile(rng)
    else:
        vertices[index] = _hostile(rng)
    return "vertex"


def _integers(value, found: list, depth: int = 0) -> None:
    """The (list, index) of every integer in nested lists."""
    if depth > 50 or not isinstance(value, list):
        return
    for index, item in enumerate(value):
        if isinstance(item, int) and not isinstance(item, bool):
            found.append((value, index))
        else:
            _integers(item, found, depth + 1)


def _boundary_index(document: dict, rng: random.Random) -> str | None:
    found: list = []
    for geometry in _geometries(document):
        _integers(geometry.get("boundaries"), found)
    if not found:
        return None
    holder, index = rng.choice(found)
    holder[index] = rng.choice((-1, -2, 10**9, 2**31, 2**63, len(document.get("vertices") or [])))
    return "boundary-index"


def _template_bomb(document: dict, rng: random.Random) -> str | None:
    """Many GeometryInstances of one template: points made by placing it."""
    points = rng.choice((10, 1000, 100_000))
    copies = rng.choice((10, 1000, 50_000))
    template = {
        "type": "MultiSurface",
        "lod": "1",
        "boundaries": [[[i, i + 1, i + 2]] for i in range(0, points - 2, 3)],
    }
    document["geometry-templates"] = {
        "templates": [template],
        "vertices-templates": [[i * 0.01, (i % 7) * 0.1, (i % 3) * 0.2] for i in range(points)],
    }
    vertices = document.setdefault("vertices", [])
    if not isinstance(vertices, list):
        return None
    vertices.append([0, 0, 0])
    anchor = len(vertices) - 1
    instance = {
        "type": "GeometryInstance",
        "template": 0,
        "boundaries": [anchor],
        "transformationMatrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
    }
    objects = document.setdefault("CityObjects", {})
    if not isinstance(objects, dict):
        return None
    objects["fuzz-instances"] = {"type": "CityFurniture", "geometry": [instance] * copies}
    return f"template-bomb-{points}x{copies}"


def _geometry_type(document: dict, rng: random.Random) -> str | None:
    geometries = _geometries(document)
    if not geometries:
        return None
    kinds = ("Solid", "MultiSolid", "CompositeSolid", "MultiSurface", "CompositeSurface")
    rng.choice(geometries)["type"] = rng.choice((*kinds, "GeometryInstance", "Point", "", 3))
    return "geometry-type"


def _lod(document: dict, rng: random.Random) -> str | None:
    geometries = _geometries(document)
    if not geometries:
        return None
    rng.choice(geometries)["lod"] = rng.choice(("0", "3.3", "9", 2, -1, None, "", "1e308"))
    return "lod"


def _reference_system(document: dict, rng: random.Random) -> str | None:
    metadata = document.setdefault("metadata", {})
    if not isinstance(metadata, dict):
        return None
    metadata["referenceSystem"] = rng.choice(
        (
            "https://www.opengis.net/def/crs/EPSG/0/4326",
            "https://www.opengis.net/def/crs/EPSG/0/99999",
            "urn:ogc:def:crs:EPSG::7415",
            "EPSG:3857",
            "",
            7415,
        )
    )
    return "reference-system"


def _deep_boundaries(document: dict, rng: random.Random) -> str | None:
    depth = rng.choice((10, 100, 900))
    nested: list = [0, 1, 2]
    for _ in range(depth):
        nested = [nested]
    if "CityObjects" in document:
        objects = document["CityObjects"] if isinstance(document["CityObjects"], dict) else {}
        objects["fuzz-deep"] = {
            "type": "Building",
            "geometry": [{"type": "MultiSurface", "lod": "1", "boundaries": nested}],
        }
        document["CityObjects"] = objects
    else:
        features = document.get("features") if isinstance(document.get("features"), list) else []
        features.append(
            {
                "type": "Feature",
                "properties": {"height": 10},
                "geometry": {"type": "Polygon", "coordinates": nested},
            }
        )
        document["features"] = features
    return f"deep-boundaries-{depth}"


def _features(document: dict) -> list[dict]:
    features = document.get("features")
    if isinstance(features, list):
        return [f for f in features if isinstance(f, dict)]
    return [document] if document.get("type") == "Feature" else []


def _coordinate(document: dict, rng: random.Random) -> str | None:
    found: list = []

    def numbers(value, depth: int = 0) -> None:
        if depth > 50 or not isinstance(value, list):
            return
        for index, item in enumerate(value):
            if isinstance(item, int | float) and not isinstance(item, bool):
                found.append((value, index))
            else:
                numbers(item, depth + 1)

    for feature in _features(document):
        geometry = feature.get("geometry")
        if isinstance(geometry, dict):
            numbers(geometry.get("coordinates"))
    if not found:
        return None
    holder, index = rng.choice(found)
    holder[index] = _hostile(rng)
    return "coordinate"


def _ring(document: dict, rng: random.Random) -> str | None:
    """A ring cut short, reversed, left open or repeated many times."""
    rings = [
        ring
        for feature in _features(document)
        if isinstance(feature.get("geometry"), dict)
        for ring in (feature["geometry"].get("coordinates") or [])
        if isinstance(ring, list) and ring and isinstance(ring[0], list)
    ]
    if not rings:
        return None
    ring = rng.choice(rings)
    kind = rng.choice(("short", "reverse", "open", "repeat"))
    if kind == "short":
        del ring[rng.randint(0, 2) :]
    elif kind == "reverse":
        ring.reverse()
    elif kind == "open" and len(ring) > 1:
        ring.pop()
    else:
        ring.extend(ring[:-1] * rng.choice((2, 100, 5000)))
    return f"ring-{kind}"


def _height(document: dict, rng: random.Random) -> str | None:
    features = _features(document)
    if not features:
        return None
    properties = rng.choice(features).setdefault("properties", {})
    if not isinstance(properties, dict):
        return None
    key = rng.choice(("height", "Floor", "floors", "base"))
    properties[key] = _hostile(rng)
    return f"property-{key}"


def _geometry_type_geojson(document: dict, rng: random.Random) -> str | None:
    features = _features(document)
    if not features or not isinstance(features[0].get("geometry"), dict):
        return None
    geometry = rng.choice([f["geometry"] for f in features if isinstance(f.get("geometry"), dict)])
    kinds = ("Polygon", "MultiPolygon", "Point", "LineString", "GeometryCollection", "", 7)
    geometry["type"] = rng.choice(kinds)
    return "geometry-type"


def _copies(document: dict, rng: random.Random) -> str | None:
    features = document.get("features")
    if not isinstance(features, list) or not features:
        return None
    features.extend(features[:3] * rng.choice((10, 1000, 20_000)))
    return "feature-copies"


def _crs(document: dict, rng: random.Random) -> str | None:
    name = rng.choice(
        ("urn:ogc:def:crs:EPSG::28992", "EPSG:4326", "urn:ogc:def:crs:EPSG::99999", "", "x")
    )
    document["crs"] = {"type": "name", "properties": {"name": name}}
    return "crs"


def subset(data: bytes, encoding: str, count: int) -> bytes | None:
    """A small seed cut from a big city file: its first ``count`` city objects
    (their vertices renumbered) or features; None when it cannot be cut."""
    try:
        document = json.loads(data)
    except (ValueError, UnicodeDecodeError):
        return None
    if encoding == "geojson" and isinstance(document.get("features"), list):
        document["features"] = document["features"][:count]
        return json.dumps(document).encode()
    objects = document.get("CityObjects")
    if encoding != "cityjson" or not isinstance(objects, dict):
        return None
    kept = dict(list(objects.items())[:count])
    for value in kept.values():  # links to objects left out
        value.pop("children", None)
        value.pop("parents", None)
    numbers: dict[int, int] = {}
    for value in kept.values():
        for geometry in value.get("geometry") or []:
            geometry["boundaries"] = _renumbered(geometry.get("boundaries"), numbers)
    vertices = document.get("vertices") or []
    document["vertices"] = [vertices[old] for old in sorted(numbers, key=numbers.get)]
    document["CityObjects"] = kept
    document.pop("geometry-templates", None)
    return json.dumps(document).encode()


def _renumbered(value, numbers: dict[int, int]):
    if isinstance(value, list):
        return [_renumbered(item, numbers) for item in value]
    if isinstance(value, int):
        return numbers.setdefault(value, len(numbers))
    return value
