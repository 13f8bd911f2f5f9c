"""Long number fields of an X3D document, held as bytes beside the lxml tree
from reading to writing: the same scene, the same files, in every encoding."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
from lxml import etree

import shadowgeo as sg
from shadowgeo.io.x3d import numbers as x3d_numbers

SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False)


def _grid(rows: int = 120) -> tuple[np.ndarray, np.ndarray, str, str]:
    """A bumpy grid whose point text is more than 64 KB; its points, faces,
    and the point and index text as written in the file."""
    rng = np.random.default_rng(8)
    x, z = np.meshgrid(np.arange(rows, dtype=float), np.arange(rows, dtype=float))
    points = np.column_stack([x.ravel(), rng.normal(size=rows * rows), z.ravel()])
    corner = (np.arange(rows - 1)[:, None] * rows + np.arange(rows - 1)).ravel()
    faces = np.concatenate(
        [
            np.column_stack([corner, corner + rows, corner + 1]),
            np.column_stack([corner + 1, corner + rows, corner + rows + 1]),
        ]
    )
    point_text = ", ".join(" ".join(map(repr, row)) for row in points.tolist())
    index_text = " ".join(map(str, faces.ravel().tolist()))
    assert len(point_text) > x3d_numbers.LONG_VALUE
    return points, faces, point_text, index_text


def _source(tmp_path, point_text, index_text):
    # The grid's Coordinate is DEF'd in one shape and USE'd in another
    # (moved up): the reader reads it twice. A prototype's body holds a long
    # number field too (read only through copies of it), and a WorldInfo a
    # long text.
    path = tmp_path / "grid.x3d"
    path.write_text(
        '<X3D version="4.0"><Scene>\n'
        '<ProtoDeclare name="Strip"><ProtoBody><Shape><IndexedTriangleSet index="0 1 2">'
        f'<Coordinate point="{point_text}"/></IndexedTriangleSet></Shape></ProtoBody>'
        "</ProtoDeclare>\n"
        f'<WorldInfo title="long" info="{"words, not numbers " * 5000}"/>\n'
        f'<Shape DEF="ground"><IndexedTriangleSet index="{index_text}">'
        f'<Coordinate DEF="grid" point="{point_text}"/></IndexedTriangleSet></Shape>\n'
        '<Transform translation="0 10 0"><Shape DEF="roof">'
        f'<IndexedTriangleSet index="{index_text}"><Coordinate USE="grid"/>'
        "</IndexedTriangleSet></Shape></Transform>\n"
        '<ProtoInstance name="Strip" DEF="strip"/>\n'
        '<DirectionalLight direction="0.2 -1 0.1" shadows="true"/>\n'
        "</Scene></X3D>"
    )
    return path


def test_long_numbers_are_held_as_bytes_and_read_again_through_a_use(tmp_path):
    points, faces, point_text, index_text = _grid()
    path = _source(tmp_path, point_text, index_text)
    scene = sg.load(path)
    shapes = {shape.name: shape for shape in scene.shapes}
    assert np.array_equal(shapes["ground"].world_vertices, points)
    assert np.array_equal(shapes["roof"].world_vertices, points + [0.0, 10.0, 0.0])
    assert np.array_equal(shapes["roof"].faces, faces)
    # In the tree, the grid's point and the shapes' index are placeholders;
    # the prototype's body and the WorldInfo keep their text.
    held = [
        value
        for element in scene.document.iter(etree.Element)
        for value in element.attrib.values()
        if value.startswith("shadowgeo-numbers-")
    ]
    assert len(held) == 3 and len(scene.numbers.texts) == 3
    body = scene.document.find(".//ProtoBody//Coordinate")
    assert body.get("point") == point_text
    assert scene.document.find(".//WorldInfo").get("info").startswith("words, not numbers")
    # the document with its numbers is the file as parsed
    fresh = etree.parse(str(path), SAFE)
    filled = scene.numbers.filled_copy(scene.document)
    assert etree.tostring(filled) == etree.tostring(fresh)


@pytest.mark.parametrize("suffix", [".x3d", ".x3dz", ".x3dv", ".x3dj", ".wrl"])
def test_held_numbers_are_written_in_every_encoding(tmp_path, monkeypatch, suffix):
    points, faces, point_text, index_text = _grid()
    path = _source(tmp_path, point_text, index_text)
    scene = sg.add_shadows(sg.load(path), surfaces=False)
    target = tmp_path / f"out{suffix}"
    sg.save(scene, target)
    data = target.read_bytes()
    if suffix == ".x3dz":
        data = gzip.decompress(data)
    assert b"shadowgeo-numbers" not in data
    back = {shape.name: shape for shape in sg.load(target).shapes}
    assert np.array_equal(back["ground"].world_vertices, points)
    assert np.array_equal(back["roof"].world_vertices, points + [0.0, 10.0, 0.0])
    assert len(back) == len(scene.shapes)
    # the same file as when nothing is held (the reader's threshold out of reach)
    monkeypatch.setattr(x3d_numbers, "LONG_VALUE", 1 << 60)
    plain = sg.add_shadows(sg.load(path), surfaces=False)
    assert not plain.numbers.texts
    again = tmp_path / f"plain{suffix}"
    sg.save(plain, again)
    expected = again.read_bytes()
    if suffix == ".x3dz":
        expected = gzip.decompress(expected)
    assert data == expected


def test_only_a_placeholder_of_held_numbers_is_replaced():
    splicer = x3d_numbers.Splicer()
    root = etree.Element("Coordinate")
    text = "1 2 3, " * 20_000
    splicer.hold(root, "point", text, root)
    token = root.get("point")
    assert token.startswith("shadowgeo-numbers-") and splicer.held(token) == text
    head = token[:-9]
    # text that only looks like a placeholder is left as it is
    for other in ["1 2 3", head + "é", head + "000000001", head + "00000000x", token + " "]:
        assert splicer.held(other) == other
