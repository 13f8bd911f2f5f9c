"""The X3D ``shadowgeo convert`` writes shows its baked shadow in a real X3D browser.

X_ITE (the npm package ``x_ite``) runs in headless Debian Chromium with
software WebGL (SwiftShader). Everything is served from a thread on
127.0.0.1; Chromium is told not to touch the network otherwise. The page holds
its ``load`` event (which Chromium's ``--screenshot`` waits for) on an image
the server answers only once X_ITE has loaded the scene and drawn a few
frames, so the screenshot is of the rendered scene, not of a blank canvas.

The check: looking straight down with an OrthoViewpoint whose field of view we
set (in the input scene; the converter keeps it), the pixels inside the shadow
polygon are dark and those around it are lit. The polygon is an independent
reference: the convex hull of the box's corners projected from the light by
similar triangles.
"""

from __future__ import annotations

import http.server
import os
import subprocess
import threading
from pathlib import Path

import numpy as np
import shapely
from needs import need
from reference import ray_plane

ROOT = Path(__file__).resolve().parents[1]
X_ITE = ROOT / "tests" / "node" / "node_modules" / "x_ite" / "dist"
LIGHT = np.array([3.0, 6.0, 2.0])
BOX = np.array([[-0.5, 1.5, -0.5], [0.5, 2.5, 0.5]])
HALF_VIEW = 10.0  # the OrthoViewpoint shows x, z in [-10, 10]
PIXELS = 400
LOAD_TIMEOUT = 45.0  # seconds for X_ITE to load and draw, in software

# The input scene: ground, a red box (an X3D Box, tessellated by the reader), a lamp.
# shadows="false": X_ITE must show the shadow shadowgeo baked, not one of its own.
SCENE = f"""<?xml version="1.0" encoding="UTF-8"?>
<X3D profile="Interchange" version="4.0">
  <Scene>
    <NavigationInfo headlight="true" type='"NONE"'/>
    <OrthoViewpoint position="0 50 0" orientation="1 0 0 -1.5707963267948966"
                    fieldOfView="{-HALF_VIEW} {-HALF_VIEW} {HALF_VIEW} {HALF_VIEW}"/>
    <PointLight DEF="lamp" location="{LIGHT[0]} {LIGHT[1]} {LIGHT[2]}" shadows="false"/>
    <Shape DEF="ground">
      <Appearance><Material diffuseColor="0.8 0.8 0.8"/></Appearance>
      <IndexedFaceSet coordIndex="0 1 2 3 -1" solid="false">
        <Coordinate point="-15 0 -15, -15 0 15, 15 0 15, 15 0 -15"/>
      </IndexedFaceSet>
    </Shape>
    <Transform translation="{BOX.mean(axis=0)[0]} {BOX.mean(axis=0)[1]} {BOX.mean(axis=0)[2]}">
      <Shape DEF="box">
        <Appearance><Material diffuseColor="0.8 0.1 0.1"/></Appearance>
        <Box size="{BOX[1, 0] - BOX[0, 0]} {BOX[1, 1] - BOX[0, 1]} {BOX[1, 2] - BOX[0, 2]}"/>
      </Shape>
    </Transform>
  </Scene>
</X3D>
"""

PAGE = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8">
<style>html, body {{ margin: 0; overflow: hidden; background: #f0f; }}</style>
<script src="x_ite/x_ite.min.js"></script></head>
<body>
<x3d-canvas src="converted.x3d" splashScreen="false" notifications="false" contextMenu="false"
            style="display: block; width: {PIXELS}px; height: {PIXELS}px"></x3d-canvas>
<script>
  const canvas = document.querySelector("x3d-canvas");
  const report = (path, text) => fetch(path, {{method: "POST", body: text}});
  canvas.addEventListener("load", () => {{
    let frames = 0;
    const tick = () => (++frames < 10 ? requestAnimationFrame(tick) : report("/rendered", "ok"));
    requestAnimationFrame(tick);
  }});
  canvas.addEventListener("error", () => report("/rendered", "X_ITE could not load the scene"));
</script>
<img src="/ready" width="1" height="1">
</body></html>
"""


def reference_shadow():
    """shapely Polygon of the box's shadow on y = 0, in (x, z)."""
    corners = np.array([[x, y, z] for x in BOX[:, 0] for y in BOX[:, 1] for z in BOX[:, 2]])
    landed = ray_plane(corners, LIGHT, np.array([0.0, 1.0, 0.0]), 0.0)
    return shapely.MultiPoint(landed[:, [0, 2]]).convex_hull


def convert(folder: Path) -> Path:
    """``shadowgeo convert`` the input scene to ``converted.x3d``."""
    from cli.main import main

    source, target = folder / "scene.x3d", folder / "converted.x3d"
    source.write_text(SCENE)
    assert main(["convert", str(source), str(target)]) == 0
    return target


class _Server(http.server.ThreadingHTTPServer):
    daemon_threads = True

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.rendered = threading.Event()
        self.status = "X_ITE did not report the scene loaded"
        super().__init__(("127.0.0.1", 0), _Handler)


class _Handler(http.server.SimpleHTTPRequestHandler):
    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, directory=str(args[2].folder), **kwargs)

    def do_GET(self) -> None:
        if self.path == "/ready":  # held until the page reports; holds the load event
            self.server.rendered.wait(LOAD_TIMEOUT)
            self.send_response(204)
            self.end_headers()
            return
        super().do_GET()

    def do_POST(self) -> None:
        length = int(self.headers.get("Content-Length") or 0)
        text = self.rfile.read(length).decode("utf-8", "replace")
        if self.path == "/rendered":
            self.server.status = text
            self.server.rendered.set()
        self.send_response(204)
        self.end_headers()

    def log_message(self, *args) -> None:  # keep the test output quiet
        pass


def screenshot(folder: Path, browser: str) -> np.ndarray:
    from PIL import Image

    server = _Server(folder)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    shot = folder / "shot.png"
    command = [
        browser,
        "--headless",
        "--no-sandbox",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-extensions",
        "--disable-default-apps",
        "--no-first-run",
        "--disable-quic",
        "--disable-dev-shm-usage",  # containers often have a tiny /dev/shm
        "--mute-audio",
        "--hide-scrollbars",
        f"--user-data-dir={folder / 'profile'}",
        f"--screenshot={shot}",
        f"--window-size={PIXELS},{PIXELS}",
        f"--timeout={int(LOAD_TIMEOUT * 1000) + 5000}",
        f"http://127.0.0.1:{server.server_address[1]}/index.html",
    ]
    try:
        result = subprocess.run(
            command,
            capture_output=True,
            timeout=LOAD_TIMEOUT + 60,
            env={**os.environ, "HOME": str(folder)},
            check=False,
        )
    finally:
        server.rendered.set()  # release a held /ready
        server.shutdown()
        server.server_close()
    assert server.status == "ok", server.status
    assert shot.is_file(), result.stderr.decode("utf-8", "replace")[-2000:]
    return np.asarray(Image.open(shot).convert("RGB"))


def test_x_ite_shows_the_baked_shadow(tmp_path):
    convert(tmp_path)
    (tmp_path / "index.html").write_text(PAGE)
    need("x_ite")
    (tmp_path / "x_ite").symlink_to(X_ITE, target_is_directory=True)
    image = screenshot(tmp_path, str(need("chromium")))
    assert image.shape[:2] == (PIXELS, PIXELS)

    # Pixel centres -> world (x, z): looking down -y with screen-up = -z.
    centres = (np.arange(PIXELS) + 0.5) / PIXELS * 2 * HALF_VIEW - HALF_VIEW
    x, z = np.meshgrid(centres, centres)  # rows run along +z, columns along +x
    points = shapely.points(x.ravel(), z.ravel())
    shadow = reference_shadow()
    box = shapely.box(*BOX[0, [0, 2]], *BOX[1, [0, 2]])
    margin = 2.5 * 2 * HALF_VIEW / PIXELS  # a few pixels of antialiasing
    inside = shapely.contains(shadow.buffer(-margin).difference(box.buffer(margin)), points)
    outside = ~shapely.intersects(shadow.union(box).buffer(margin), points)
    brightness = image.astype(float).mean(axis=2).ravel()

    assert inside.sum() > 1000
    assert np.mean(brightness[inside] < 40) > 0.99, np.percentile(brightness[inside], 99)
    assert np.mean(brightness[outside] > 80) > 0.99, np.percentile(brightness[outside], 1)
    # The dark region has the reference's area (in pixels), to within its outline's width.
    dark = (brightness < 40).sum() * (2 * HALF_VIEW / PIXELS) ** 2
    expected = shadow.difference(box).area
    assert abs(dark - expected) < shadow.length * 3 * margin, (dark, expected)
