"""Relative urls rewritten for the output's folder: a scene written to another
folder still names the files its input named (checked by resolving each url
from the output's folder, and by reading the output back); remote urls, lone
fragments and a document written in its own folder are left as they were."""

from __future__ import annotations

import struct
import zlib

import pytest

import shadowgeo as sg
from shadowgeo.io.x3d import parse as x3d_parse

SCENE = """<X3D profile="Immersive" version="4.0"><head/><Scene>
  <Viewpoint DEF="vp" position="0 2 20"/>
  <ExternProtoDeclare name="Lamp" url='"protos.x3d#Lamp"'/>
  <Inline url='"house.x3d"'/>
  <Transform translation="0 0 5"><Inline url='"parts/shed.x3dv"'/></Transform>
  <Inline url='"gone.x3d" "parts/shed.x3dv"'/>
  <Shape DEF="crate"><Appearance>
    <ImageTexture url='"tex/brick.png" "https://example.org/brick.png" "my%20skin.png"'/>
  </Appearance><Box/></Shape>
  <Script DEF="logic" url='"logic.js" "ecmascript: function initialize() {}"'/>
  <Anchor url='"#vp"'><Shape><Sphere/></Shape></Anchor>
  <Background frontUrl='"sky/front.png" "urn:web3d:sky"'/>
  <ProtoDeclare name="Decal"><ProtoInterface>
    <field name="url" type="MFString" accessType="inputOutput" value='"tex/brick.png"'/>
  </ProtoInterface><ProtoBody><ImageTexture><IS><connect nodeField="url" protoField="url"/></IS>
  </ImageTexture></ProtoBody></ProtoDeclare>
  <ProtoInstance name="Decal" DEF="decal"><fieldValue name="url" value='"sky/front.png"'/>
  </ProtoInstance>
</Scene></X3D>
"""
HOUSE = '<X3D version="4.0"><Scene><Shape DEF="house"><Box size="4 3 4"/></Shape></Scene></X3D>'
SHED = "#X3D V4.0 utf8\nDEF shed Shape { geometry Cone { } }\n"


def png() -> bytes:
    """A 1 x 1 grey PNG, chunk by chunk."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(b"\x00\x80"))
        + chunk(b"IEND", b"")
    )


@pytest.fixture
def source(tmp_path):
    folder = tmp_path / "in"
    for name, text in [
        ("scene.x3d", SCENE),
        ("house.x3d", HOUSE),
        ("parts/shed.x3dv", SHED),
        ("protos.x3d", HOUSE),
        ("logic.js", "function initialize() {}\n"),
    ]:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    for name in ("tex/brick.png", "my skin.png", "sky/front.png"):
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(png())
    return folder / "scene.x3d"


def urls(path) -> dict[str, list[str]]:
    """Each node's (DEF or tag) url field values, as the X3D reader parses them;
    a prototype's as ``field url`` and ``fieldValue url``."""
    found: dict[str, list[str]] = {}
    for element in x3d_parse.parse(path, []).getroot().iter():
        if element.tag in ("field", "fieldValue") and element.get("name") == "url":
            found.setdefault(f"{element.tag} url", []).append(element.get("value"))
            continue
        for name, value in element.items():
            if name == "url" or name.endswith("Url"):
                key = element.get("DEF") or element.get("name") or element.tag
                found.setdefault(key, []).append(value)
    return found


@pytest.mark.parametrize("suffix", [".x3d", ".x3dv", ".x3dj"])
def test_urls_name_the_same_files_from_another_folder(tmp_path, source, suffix):
    scene = sg.load(source)
    out = tmp_path / "out" / "deeper" / f"scene{suffix}"
    out.parent.mkdir(parents=True)
    sg.save(scene, out)
    written = urls(out)
    # Each rewritten url, resolved from the output's folder, is the input's file.
    texture = x3d_parse.parse(out, []).getroot().find(".//ImageTexture")
    first, remote, encoded = sg.io.x3d.fields.parse(texture.get("url"), "MFString")
    assert (out.parent / first).resolve() == (source.parent / "tex/brick.png").resolve()
    assert (out.parent / first).read_bytes() == png()
    assert first == "../../in/tex/brick.png"
    assert remote == "https://example.org/brick.png"  # remote: untouched
    assert encoded == "../../in/my%20skin.png"  # %-encoded as it was
    assert written["Lamp"] == ['"../../in/protos.x3d#Lamp"']  # the fragment kept
    assert written["logic"] == ['"../../in/logic.js" "ecmascript: function initialize() {}"']
    assert written["Anchor"] == ['"#vp"']
    assert written["Background"] == ['"../../in/sky/front.png" "urn:web3d:sky"']
    assert written["field url"] == ['"../../in/tex/brick.png"']
    assert written["fieldValue url"] == ['"../../in/sky/front.png"']
    assert written["Inline"] == [
        '"../../in/house.x3d"',
        '"../../in/parts/shed.x3dv"',
        '"gone.x3d" "../../in/parts/shed.x3dv"',
    ]
    # One note for the url that names no file, with file, line and url; it is kept.
    (note,) = [note for note in scene.warnings if "names no file" in note]
    assert note.startswith("scene.x3d line 6, Inline: url 'gone.x3d' names no file")
    # Read back, trusting the folder above both: the inlined shapes are there.
    back = sg.load(out, root=tmp_path)
    names = sorted(shape.name for shape in back.shapes if shape.name)
    assert names == ["crate", "house", "shed", "shed"]
    assert not [note for note in back.warnings if "not found" in note]
    # By default the reader still opens nothing outside the output's folder.
    refused = [note for note in sg.load(out).warnings if "Inline skipped" in note]
    assert len(refused) == 3 and all("leaves the scene's folder" in n for n in refused)


def test_the_same_folder_keeps_every_url_as_it_was(tmp_path, source):
    out = source.parent / "copy.x3d"
    scene = sg.load(source)
    sg.save(scene, out)
    assert urls(out) == urls(source)
    assert not [note for note in scene.warnings if "names no file" in note]


def test_a_parent_folder_gets_paths_down_into_the_input(tmp_path, source):
    out = tmp_path / "scene.x3dv"
    sg.save(sg.load(source), out)
    assert urls(out)["Inline"][0] == '"in/house.x3d"'
    # inside the output's folder: the reader follows it with no option
    assert "house" in {shape.name for shape in sg.load(out).shapes}


def test_a_root_must_hold_the_scene(tmp_path, source):
    with pytest.raises(sg.SceneError, match="not inside root"):
        sg.load(source, root=tmp_path / "elsewhere")


def test_info_root_lists_the_inlined_shapes(tmp_path, source, capsys):
    from cli.main import main

    out = tmp_path / "out" / "scene.x3d"
    assert main(["convert", str(source), str(out)]) == 0
    capsys.readouterr()
    assert main(["info", str(out), "--root", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "Inline skipped" not in printed and " house " in printed
    assert main(["info", str(out)]) == 0
    assert "leaves the scene's folder" in capsys.readouterr().out
