"""X3D light scope: a light with ``global`` false lights, shadows and casts
only within its parent grouping node (DirectionalLight's default); PointLight
and SpotLight are global by default.

The scenes are two groups 20 apart, west (x = -10) and east (x = +10), each
with its own light, a 10 x 10 floor at y = 0, a 4 x 0.5 x 4 slab resting on
it and a 2 x 2 x 2 box floating above (y from 1 to 3). The reference areas
are the projections worked out by hand (in the groups' own coordinates):

- straight down (0, -1, 0): on the floor the slab's 4 x 4 footprint, which
  holds the box's 2 x 2 shadow: 16; on the slab's top the box's 2 x 2: 4;
- along (1, -1, 0), a point (x, y) goes to x + y on the floor: the slab to
  [-2, 2.5] x [-2, 2] (18), the box to [0, 4] x [-1, 1], of which
  [2.5, 4] x [-1, 1] (3) lies outside the slab's: 21; on the slab's top
  (y = 0.5) the box goes to x in [-0.5, 3.5], cut at the slab's edge x = 2:
  2.5 x 2 = 5.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest
from lxml import etree

import shadowgeo as sg
from shadowgeo.scene.darkness import shadow_darkness

FLOOR_POINTS = "-5 0 -5 -5 0 5 5 0 5 5 0 -5"
DOWN = "0 -1 0"
SLANT = "1 -1 0"


def _xml_light(tag: str, fields: dict[str, str]) -> str:
    return f"<{tag} " + " ".join(f'{k}="{v}"' for k, v in fields.items()) + "/>"


def _xml_group(side: str, x: float, light: str) -> str:
    look = "<Appearance><Material/></Appearance>"
    return (
        f'<Group DEF="{side}">{light}<Transform translation="{x} 0 0">'
        f'<Shape DEF="floor{side}">{look}<IndexedFaceSet solid="false" coordIndex="0 1 2 3 -1">'
        f'<Coordinate point="{FLOOR_POINTS}"/></IndexedFaceSet></Shape>'
        f'<Transform translation="0 0.25 0"><Shape DEF="slab{side}">{look}'
        '<Box size="4 0.5 4"/></Shape></Transform>'
        f'<Transform translation="0 2 0"><Shape DEF="box{side}">{look}<Box/></Shape></Transform>'
        "</Transform></Group>"
    )


def _classic_light(tag: str, fields: dict[str, str]) -> str:
    fields = dict(fields)
    name = fields.pop("DEF")
    written = " ".join(
        f"{k} {v.upper() if v in ('true', 'false') else v}" for k, v in fields.items()
    )
    return f"DEF {name} {tag} {{ {written} }}"


def _classic_group(side: str, x: float, light: str) -> str:
    look = "appearance Appearance { material Material { } }"
    return (
        f"DEF {side} Group {{ children [ {light} Transform {{ translation {x} 0 0 children [\n"
        f"  DEF floor{side} Shape {{ {look} geometry IndexedFaceSet {{ solid FALSE\n"
        f"    coord Coordinate {{ point [ {FLOOR_POINTS} ] }} coordIndex [ 0 1 2 3 -1 ] }} }}\n"
        f"  Transform {{ translation 0 0.25 0 children DEF slab{side} Shape {{ {look}\n"
        "    geometry Box { size 4 0.5 4 } } }\n"
        f"  Transform {{ translation 0 2 0 children DEF box{side} Shape {{ {look}\n"
        "    geometry Box { } } }\n"
        "] } ] }\n"
    )


# A 2 x 0.2 x 2 roof at the top of the scene, over the west floor's corner
# (x from -14 to -12, z from 2 to 4), in neither group.
ROOF_XML = (
    '<Transform translation="-13 6 3"><Shape DEF="roof"><Box size="2 0.2 2"/></Shape></Transform>'
)
ROOF_CLASSIC = (
    "Transform { translation -13 6 3 children DEF roof Shape { geometry Box { size 2 0.2 2 } } }"
)
# A 1 x 0.1 x 1 ring at the top of the scene, between the west box and slab
# (y from 0.7 to 0.8), wholly in the box's shadow under a sun straight down.
RING_XML = (
    '<Transform translation="-10 0.75 0">'
    '<Shape DEF="ring"><Box size="1 0.1 1"/></Shape></Transform>'
)
RING_CLASSIC = (
    "Transform { translation -10 0.75 0 children DEF ring Shape { geometry Box { size 1 0.1 1 } } }"
)


def write_scene(
    folder,
    encoding: str,
    west: tuple[str, dict],
    east: tuple[str, dict],
    roof: bool = False,
    ring: bool = False,
):
    """The two-group scene in ``encoding`` ("xml" or "classic"), each group's
    light given as (node type, fields), with the roof or not; no headlight."""
    if encoding == "xml":
        body = _xml_group("W", -10, _xml_light(*west)) + _xml_group("E", 10, _xml_light(*east))
        body += (ROOF_XML if roof else "") + (RING_XML if ring else "")
        text = f'<X3D version="4.0"><Scene><NavigationInfo headlight="false"/>{body}</Scene></X3D>'
        path = folder / "scope.x3d"
    else:
        body = _classic_group("W", -10, _classic_light(*west))
        body += _classic_group("E", 10, _classic_light(*east))
        body += (ROOF_CLASSIC if roof else "") + (RING_CLASSIC if ring else "")
        text = f"#X3D V4.0 utf8\nPROFILE Immersive\nNavigationInfo {{ headlight FALSE }}\n{body}"
        path = folder / "scope.x3dv"
    path.write_text(text)
    return path


def sun(name: str, direction: str, **more: str) -> tuple[str, dict]:
    return ("DirectionalLight", {"DEF": name, "direction": direction, "intensity": "0.5", **more})


def shadow_areas(scene: sg.Scene) -> dict[tuple[str, str], float]:
    """(light, receiver) -> the area of the shadow shapes named for them."""
    areas: dict[tuple[str, str], float] = defaultdict(float)
    for shape in scene.shapes_with_role("shadow"):
        _, light, receiver = shape.name.split("_")[:3]
        corners = shape.world_vertices[shape.faces]
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        areas[light, receiver] += 0.5 * float(np.linalg.norm(cross, axis=1).sum())
    return dict(areas)


def shadow(scene: sg.Scene, name: str) -> sg.Shape:
    return next(shape for shape in scene.shapes_with_role("shadow") if shape.name == name)


ENCODINGS = ["xml", "classic"]


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_scoped_suns_shadow_only_their_own_group(tmp_path, encoding):
    path = write_scene(tmp_path, encoding, sun("sunW", DOWN), sun("sunE", SLANT))
    scene = sg.load(path)
    assert [light.global_ for light in scene.lights] == [False, False]
    result = sg.add_shadows(scene)
    areas = shadow_areas(result)
    assert sorted(areas) == [
        ("sunE", "floorE"),
        ("sunE", "surfaces"),
        ("sunW", "floorW"),
        ("sunW", "surfaces"),
    ]
    assert areas["sunW", "floorW"] == pytest.approx(16, rel=1e-6)
    assert areas["sunE", "floorE"] == pytest.approx(21, rel=1e-6)
    assert areas["sunW", "surfaces"] == pytest.approx(4, rel=1e-6)  # the west slab's top
    assert areas["sunE", "surfaces"] == pytest.approx(5, rel=1e-6)  # the east slab's top
    assert any(note.startswith("shadows: lights sunW, sunE: global") for note in result.warnings)
    west = shadow(result, "shadow_sunW_surfaces").world_vertices[:, 0]
    east = shadow(result, "shadow_sunE_surfaces").world_vertices[:, 0]
    assert west.max() < -5 and east.min() > 5
    # each floor lit by its own sun only: the shadow takes all of its light
    assert shadow(result, "shadow_sunW_floorW").material.transparency == pytest.approx(0, abs=1e-9)
    assert shadow(result, "shadow_sunE_floorE").material.transparency == pytest.approx(0, abs=1e-9)
    assert shadow(result, "shadow_sunW_surfaces").material.transparency == pytest.approx(
        0, abs=1e-9
    )


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_global_suns_shadow_everything(tmp_path, encoding):
    path = write_scene(
        tmp_path,
        encoding,
        sun("sunW", DOWN, **{"global": "true"}),
        sun("sunE", SLANT, **{"global": "true"}),
    )
    result = sg.add_shadows(sg.load(path))
    areas = shadow_areas(result)
    expected = {
        ("sunW", "floorW"): 16,
        ("sunW", "floorE"): 16,
        ("sunE", "floorW"): 21,
        ("sunE", "floorE"): 21,
        ("sunW", "surfaces"): 8,
        ("sunE", "surfaces"): 10,
    }
    assert sorted(areas) == sorted(expected)
    for key, area in expected.items():
        assert areas[key] == pytest.approx(area, rel=1e-6), key
    # both suns light each floor: sunW's shadow takes 0.5 of 0.5 + 0.5 cos 45
    share = 0.5 / (0.5 + 0.5 * math.sqrt(0.5))
    dark = 1 - shadow(result, "shadow_sunW_floorW").material.transparency
    assert dark == pytest.approx(share, rel=1e-9)


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_a_shape_outside_the_scope_casts_nothing_for_the_light(tmp_path, encoding):
    # X_ITE draws only the light's parent group into its shadow map
    path = write_scene(tmp_path, encoding, sun("sunW", DOWN), sun("sunE", SLANT), roof=True)
    areas = shadow_areas(sg.add_shadows(sg.load(path)))
    assert areas["sunW", "floorW"] == pytest.approx(16, rel=1e-6)
    path = write_scene(
        tmp_path, encoding, sun("sunW", DOWN, **{"global": "true"}), sun("sunE", SLANT), roof=True
    )
    areas = shadow_areas(sg.add_shadows(sg.load(path)))
    assert areas["sunW", "floorW"] == pytest.approx(16 + 4, rel=1e-6)  # the roof's 2 x 2 too


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_a_shape_outside_the_scope_receives_nothing_from_the_light(tmp_path, encoding):
    scoped = write_scene(tmp_path, encoding, sun("sunW", DOWN), sun("sunE", SLANT), ring=True)
    both = sun("sunW", DOWN, **{"global": "true"})
    (tmp_path / "global").mkdir()
    unscoped = write_scene(tmp_path / "global", encoding, both, sun("sunE", SLANT), ring=True)
    # the ring named as a planar receiver
    areas = shadow_areas(sg.add_shadows(sg.load(scoped), receivers=["floorW", "ring"]))
    assert ("sunW", "ring") not in areas and areas["sunW", "floorW"] == pytest.approx(16)
    areas = shadow_areas(sg.add_shadows(sg.load(unscoped), receivers=["floorW", "ring"]))
    assert areas["sunW", "ring"] == pytest.approx(1, rel=1e-6)
    # the ring's top among every other surface: the slab's top only, or with the ring's
    areas = shadow_areas(sg.add_shadows(sg.load(scoped)))
    assert areas["sunW", "surfaces"] == pytest.approx(4, rel=1e-6)
    areas = shadow_areas(sg.add_shadows(sg.load(unscoped)))
    assert areas["sunW", "surfaces"] == pytest.approx(4 + 4 + 1, rel=1e-6)


@pytest.mark.parametrize("global_", ["false", "true"])
def test_the_added_ground_lies_in_the_scoped_lights_group(tmp_path, global_):
    # the group is turned and scaled: the ground is written in its coordinates
    path = tmp_path / "ground.x3d"
    path.write_text(
        '<X3D version="3.0"><Scene><Transform DEF="lot" rotation="0 1 0 0.5" scale="2 2 2">'
        f'<DirectionalLight DEF="sun" direction="0 -1 0" global="{global_}"/>'
        '<Transform translation="0 2 0"><Shape DEF="box"><Box/></Shape></Transform>'
        "</Transform></Scene></X3D>"
    )
    result = sg.add_shadows(sg.load(path))
    (ground,) = result.shapes_with_role("ground")
    # either way the sun shadows the ground: the 4 x 4 box (scaled by 2)
    assert shadow_areas(result) == {("sun", "ground"): pytest.approx(16, rel=1e-6)}
    out = tmp_path / "out.x3d"
    sg.save(result, out)
    tree = etree.parse(str(out))
    (written,) = tree.xpath("//Shape[@DEF='ground']")
    parents = [e.get("DEF") for e in written.iterancestors() if e.get("DEF")]
    if global_ == "false":  # in the sun's group, lit by it in every browser
        assert parents[1] == "lot" and ground.placement is not None
    else:  # a global sun lights it anywhere: at the top
        assert "lot" not in parents and ground.placement is None
    back = sg.load(out)
    (again,) = back.shapes_with_role("ground")
    np.testing.assert_allclose(again.world_vertices, ground.world_vertices, atol=1e-12)
    assert shadow_areas(sg.add_shadows(back)) == shadow_areas(result)  # converted again


def test_the_added_ground_stays_at_the_top_under_lights_of_two_groups(tmp_path):
    path = write_scene(tmp_path, "xml", sun("sunW", DOWN), sun("sunE", DOWN))
    tree = etree.parse(str(path))  # without the floors: the ground plane receives
    for floor in tree.xpath("//Shape[starts-with(@DEF, 'floor')]"):
        floor.getparent().remove(floor)
    tree.write(str(path))
    result = sg.add_shadows(sg.load(path))
    (ground,) = result.shapes_with_role("ground")
    assert ground.placement is None and ground.scopes == frozenset()
    assert not [k for k in shadow_areas(result) if k[1] == "ground"]  # neither sun lights it


def test_darkness_counts_each_triangles_own_lights():
    # two triangles of equal area straight under both lights; the bright one
    # lights only the first: the dim one's shadow takes 0.25 / (0.25 + 0.75)
    # of the first's light and all of the second's
    vertices = [[0, 0, 0], [1, 0, 0], [0, 0, 1], [5, 0, 0], [6, 0, 0], [5, 0, 1]]
    faces = [[0, 2, 1], [3, 5, 4]]
    dim = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), intensity=0.25)
    bright = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), intensity=0.75, global_=False, scope=7)
    lights = [dim, bright]
    both = shadow_darkness(dim, vertices, faces, lights, scopes=[frozenset({7}), frozenset()])
    assert both == pytest.approx((0.25 + 1.0) / 2, rel=1e-12)
    assert shadow_darkness(dim, vertices, faces, lights) == pytest.approx(0.25, rel=1e-12)
    assert shadow_darkness(dim, vertices, faces, lights, scopes=frozenset()) == pytest.approx(1)


def _brute_area(light, boxes, floor_low, floor_high, n=400):
    """The area of the floor (y = 0, x and z from ``floor_low`` to
    ``floor_high``) whose segment to ``light`` meets one of the boxes
    ((low, high) corners), sampled at the centres of an n x n grid."""
    steps = (np.arange(n) + 0.5) / n
    x = floor_low[0] + (floor_high[0] - floor_low[0]) * steps
    z = floor_low[1] + (floor_high[1] - floor_low[1]) * steps
    points = np.stack(np.meshgrid(x, [0.0], z, indexing="ij"), axis=-1).reshape(-1, 3)
    way = np.asarray(light, dtype=float) - points
    hit = np.zeros(len(points), dtype=bool)
    for low, high in boxes:
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (np.asarray(low) - points) / way
            b = (np.asarray(high) - points) / way
        enter = np.nanmax(np.minimum(a, b), axis=1)
        leave = np.nanmin(np.maximum(a, b), axis=1)
        hit |= (enter <= leave) & (leave >= 0) & (enter <= 1)
    cell = (floor_high[0] - floor_low[0]) * (floor_high[1] - floor_low[1]) / n**2
    return float(hit.sum()) * cell


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_point_light_is_global_by_default(tmp_path, encoding):
    lamp = ("PointLight", {"DEF": "lamp", "location": "-10 10 0"})  # inside the west group
    path = write_scene(tmp_path, encoding, lamp, sun("sunE", SLANT))
    scene = sg.load(path)
    assert [light.global_ for light in scene.lights] == [True, False]
    areas = shadow_areas(sg.add_shadows(scene))
    position = (-10.0, 10.0, 0.0)
    for side, x in (("W", -10.0), ("E", 10.0)):
        boxes = [((x - 2, 0, -2), (x + 2, 0.5, 2)), ((x - 1, 1, -1), (x + 1, 3, 1))]
        expected = _brute_area(position, boxes, (x - 5, -5), (x + 5, 5))
        assert areas["lamp", f"floor{side}"] == pytest.approx(expected, rel=0.01), side
    assert ("sunE", "floorW") not in areas and areas["sunE", "floorE"] == pytest.approx(21)


def test_scopes_follow_use_and_the_top_of_the_file(tmp_path):
    path = tmp_path / "use.x3d"
    path.write_text(
        '<X3D version="4.0"><Scene>'
        '<DirectionalLight DEF="top"/>'
        '<Group DEF="lit"><DirectionalLight DEF="inner"/>'
        '<Shape DEF="ball"><Sphere/></Shape></Group>'
        '<Transform translation="5 0 0"><Group USE="lit"/></Transform>'
        '<Shape DEF="alone"><Box/></Shape>'
        "</Scene></X3D>"
    )
    scene = sg.load(path)
    top, first, second = scene.lights
    assert top.scope is None  # at the top of the scene: it lights everything
    assert first.scope is not None and second.scope is not None and first.scope != second.scope
    ball, copy, alone = scene.shapes
    assert ball.scopes == {first.scope} and copy.scopes == {second.scope}
    assert alone.scopes == frozenset()


def test_nested_scopes(tmp_path):
    path = tmp_path / "nested.x3d"
    path.write_text(
        '<X3D version="4.0"><Scene><Group><DirectionalLight DEF="outer"/>'
        '<Shape DEF="high"><Box/></Shape>'
        '<Transform><Group><DirectionalLight DEF="inner"/><Shape DEF="deep"><Box/></Shape>'
        "</Group></Transform></Group></Scene></X3D>"
    )
    scene = sg.load(path)
    outer, inner = scene.lights
    high, deep = scene.shapes
    assert len({outer.scope, inner.scope, None}) == 3
    assert high.scopes == {outer.scope} and deep.scopes == {outer.scope, inner.scope}


def test_an_inlined_files_top_light_lights_the_inline(tmp_path):
    (tmp_path / "part.x3d").write_text(
        '<X3D version="4.0"><Scene><DirectionalLight DEF="own"/>'
        '<Shape DEF="inside"><Box/></Shape></Scene></X3D>'
    )
    path = tmp_path / "main.x3d"
    path.write_text(
        '<X3D version="4.0"><Scene><Inline url="part.x3d"/>'
        '<Shape DEF="outside"><Sphere/></Shape></Scene></X3D>'
    )
    scene = sg.load(path)
    (light,) = scene.lights
    inside, outside = scene.shapes
    assert light.scope is not None
    assert light.scope in inside.scopes and light.scope not in outside.scopes


def test_x3d_writer_keeps_global_and_gltf_lights_come_back_global(tmp_path):
    path = write_scene(tmp_path, "xml", sun("sunW", DOWN), sun("sunE", SLANT, **{"global": "true"}))
    out = tmp_path / "out.x3d"
    sg.save(sg.add_shadows(sg.load(path)), out)
    written = {
        e.get("DEF"): e.get("global") for e in etree.parse(str(out)).iter("DirectionalLight")
    }
    assert written == {"sunW": None, "sunE": "true"}  # as the author wrote them
    # glTF's lights have no scope: a scene of them, written as X3D, is lit everywhere
    floor = sg.Shape([[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]], [[0, 1, 2], [0, 2, 3]])
    light = sg.SceneLight(sg.DirectionalLight([0, -1, 0]), name="sun")
    sg.save(sg.Scene([floor], [light]), tmp_path / "plain.glb")
    back = sg.load(tmp_path / "plain.glb")
    assert [(each.global_, each.scope) for each in back.lights] == [(True, None)]
    sg.save(back, tmp_path / "plain.x3d")
    (element,) = etree.parse(str(tmp_path / "plain.x3d")).iter("DirectionalLight")
    assert element.get("global") == "true"


def test_shadow_volumes_of_a_scoped_light_are_its_groups_shapes_only(tmp_path):
    path = write_scene(tmp_path, "xml", sun("sunW", DOWN), sun("sunE", SLANT, **{"global": "true"}))
    result = sg.add_shadows(sg.load(path), method="volume")
    names = sorted(shape.name for shape in result.shapes_with_role("volume"))
    west = ["boxW", "floorW", "slabW"]
    east = ["boxE", "floorE", "slabE"]
    expected = sorted([f"volume_sunW_{name}" for name in west])
    expected += sorted(f"volume_sunE_{name}" for name in east + west)
    assert names == sorted(expected)
