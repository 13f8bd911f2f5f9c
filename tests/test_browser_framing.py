"""A scene converted into another folder opens framed in X_ITE, its Inline and
texture found: the input has no Viewpoint, a textured ground and an inlined
box in a subfolder; the output goes to ``out/deeper/``, and the page is served
from the folder above both (as a web site holding both would be).

The checks are on the picture: the texture's red covers the ground and the
inlined box's blue is there (neither shows unless its rewritten url names
the file), and no red touches the picture's edge (the ground is framed
whole, not cut by the window or seen from inside)."""

from __future__ import annotations

import struct
import zlib

import numpy as np
from needs import need
from test_browser import screenshot

SCENE = """<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Immersive" version="4.0">
  <Scene>
    <DirectionalLight direction="0.3 -1 0.2"/>
    <Shape DEF="ground">
      <Appearance>
        <Material diffuseColor="1 1 1"/>
        <ImageTexture url='"textures/red.png"'/>
      </Appearance>
      <IndexedFaceSet coordIndex="0 1 2 3 -1" solid="false">
        <Coordinate point="-6 0 -6, -6 0 6, 6 0 6, 6 0 -6"/>
      </IndexedFaceSet>
    </Shape>
    <Transform translation="0 1 0"><Inline url='"parts/box.x3d"'/></Transform>
  </Scene>
</X3D>
"""
BOX = """<X3D profile="Interchange" version="4.0"><Scene><Shape DEF="box">
  <Appearance><Material diffuseColor="0 0 1" emissiveColor="0 0 0.6"/></Appearance>
  <Box size="2 2 2"/></Shape></Scene></X3D>"""


def red_png() -> bytes:
    """A 1 x 1 pure red RGB PNG, chunk by chunk."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    header = struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)
    pixels = zlib.compress(b"\x00\xff\x00\x00")
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", pixels) + chunk(b"IEND", b"")
    )


def test_x_ite_opens_a_scene_converted_elsewhere_framed_with_its_links(tmp_path):
    from cli.main import main

    source = tmp_path / "in" / "scene.x3d"
    for name, data in [
        ("scene.x3d", SCENE.encode()),
        ("parts/box.x3d", BOX.encode()),
        ("textures/red.png", red_png()),
    ]:
        (source.parent / name).parent.mkdir(parents=True, exist_ok=True)
        (source.parent / name).write_bytes(data)
    target = tmp_path / "out" / "deeper" / "scene.x3d"
    assert main(["convert", str(source), str(target)]) == 0
    need("x_ite")
    image = screenshot(tmp_path, need("chromium"), "out/deeper/scene.x3d").astype(int)

    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    reddish = (red > 2 * green + 30) & (red > 2 * blue + 30)
    bluish = (blue > 2 * red + 30) & (blue > 2 * green + 30)
    assert reddish.mean() > 0.1, reddish.mean()  # the texture was found
    assert bluish.mean() > 0.005, bluish.mean()  # the Inline was found
    edge = np.concatenate([reddish[0], reddish[-1], reddish[:, 0], reddish[:, -1]])
    assert not edge.any()  # the whole ground is in the picture
