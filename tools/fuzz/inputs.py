"""What the campaign feeds the converter: the encodings, where their seed
files are, the command lines a mutant runs with, and the hostile values and
node names the mutators write."""

from __future__ import annotations

import gzip
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared"
EXAMPLES = ROOT / "examples" / "scenes"
KNOWN = SHARED / "findings" / "robustness"

# Encoding name -> the suffix its mutants get; every one is tried, whether the
# reader knows it or not (an exit 1 "cannot read" is a correct, clear error).
ENCODINGS = {
    "x3d": ".x3d",
    "x3dz": ".x3dz",
    "x3dv": ".x3dv",
    "wrl": ".wrl",
    "json": ".json",
    "x3dj": ".x3dj",
    "glb": ".glb",
    "gltf": ".gltf",
    "usda": ".usda",
    "usdc": ".usdc",
    "obj": ".obj",
    "stl": ".stl",
    "ply": ".ply",
    "off": ".off",
    "cityjson": ".city.json",
    "geojson": ".geojson",
}
# Seeds written from the X3D seeds: by shadowgeo, or (meshes that shadowgeo
# reads but does not write) by trimesh.
WRITTEN = ("glb", "gltf", "usda", "usdc", "obj", "stl", "ply", "off")
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off")
TEXT_ENCODINGS = {"x3d", "x3dv", "wrl", "json", "x3dj", "gltf", "usda", "cityjson", "geojson"}
XML_ENCODINGS = {"x3d"}
JSON_ENCODINGS = {"json", "x3dj", "gltf", "cityjson", "geojson"}
# City data (Z up, a site on Earth): its own command lines, and seeds cut
# from the corpus's big files (their first objects) as well as the small ones.
CITY_ENCODINGS = {"cityjson", "geojson"}
CITY_SEED_OBJECTS = 12

SUN = "0.3,-1,0.2"
GROUND = "0,1,0,0"
# Command lines a mutant runs with; IN and OUT are filled in. The one with
# --sun and --plane also gets the independent shadow-area check.
TEMPLATES = [
    ("convert", "IN", "OUT.x3d"),
    ("convert", "IN", "OUT.glb", "--sun", SUN, "--plane", GROUND),
    ("convert", "IN", "OUT.usda", "--sun", "0.2,-1,-0.1"),
    ("convert", "IN", "OUT.x3d", "--method", "volume", "--sun", SUN),
    ("info", "IN"),
    ("convert", "IN", "OUT.gltf"),
    ("convert", "IN", "OUT.x3dz", "--sun=-0.5,-1,0.3", "--method", "planar"),
]
REFERENCE_TEMPLATE = 1
CITY_TEMPLATES = [
    ("convert", "IN", "OUT.x3d"),
    ("convert", "IN", "OUT.glb", "--sun", "0.3,0.2,-1", "--plane", "0,0,1,0"),
    ("info", "IN"),
    ("convert", "IN", "OUT.usda", "--method", "volume"),
    ("sun", "IN", "OUT.x3d", "--at", "52.0,4.36", "--serial", "--every", "240"),
]
CITY_REFERENCE_TEMPLATE = 1

SPECIAL_FLOATS = ["0", "-0", "1e308", "-1e308", "1e-320", "nan", "inf", "-inf", "1e155", "3e38"]
SPECIAL_INTS = ["2147483647", "-1", "-2", "-2147483648", "999999999", "4294967296", "-1000"]
NODE_NAMES = (
    "Transform Group Shape Box Sphere Cone Cylinder IndexedFaceSet IndexedTriangleSet "
    "TriangleSet Coordinate Extrusion ElevationGrid PointLight SpotLight DirectionalLight "
    "Inline Switch LOD Billboard Collision Appearance Material Viewpoint ProtoInstance "
    "ProtoDeclare ExternProtoDeclare IndexedLineSet Text Anchor StaticGroup Scene X3D "
    "fieldValue field IS connect ROUTE MetadataFloat TextureTransform"
).split()
MAX_MUTANT = 4 << 20


def gunzip(data: bytes) -> bytes:
    try:
        return gzip.decompress(data)
    except (OSError, EOFError, ValueError, zlib.error):
        return data
