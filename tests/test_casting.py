"""What casts, as the author said: X3D 4 ``castShadow``, Castle's
``shadowCaster`` and transparency (see shadowgeo.scene.opacity).

Scenes are written here (X3D XML, ClassicVRML, X3D JSON, glTF); the
references are hand-derived: a box's shadow under a point light is the convex
hull of its corners projected from the light, built with shapely in the test.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely

import shadowgeo as sg
from shadowgeo.scene.opacity import casting_opacity

LIGHT = np.array([0.0, 8.0, 0.0])  # a point light 8 above the ground y = 0


def projected_hull(center, size, light=LIGHT):
    """The shadow on y = 0 of a box (``center``, ``size``) lit from the point
    ``light``: the hull of its corners projected from the light, in (x, z)."""
    center, half = np.asarray(center, float), 0.5 * np.asarray(size, float)
    corners = np.array(
        [center + half * [sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    )
    scale = light[1] / (light[1] - corners[:, 1])
    images = light + (corners - light) * scale[:, None]
    return shapely.MultiPoint(images[:, [0, 2]]).convex_hull


def region(shape):
    """A shadow shape's triangles as one shapely region in (x, z), and the sum
    of the triangles' areas (equal to the region's iff they do not overlap)."""
    triangles = shape.world_vertices[shape.faces][:, :, [0, 2]]
    polygons = [shapely.Polygon(t) for t in triangles]
    return shapely.union_all(polygons), sum(p.area for p in polygons)


def on_ground(scene):
    return {s.name: s for s in scene.shapes_with_role("shadow") if "_ground" in s.name}


def x3d(body, light='<PointLight DEF="lamp" location="0 8 0" shadows="true"/>'):
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0"><Scene>
<NavigationInfo headlight="false"/>
{light}
<Shape DEF="ground"><Appearance><Material/></Appearance>
  <IndexedFaceSet solid="false" coordIndex="0 3 2 1 -1">
    <Coordinate point="-10 0 -10 10 0 -10 10 0 10 -10 0 10"/></IndexedFaceSet></Shape>
{body}
</Scene></X3D>
"""


def box(name, center, size=(2, 1, 2), shape="", appearance="", material=""):
    x, y, z = center
    return (
        f'<Transform translation="{x} {y} {z}"><Shape DEF="{name}" {shape}>'
        f"<Appearance {appearance}><Material {material}/></Appearance>"
        f'<Box size="{" ".join(map(str, size))}"/></Shape></Transform>'
    )


def converted(tmp_path, text, name="scene.x3d", **options):
    path = tmp_path / name
    path.write_text(text)
    return sg.add_shadows(sg.load(path), surfaces=False, **options)


def test_cast_shadow_false_casts_nothing_while_its_twin_casts_its_hull(tmp_path):
    text = x3d(box("quiet", (-4, 2.5, 0), shape='castShadow="false"') + box("loud", (4, 2.5, 0)))
    scene = converted(tmp_path, text)
    assert [s.casts_shadow for s in scene.shapes if s.role == "geometry"] == [True, False, True]
    shadow, summed = region(on_ground(scene)["shadow_lamp_ground"])
    expected = projected_hull((4, 2.5, 0), (2, 1, 2))
    # hand check of the reference: the top face (y = 3) scales by 8/5, the
    # bottom (y = 2) by 8/6: x from 3 * 8/6 to 5 * 8/5, z within 1 * 8/5
    assert expected.bounds == pytest.approx((4.0, -1.6, 8.0, 1.6))
    assert shadow.area == pytest.approx(expected.area, rel=1e-9)
    assert summed == pytest.approx(expected.area, rel=1e-9)
    assert shadow.symmetric_difference(expected).area < 1e-9
    assert shadow.intersection(projected_hull((-4, 2.5, 0), (2, 1, 2))).area == 0


def test_a_shape_that_does_not_cast_still_receives(tmp_path):
    # the ground itself says castShadow="false", and a slab under the box too
    text = x3d(box("loud", (0, 2.5, 0))).replace(
        '<Shape DEF="ground">', '<Shape DEF="ground" castShadow="false">'
    )
    scene = converted(tmp_path, text)
    shadow, _ = region(on_ground(scene)["shadow_lamp_ground"])
    assert shadow.area == pytest.approx(projected_hull((0, 2.5, 0), (2, 1, 2)).area, rel=1e-9)
    # every surface: a non-casting slab's top (y = 1) under the box takes its shadow
    path = tmp_path / "slab.x3d"
    path.write_text(
        x3d(
            box("loud", (0, 2.5, 0))
            + box("slab", (0, 0.5, 0), (3, 1, 3), shape='castShadow="false"')
        )
    )
    every = sg.add_shadows(sg.load(path), receivers=["ground"], surfaces=True)
    surfaces = [s for s in every.shapes_with_role("shadow") if s.name.endswith("_surfaces")]
    assert len(surfaces) == 1
    triangles = surfaces[0].world_vertices[surfaces[0].faces]
    on_top = np.all(np.abs(triangles[:, :, 1] - 1.0) < 0.05, axis=1)
    top, _ = region(sg.Shape(triangles[on_top].reshape(-1, 3), np.arange(3 * on_top.sum())))
    # the box's top (y = 3, half-width 1) seen from y = 8 onto y = 1: 7/5 wider
    half = 7 / 5
    assert top.area == pytest.approx((2 * half) ** 2, rel=1e-6)


CLASSIC = """#X3D V4.0 utf8
PROFILE Interchange
DEF lamp PointLight {{ location 0 8 0 shadows TRUE }}
DEF ground Shape {{
  appearance Appearance {{ material Material {{ }} }}
  geometry IndexedFaceSet {{ solid FALSE coordIndex [ 0 3 2 1 -1 ]
    coord Coordinate {{ point [ -10 0 -10, 10 0 -10, 10 0 10, -10 0 10 ] }} }}
}}
Transform {{ translation -4 2.5 0 children DEF quiet Shape {{
  appearance Appearance {{ {quiet} material Material {{ }} }}
  geometry Box {{ size 2 1 2 }} }} }}
Transform {{ translation 4 2.5 0 children DEF loud Shape {{
  appearance Appearance {{ material Material {{ transparency {loud} }} }}
  geometry Box {{ size 2 1 2 }} }} }}
"""


def test_castle_shadow_caster_false_in_classic_vrml(tmp_path):
    scene = converted(tmp_path, CLASSIC.format(quiet="shadowCaster FALSE", loud=0), "s.x3dv")
    shadow, _ = region(on_ground(scene)["shadow_lamp_ground"])
    expected = projected_hull((4, 2.5, 0), (2, 1, 2))
    assert shadow.symmetric_difference(expected).area < 1e-9
    assert len(on_ground(scene)) == 1
    # without the field, both cast (the default is TRUE)
    both = converted(tmp_path, CLASSIC.format(quiet="", loud=0), "t.x3dv")
    shadow, _ = region(on_ground(both)["shadow_lamp_ground"])
    assert shadow.area == pytest.approx(2 * expected.area, rel=1e-9)


def test_cast_shadow_false_in_x3d_json(tmp_path):
    def shape(name, x, **fields):
        body = {"@DEF": name, **fields, "-geometry": {"Box": {"@size": [2, 1, 2]}}}
        return {"Transform": {"@translation": [x, 2.5, 0], "-children": [{"Shape": body}]}}

    ground = {
        "@DEF": "ground",
        "-geometry": {
            "IndexedFaceSet": {
                "@solid": False,
                "@coordIndex": [0, 3, 2, 1, -1],
                "-coord": {
                    "Coordinate": {"@point": [-10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10]}
                },
            }
        },
    }
    document = {
        "X3D": {
            "@profile": "Interchange",
            "@version": "4.0",
            "Scene": {
                "-children": [
                    {"PointLight": {"@DEF": "lamp", "@location": [0, 8, 0], "@shadows": True}},
                    {"Shape": ground},
                    shape("quiet", -4, **{"@castShadow": False}),
                    shape("loud", 4),
                ]
            },
        }
    }
    scene = converted(tmp_path, json.dumps(document), "s.x3dj")
    shadow, _ = region(on_ground(scene)["shadow_lamp_ground"])
    assert shadow.symmetric_difference(projected_hull((4, 2.5, 0), (2, 1, 2))).area < 1e-9


def test_a_fully_transparent_shape_casts_nothing_and_costs_no_pass(tmp_path):
    scene = converted(tmp_path, CLASSIC.format(quiet="shadowCaster FALSE", loud=1), "s.x3dv")
    assert on_ground(scene) == {}
    assert any("no shadow falls" in note for note in scene.warnings)
    # nearly transparent (opacity below 1/32) is the same
    assert casting_opacity(sg.Shape([], [], material=sg.Material(transparency=0.97))) == 0


@pytest.mark.parametrize(("intensity", "transparency"), [(1.0, 0.5), (0.8, 0.6)])
def test_half_transparent_casts_a_half_dark_shadow_of_the_same_area(
    tmp_path, intensity, transparency
):
    lamp = f'<PointLight DEF="lamp" location="0 8 0" shadows="true" shadowIntensity="{intensity}"/>'
    text = x3d(box("glass", (4, 2.5, 0), material='transparency="0.5"'), lamp)
    scene = converted(tmp_path, text)
    ((name, shadow),) = on_ground(scene).items()
    assert name == "shadow_lamp_ground_opacity50"
    # one light, no headlight, no ambient: the light's darkness is its
    # shadowIntensity (see .darkness), so darkness = shadowIntensity x opacity
    assert shadow.material.transparency == pytest.approx(transparency, abs=1e-12)
    assert 1 - shadow.material.transparency == pytest.approx(intensity * 0.5)
    area, _ = region(shadow)
    assert area.symmetric_difference(projected_hull((4, 2.5, 0), (2, 1, 2))).area < 1e-9


def test_overlapping_opaque_and_translucent_shadows_are_disjoint_layers(tmp_path):
    # an opaque box and a glass box side by side: their shadows overlap
    text = x3d(
        box("stone", (1, 2.5, 0)) + box("glass", (2, 4.5, 0.5), material='transparency="0.5"')
    )
    scene = converted(tmp_path, text)
    layers = on_ground(scene)
    assert sorted(layers) == ["shadow_lamp_ground", "shadow_lamp_ground_opacity50"]
    stone_hull = projected_hull((1, 2.5, 0), (2, 1, 2))
    glass_hull = projected_hull((2, 4.5, 0.5), (2, 1, 2))
    overlap = stone_hull.intersection(glass_hull).area
    assert overlap > 0.5  # the scene tests what it means to
    opaque, opaque_sum = region(layers["shadow_lamp_ground"])
    glass, glass_sum = region(layers["shadow_lamp_ground_opacity50"])
    assert opaque.area == pytest.approx(stone_hull.area, rel=1e-9)
    assert glass.area == pytest.approx(glass_hull.area - overlap, rel=1e-9)
    assert glass_sum == pytest.approx(glass.area, rel=1e-9)  # no triangle over another
    assert opaque.intersection(glass).area < 1e-9  # never darkened twice
    assert opaque.union(glass).symmetric_difference(stone_hull.union(glass_hull)).area < 1e-9
    assert layers["shadow_lamp_ground"].material.transparency == 0
    assert layers["shadow_lamp_ground_opacity50"].material.transparency == 0.5


def test_opacity_levels_round_to_sixteenths():
    def opacity(transparency):
        return casting_opacity(sg.Shape([], [], material=sg.Material(transparency=transparency)))

    assert [opacity(t) for t in (0, 0.02, 0.5, 0.8, 0.96, 0.97, 1)] == [
        1, 1, 0.5, 3 / 16, 1 / 16, 0, 0,
    ]  # fmt: skip
    assert opacity(1 - 1 / 32) == 1 / 16  # halves round up: 1/32 still casts


def on_slope(shape, tolerance=0.05):
    """The triangles of a shadow shape lying on the ramp y = (x + 3) / 2, as a
    shapely region in (x, z) (seen from above)."""
    triangles = shape.world_vertices[shape.faces]
    on = np.all(np.abs(triangles[:, :, 1] - (triangles[:, :, 0] + 3) / 2) < tolerance, axis=1)
    return shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in triangles[on]])


def test_every_surface_a_translucent_caster_over_a_slope(tmp_path):
    # a ramp y = (x + 3) / 2, a glass cube over it and a stone cube above
    # that, sun straight down: seen from above, each shadow is its cube's
    # square; on the ramp each is sqrt(1 + 1/4) times larger
    sun = '<DirectionalLight DEF="sun" direction="0 -1 0" shadows="true"/>'
    ramp = (
        '<Shape DEF="ramp"><Appearance><Material/></Appearance>'
        '<IndexedFaceSet solid="false" coordIndex="0 3 2 1 -1">'
        '<Coordinate point="-3 0 -3 3 3 -3 3 3 3 -3 0 3"/></IndexedFaceSet></Shape>'
    )
    glass = box("glass", (0, 4, 0), (1, 1, 1), material='transparency="0.5"')
    stone = box("stone", (0.5, 5.5, 0.5), (1, 1, 1))
    path = tmp_path / "ramp.x3d"
    path.write_text(x3d(ramp + glass + stone, sun))
    # no lift: it moves a shadow on the ramp sideways along the ramp's normal
    scene = sg.add_shadows(sg.load(path), receivers=["ground"], surfaces=True, offset=0)
    layers = {s.name: s for s in scene.shapes_with_role("shadow") if "_surfaces" in s.name}
    assert sorted(layers) == ["shadow_sun_surfaces", "shadow_sun_surfaces_opacity50"]
    glass_square = shapely.box(-0.5, -0.5, 0.5, 0.5)
    stone_square = shapely.box(0, 0, 1, 1)
    opaque = on_slope(layers["shadow_sun_surfaces"])
    translucent = on_slope(layers["shadow_sun_surfaces_opacity50"])
    assert opaque.symmetric_difference(stone_square).area < 1e-6
    expected = glass_square.difference(stone_square)  # 3/4 of the glass's square
    assert translucent.symmetric_difference(expected).area < 1e-6
    assert opaque.intersection(translucent).area < 1e-6
    slope = np.sqrt(1.25)
    flat = layers["shadow_sun_surfaces_opacity50"]
    triangles = flat.world_vertices[flat.faces]
    on = np.all(np.abs(triangles[:, :, 1] - (triangles[:, :, 0] + 3) / 2) < 0.05, axis=1)
    sides = np.cross(triangles[on, 1] - triangles[on, 0], triangles[on, 2] - triangles[on, 0])
    assert 0.5 * np.linalg.norm(sides, axis=1).sum() == pytest.approx(0.75 * slope, rel=1e-6)
    assert layers["shadow_sun_surfaces_opacity50"].material.transparency == 0.5
    # the stone's shadow on the glass's top (y = 4.5) is opaque: x, z in [0, 0.5]
    stone_layer = layers["shadow_sun_surfaces"]
    top = stone_layer.world_vertices[stone_layer.faces]
    on_top = np.all(np.abs(top[:, :, 1] - 4.5) < 0.05, axis=1)
    top_region = shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in top[on_top]])
    assert top_region.symmetric_difference(shapely.box(0, 0, 0.5, 0.5)).area < 1e-6


def gltf_scene(alpha_mode):
    """A glTF document: a ground quad and a 2 x 1 x 2 box at (4, 2.5, 0) of
    alpha 0.5 under ``alpha_mode``, a point light at (0, 8, 0)."""
    import base64

    import trimesh

    cube = trimesh.creation.box(extents=[2, 1, 2])
    ground = np.array([[-10, 0, -10], [10, 0, -10], [10, 0, 10], [-10, 0, 10]], np.float32)
    quad = np.array([[0, 3, 2], [0, 2, 1]], np.uint16)  # counter-clockwise from +y
    parts = [
        np.asarray(cube.vertices, np.float32),
        np.asarray(cube.faces, np.uint16),
        ground,
        quad,
    ]
    blobs = [part.tobytes() + b"\0" * (-len(part.tobytes()) % 4) for part in parts]
    offsets = np.cumsum([0] + [len(b) for b in blobs]).tolist()
    views = [
        {"buffer": 0, "byteOffset": offsets[k], "byteLength": len(parts[k].tobytes())}
        for k in range(4)
    ]

    def accessor(k, kind):
        part = parts[k]
        if kind == "VEC3":
            low, high = part.min(axis=0).tolist(), part.max(axis=0).tolist()
            return {"bufferView": k, "componentType": 5126, "count": len(part), "type": "VEC3",
                    "min": low, "max": high}  # fmt: skip
        return {"bufferView": k, "componentType": 5123, "count": part.size, "type": "SCALAR"}

    data = base64.b64encode(b"".join(blobs)).decode()
    return {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "name": "lamp"}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "name": "glass", "translation": [4, 2.5, 0]},
            {"mesh": 1, "name": "ground"},
            {
                "name": "lamp",
                "translation": [0, 8, 0],
                "extensions": {"KHR_lights_punctual": {"light": 0}},
            },
        ],  # fmt: skip
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 2}, "indices": 3}]},
        ],
        "materials": [
            {
                "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.9, 0.5]},
                "alphaMode": alpha_mode,
            }
        ],
        "accessors": [accessor(0, "VEC3"), accessor(1, ""), accessor(2, "VEC3"), accessor(3, "")],
        "bufferViews": views,
        "buffers": [
            {"byteLength": offsets[-1], "uri": "data:application/octet-stream;base64," + data}
        ],
    }


@pytest.mark.parametrize(("mode", "transparency"), [("BLEND", 0.5), ("MASK", 0), ("OPAQUE", 0)])
def test_gltf_alpha_under_blend_casts_half_dark(tmp_path, mode, transparency):
    path = tmp_path / "scene.gltf"
    path.write_text(json.dumps(gltf_scene(mode)))
    scene = sg.add_shadows(sg.load(path), surfaces=False)
    (shadow,) = on_ground(scene).values()
    assert shadow.material.transparency == pytest.approx(transparency, abs=1e-6)
    area, _ = region(shadow)
    assert area.symmetric_difference(projected_hull((4, 2.5, 0), (2, 1, 2))).area < 1e-6


@pytest.mark.parametrize(
    ("appearance", "transparency", "expected"),
    [
        ('alphaMode="OPAQUE"', 0.5, 0.0),  # drawn opaque: casts fully
        ('alphaMode="MASK"', 0.4, 0.0),  # alpha 0.6 >= cutoff 0.5: opaque
        ('alphaMode="MASK" alphaCutoff="0.7"', 0.4, 1.0),  # below the cutoff: not drawn
        ('alphaMode="BLEND"', 0.5, 0.5),
        ("", 0.5, 0.5),  # AUTO blends
    ],
)
def test_x3d_alpha_mode_decides_the_transparency_that_casts(
    tmp_path, appearance, transparency, expected
):
    text = x3d(box("pane", (4, 2.5, 0), appearance=appearance,
                   material=f'transparency="{transparency}"'))  # fmt: skip
    path = tmp_path / "pane.x3d"
    path.write_text(text)
    (pane,) = [shape for shape in sg.load(path).shapes if shape.name == "pane"]
    assert pane.material.transparency == expected


def test_a_shape_that_does_not_cast_keeps_saying_so_in_x3d_written_afresh(tmp_path):
    quad = [[-1, 0, -1], [1, 0, -1], [1, 0, 1]]
    scene = sg.Scene([sg.Shape(quad, [[0, 2, 1]], name="veil", casts_shadow=False)])
    sg.save(scene, tmp_path / "out.x3d")
    assert 'castShadow="false"' in (tmp_path / "out.x3d").read_text()
    (back,) = sg.load(tmp_path / "out.x3d").shapes
    assert not back.casts_shadow


def test_shadow_volumes_only_for_shapes_that_cast(tmp_path):
    text = x3d(
        box("quiet", (-4, 2.5, 0), shape='castShadow="false"')
        + box("glass", (0, 2.5, 0), material='transparency="1"')
        + box("loud", (4, 2.5, 0))
    )
    path = tmp_path / "scene.x3d"
    path.write_text(text)
    scene = sg.add_shadows(sg.load(path), method="volume")
    names = [shape.name for shape in scene.shapes_with_role("volume")]
    assert names == ["volume_lamp_ground", "volume_lamp_loud"]


USDA = """#usda 1.0
(
    upAxis = "Y"
    metersPerUnit = 1
)
def Xform "World"
{
    def Mesh "ground"
    {
        uniform bool doubleSided = 1
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 3, 2, 1]
        point3f[] points = [(-10, 0, -10), (10, 0, -10), (10, 0, 10), (-10, 0, 10)]
    }
    def Mesh "glass"
    {
        int[] faceVertexCounts = [4, 4, 4, 4, 4, 4]
        int[] faceVertexIndices = [0, 1, 3, 2, 4, 6, 7, 5, 0, 4, 5, 1, 2, 3, 7, 6, 0, 2, 6, 4,
                                   1, 5, 7, 3]
        point3f[] points = [(3, 2, -1), (3, 2, 1), (3, 3, -1), (3, 3, 1),
                            (5, 2, -1), (5, 2, 1), (5, 3, -1), (5, 3, 1)]
        float[] primvars:displayOpacity = [0.5] (interpolation = "constant")
    }
    def SphereLight "lamp"
    {
        float inputs:radius = 0
        double3 xformOp:translate = (0, 8, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
}
"""


def test_usd_display_opacity_half_casts_half_dark(tmp_path):
    path = tmp_path / "scene.usda"
    path.write_text(USDA)
    scene = sg.add_shadows(sg.load(path), surfaces=False)
    (shadow,) = on_ground(scene).values()
    assert shadow.material.transparency == pytest.approx(0.5)
    area, _ = region(shadow)
    assert area.symmetric_difference(projected_hull((4, 2.5, 0), (2, 1, 2))).area < 1e-6
