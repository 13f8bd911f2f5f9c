"""The readers' budgets of memory (triangles) and walking (visits), checked
before the work that would pass them (issue 34 item 4; shadowgeo.limits).

Each bomb is refused before a node is walked or a geometry built: the tests
count that work, and name the node the error names. The references are
analytic counts (10 ** k copies of a 12-triangle Box, 2 n ** 2 triangles of
an n x n grid)."""

from __future__ import annotations

import base64
import json
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from needs import SHARED, absent

import shadowgeo as sg
from cli.main import main
from shadowgeo import limits
from shadowgeo.io import gltf_read
from shadowgeo.io.x3d import budget as x3d_budget
from shadowgeo.io.x3d import read as x3d_read

USE_CHAIN = SHARED / "findings" / "outsider-2" / "budget_cpu_USE_chain_under_node_limit"


@pytest.fixture
def work(monkeypatch):
    """Counts of the reader's work: node instances walked, geometry built."""
    counts = {"walked": 0, "built": 0}
    node, geometry = x3d_read._Reader.node, x3d_read.geometry

    def walked(self, *args):
        counts["walked"] += 1
        return node(self, *args)

    def built(*args):
        counts["built"] += 1
        return geometry(*args)

    monkeypatch.setattr(x3d_read._Reader, "node", walked)
    monkeypatch.setattr(x3d_read, "geometry", built)
    return counts


def x3d(path: Path, body: str) -> Path:
    path.write_text(f'<X3D version="4.0"><Scene>\n{body}\n</Scene></X3D>\n')
    return path


def use_nest(levels: int, fan_out: int = 10, bottom: str = "<Shape><Box/></Shape>") -> str:
    """Level 0 a Transform around ``bottom``; each level after it USEs the one
    before ``fan_out`` times: fan_out ** levels copies of ``bottom``, one line each."""
    lines = [f'<Transform DEF="L0">{bottom}</Transform>']
    for level in range(1, levels + 1):
        uses = f'<Transform USE="L{level - 1}"/>' * fan_out
        lines.append(f'<Transform DEF="L{level}">{uses}</Transform>')
    return "\n".join(lines)


def grid(n: int) -> str:
    """An IndexedFaceSet of n x n quads: 2 n ** 2 triangles."""
    points = " ".join(f"{i} 0 {j}" for i in range(n + 1) for j in range(n + 1))
    quads = " ".join(
        f"{i * (n + 1) + j} {i * (n + 1) + j + 1} {(i + 1) * (n + 1) + j + 1} "
        f"{(i + 1) * (n + 1) + j} -1"
        for i in range(n)
        for j in range(n)
    )
    mesh = f'<IndexedFaceSet coordIndex="{quads}"><Coordinate point="{points}"/></IndexedFaceSet>'
    return f"<Shape>{mesh}</Shape>"


# -- memory: triangles estimated before they are built --------------------------------------


def test_a_def_use_nest_ten_deep_is_refused_before_any_work_naming_the_node(tmp_path, work, capsys):
    # 10 ** 10 Boxes from 2.5 KB; level 6 alone stands for 10 ** 6 boxes,
    # 12 million triangles: the first past the 5 million of the budget
    scene = x3d(tmp_path / "nest.x3d", use_nest(10))
    assert main(["info", str(scene)]) == 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1
    assert f"{scene} line 8, Transform DEF='L6': " in error
    total = 12 * sum(10**k for k in range(11))  # every level's boxes, 1.3e11 triangles
    assert f"about {total:.2g} triangles" in error and "MAX_TRIANGLES" in error
    assert work == {"walked": 0, "built": 0}


def test_a_prototype_expansion_bomb_is_refused_naming_the_instance(tmp_path, work):
    # a 200 x 200 grid (80,000 triangles) in a prototype, instanced 100 times:
    # 8 million triangles from 1.3 MB, past the budget at the 63rd copy
    body = (
        f'<ProtoDeclare name="Big"><ProtoBody>{grid(200)}</ProtoBody></ProtoDeclare>\n'
        + '<ProtoInstance name="Big"/>\n' * 100
    )
    scene = x3d(tmp_path / "protos.x3d", body)
    with pytest.raises(sg.SceneError) as raised:
        sg.load(scene)
    first_over = limits.MAX_TRIANGLES // 80_000 + 1
    assert raised.value.node == "ProtoInstance" and raised.value.line == 2 + first_over
    assert "triangles" in str(raised.value) and "refused before it is built" in str(raised.value)
    assert work["built"] == first_over - 1  # each copy before it was built, none after


def test_prototypes_inside_prototypes_are_refused_before_their_boxes_are_built(tmp_path, work):
    # P1 holds ten P0 (a Box), P2 ten P1, ... P6: 10 ** 6 boxes in all
    declarations = [
        '<ProtoDeclare name="P0"><ProtoBody><Shape><Box/></Shape></ProtoBody></ProtoDeclare>'
    ]
    for level in range(1, 7):
        inner = f'<ProtoInstance name="P{level - 1}"/>' * 10
        declarations.append(
            f'<ProtoDeclare name="P{level}"><ProtoBody><Group>{inner}</Group></ProtoBody>'
            "</ProtoDeclare>"
        )
    scene = x3d(tmp_path / "nested.x3d", "\n".join(declarations) + '\n<ProtoInstance name="P6"/>')
    with pytest.raises(sg.SceneError, match="ProtoInstance: prototypes expand more than 10000"):
        sg.load(scene)
    assert work["built"] <= limits.MAX_PROTO_EXPANSIONS  # a copy of a Box built once at most


@pytest.mark.parametrize("n", [50, 30])
def test_a_scene_at_the_budget_is_read_and_one_triangle_over_is_refused_unbuilt(tmp_path, work, n):
    # L0 to L3 drawn where they are defined: 1 + 10 + 100 + 1000 copies of an
    # n x n grid, 1111 * 2 n ** 2 triangles exactly
    triangles = 1111 * 2 * n * n
    scene = x3d(tmp_path / "grids.x3d", use_nest(3, bottom=grid(n)))
    loaded = sg.load(scene, max_triangles=triangles)
    assert sum(shape.n_faces for shape in loaded.shapes) == triangles
    assert len(loaded.shapes) == 1111 and work["built"] == 1  # one mesh, instanced
    work.update(walked=0, built=0)
    with pytest.raises(sg.SceneError, match=f"Scene: .*more than the budget of {triangles - 1:,}"):
        sg.load(scene, max_triangles=triangles - 1)
    assert work == {"walked": 0, "built": 0}


def test_the_estimate_bounds_each_kind_of_mesh_from_above(tmp_path):
    # hand-counted triangles of each mesh node; the estimate is never below
    # them (a face of k indices makes k - 2) and exact for these
    square = '<Coordinate point="0 0 0 1 0 0 1 1 0 0 1 0"/>'
    meshes = {
        f'<IndexedFaceSet coordIndex="0 1 2 3 -1 0 1 2">{square}</IndexedFaceSet>': 3,
        f'<IndexedTriangleSet index="0 1 2 0 2 3">{square}</IndexedTriangleSet>': 2,
        f'<IndexedQuadSet index="0 1 2 3">{square}</IndexedQuadSet>': 2,
        '<TriangleSet><Coordinate point="0 0 0 1 0 0 1 1 0 0 0 1 1 0 1 1 1 1"/></TriangleSet>': 2,
        '<ElevationGrid xDimension="4" zDimension="3" height="0 0 0 0 0 0 0 0 0 0 0 0"/>': 12,
        "<Box/>": 12,
    }
    for number, (mesh, expected) in enumerate(meshes.items()):
        scene = x3d(tmp_path / f"mesh{number}.x3d", f"<Shape>{mesh}</Shape>")
        built = sum(shape.n_faces for shape in sg.load(scene).shapes)
        assert built == expected, mesh
        sg.load(scene, max_triangles=expected)
        with pytest.raises(sg.SceneError, match="refused before it is built"):
            sg.load(scene, max_triangles=expected - 1)


def test_tokens_are_counted_across_chunks(monkeypatch):
    monkeypatch.setattr(x3d_budget, "_CHUNK", 7)
    text = " 12 3,4 ,, 567890 -1\n8 " * 5
    assert x3d_budget.tokens(text) == len(text.replace(",", " ").split()) == 30


# -- walking: node instances counted before the walk -----------------------------------------


@pytest.mark.parametrize("suffix", [".x3dv", ".wrl", ".json"])
def test_the_outsider_use_chain_is_refused_before_the_walk(suffix, work, capsys):
    # outsider-2 budget_cpu_USE_chain_under_node_limit: 1.1M empty Transforms
    # (10 USEs a level, 6 levels, under MAX_NODES) took 19-36 CPU-s to walk
    repro = USE_CHAIN / f"repro{suffix}"
    if not repro.is_file():
        absent(f"the outsider-2 reproducer {repro} is missing")
    assert main(["info", str(repro)]) == 1
    error = capsys.readouterr().err
    assert "1,234,567 grouping nodes and Shapes to walk" in error  # 1 + 10 + ... + 10 ** 6
    assert "MAX_VISITS" in error and error.count("\n") == 1
    assert work == {"walked": 0, "built": 0}


def test_the_use_chain_is_refused_within_a_cpu_second_in_a_fresh_process():
    # a hang guard, not a timing: the CLI in a child held to 20 CPU-s (it
    # took 19-36 before); the refusal must come, whole, long before
    repro = USE_CHAIN / "repro.x3dv"
    if not repro.is_file():
        absent(f"the outsider-2 reproducer {repro} is missing")
    guard = "import resource, sys; resource.setrlimit(resource.RLIMIT_CPU, (20, 20)); "
    guard += "from cli.main import main; sys.exit(main(sys.argv[1:]))"
    done = subprocess.run(
        [sys.executable, "-c", guard, "info", str(repro)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path(__file__).resolve().parents[1],
    )
    assert done.returncode == 1 and "MAX_VISITS" in done.stderr


def test_a_walk_at_the_visit_budget_is_read(tmp_path, monkeypatch, work):
    # L_k drawn where it is defined holds 10 ** k copies of L0 (a Transform
    # and a Shape) and 1 + 10 + ... + 10 ** (k - 1) other Transforms:
    # 2 + 21 + 211 + 2111 = 2345 visits
    monkeypatch.setattr(limits, "MAX_VISITS", 2345)
    scene = x3d(tmp_path / "chain.x3d", use_nest(3))
    assert len(sg.load(scene).shapes) == 1111
    walked = work["walked"]
    assert walked == 2345  # the count is the walk's
    monkeypatch.setattr(limits, "MAX_VISITS", 2344)
    work.update(walked=0, built=0)
    with pytest.raises(sg.SceneError, match="Scene: .* 2,345 grouping nodes and Shapes"):
        sg.load(scene)
    assert work == {"walked": 0, "built": 0}


# -- glTF: meshes counted once for each node that uses them -----------------------------------


def square_gltf(path: Path, n_nodes: int) -> Path:
    """A glTF of one two-triangle square (4 float32 points, 6 uint16
    indices, in a data: buffer) that ``n_nodes`` nodes use."""
    points = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1)
    indices = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    data = points + indices
    document = {
        "asset": {"version": "2.0"},
        "buffers": [
            {
                "byteLength": len(data),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
            }
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 12},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 4,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 0, 1],
            },
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],  # fmt: skip
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [
            {"mesh": 0, "name": f"tile{i}", "translation": [2 * i, 0, 0]} for i in range(n_nodes)
        ],
        "scenes": [{"nodes": list(range(n_nodes))}],
        "scene": 0,
    }
    path.write_text(json.dumps(document))
    return path


def test_a_gltf_mesh_used_by_many_nodes_is_refused_before_it_is_decoded(tmp_path, monkeypatch):
    scene = square_gltf(tmp_path / "tiles.gltf", 50)
    loaded = sg.load(scene, max_triangles=100)  # 50 nodes x 2 triangles, at the budget
    assert len(loaded.shapes) == 50 and sum(s.n_faces for s in loaded.shapes) == 100

    def decoded(*args, **kwargs):
        raise AssertionError("decoded past the budget")

    monkeypatch.setattr(gltf_read, "plain_meshes", decoded)
    monkeypatch.setattr(gltf_read, "load_scene", decoded)
    with pytest.raises(sg.SceneError) as raised:
        sg.load(scene, max_triangles=99)
    assert raised.value.node == "nodes[49] 'tile49'"  # the node whose mesh passes it
    assert "about 1e+02 triangles" in str(raised.value) and "through nodes" in str(raised.value)


# -- USD: every instance of a mesh counted before its arrays are read ------------------------


def instanced_usda(path: Path, n_instances: int) -> Path:
    """A quad (one face of 4 corners: 2 triangles) under /Proto, and
    ``n_instances`` instanceable references to it: n + 1 quads drawn."""
    lines = [
        "#usda 1.0",
        'def Xform "Proto" {',
        '    def Mesh "quad" {',
        "        int[] faceVertexCounts = [4]",
        "        int[] faceVertexIndices = [0, 1, 2, 3]",
        "        point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)]",
        "    }",
        "}",
    ]
    for index in range(n_instances):
        lines.append(
            f'def Xform "copy{index}" (\n    instanceable = true\n    references = </Proto>\n) {{'
        )
        lines.append(f"    double3 xformOp:translate = ({2 * index + 2}, 0, 0)")
        lines.append('    uniform token[] xformOpOrder = ["xformOp:translate"]')
        lines.append("}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_usd_instances_past_the_budget_are_refused_before_their_arrays_are_read(
    tmp_path, monkeypatch
):
    usd_read = pytest.importorskip("shadowgeo.io.usd_read")
    scene = instanced_usda(tmp_path / "copies.usda", 30)
    loaded = sg.load(scene, max_triangles=62)  # 31 quads of 2 triangles: at the budget
    assert len(loaded.shapes) == 31 and sum(s.n_faces for s in loaded.shapes) == 62
    read = []
    original = usd_read._read_mesh

    def counted(scene, prim, *args):
        read.append(str(prim.GetPath()))
        return original(scene, prim, *args)

    monkeypatch.setattr(usd_read, "_read_mesh", counted)
    with pytest.raises(sg.SceneError) as raised:
        sg.load(scene, max_triangles=61)
    assert "copy29" in raised.value.node and "through instancing" in str(raised.value)
    assert len(read) == 30 and not any("copy29" in prim for prim in read)


def test_many_spheres_under_the_budget_are_not_refused_for_their_estimate(tmp_path):
    """A molecule of spheres fits its budget: the estimate counts a Sphere at
    the fewest triangles it makes, so only the exact count, made shape by
    shape as they are tessellated, can refuse it, and it stops at the
    budget."""
    spheres = "".join(
        f'<Transform translation="{3 * k} 0 0"><Shape><Sphere/></Shape></Transform>'
        for k in range(40)
    )
    path = tmp_path / "molecule.x3d"
    path.write_text(f'<X3D version="4.0"><Scene>{spheres}</Scene></X3D>')
    count = sum(shape.n_faces for shape in sg.load(path).shapes)
    assert count > 40 * 48  # more than the estimate counts
    assert len(sg.load(path, max_triangles=count).shapes) == 40
    with pytest.raises(sg.SceneError, match=r"molecule\.x3d line 1.*after tessellation") as error:
        sg.load(path, max_triangles=count - 1)
    assert f"{count:,} triangles" in str(error.value)


def test_the_flat_count_is_the_node_by_node_count_with_namespaces_and_declarations():
    # flat_expansion counts a subtree with no USE by lxml (its tag filter, or
    # XPath where a prototype declaration is in or above it); the node-by-node
    # expansion is the reference, in a namespace, without, and with a
    # ProtoDeclare whose body counts as its nodes only
    import copy

    from lxml import etree

    from shadowgeo.io.x3d.fields import Context

    shapes = "<Transform><Shape><Box/></Shape><Group><Shape><Sphere/></Shape></Group></Transform>"
    declared = '<ProtoDeclare name="P"><ProtoBody><Shape><Box/></Shape></ProtoBody></ProtoDeclare>'
    documents = [
        f"<Scene>{shapes}</Scene>",
        f'<Scene xmlns="http://www.web3d.org/specifications/x3d-namespace">{shapes}</Scene>',
        '<Scene xmlns:x="urn:x"><x:Transform><x:Shape><x:Box/></x:Shape></x:Transform>'
        f"{shapes}</Scene>",
        f"<Scene>{declared}{shapes}</Scene>",
    ]
    budget = x3d_budget.Expansion(10**6, 10**6, 10**6)
    for text in documents:
        root = etree.fromstring(text)
        context = Context("t.x3d", (4, 0))
        # the document, its subtrees, and a body copied out as an instance is
        copies = [copy.deepcopy(body) for body in root.iter("{*}ProtoBody")]
        for element in [root, *root.iter("{*}Transform"), *copies]:
            reference = x3d_budget.expansion(context, element, x3d_budget.Estimates(budget))
            assert x3d_budget.flat_expansion(context, element) == reference, (text, element.tag)


@pytest.mark.parametrize("kind", ["light", "prototype"])
def test_more_lights_or_prototype_instances_than_the_budget_are_refused_before_the_walk(
    tmp_path, monkeypatch, work, kind
):
    # the budget made small here; nodes inside a declaration never instanced
    # are not counted (they exist only in copies, which the walk counts)
    monkeypatch.setattr(limits, "MAX_LIGHTS", 4)
    monkeypatch.setattr(limits, "MAX_PROTO_EXPANSIONS", 4)
    node = "<PointLight/>" if kind == "light" else '<ProtoInstance name="P"/>'
    declarations = (
        '<ProtoDeclare name="P"><ProtoBody><Group/></ProtoBody></ProtoDeclare>'
        f'<ProtoDeclare name="Q"><ProtoBody><Group>{node * 3}</Group></ProtoBody></ProtoDeclare>'
    )
    scene = sg.load(x3d(tmp_path / "four.x3d", declarations + "\n".join([node] * 4)))
    assert len(scene.lights) == (4 if kind == "light" else 0)
    walked = work["walked"]
    assert walked >= 4
    over = x3d(tmp_path / "five.x3d", declarations + "\n" + "\n".join([node] * 5))
    with pytest.raises(sg.SceneError, match="refused before") as refused:
        sg.load(over)
    assert work["walked"] == walked  # not one node of it walked
    assert "five.x3d line 7" in str(refused.value)  # the fifth, on line 7
