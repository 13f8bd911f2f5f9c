"""Pictures of scenes and their shadows with pyvista (VTK).

pyvista is imported inside the functions, so ``import shadowgeo`` stays cheap
and works where VTK cannot load. Off-screen rendering needs no display: VTK
uses EGL (Mesa's software renderer on a machine without a GPU) when there is
no X server.

What is drawn:

* the scene's own shapes with their diffuse colour, Phong-shaded (smooth
  normals, sharp edges kept) or physically based (``pbr=True``);
* planar shadows dark and unlit, so they read as shadow whatever the lighting;
* shadow volumes semi-transparent blue;
* the lights: a small sphere at a point light, a cone opening along a spot
  light's axis, an arrow along a directional light's rays.

The camera is the scene's first Viewpoint (what the author framed) unless a
view is asked for; without one, the automatic view frames the geometry and
its shadows (and only the lights near them), and a directional light's arrow
is put beside the geometry, never in front of it.

VTK's own lighting casts no shadows here: every dark region in the picture is
shadow geometry that shadowgeo computed.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any, TypeAlias, TypeGuard, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError, SceneError
from .io.atomic import atomic_path
from .lights import AreaLight, DirectionalLight, DiskLight, Light, PointLight, RectLight, SpotLight
from .limits import SMALLEST_DRAWN_SIZE
from .scene.model import Scene, SceneLight, Shape, Viewpoint
from .shadow import Shadow
from .soft import SoftShadow
from .soft_surface import SoftSurfaceShadow

if TYPE_CHECKING:
    import pyvista as pv
    import trimesh

__all__ = [
    "AnyLight",
    "BACKGROUND",
    "LIGHT_COLOR",
    "Plottable",
    "SHADOW_COLOR",
    "VIEWS",
    "VOLUME_COLOR",
    "VOLUME_OPACITY",
    "no_display_reason",
    "plot",
    "scene_plotter",
    "view_angle",
]

# What plot() draws: a scene, shape, shadow (hard or soft) or mesh, or any
# nesting of lists of them.
Plottable: TypeAlias = Union[  # noqa: UP007
    Scene, Shape, Shadow, SoftShadow, SoftSurfaceShadow, "trimesh.Trimesh", Iterable["Plottable"]
]
# A light as plot() takes it: bare, or with its scene colour and intensity.
AnyLight: TypeAlias = Light | SceneLight

SHADOW_COLOR = (0.06, 0.06, 0.08)
VOLUME_COLOR = (0.25, 0.45, 0.95)
VOLUME_OPACITY = 0.3
LIGHT_COLOR = (1.0, 0.85, 0.1)
BACKGROUND = (1.0, 1.0, 1.0)

# Directions from the scene's centre to the camera, for a Y-up scene.
VIEWS = {"iso": (1.0, 0.8, 1.2), "top": (0.0, 1.0, 0.0), "front": (0.0, 0.0, 1.0)}


class _Item:
    """One mesh to draw: world vertices, faces, role and look."""

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        role: str,
        color: Sequence[float] = (0.8, 0.8, 0.8),
        opacity: float = 1.0,
        unlit: bool = False,
    ) -> None:
        self.vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        self.role = role
        self.color = tuple(float(c) for c in color)
        self.opacity = float(opacity)
        self.unlit = unlit


def _is_trimesh(thing: object) -> TypeGuard[trimesh.Trimesh]:
    """Whether ``thing`` is a ``trimesh.Trimesh`` (trimesh is not imported to
    find out: none exists before it is)."""
    module = sys.modules.get("trimesh")
    return module is not None and isinstance(thing, module.Trimesh)


def _shape_item(shape: Shape, role: str) -> _Item:
    """A shape as drawn: its role's look (``role`` other than "geometry"
    overrides its own), its material's colour and opacity."""
    shape_role = shape.role if role == "geometry" else role
    material = shape.material
    # X3D's colour is the emissive plus the lit diffuse; with no diffuse
    # (a Shape without Appearance: unlit white) it is drawn unlit
    unlit = not any(material.diffuse_color) and any(material.emissive_color)
    lit = np.clip(np.add(material.diffuse_color, material.emissive_color), 0.0, 1.0)
    # a baked shadow is drawn in the shadow colour; one that glows (a sun
    # study's map of sunlight hours, emissive) in its own colour
    dark = shape_role == "shadow" and not any(material.emissive_color)
    color = SHADOW_COLOR if dark else tuple(lit.tolist())
    opacity = VOLUME_OPACITY if shape_role == "volume" else 1.0 - material.transparency
    return _Item(shape.world_vertices, shape.faces, shape_role, color, opacity, unlit=unlit)


def _collect(
    things: Plottable | None, role: str, items: list[_Item], lights: list[AnyLight]
) -> None:
    """Flatten scenes, shapes, meshes and shadows into ``items`` and ``lights``."""
    if things is None:
        return
    if isinstance(things, Scene):
        for shape in things.shapes:
            _collect(shape, role, items, lights)
        lights.extend(things.lights)
    elif isinstance(things, Shape):
        items.append(_shape_item(things, role))
    elif isinstance(things, Shadow):
        items.append(_Item(things.mesh.vertices, things.mesh.faces, "shadow", SHADOW_COLOR))
        lights.append(things.light)
    elif isinstance(things, SoftShadow | SoftSurfaceShadow):
        # each level as dark as its share of the light hidden: the soft edge shows
        for fraction, level in things.levels:
            mesh = (level.mesh.vertices, level.mesh.faces)
            items.append(_Item(*mesh, "shadow", SHADOW_COLOR, opacity=fraction))
        lights.append(SceneLight(things.light))  # type: ignore[arg-type]  # (an area light too)
    elif _is_trimesh(things):
        color = {"shadow": SHADOW_COLOR, "volume": VOLUME_COLOR}.get(role, (0.8, 0.8, 0.8))
        opacity = VOLUME_OPACITY if role == "volume" else 1.0
        items.append(_Item(things.vertices, things.faces, role, color, opacity))
    elif isinstance(things, Iterable) and not isinstance(things, str | bytes | np.ndarray):
        for thing in things:
            _collect(thing, role, items, lights)
    else:
        raise GeometryError(
            f"cannot plot {type(things).__name__}: expected a Scene, Shape, Shadow, "
            "trimesh.Trimesh or a list of them"
        )


def _bare(light: AnyLight) -> Light:
    """The PointLight, SpotLight or DirectionalLight, unwrapped from a SceneLight."""
    return light.light if isinstance(light, SceneLight) else light


def _emitter(light: AnyLight) -> Light | AreaLight:
    """The light as its glyph shows it: a rectangle or disc light as itself."""
    return light.emitter if isinstance(light, SceneLight) else light


def _unique_lights(lights: list[AnyLight]) -> list[AnyLight]:
    """``lights`` without repeats: a scene's light and the same light carried by
    a Shadow of it are drawn and lit once (the scene's, with its colour)."""
    seen: set[tuple[object, ...]] = set()
    unique: list[AnyLight] = []
    for light in sorted(lights, key=lambda light: not isinstance(light, SceneLight)):
        geometry = _bare(light)
        # Position and direction both: two spots at one place may aim different ways.
        where = [getattr(geometry, name, ()) for name in ("position", "direction")]
        key = (type(geometry).__name__, *np.round(np.concatenate(where), 12).tolist())
        if key not in seen:
            seen.add(key)
            unique.append(light)
    return unique


def _polydata(item: _Item) -> pv.PolyData:
    import pyvista as pv

    cells = np.column_stack([np.full(len(item.faces), 3), item.faces]).ravel()
    return pv.PolyData(item.vertices, cells)


def _bounds(items: list[_Item], lights: list[AnyLight]) -> tuple[np.ndarray, float]:
    """Centre and diagonal of the drawn geometry (lights excluded unless alone)."""
    points = [item.vertices for item in items if len(item.vertices)]
    if not points:
        positions = [_bare(light) for light in lights]
        points = [np.array([light.position]) for light in positions if hasattr(light, "position")]
    if not points:
        return np.zeros(3), 1.0
    stacked = np.concatenate(points)
    low, high = stacked.min(axis=0), stacked.max(axis=0)
    return (low + high) / 2, max(float(np.linalg.norm(high - low)), SMALLEST_DRAWN_SIZE)


def _light_glyph(
    light: Light | AreaLight, center: np.ndarray, size: float, start: np.ndarray | None = None
) -> pv.PolyData:
    """A mesh marking ``light``: sphere (point), cone (spot), arrow
    (directional, from ``start`` when given), or the rectangle or disc itself."""
    import pyvista as pv

    if isinstance(light, RectLight):
        across, up = light.axes
        corners = [
            light.position + 0.5 * (i * light.width * across + j * light.height * up)
            for i, j in ((-1, -1), (1, -1), (1, 1), (-1, 1))
        ]
        return pv.PolyData(np.array(corners), np.array([4, 0, 1, 2, 3]))
    if isinstance(light, DiskLight):
        return pv.Disc(center=light.position, inner=0.0, outer=light.radius, normal=light.direction)
    if isinstance(light, SpotLight):
        height = 2.5 * size
        # vtkConeSource's tip points along ``direction``: point it back at the light.
        return pv.Cone(
            center=light.position + light.direction * height / 2,
            direction=-light.direction,
            height=height,
            radius=height * np.tan(min(light.cut_off_angle, 1.2)),
            resolution=24,
        )
    if isinstance(light, PointLight):
        return pv.Sphere(radius=size, center=light.position)
    length = 12 * size
    # Up-light of the scene and off to one side, clear of point lights above the centre.
    side = np.cross(light.direction, [0.0, 1.0, 0.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.array([1.0, 0.0, 0.0])
    side = side / np.linalg.norm(side)
    start = center - light.direction * length * 1.5 + side * length if start is None else start
    return pv.Arrow(start=start, direction=light.direction, scale=length)


def _arrow_start(
    direction: ArrayLike, length: float, camera: Any, points: np.ndarray, margin: float
) -> np.ndarray | None:
    """Where an arrow along ``direction`` starts so that, seen from ``camera``,
    it lies right of every point of ``points`` (in perspective), halfway up,
    at the depth of their middle; None when the camera is among the points."""
    position = np.array(camera.position)
    forward = np.array(camera.focal_point) - position
    forward /= np.linalg.norm(forward)
    up = np.array(camera.up) - forward * (np.array(camera.up) @ forward)
    up /= np.linalg.norm(up)
    right = np.cross(forward, up)
    relative = points - position
    depth = relative @ forward
    if np.any(depth <= 0):
        return None
    slope_x, slope_y = (relative @ right) / depth, (relative @ up) / depth
    middle = float(np.median(depth))
    arrow = np.asarray(direction) * length
    # Midpoint of the arrow at the middle depth, on the line of the points' middle height.
    mid_y = (slope_y.max() + slope_y.min()) / 2
    start = position + forward * middle + up * (mid_y * middle) - arrow / 2
    ends = np.array([start, start + arrow]) - position
    ends_depth = ends @ forward
    if np.any(ends_depth <= 0):
        return None
    needed = (slope_x.max() + margin / middle) * ends_depth - ends @ right
    beside: np.ndarray = start + right * float(needed.max())
    return beside


def _vtk_light(scene_light: AnyLight, center: np.ndarray, scale: float) -> pv.Light:
    """A pyvista light matching a shadowgeo light (or a scene light)."""
    import pyvista as pv

    light = _bare(scene_light)
    intensity = scene_light.intensity if isinstance(scene_light, SceneLight) else 1.0
    color = scene_light.color if isinstance(scene_light, SceneLight) else (1.0, 1.0, 1.0)
    if isinstance(light, DirectionalLight):
        result = pv.Light(
            position=tuple(center - light.direction * scale),
            focal_point=tuple(center),
            light_type="scene light",
        )
        result.positional = False
    else:
        aim = light.direction if isinstance(light, SpotLight) else center - light.position
        result = pv.Light(
            position=tuple(light.position),
            focal_point=tuple(light.position + aim),
            light_type="scene light",
        )
        result.positional = True
        result.cone_angle = np.degrees(light.cut_off_angle) if isinstance(light, SpotLight) else 90
    result.intensity = float(min(intensity, 1.0))
    result.diffuse_color = tuple(float(c) for c in color)  # ints would read as 0..255
    return result


def view_angle(field_of_view: float, width: int, height: int) -> float:
    """VTK's (vertical) view angle, in degrees, for an X3D ``fieldOfView``
    (radians, the smaller of the picture's two angles).

    >>> round(view_angle(math.pi / 2, 800, 600), 9), round(view_angle(math.pi / 2, 600, 800), 4)
    (90.0, 106.2602)
    """
    if width >= height:
        return math.degrees(field_of_view)
    return math.degrees(2 * math.atan(math.tan(field_of_view / 2) * height / width))


def _viewpoint_camera(
    plotter: pv.Plotter, viewpoint: Viewpoint, center: np.ndarray, scale: float
) -> None:
    """The camera of an X3D Viewpoint: its position, looking along its
    orientation's -Z with its +Y up, and its field of view."""
    position = np.asarray(viewpoint.position, dtype=np.float64)
    direction, up = viewpoint.direction, viewpoint.up
    # The focal point only matters to interaction: the scene's centre's depth.
    distance = max(float((center - position) @ direction), 1e-3 * scale)
    plotter.camera_position = [tuple(position), tuple(position + direction * distance), tuple(up)]
    width, height = plotter.window_size
    plotter.camera.view_angle = view_angle(viewpoint.field_of_view, width, height)
    plotter.renderer.ResetCameraClippingRange()


def _camera(
    plotter: pv.Plotter,
    view: str | ArrayLike | Viewpoint | None,
    center: np.ndarray,
    scale: float,
    z_up: bool,
    framed: np.ndarray,
) -> None:
    """Point the camera at ``center`` from the direction ``view`` names, or
    place it where a Viewpoint says."""
    if isinstance(view, Viewpoint):
        _viewpoint_camera(plotter, view, center, scale)
        return
    if view is None:
        view = "iso"
    if isinstance(view, str):
        if view not in VIEWS:
            raise GeometryError(f"view must be one of {sorted(VIEWS)} or (x, y, z), got {view!r}")
        direction = np.array(VIEWS[view])
        if z_up:  # Y-up directions rotated to Z-up: (x, y, z) -> (x, -z, y)
            direction = np.array([direction[0], -direction[2], direction[1]])
    else:
        direction = np.asarray(view, dtype=np.float64).reshape(3)
    norm = np.linalg.norm(direction)
    if not np.isfinite(norm) or norm == 0:
        raise GeometryError(f"view direction must be finite and non-zero, got {view!r}")
    direction = direction / norm
    up = np.array([0.0, 0.0, 1.0]) if z_up else np.array([0.0, 1.0, 0.0])
    if abs(direction @ up) > 0.999:  # looking along the up axis: screen-up is -z (or +y)
        up = np.array([0.0, 1.0, 0.0]) if z_up else np.array([0.0, 0.0, -1.0])
    plotter.camera_position = [tuple(center + direction * 3 * scale), tuple(center), tuple(up)]
    frame = np.column_stack([framed.min(axis=0), framed.max(axis=0)]).ravel()
    # pyvista's keyword-deprecation wrapper hides this signature from mypy in
    # some releases and not in others: call it untyped.
    reset_camera: Any = plotter.reset_camera
    reset_camera(bounds=frame)
    _fit(plotter, framed)


def _fit(plotter: pv.Plotter, points: np.ndarray, fill: float = 0.9) -> None:
    """Pan and zoom so ``points`` (n, 3) fill ``fill`` of the picture
    (reset_camera fits a bounding sphere, which leaves wide margins)."""
    camera = plotter.camera
    position, focal = np.array(camera.position), np.array(camera.focal_point)
    forward = (focal - position) / np.linalg.norm(focal - position)
    up = np.array(camera.up) - forward * (np.array(camera.up) @ forward)
    up /= np.linalg.norm(up)
    right = np.cross(forward, up)
    width, height = plotter.window_size
    tangent = np.tan(np.radians(camera.view_angle) / 2)
    relative = points - position
    depth = relative @ forward
    if np.any(depth <= 0):
        return
    screen_x = (relative @ right) / depth / (tangent * width / height)
    screen_y = (relative @ up) / depth / tangent
    distance = np.linalg.norm(focal - position)
    middle_x, middle_y = (
        (screen_x.max() + screen_x.min()) / 2,
        (screen_y.max() + screen_y.min()) / 2,
    )
    shift = distance * tangent * (right * middle_x * width / height + up * middle_y)
    camera.position, camera.focal_point = tuple(position + shift), tuple(focal + shift)
    half = max(np.ptp(screen_x), np.ptp(screen_y)) / 2
    if half > 0:
        camera.zoom(fill / half)  # type: ignore[no-untyped-call]


def _gather(
    scene_or_meshes: Plottable,
    shadows: Plottable | None,
    volumes: Plottable | None,
    lights: bool | Iterable[AnyLight],
) -> tuple[list[_Item], list[AnyLight]]:
    """The meshes to draw and the lights to draw them by (each light once):
    the scene's own, or ``lights`` when it is a list."""
    items: list[_Item] = []
    scene_lights: list[AnyLight] = []
    _collect(scene_or_meshes, "geometry", items, scene_lights)
    _collect(shadows, "shadow", items, scene_lights)
    _collect(volumes, "volume", items, scene_lights)
    if not isinstance(lights, bool):
        scene_lights = list(lights)
    return items, _unique_lights(scene_lights)


def _new_plotter(off_screen: bool, window_size: Sequence[int]) -> pv.Plotter:
    """An empty plotter with the background set and VTK's own lights off."""
    import pyvista as pv

    if off_screen and no_display_reason() is not None:
        # VTK would try X first and print "bad X server connection" before
        # falling back to EGL; go to EGL directly (a user's own choice stands).
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    width, height = (int(v) for v in window_size)
    plotter = pv.Plotter(off_screen=off_screen, window_size=[width, height], lighting="none")
    plotter.set_background(BACKGROUND)  # type: ignore[arg-type]
    return plotter


def _add_lights(
    plotter: pv.Plotter, scene_lights: list[AnyLight], center: np.ndarray, scale: float
) -> None:
    """Light the picture by ``scene_lights`` and a dim headlight."""
    import pyvista as pv

    for scene_light in scene_lights:
        plotter.add_light(_vtk_light(scene_light, center, scale))
    # A dim headlight keeps faces turned from every light readable; alone, it is
    # kept below full so a face seen head-on does not saturate to the white background.
    headlight = pv.Light(light_type="headlight", intensity=0.35 if scene_lights else 0.75)
    plotter.add_light(headlight)


def _add_meshes(plotter: pv.Plotter, items: list[_Item], pbr: bool) -> None:
    """Add each item with the look of its role: shadows unlit, volumes flat,
    the rest Phong-shaded (or physically based with ``pbr``)."""
    for item in items:
        if not len(item.faces):
            continue
        mesh = _polydata(item)
        if item.role == "shadow" or item.unlit:
            plotter.add_mesh(mesh, color=item.color, opacity=item.opacity, lighting=False)
        elif item.role == "volume":
            plotter.add_mesh(mesh, color=item.color, opacity=item.opacity, smooth_shading=False)
        elif pbr:
            plotter.add_mesh(
                mesh, color=item.color, opacity=item.opacity, pbr=True, metallic=0.0, roughness=0.6
            )
        else:
            plotter.add_mesh(
                mesh,
                color=item.color,
                opacity=item.opacity,
                smooth_shading=True,
                split_sharp_edges=True,
                specular=0.3,
                specular_power=20,
            )


def _framed_points(
    drawn: list[np.ndarray], glyph_lights: list[Light | AreaLight], center: np.ndarray, scale: float
) -> np.ndarray:
    """(n, 3) points the automatic camera frames: the ``drawn`` geometry and
    its shadows, and the positional lights near them (a far lamp would shrink
    the scene to a dot); not the directional arrows."""
    near = [
        np.reshape(light.position, (1, 3))
        for light in glyph_lights
        if not isinstance(light, DirectionalLight)
        and (not drawn or np.linalg.norm(light.position - center) <= scale)
    ]
    return np.concatenate(drawn + near) if drawn + near else np.zeros((1, 3))


def _add_light_glyphs(
    plotter: pv.Plotter,
    glyph_lights: list[Light | AreaLight],
    center: np.ndarray,
    scale: float,
    framed: np.ndarray,
    beside: bool,
) -> list[np.ndarray]:
    """Mark each light; a directional light's arrow goes beside the
    ``framed`` points when ``beside`` (there is geometry to go beside).
    Returns the (2, 3) ends of the arrows placed so."""
    size = 0.02 * scale
    arrows = []
    for light in glyph_lights:
        start = None
        if isinstance(light, DirectionalLight) and beside:
            start = _arrow_start(light.direction, 12 * size, plotter.camera, framed, 2 * size)
            if start is not None:
                arrows.append(np.array([start, start + light.direction * 12 * size]))
        glyph = _light_glyph(light, center, size, start)
        plotter.add_mesh(glyph, color=LIGHT_COLOR, lighting=False)
    return arrows


def scene_plotter(
    scene_or_meshes: Plottable,
    *,
    shadows: Plottable | None = None,
    volumes: Plottable | None = None,
    lights: bool | Iterable[AnyLight] = True,
    off_screen: bool = False,
    window_size: Sequence[int] = (1024, 768),
    view: str | ArrayLike | Viewpoint | None = None,
    pbr: bool = False,
) -> pv.Plotter:
    """A ``pyvista.Plotter`` holding the picture :func:`plot` draws, not yet shown.

    Parameters are those of :func:`plot`. Use it to add to the picture or to
    read the camera (``plotter.renderer``) before ``plotter.show()`` or
    ``plotter.screenshot()``.
    """
    items, scene_lights = _gather(scene_or_meshes, shadows, volumes, lights)
    z_up = isinstance(scene_or_meshes, Scene) and (scene_or_meshes.up_axis or "Y").upper() == "Z"
    plotter = _new_plotter(off_screen, window_size)
    center, scale = _bounds(items, scene_lights)
    _add_lights(plotter, scene_lights, center, scale)
    _add_meshes(plotter, items, pbr)
    glyph_lights = [_emitter(light) for light in scene_lights] if lights is not False else []
    # No depth peeling: with EGL off-screen it renders a blank picture, and a few
    # convex translucent volumes sort well enough without it.
    if view is None and isinstance(scene_or_meshes, Scene) and scene_or_meshes.viewpoints:
        view = scene_or_meshes.viewpoints[0]  # what the author framed
    drawn = [item.vertices for item in items if len(item.faces)]
    framed = _framed_points(drawn, glyph_lights, center, scale)
    _camera(plotter, view, center, scale, z_up, framed)
    arrows = _add_light_glyphs(plotter, glyph_lights, center, scale, framed, bool(drawn))
    if arrows and not isinstance(view, Viewpoint):
        _fit(plotter, np.concatenate([framed, *arrows]))  # room for the arrows beside
        plotter.renderer.ResetCameraClippingRange()
    return plotter


def plot(
    scene_or_meshes: Plottable,
    *,
    shadows: Plottable | None = None,
    volumes: Plottable | None = None,
    lights: bool | Iterable[AnyLight] = True,
    off_screen: bool = False,
    screenshot: str | os.PathLike[str] | None = None,
    window_size: Sequence[int] = (1024, 768),
    view: str | ArrayLike | Viewpoint | None = None,
    pbr: bool = False,
) -> NDArray[np.uint8] | pv.Plotter:
    """Draw a scene, its shadows and shadow volumes with pyvista.

    Parameters
    ----------
    scene_or_meshes : Scene, Shape, Shadow, trimesh.Trimesh or a list of them
        What to draw. A scene's shapes keep their roles: ``"shadow"`` shapes
        are drawn dark, ``"volume"`` shapes semi-transparent. A
        :class:`~shadowgeo.Shadow` is drawn dark and its light marked.
    shadows : Shadow, trimesh.Trimesh or a list of them, optional
        More planar shadows, drawn dark and unlit.
    volumes : trimesh.Trimesh or a list of them, optional
        Shadow volumes, drawn semi-transparent.
    lights : bool or list of lights
        Mark (and light the picture with) the scene's lights; ``False`` for
        neither, or a list of ``PointLight`` / ``SpotLight`` /
        ``DirectionalLight`` / ``SceneLight`` to use instead.
    off_screen : bool
        Render without a window and return the image.
    screenshot : path, optional
        Also write the image to this PNG file (atomically); implies off-screen.
    window_size : (width, height)
        In pixels.
    view : {"iso", "top", "front"}, (3,) array_like or Viewpoint, optional
        Where the camera looks from: a named view (relative to the scene's
        up axis), a direction from the scene's centre, or a
        :class:`~shadowgeo.Viewpoint` (its position, orientation and field of
        view). Default: the scene's first Viewpoint, else ``"iso"``.
    pbr : bool
        Physically based shading instead of Phong.

    Returns
    -------
    (height, width, 3) uint8 array
        The picture, when rendered off-screen.
    pyvista.Plotter
        Otherwise, after its interactive window is closed.

    Raises
    ------
    GeometryError
        Something that cannot be drawn, or a bad view.
    RuntimeError
        An interactive window was asked for where there is no display.
    SceneError
        ``screenshot`` cannot be written (a full disk, a folder that cannot
        be written), naming it; no file, whole or partial, is left there.

    Examples
    --------
    >>> import shadowgeo as sg, trimesh
    >>> box = trimesh.creation.box(extents=[1, 1, 1])
    >>> _ = box.apply_translation([0, 2, 0])
    >>> shadow = sg.project_shadow(box, sg.PointLight([1, 5, 1]), sg.Plane([0, 1, 0], 0))
    >>> image = sg.plot([box, shadow], off_screen=True, window_size=(160, 120))
    >>> image.shape
    (120, 160, 3)
    """
    off_screen = bool(off_screen or screenshot is not None)
    reason = None if off_screen else no_display_reason()
    if reason is not None:
        raise RuntimeError(
            f"no display for an interactive window ({reason}); "
            "pass off_screen=True or screenshot=..."
        )
    plotter = scene_plotter(
        scene_or_meshes,
        shadows=shadows,
        volumes=volumes,
        lights=lights,
        off_screen=off_screen,
        window_size=window_size,
        view=view,
        pbr=pbr,
    )
    if not off_screen:
        plotter.show()
        return plotter
    try:
        image = np.asarray(plotter.screenshot(return_img=True))
    finally:
        plotter.close()
    if screenshot is not None:
        _write_png(image, screenshot)
    return image


def no_display_reason() -> str | None:
    """Why no interactive window can open here, or ``None`` if one can.

    On Linux and the BSDs a window needs an X server (``DISPLAY``) or a
    Wayland compositor (``WAYLAND_DISPLAY``); macOS and Windows always have one.
    """
    if not sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return None
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None
    return "neither DISPLAY nor WAYLAND_DISPLAY is set"


def _write_png(image: np.ndarray, path: str | os.PathLike[str]) -> None:
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk

    height, width, channels = image.shape
    data = vtk.vtkImageData()
    data.SetDimensions(width, height, 1)
    # PNG rows run top to bottom, VTK image rows bottom to top.
    flat = np.ascontiguousarray(image[::-1].reshape(-1, channels))
    data.GetPointData().SetScalars(numpy_to_vtk(flat, deep=True))
    try:
        with atomic_path(path, suffix=".png") as temporary:
            writer = vtk.vtkPNGWriter()
            writer.SetFileName(str(temporary))
            writer.SetInputData(data)
            writer.SetCompressionLevel(9)
            writer.Write()
            # VTK does not raise: a failed write (a full disk) only sets the code,
            # and the rename would put the truncated file in place
            if writer.GetErrorCode():
                code = vtk.vtkErrorCode.GetStringFromErrorCode(writer.GetErrorCode())
                raise SceneError(f"cannot write: VTK's PNG writer failed ({code})", path=str(path))
    except OSError as error:
        raise SceneError(f"cannot write: {error.strerror or error}", path=str(path)) from None
