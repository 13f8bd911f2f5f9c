"""USD reader: ``UsdGeom.Mesh`` prims and UsdLux lights into a :class:`Scene`.

:mod:`.usd_layout` describes the layout :mod:`.usd_write` writes; this reads it
back exactly (``shadowgeo:`` attributes restore the float64 points, roles,
groups and X3D light fields) and reads USD from other tools too: convex
polygons are fanned into triangles and others triangulated in their plane,
``leftHanded`` meshes are flipped, an animated stage is read at its first time
sample, invisible and guide meshes are skipped, other geometry (Cube, Sphere,
...) and lights (Rect, Dome, ...) are skipped with a warning.

Before usd-core composes a file, every asset path in it and in every layer it
would pull in (sublayers, references, payloads, value clips, textures, ...)
must stay inside the scene's folder (:mod:`.usd_assets`); anything else is
refused.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from .. import limits
from ..errors import SceneError
from ..lights import (
    AreaLight,
    DirectionalLight,
    DiskLight,
    Light,
    PointLight,
    RectLight,
    SpotLight,
    centre_light,
)
from ..plane2d import polygons_triangles
from ..scene import Material, Scene, SceneLight, Shape
from . import float_triple
from .usd_assets import check_assets
from .usd_layout import custom, error_text, opened, pxr, stored_name

__all__ = ["read"]


def _world(xformable: Any, time: Any, path: Path, where: str) -> np.ndarray:
    """(4, 4) column-vector local-to-world transform of a prim (named
    ``where``); a SceneError naming it when usd-core cannot compute it (an
    unknown xformOp) or it is not finite."""
    Tf = pxr()[2]
    try:
        world = np.array(xformable.ComputeLocalToWorldTransform(time), dtype=np.float64).T
    except Tf.ErrorException as error:
        raise SceneError(
            f"bad transform: {error_text(error, first=True)}", path=str(path), node=where
        ) from None
    if not np.isfinite(world).all():
        raise SceneError("transform is not finite", path=str(path), node=where)
    return world


def _finite(value: Any, what: str, path: Path, where: str) -> Any:
    """``value`` (a number or a tuple) unchanged when every component is finite;
    otherwise a SceneError: a float32 attribute overflows to inf past ~3.4e38."""
    try:
        finite = bool(np.isfinite(np.asarray(value, dtype=np.float64)).all())
    except (TypeError, ValueError):
        finite = False
    if not finite:
        raise SceneError(f"{what} {value} is not a finite number", path=str(path), node=where)
    return value


# What each kind of value _typed accepts, as its messages name it.
_KINDS = {
    "number": "a number",
    "triple": "three numbers",
    "text": "text",
    "flag": "true or false",
    "integer": "an integer",
}


def _typed(value: Any, kind: str, what: str, path: Path, where: str, finite: bool = False) -> Any:
    """``value`` unchanged when it is of ``kind`` (a key of ``_KINDS``), and
    with ``finite`` every number finite (see :func:`_finite`); otherwise a
    SceneError naming ``what``. A corrupt crate can hand back any value for
    any attribute (one value's entry can point at another's), and a
    hand-edited layer can author any type under a shadowgeo name."""
    if kind == "text":
        ok = isinstance(value, str)
    elif kind == "flag":
        ok = isinstance(value, bool | int | np.bool_)
    elif kind in ("number", "integer"):
        ok = isinstance(value, int if kind == "integer" else int | float)
        ok = ok and not isinstance(value, bool)
    else:
        try:
            ok = np.asarray(value, dtype=np.float64).shape == (3,)
        except (TypeError, ValueError):
            ok = False
    if not ok:
        raise SceneError(
            f"{what} holds {type(value).__name__}, not {_KINDS[kind]}", path=str(path), node=where
        )
    return _finite(value, what, path, where) if finite else value


def _get(
    attribute: Any,
    kind: str,
    default: Any,
    time: Any,
    path: Path,
    where: str,
    finite: bool = False,
) -> Any:
    """The attribute's value at ``time`` (``default`` when it has none),
    checked by :func:`_typed`."""
    value = attribute.Get(time)
    if value is None:
        return default
    return _typed(value, kind, str(attribute.GetName()), path, where, finite)


def _custom(
    prim: Any, name: str, kind: str, default: Any, path: Path, where: str, finite: bool = False
) -> Any:
    """:func:`~shadowgeo.io.usd_layout.custom`, checked by :func:`_typed`."""
    value = custom(prim, name)
    if value is None:
        return default
    return _typed(value, kind, f"shadowgeo:{name}", path, where, finite)


def _triangles(
    points: np.ndarray, counts: np.ndarray, indices: np.ndarray, holes: Any
) -> tuple[np.ndarray, int]:
    """Triangulate USD polygons.

    Returns (m, 3) triangles in the file's polygon order and the number of
    polygons dropped (fewer than 3 vertices, or holes). Convex polygons are
    fanned; others are triangulated in their own plane.
    """
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    keep = counts >= 3
    holes = np.asarray(holes, dtype=np.int64).reshape(-1)
    keep[holes[(holes >= 0) & (holes < len(counts))]] = False
    owners, pieces = [], []
    for size in np.unique(counts[keep]):
        polygons = np.flatnonzero(keep & (counts == size))
        block = indices[starts[polygons][:, None] + np.arange(size)]
        triangles, rows = polygons_triangles(points, block)
        pieces.append(triangles)
        owners.append(polygons[rows])
    dropped = int((~keep).sum())
    if not pieces:
        return np.zeros((0, 3), dtype=np.int64), dropped
    order = np.argsort(np.concatenate(owners), kind="stable")
    return np.concatenate(pieces).astype(np.int64)[order], dropped


def _array(attribute: Any, time: Any, dtype: Any, path: Path, where: str) -> np.ndarray:
    """The attribute's value at ``time`` as a flat-or-nested numpy array of
    ``dtype`` (empty when unset); a SceneError naming it when the value is of
    another type (a corrupt crate can hold a token where numbers belong)."""
    value = attribute.Get(time)
    try:
        return np.array(value or [], dtype=dtype)
    except (TypeError, ValueError):
        raise SceneError(
            f"{attribute.GetName()} holds {type(value).__name__}, not numbers",
            path=str(path),
            node=where,
        ) from None


def _points(mesh: Any, time: Any, path: Path, where: str) -> np.ndarray:
    """(n, 3) float64 points: the writer's exact ``shadowgeo:points`` while
    they still match ``points`` (what other tools see and may have edited)."""
    points = _array(mesh.GetPointsAttr(), time, np.float64, path, where)
    if points.size % 3:
        raise SceneError(f"points hold {points.size} numbers", path=str(path), node=where)
    points = points.reshape(-1, 3)
    exact = custom(mesh.GetPrim(), "points")
    if exact is not None:
        try:
            exact = np.array(exact, dtype=np.float64)
        except (TypeError, ValueError):
            return points  # not the writer's
        if exact.size == points.size:  # else not the writer's (a corrupt or edited file)
            exact = exact.reshape(-1, 3)
            if np.array_equal(exact.astype(np.float32), points):
                return exact
    return points


def _polygons(
    mesh: Any, time: Any, n_points: int, path: Path, where: str
) -> tuple[np.ndarray, np.ndarray]:
    """``faceVertexCounts`` and ``faceVertexIndices`` as int64 arrays, checked
    to agree with each other and with the ``n_points`` points."""
    counts = _array(mesh.GetFaceVertexCountsAttr(), time, np.int64, path, where)
    indices = _array(mesh.GetFaceVertexIndicesAttr(), time, np.int64, path, where)
    if len(counts) and counts.min() < 0:
        raise SceneError(f"faceVertexCounts holds {int(counts.min())}", path=str(path), node=where)
    if counts.sum() != len(indices):
        raise SceneError(
            f"faceVertexCounts add up to {int(counts.sum())} but there are "
            f"{len(indices)} faceVertexIndices",
            path=str(path),
            node=where,
        )
    if len(indices) and (indices.min() < 0 or indices.max() >= n_points):
        raise SceneError(
            f"faceVertexIndices refer to point {int(indices.max())} of {n_points}",
            path=str(path),
            node=where,
        )
    return counts, indices


def _material(mesh: Any, time: Any, path: Path, where: str) -> Material:
    """The display colour and opacity, refined by a bound UsdPreviewSurface's
    emissive colour and roughness and the material's name; a SceneError for
    any of them that is not finite (it would be written out again)."""
    UsdShade = pxr()[6]
    opacity = _array(mesh.GetDisplayOpacityPrimvar(), time, np.float64, path, where).ravel()
    color = _array(mesh.GetDisplayColorPrimvar(), time, np.float64, path, where)
    if color.size and (color.ndim != 2 or color.shape[1] != 3):
        raise SceneError(
            f"displayColor holds {color.size} numbers, not colours", path=str(path), node=where
        )
    material = Material(
        diffuse_color=float_triple(_finite(color[0], "displayColor", path, where))
        if color.size
        else Material().diffuse_color,
        transparency=1.0 - float(_finite(opacity[0], "displayOpacity", path, where))
        if opacity.size
        else 0.0,
    )
    bound, _ = UsdShade.MaterialBindingAPI(mesh.GetPrim()).ComputeBoundMaterial()
    if bound:
        shader = bound.ComputeSurfaceSource()[0]
        emissive = shader.GetInput("emissiveColor") if shader else None
        if emissive:
            value = _get(emissive.GetAttr(), "triple", None, time, path, where, True)
            if value is not None:
                material.emissive_color = float_triple(value)
        roughness = shader.GetInput("roughness") if shader else None
        if roughness:
            value = _get(roughness.GetAttr(), "number", None, time, path, where, True)
            if value is not None:
                material.shininess = 1.0 - float(value)
        material.name = bound.GetPrim().GetDisplayName() or None
    return material


def _read_mesh(scene: Scene, prim: Any, path: Path, time: Any, where: str) -> None:
    """Append the shape of the ``UsdGeom.Mesh`` at ``prim``: its points,
    triangulated polygons, material, world transform and shadowgeo fields."""
    UsdGeom = pxr()[4]
    mesh = UsdGeom.Mesh(prim)
    points = _points(mesh, time, path, where)
    counts, indices = _polygons(mesh, time, len(points), path, where)
    holes = _array(mesh.GetHoleIndicesAttr(), time, np.int64, path, where)
    faces, dropped = _triangles(points, counts, indices, holes)
    if dropped:
        scene.warnings.append(f"{path.name}: {where}: skipped {dropped} holes or degenerate faces")
    if mesh.GetOrientationAttr().Get(time) == UsdGeom.Tokens.leftHanded:
        faces = faces[:, ::-1]
    parent = prim.GetParent()
    scene.shapes.append(
        Shape(
            points,
            faces,
            _world(mesh, time, path, where),
            material=_material(mesh, time, path, where),
            name=stored_name(prim, "role"),
            solid=not _get(mesh.GetDoubleSidedAttr(), "flag", False, time, path, where),
            role=_custom(prim, "role", "text", "geometry", path, where),
            group=_custom(parent, "group", "text", None, path, where)
            if parent and not parent.IsPseudoRoot()
            else None,
            source=f"{path.name}, {where}",
            casts_shadow=bool(_custom(prim, "castsShadow", "flag", True, path, where)),
            receives_shadow=bool(_custom(prim, "receivesShadow", "flag", False, path, where)),
        )
    )


def _size(prim: Any, world: np.ndarray, path: Path, where: str) -> float:
    """A SphereLight's radius in world units (UsdLux's default 0.5; 0 when
    ``treatAsPoint``), scaled as its transform scales volumes."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    sphere = UsdLux.SphereLight(prim)
    if bool(sphere.GetTreatAsPointAttr().Get()):
        return 0.0
    radius = sphere.GetRadiusAttr().Get()
    radius = 0.5 if radius is None else float(radius)
    scale = abs(float(np.linalg.det(world[:3, :3]))) ** (1.0 / 3.0)
    size = _exact(radius, prim, "sourceRadius", path, where) * scale
    return size if math.isfinite(size) and size > 0 else 0.0


def _exact(value: float, prim: Any, name: str, path: Path, where: str) -> float:
    """``value`` read from a float32 attribute, or the float64 custom
    attribute ``name`` shadowgeo's writer keeps beside it when the two agree
    to float32's precision."""
    exact = _custom(prim, name, "number", None, path, where)
    if exact is not None and abs(float(exact) - value) <= limits.FLOAT32_AGREEMENT * abs(value):
        return float(exact)
    return value


# The UsdLux lights shadowgeo reads, by schema name.
_LIGHT_SCHEMAS = ("DistantLight", "SphereLight", "RectLight", "DiskLight")


def _usd_light(prim: Any) -> Any:
    """``prim`` as the UsdLux light schema it is, of those read; None for another."""
    UsdLux = pxr()[5]
    for name in _LIGHT_SCHEMAS:
        schema = getattr(UsdLux, name)
        if prim.IsA(schema):
            return schema(prim)
    return None


def _read_light(scene: Scene, prim: Any, time: Any, path: Path, where: str) -> bool:
    """Append the light at ``prim``; False when it is no light shadowgeo models."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    usd_light = _usd_light(prim)
    if usd_light is None:
        return False
    world = _world(usd_light, time, path, where)
    area = (
        _area_light(usd_light, world, time, path, where)
        if isinstance(usd_light, UsdLux.RectLight | UsdLux.DiskLight)
        else None
    )
    direction = world[:3, :3] @ [0.0, 0.0, -1.0]
    radius = float(_custom(prim, "range", "number", math.inf, path, where))
    beam = _custom(prim, "beamWidth", "number", None, path, where)
    light: Light
    if area is not None:
        light, beam = centre_light(area), math.pi / 4 if beam is None else beam
    elif isinstance(usd_light, UsdLux.DistantLight):
        # the disc's angular diameter, degrees (UsdLux's default 0.53: the sun's)
        angle = _get(usd_light.GetAngleAttr(), "number", 0.53, time, path, where)
        radians = _exact(
            math.radians(min(max(float(angle), 0.0), 179.0)), prim, "angle", path, where
        )
        light = DirectionalLight(direction, radians)
    else:
        shaping = UsdLux.ShapingAPI(prim)
        cone = (
            _get(shaping.GetShapingConeAngleAttr(), "number", None, time, path, where)
            if prim.HasAPI(UsdLux.ShapingAPI)
            else None
        )
        if cone is not None and 0 < cone <= 90:
            cut_off = math.radians(cone)
            exact = _custom(prim, "cutOffAngle", "number", None, path, where)
            if exact is not None and abs(exact - cut_off) <= limits.FLOAT32_AGREEMENT * cut_off:
                cut_off = float(exact)
            light = SpotLight(
                world[:3, 3],
                direction,
                min(cut_off, math.pi / 2),
                radius,
                _size(prim, world, path, where),
            )
            if beam is None:
                softness = _get(
                    shaping.GetShapingConeSoftnessAttr(), "number", 0.0, time, path, where
                )
                beam = (1.0 - softness) * light.cut_off_angle
        else:
            light = PointLight(world[:3, 3], radius, _size(prim, world, path, where))
    shadow = _get(UsdLux.ShadowAPI(prim).GetShadowEnableAttr(), "flag", False, time, path, where)
    visibility = usd_light.ComputeVisibility(time)
    color = _get(usd_light.GetColorAttr(), "triple", (1, 1, 1), time, path, where, True)
    intensity = _get(usd_light.GetIntensityAttr(), "number", 0.0, time, path, where, True)
    ambient = _custom(prim, "ambientIntensity", "number", 0.0, path, where, True)
    attenuation = _custom(prim, "attenuation", "triple", (1.0, 0.0, 0.0), path, where, True)
    baked = bool(_custom(prim, "shadowsBaked", "flag", False, path, where))
    limits.check_lights(len(scene.lights) + 1, str(path))
    scene.lights.append(
        SceneLight(
            light,
            name=stored_name(prim, "global"),
            color=float_triple(color),
            intensity=float(intensity),
            ambient_intensity=float(ambient),
            attenuation=float_triple(attenuation),
            beam_width=float(beam if beam is not None else math.pi / 4),
            on=visibility != UsdGeom.Tokens.invisible,
            global_=bool(_custom(prim, "global", "flag", True, path, where)),
            shadows=bool(shadow) or baked,  # baked: on before shadowgeo turned them off
            shadow_intensity=float(_custom(prim, "shadowIntensity", "number", 1.0, path, where)),
            baked=baked,
            area=area,
        )
    )
    return True


def _area_light(usd_light: Any, world: np.ndarray, time: Any, path: Path, where: str) -> AreaLight:
    """A UsdLux ``RectLight`` (``width`` along its local X, ``height`` along
    Y; UsdLux's defaults 1) or ``DiskLight`` (``radius``, default 0.5), both
    emitting along local -Z, in world units: each size scaled as the
    transform scales its axis (a disc: the mean of X's and Y's), and the
    exact float64 size shadowgeo's writer keeps beside it when they agree."""
    UsdLux = pxr()[5]
    prim = usd_light.GetPrim()
    rotation = world[:3, :3]
    axes = np.linalg.norm(rotation, axis=0)
    direction = rotation @ [0.0, 0.0, -1.0]
    if isinstance(usd_light, UsdLux.RectLight):
        sizes = []
        for name, attribute, axis in (
            ("width", usd_light.GetWidthAttr(), 0),
            ("height", usd_light.GetHeightAttr(), 1),
        ):
            value = float(_get(attribute, "number", 1.0, time, path, where))
            sizes.append(_exact(value * float(axes[axis]), prim, name, path, where))
        width, height = sizes
        return RectLight(world[:3, 3], direction, width, height, up=rotation[:, 1] / axes[1])
    value = float(_get(usd_light.GetRadiusAttr(), "number", 0.5, time, path, where))
    scale = 0.5 * float(axes[0] + axes[1])
    return DiskLight(
        world[:3, 3], direction, _exact(value * scale, prim, "sourceRadius", path, where)
    )


def read(
    path: str | os.PathLike[str], *, max_triangles: int | None = None, **options: Any
) -> Scene:
    """Read a USD file into a :class:`Scene`.

    Parameters
    ----------
    path : str or Path
        ``.usda``, ``.usdc`` or ``.usd``.
    max_triangles : int, optional
        The triangle (memory) budget, default
        :data:`~shadowgeo.limits.MAX_TRIANGLES`: each mesh (every instance
        counted) adds its faces' triangles, from its ``faceVertexCounts``
        alone, before its points and indices are read; past the budget the
        file is refused naming the mesh.

    Returns
    -------
    Scene
        One shape per ``UsdGeom.Mesh`` (world transform at the first time,
        polygons fanned into triangles, left-handed ones flipped), the sphere,
        spot and distant lights, the stage's ``upAxis`` and ``metersPerUnit``.
        Other geometry and lights are skipped with a warning; invisible and
        guide-purpose meshes are skipped.

    Raises
    ------
    SceneError
        Missing or corrupt file, an asset path outside the file's folder, or a mesh
        whose indices do not match its points.
    """
    path = Path(path)
    if options:
        raise SceneError(f"USD reader takes no options, got {sorted(options)}", path=str(path))
    if not path.is_file():
        raise SceneError("no such file", path=str(path))
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    notes: list[str] = []
    with _corrupt_data(path):
        check_assets(path, notes)
        stage = opened(Usd.Stage.Open, path, "cannot open")
        return _stage_scene(stage, path, notes, max_triangles)


@contextlib.contextmanager
def _corrupt_data(path: Path, where: str | None = None) -> Iterator[None]:
    """Turn what corrupt data raises into a SceneError naming ``path`` (and
    the prim ``where``): usd-core unpacks a crate's values lazily, so a
    corrupt one surfaces as ``Tf.ErrorException`` from any ``Get()``, or as
    text that is not UTF-8."""
    Tf = pxr()[2]
    try:
        yield
    except Tf.ErrorException as error:
        raise SceneError(
            f"corrupt USD data: {_message(error)}", path=str(path), node=where
        ) from None
    except UnicodeDecodeError:
        raise SceneError(
            "corrupt USD data: text that is not UTF-8", path=str(path), node=where
        ) from None


def _where(prim: Any) -> str:
    """``Type </path>`` of a prim, for messages; a corrupt crate's names may
    not be UTF-8."""
    try:
        return f"{prim.GetTypeName()} <{prim.GetPath()}>"
    except UnicodeDecodeError:
        return "a prim whose name is not UTF-8"


def _message(error: Exception) -> str:
    """usd-core's message without its C++ function, line and file."""
    text = error_text(error)
    found = re.fullmatch(r"Error in '.*?' at line \d+ in file \S+ : '(.*)'", text, re.S)
    return found.group(1) if found else text


def _stage_scene(
    stage: Any, path: Path, notes: list[str], max_triangles: int | None = None
) -> Scene:
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    up = UsdGeom.GetStageUpAxis(stage)
    scene = Scene(
        path=str(path),
        up_axis="Z" if up == UsdGeom.Tokens.z else "Y",
        meters_per_unit=float(UsdGeom.GetStageMetersPerUnit(stage)),
    )
    scene.warnings.extend(notes)
    # An animated stage reads at its first time sample; a static one at its defaults.
    time = Usd.TimeCode.EarliestTime()
    indices: list[int | None] = []
    triangles = 0  # of the meshes so far, every instance counted
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        where = _where(prim)
        with _corrupt_data(path, where):
            if prim.IsA(UsdGeom.Mesh):
                triangles += _mesh_triangles(prim, time, path, where)
                through = "instancing and references"
                limits.check_expansion(
                    triangles, str(path), where, None, max_triangles, through=through
                )
            _read_prim(scene, prim, path, time, where, indices)
    # Shapes shadowgeo wrote carry their place in the scene; others follow in file order.
    keys = [(0, index) if index is not None else (1, 0) for index in indices]
    order = sorted(range(len(keys)), key=keys.__getitem__)
    scene.shapes = [scene.shapes[i] for i in order]
    return scene


def _mesh_triangles(prim: Any, time: Any, path: Path, where: str) -> int:
    """Triangles the mesh at ``prim`` makes at most (a face of ``k`` corners
    ``k - 2``), from its ``faceVertexCounts`` alone (a SceneError naming the
    prim when they are not numbers)."""
    counts = _array(pxr()[4].Mesh(prim).GetFaceVertexCountsAttr(), time, np.int64, path, where)
    return int(np.maximum(counts.reshape(-1) - 2, 0).sum())


def _read_prim(
    scene: Scene, prim: Any, path: Path, time: Any, where: str, indices: list[int | None]
) -> None:
    """Add ``prim``'s (named ``where``) mesh, and its index in ``indices``, or
    its light to ``scene``."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    if prim.IsA(UsdGeom.Mesh):
        imageable = UsdGeom.Imageable(prim)
        if imageable.ComputeVisibility(time) == UsdGeom.Tokens.invisible:
            return
        if imageable.ComputePurpose() == UsdGeom.Tokens.guide:
            return
        _read_mesh(scene, prim, path, time, where)
        indices.append(_custom(prim, "index", "integer", None, path, where))
    elif prim.IsA(UsdGeom.Gprim):
        scene.warnings.append(f"{path.name}: skipped {where}: only meshes are read")
    elif prim.HasAPI(UsdLux.LightAPI) or prim.IsA(UsdLux.BoundableLightBase):
        if not _read_light(scene, prim, time, path, where):
            scene.warnings.append(
                f"{path.name}: skipped {where}: not a point, spot, rectangle or disc light or a sun"
            )
