"""X3D scenes drawn by X_ITE in headless Chromium: one page, one screenshot.

Used by the browser tests and ``benchmarks/bench_viewer.py``::

    from xite import Canvas, View, render

    shots = render(folder, [Canvas("a.x3d", shadows="cast"), Canvas("a.x3d", shadows="off")],
                   size=256, browser=chromium)

X_ITE (the npm package ``x_ite``, in ``tests/node/node_modules``) runs in
headless Debian Chromium with software WebGL (SwiftShader). ``folder`` is
served from a thread on 127.0.0.1 (X_ITE itself under ``x_ite/``), and every
host but 127.0.0.1 resolves to nothing, so a scene's outside url fails at once
instead of reaching the network. The canvases sit side by side in one window;
the page holds its ``load`` event (which Chromium's ``--screenshot`` waits
for) on an image the server answers only once every canvas has loaded its
scene, been set up as its :class:`Canvas` asks and drawn a few frames, so the
screenshot is of the rendered scenes, not of blank canvases.

Per canvas, after X_ITE loads the scene and before those frames, the page
sets the lights' X3D 4 ``shadows`` field (X_ITE draws shadow maps for
DirectionalLight, PointLight and SpotLight) and binds a :class:`View`; it
reports every light it reached (through the scene's root nodes and their node
fields, PROTO instances' own fields included, Inline scenes not) and which
Viewpoint was bound, so a caller can check the picture is what it claims.
"""

from __future__ import annotations

import http.server
import json
import os
import subprocess
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
X_ITE = ROOT / "tests" / "node" / "node_modules" / "x_ite" / "dist"
# Frames X_ITE draws after the set-up before the page reports: the first
# frames after a change render the shadow maps and settle the headlight.
FRAMES = 8
# Canvases smaller than this are not drawn reliably in headless Chromium (at
# 128 pixels X_ITE never reported a frame): render() refuses them.
MIN_SIZE = 256


@dataclass(frozen=True)
class View:
    """A Viewpoint the page adds to the scene's root and binds, at once (no
    transition): world ``position``, ``orientation`` (axis, angle in
    radians) and ``field_of_view`` (radians)."""

    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    field_of_view: float = 0.7853981633974483


@dataclass(frozen=True)
class Canvas:
    """One scene on the page, and how its lights are set before it is drawn.

    Parameters
    ----------
    scene : str
        The scene's url relative to the served folder.
    shadows : {"as-is", "cast", "off"}
        ``"as-is"``: the lights as the file says. ``"cast"``: the lights with
        ``shadows TRUE`` cast, and when none has it every light that is on
        (shadowgeo's rule for which lights it bakes), each with a shadow map
        of ``shadow_map_size`` pixels; the others get ``shadows FALSE``.
        ``"off"``: ``shadows FALSE`` on every light.
    view : View, optional
        Bound in place of the scene's own first Viewpoint.
    shadow_map_size : int
        X3D 4's ``shadowMapSize`` (X_ITE's default is 1024) for casting lights.
    """

    scene: str
    shadows: Literal["as-is", "cast", "off"] = "as-is"
    view: View | None = None
    shadow_map_size: int = 2048


@dataclass
class Shot:
    """What one canvas showed: ``image`` (size, size, 3) uint8, ``status``
    ("ok" or X_ITE's complaint), ``lights`` (one dict per light reached: type,
    DEF name, on, shadows as drawn) and the bound ``viewpoint`` (its
    description, position and orientation, or None)."""

    image: np.ndarray
    status: str
    lights: list[dict[str, Any]] = field(default_factory=list)
    viewpoint: dict[str, Any] | None = None


# One canvas's set-up and report, run on X_ITE's load event. It uses the X3D
# SAI (fields read and written, createNode, addRootNode) and two X_ITE
# internals: a light's shadowMapSize is set on the node (the field is
# initializeOnly, X_ITE reads it every frame), and the bound NavigationInfo's
# transitionTime is zeroed for the bind (a zero time teleports, no animation).
SCRIPT = r"""
const LIGHT = X3D.X3DConstants.X3DLightNode;
const VIEWPOINT = X3D.X3DConstants.X3DViewpointNode;
const isType = (node, type) => node.getNodeType().includes(type);

function nodes(roots) {  // every node reachable through node fields, once
  const seen = new Set(), found = [];
  const visit = (node) => {
    if (!node || seen.has(node.getValue())) return;
    seen.add(node.getValue());
    found.push(node);
    for (const definition of node.getFieldDefinitions()) {
      let value;
      try { value = node[definition.name]; } catch (error) { continue; }
      if (value === undefined || value === null) continue;  // inputOnly fields
      if (definition.dataType === X3D.X3DConstants.SFNode) visit(value);
      else if (definition.dataType === X3D.X3DConstants.MFNode)
        for (let i = 0; i < value.length; ++i) visit(value[i]);
    }
  };
  for (let i = 0; i < roots.length; ++i) visit(roots[i]);
  return found;
}

function setUp(canvas, config) {
  const browser = canvas.browser, scene = browser.currentScene;
  const all = nodes(scene.rootNodes);
  const lights = all.filter((node) => isType(node, LIGHT));
  if (config.shadows !== "as-is") {
    const authored = lights.some((light) => light.shadows);
    for (const light of lights) {
      const cast = config.shadows === "cast" && (authored ? light.shadows : light.on);
      light.shadows = cast;
      if (cast) light.getValue()._shadowMapSize = config.shadowMapSize;  // initializeOnly
    }
  }
  let bound = all.find((node) => isType(node, VIEWPOINT)) ?? null;
  if (config.view) {
    const view = scene.createNode("Viewpoint");
    view.position = new X3D.SFVec3f(...config.view.position);
    view.orientation = new X3D.SFRotation(...config.view.orientation);
    view.fieldOfView = config.view.field_of_view;
    view.description = "bound by the test page";
    scene.addRootNode(view);
    const navigation = browser.getActiveNavigationInfo();
    if (navigation) navigation._transitionTime = 0;
    view.set_bind = true;
    bound = view;
  }
  return {
    lights: lights.map((light) => ({
      type: light.getNodeTypeName(), name: light.getNodeName(), on: light.on,
      shadows: light.shadows, shadowMapSize: light.getValue()._shadowMapSize.getValue(),
    })),
    viewpoint: bound && {
      description: bound.description, position: [...bound.position],
      orientation: [...bound.orientation],
    },
  };
}

for (const [index, config] of CONFIGS.entries()) {
  const canvas = document.getElementById(`canvas${index}`);
  const report = (body) => {
    let text;
    try { text = JSON.stringify(body); }
    catch (error) { text = JSON.stringify({status: `report failed: ${error}`}); }
    fetch(`/rendered/${index}`, {method: "POST", body: text});
  };
  canvas.addEventListener("load", () => {
    let result;
    try { result = setUp(canvas, config); }
    catch (error) { report({status: `set-up failed: ${error}`}); return; }
    let frames = 0;
    const tick = () => (++frames < FRAMES ? requestAnimationFrame(tick)
                                            : report({status: "ok", ...result}));
    requestAnimationFrame(tick);
  });
  canvas.addEventListener("error", () => report({status: "X_ITE could not load the scene"}));
}
"""


def page(canvases: list[Canvas], size: int) -> str:
    """The HTML page: the canvases side by side, each ``size`` pixels square."""
    configs = [
        {
            "shadows": canvas.shadows,
            "shadowMapSize": canvas.shadow_map_size,
            "view": None if canvas.view is None else canvas.view.__dict__,
        }
        for canvas in canvases
    ]
    tags = "\n".join(
        f'<x3d-canvas id="canvas{index}" src="{canvas.scene}" splashScreen="false" '
        'notifications="false" contextMenu="false" '
        f'style="display: block; float: left; width: {size}px; height: {size}px"></x3d-canvas>'
        for index, canvas in enumerate(canvases)
    )
    script = SCRIPT.replace("CONFIGS", json.dumps(configs)).replace("FRAMES", str(FRAMES))
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8">
<style>html, body {{ margin: 0; overflow: hidden; background: #f0f; }}</style>
<script src="x_ite/x_ite.min.js"></script></head>
<body>
{tags}
<script>{script}</script>
<img src="/ready" width="1" height="1" style="position: absolute; left: 0; top: {size}px">
</body></html>
"""


class _Server(http.server.ThreadingHTTPServer):
    daemon_threads = True

    def __init__(self, folder: Path, n_canvases: int, timeout: float) -> None:
        self.folder = folder
        self.timeout = timeout
        self.reports: dict[int, dict[str, Any]] = {}
        self.lock = threading.Lock()
        self.n_canvases = n_canvases
        self.rendered = threading.Event()
        super().__init__(("127.0.0.1", 0), _Handler)


class _Handler(http.server.SimpleHTTPRequestHandler):
    server: _Server

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, directory=str(args[2].folder), **kwargs)

    def do_GET(self) -> None:
        if self.path == "/ready":  # held until every canvas reports; holds the load event
            self.server.rendered.wait(self.server.timeout)
            self.send_response(204)
            self.end_headers()
            return
        super().do_GET()

    def do_POST(self) -> None:
        length = int(self.headers.get("Content-Length") or 0)
        text = self.rfile.read(length).decode("utf-8", "replace")
        if self.path.startswith("/rendered/"):
            index = int(self.path.rsplit("/", 1)[1])
            with self.server.lock:
                self.server.reports[index] = json.loads(text)
                if len(self.server.reports) == self.server.n_canvases:
                    self.server.rendered.set()
        self.send_response(204)
        self.end_headers()

    def log_message(self, *args: Any) -> None:  # keep the output quiet
        pass


def render(
    folder: Path, canvases: list[Canvas], size: int, browser: Path | str, timeout: float = 60.0
) -> list[Shot]:
    """Draw ``canvases`` (scene urls relative to ``folder``) with X_ITE in
    headless Chromium, each ``size`` pixels square: one :class:`Shot` each.

    ``folder`` gets ``index.html``, a ``x_ite`` link to X_ITE and Chromium's
    profile. A canvas that does not report within ``timeout`` seconds, or
    whose scene X_ITE cannot load, has that as its ``status`` (and whatever
    the screenshot shows); no exception for it.
    """
    from PIL import Image

    if size < MIN_SIZE:
        raise ValueError(f"canvas size {size} is under {MIN_SIZE} pixels (see MIN_SIZE)")
    (folder / "index.html").write_text(page(canvases, size))
    link = folder / "x_ite"
    if not link.exists():
        link.symlink_to(X_ITE, target_is_directory=True)
    server = _Server(folder, len(canvases), timeout)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    shot = folder / "shot.png"
    shot.unlink(missing_ok=True)
    command = [
        str(browser),
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
        "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
        "--mute-audio",
        "--hide-scrollbars",
        "--force-device-scale-factor=1",
        f"--user-data-dir={folder / 'profile'}",
        f"--screenshot={shot}",
        f"--window-size={size * len(canvases)},{size + 2}",
        f"--timeout={int(timeout * 1000) + 5000}",
        f"http://127.0.0.1:{server.server_address[1]}/index.html",
    ]
    try:
        result = subprocess.run(
            command,
            capture_output=True,
            timeout=timeout + 60,
            env={**os.environ, "HOME": str(folder)},
            check=False,
        )
        failure = "" if shot.is_file() else result.stderr.decode("utf-8", "replace")[-2000:]
    except subprocess.TimeoutExpired:
        failure = f"Chromium did not finish within {timeout + 60:.0f} s"
    finally:
        server.rendered.set()  # release a held /ready
        server.shutdown()
        server.server_close()
    if failure:
        blank = np.zeros((size, size, 3), np.uint8)
        return [Shot(blank, f"no screenshot: {failure}") for _ in canvases]
    picture = np.asarray(Image.open(shot).convert("RGB"))
    shots = []
    for index in range(len(canvases)):
        report = server.reports.get(index, {"status": f"no report within {timeout:.0f} s"})
        image = picture[:size, index * size : (index + 1) * size].copy()
        shots.append(
            Shot(image, report["status"], report.get("lights", []), report.get("viewpoint"))
        )
    return shots
