"""USD reader and writer (``.usda`` text, ``.usdc`` binary, ``.usd`` either) with usd-core.

Layout written
--------------
``/World`` (an Xform, the default prim) holds one ``UsdGeom.Mesh`` per scene
shape, one Xform per light group holding that group's shadows, the lights, and
``/World/Looks`` with one ``UsdPreviewSurface`` material per distinct look.
Stage metadata ``upAxis`` and ``metersPerUnit`` come from the scene.

- Meshes: ``points``, ``faceVertexCounts`` (all 3), ``faceVertexIndices``,
  ``extent``, ``orientation = rightHanded``, ``doubleSided`` when not solid,
  ``subdivisionScheme = none`` (these are polygons, not cages), the shape's
  transform as one double-precision ``xformOp:transform``, ``displayColor`` /
  ``displayOpacity`` and a bound material.
- Lights: a point light is a ``SphereLight`` with ``treatAsPoint``; a spot
  light the same with ``ShapingAPI`` (``shaping:cone:angle`` = the cut-off
  angle in degrees, softness from the beam width); a directional light a
  ``DistantLight``. Lights shine down their -Z, so the transform turns -Z onto
  the light's direction. ``ShadowAPI``'s ``inputs:shadow:enable`` carries X3D's
  ``shadows``; a light that is off is ``invisible``.
- Names: prims get valid, unique identifiers; the original name is the prim's
  ``displayName``. A shape without a name reads back with its prim's name.
- Fields USD has no place for (a light's range, beam width, shadow intensity,
  attenuation, shape roles, group names) are ``shadowgeo:`` attributes.

Precision
---------
USD's ``points`` are float32. The writer also stores the float64 vertices as
``shadowgeo:points`` (``point3d[]``); the reader uses them when they agree
with ``points`` to float32 precision (so a tool that edits ``points`` and
leaves the copy stale is still obeyed), which makes round trips exact.

Safety
------
Before usd-core composes a file, every layer it would pull in (sublayers,
references, payloads) must be a file inside the scene's folder; anything else
is refused.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..lights import DirectionalLight, PointLight, SpotLight
from ..scene import Material, Scene, SceneLight, Shape
from .atomic import atomic_path
from .gltf import look_rotation


def _pxr():
    """usd-core's modules, imported when first needed (it is slow to load)."""
    from pxr import Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt

    return Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt


class _Names:
    """Valid, unique prim names per parent path."""

    def __init__(self) -> None:
        self.taken: dict[str, set[str]] = {}

    def child(self, parent: str, wanted: str | None, fallback: str) -> str:
        from pxr import Tf

        base = Tf.MakeValidIdentifier(wanted) if wanted else fallback
        taken = self.taken.setdefault(parent, set())
        name, count = base, 1
        while name in taken:
            name = f"{base}_{count}"
            count += 1
        taken.add(name)
        return f"{parent}/{name}"


def _matrix(transform: np.ndarray):
    """Gf.Matrix4d of a (4, 4) column-vector transform (USD uses row vectors)."""
    from pxr import Gf

    return Gf.Matrix4d(np.asarray(transform, dtype=np.float64).T.tolist())


def _custom(prim, name: str, type_name, value) -> None:
    prim.CreateAttribute(f"shadowgeo:{name}", type_name, custom=True).Set(value)


class _Writer:
    def __init__(self, scene: Scene) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
        up = (scene.up_axis or "Y").upper()
        if up not in ("Y", "Z"):
            raise SceneError(f"up axis must be 'Y' or 'Z', got {scene.up_axis!r}")
        if not (math.isfinite(scene.meters_per_unit) and scene.meters_per_unit > 0):
            raise SceneError(f"metersPerUnit must be > 0, got {scene.meters_per_unit!r}")
        self.scene = scene
        self.stage = Usd.Stage.CreateInMemory()
        UsdGeom.SetStageUpAxis(self.stage, UsdGeom.Tokens.y if up == "Y" else UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(self.stage, float(scene.meters_per_unit))
        world = UsdGeom.Xform.Define(self.stage, "/World")
        self.stage.SetDefaultPrim(world.GetPrim())
        self.names = _Names()
        self.names.taken["/World"] = {"Looks"}
        self.looks: dict[tuple, object] = {}
        self.groups: dict[object, str] = {}

    def write_shapes(self) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
        for index, shape in enumerate(self.scene.shapes):
            parent = "/World"
            if shape.role != "geometry" or shape.group:
                parent = self._group(shape)
            path = self.names.child(parent, shape.name, f"Shape_{index}")
            self._mesh(shape, path)
            # Group Xforms change the traversal order; keep the scene's.
            prim = self.stage.GetPrimAtPath(path)
            _custom(prim, "index", Sdf.ValueTypeNames.Int, index)

    def _group(self, shape: Shape) -> str:
        """The Xform holding a light group's shadows; unnamed groups (one per
        role) get a display name but no ``shadowgeo:group``, so read back as None."""
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
        key = shape.group or (None, shape.role)
        if key not in self.groups:
            label = shape.group or f"shadowgeo {shape.role}s"
            path = self.names.child("/World", label, "Group")
            prim = UsdGeom.Xform.Define(self.stage, path).GetPrim()
            prim.SetDisplayName(label)
            if shape.group:
                _custom(prim, "group", Sdf.ValueTypeNames.String, shape.group)
            self.groups[key] = path
        return self.groups[key]

    def _mesh(self, shape: Shape, path: str) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
        vertices = np.ascontiguousarray(shape.vertices, dtype=np.float64)
        faces = np.asarray(shape.faces, dtype=np.int64)
        if not np.all(np.isfinite(vertices)) or not np.all(np.isfinite(shape.transform)):
            raise SceneError("non-finite vertex or transform", node=f"shape {shape.name!r}")
        if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise SceneError(
                f"faces index vertex {int(faces.max())} of {len(vertices)}",
                node=f"shape {shape.name!r}",
            )
        mesh = UsdGeom.Mesh.Define(self.stage, path)
        prim = mesh.GetPrim()
        if shape.name:
            prim.SetDisplayName(shape.name)
        points = Vt.Vec3fArray.FromNumpy(vertices.astype(np.float32))
        mesh.CreatePointsAttr(points)
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray([3] * len(faces)))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(faces.reshape(-1).tolist()))
        mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
        mesh.CreateDoubleSidedAttr(not shape.solid)
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        if len(vertices):
            mesh.CreateExtentAttr(UsdGeom.PointBased.ComputeExtent(points))
        _custom(prim, "points", Sdf.ValueTypeNames.Point3dArray, Vt.Vec3dArray.FromNumpy(vertices))
        _custom(prim, "role", Sdf.ValueTypeNames.String, shape.role)
        if not shape.casts_shadow or shape.receives_shadow:
            _custom(prim, "castsShadow", Sdf.ValueTypeNames.Bool, bool(shape.casts_shadow))
            _custom(prim, "receivesShadow", Sdf.ValueTypeNames.Bool, bool(shape.receives_shadow))
        if not np.array_equal(shape.transform, np.eye(4)):
            mesh.AddTransformOp(UsdGeom.XformOp.PrecisionDouble).Set(_matrix(shape.transform))
        look = shape.material
        mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(
            Vt.Vec3fArray([Gf.Vec3f(*look.diffuse_color)])
        )
        mesh.CreateDisplayOpacityPrimvar(UsdGeom.Tokens.constant).Set(
            Vt.FloatArray([1.0 - look.transparency])
        )
        UsdShade.MaterialBindingAPI.Apply(prim).Bind(self._look(look))

    def _look(self, look: Material):
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
        key = (
            look.diffuse_color,
            look.emissive_color,
            look.transparency,
            look.shininess,
            look.name,
        )
        if key not in self.looks:
            path = self.names.child("/World/Looks", look.name, "Look")
            if not self.stage.GetPrimAtPath("/World/Looks"):
                UsdGeom.Scope.Define(self.stage, "/World/Looks")
            material = UsdShade.Material.Define(self.stage, path)
            if look.name:
                material.GetPrim().SetDisplayName(look.name)
            shader = UsdShade.Shader.Define(self.stage, f"{path}/PreviewSurface")
            shader.CreateIdAttr("UsdPreviewSurface")
            color = Sdf.ValueTypeNames.Color3f
            shader.CreateInput("diffuseColor", color).Set(Gf.Vec3f(*look.diffuse_color))
            shader.CreateInput("emissiveColor", color).Set(Gf.Vec3f(*look.emissive_color))
            shader.CreateInput("opacity", Sdf.ValueTypeNames.Float).Set(1.0 - look.transparency)
            roughness = min(max(1.0 - look.shininess, 0.0), 1.0)
            shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(roughness)
            shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(0.0)
            output = shader.CreateOutput("surface", Sdf.ValueTypeNames.Token)
            material.CreateSurfaceOutput().ConnectToSource(output)
            self.looks[key] = material
        return self.looks[key]

    def write_lights(self) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
        for index, scene_light in enumerate(self.scene.lights):
            light = scene_light.light
            path = self.names.child("/World", scene_light.name, f"Light_{index}")
            transform = np.eye(4)
            if isinstance(light, DirectionalLight):
                usd_light = UsdLux.DistantLight.Define(self.stage, path)
            else:
                usd_light = UsdLux.SphereLight.Define(self.stage, path)
                usd_light.CreateTreatAsPointAttr(True)
                usd_light.CreateRadiusAttr(0.0)
                transform[:3, 3] = light.position
            if not isinstance(light, PointLight):
                transform[:3, :3] = look_rotation(light.direction)
            prim = usd_light.GetPrim()
            if scene_light.name:
                prim.SetDisplayName(scene_light.name)
            if isinstance(light, SpotLight):
                shaping = UsdLux.ShapingAPI.Apply(prim)
                shaping.CreateShapingConeAngleAttr(math.degrees(light.cut_off_angle))
                beam = min(max(scene_light.beam_width / light.cut_off_angle, 0.0), 1.0)
                shaping.CreateShapingConeSoftnessAttr(1.0 - beam)
                _custom(prim, "beamWidth", Sdf.ValueTypeNames.Double, scene_light.beam_width)
                # The cone angle is float32 degrees; keep the exact radians too.
                _custom(prim, "cutOffAngle", Sdf.ValueTypeNames.Double, light.cut_off_angle)
            if not isinstance(light, DirectionalLight) and math.isfinite(light.radius):
                _custom(prim, "range", Sdf.ValueTypeNames.Double, float(light.radius))
            usd_light.CreateIntensityAttr(float(scene_light.intensity))
            usd_light.CreateColorAttr(Gf.Vec3f(*scene_light.color))
            UsdLux.ShadowAPI.Apply(prim).CreateShadowEnableAttr(bool(scene_light.shadows))
            _custom(
                prim, "shadowIntensity", Sdf.ValueTypeNames.Double, scene_light.shadow_intensity
            )
            _custom(
                prim, "ambientIntensity", Sdf.ValueTypeNames.Double, scene_light.ambient_intensity
            )
            attenuation = Gf.Vec3d(*scene_light.attenuation)
            _custom(prim, "attenuation", Sdf.ValueTypeNames.Double3, attenuation)
            _custom(prim, "global", Sdf.ValueTypeNames.Bool, bool(scene_light.global_))
            if not scene_light.on:
                usd_light.CreateVisibilityAttr(UsdGeom.Tokens.invisible)
            if not np.array_equal(transform, np.eye(4)):
                usd_light.AddTransformOp(UsdGeom.XformOp.PrecisionDouble).Set(_matrix(transform))


def write(scene: Scene, path, **options) -> None:
    """Write ``scene`` as USD; ``.usda`` is text, ``.usdc`` and ``.usd`` binary.

    Parameters
    ----------
    scene : Scene
    path : str or Path

    Raises
    ------
    SceneError
        Options not understood, an up axis other than Y or Z, non-finite
        numbers, faces indexing missing vertices, or usd-core failing to save.
    """
    path = Path(path)
    if options:
        raise SceneError(f"USD writer takes no options, got {sorted(options)}", path=str(path))
    try:
        writer = _Writer(scene)
        writer.write_shapes()
        writer.write_lights()
    except SceneError as error:
        raise SceneError(error.message, path=str(path), node=error.node) from None
    with atomic_path(path) as temporary:
        if not writer.stage.GetRootLayer().Export(str(temporary)):
            raise SceneError("usd-core could not save the stage", path=str(path))


# --- reading ----------------------------------------------------------------------------------


def _check_layers(path: Path) -> None:
    """Refuse a file whose sublayers, references or payloads are remote or
    outside its folder, before usd-core composes (and so opens) them."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
    folder = path.resolve().parent
    pending, seen = [path.resolve()], set()
    while pending:
        current = pending.pop()
        if current in seen:
            continue
        seen.add(current)
        try:
            # Anonymous: read afresh, never a stale copy from the layer registry.
            layer = Sdf.Layer.OpenAsAnonymous(str(current))
        except Tf.ErrorException as error:
            raise SceneError(f"not a USD file: {_first_line(error)}", path=str(current)) from None
        if layer is None:
            raise SceneError("not a USD file", path=str(current))
        for asset in layer.GetCompositionAssetDependencies():
            where = f"layer dependency {asset!r}"
            if not asset:
                continue
            if ":" in asset.split("/")[0] or asset.startswith(("/", "\\")):
                raise SceneError("refused: not a relative path", path=str(path), node=where)
            target = (current.parent / asset).resolve()
            if not target.is_relative_to(folder):
                raise SceneError("refused: it leaves the file's folder", path=str(path), node=where)
            if not target.is_file():
                raise SceneError("missing layer", path=str(path), node=where)
            pending.append(target)


def _first_line(error: Exception) -> str:
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


def _world(xformable, time) -> np.ndarray:
    """(4, 4) column-vector local-to-world transform of a prim."""
    return np.array(xformable.ComputeLocalToWorldTransform(time), dtype=np.float64).T


def _shadowgeo(prim, name: str, default=None):
    attribute = prim.GetAttribute(f"shadowgeo:{name}")
    if attribute and attribute.HasAuthoredValue():
        return attribute.Get()
    return default


def _name(prim, marker: str) -> str | None:
    """The original name: the displayName; for an unnamed shape or light that
    shadowgeo wrote (it has the ``shadowgeo:`` ``marker`` attribute), None;
    otherwise the prim's name."""
    if prim.GetDisplayName():
        return prim.GetDisplayName()
    return None if prim.GetAttribute(f"shadowgeo:{marker}") else prim.GetName()


def _triangles(counts: np.ndarray, indices: np.ndarray, holes) -> tuple[np.ndarray, int]:
    """(m, 3) triangles fanned from polygons, and how many polygons were dropped
    (fewer than 3 vertices, or holes). Fans are right for convex polygons."""
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    keep = counts >= 3
    if len(holes):
        keep[np.asarray(holes, dtype=np.int64)] = False
    triangles = []
    for fan in range(3, int(counts.max(initial=3)) + 1):
        polygons = np.flatnonzero(keep & (counts >= fan))
        if len(polygons):
            first = starts[polygons]
            triangles.append(
                (
                    polygons,
                    np.stack(
                        [indices[first], indices[first + fan - 2], indices[first + fan - 1]],
                        axis=1,
                    ),
                )
            )
    if not triangles:
        return np.zeros((0, 3), dtype=np.int64), int((~keep).sum())
    # Keep each polygon's triangles together, in the file's polygon order.
    order = np.concatenate([polygons for polygons, _ in triangles])
    faces = np.concatenate([faces for _, faces in triangles])
    return faces[np.argsort(order, kind="stable")], int((~keep).sum())


def _read_mesh(scene: Scene, prim, path: Path, time) -> None:
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
    mesh = UsdGeom.Mesh(prim)
    where = f"{prim.GetTypeName()} <{prim.GetPath()}>"
    points = np.array(mesh.GetPointsAttr().Get(time) or [], dtype=np.float64).reshape(-1, 3)
    exact = _shadowgeo(prim, "points")
    if exact is not None:
        exact = np.array(exact, dtype=np.float64).reshape(-1, 3)
        # The float64 copy counts only while it still matches what tools see.
        if exact.shape == points.shape and np.array_equal(exact.astype(np.float32), points):
            points = exact
    counts = np.array(mesh.GetFaceVertexCountsAttr().Get(time) or [], dtype=np.int64)
    indices = np.array(mesh.GetFaceVertexIndicesAttr().Get(time) or [], dtype=np.int64)
    if counts.sum() != len(indices):
        raise SceneError(
            f"faceVertexCounts add up to {int(counts.sum())} but there are "
            f"{len(indices)} faceVertexIndices",
            path=str(path),
            node=where,
        )
    if len(indices) and (indices.min() < 0 or indices.max() >= len(points)):
        raise SceneError(
            f"faceVertexIndices refer to point {int(indices.max())} of {len(points)}",
            path=str(path),
            node=where,
        )
    faces, dropped = _triangles(counts, indices, mesh.GetHoleIndicesAttr().Get(time) or [])
    if dropped:
        scene.warnings.append(f"{path.name}: {where}: skipped {dropped} holes or degenerate faces")
    if mesh.GetOrientationAttr().Get(time) == UsdGeom.Tokens.leftHanded:
        faces = faces[:, ::-1]
    opacity = mesh.GetDisplayOpacityPrimvar().Get(time)
    color = mesh.GetDisplayColorPrimvar().Get(time)
    material = Material(
        diffuse_color=tuple(float(c) for c in color[0]) if color else Material().diffuse_color,
        transparency=1.0 - float(opacity[0]) if opacity else 0.0,
    )
    bound, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
    if bound:
        shader = bound.ComputeSurfaceSource()[0]
        emissive = shader.GetInput("emissiveColor") if shader else None
        if emissive and emissive.Get() is not None:
            material.emissive_color = tuple(float(c) for c in emissive.Get())
        roughness = shader.GetInput("roughness") if shader else None
        if roughness and roughness.Get() is not None:
            material.shininess = 1.0 - float(roughness.Get())
        material.name = bound.GetPrim().GetDisplayName() or None
    parent = prim.GetParent()
    scene.shapes.append(
        Shape(
            points,
            faces,
            _world(mesh, time),
            material=material,
            name=_name(prim, "role"),
            solid=not mesh.GetDoubleSidedAttr().Get(time),
            role=_shadowgeo(prim, "role", "geometry"),
            group=_shadowgeo(parent, "group") if parent else None,
            source=f"{path.name}, {where}",
            casts_shadow=bool(_shadowgeo(prim, "castsShadow", True)),
            receives_shadow=bool(_shadowgeo(prim, "receivesShadow", False)),
        )
    )


def _read_light(scene: Scene, prim, time) -> bool:
    """Append the light at ``prim``; False when it is no light shadowgeo models."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
    if prim.IsA(UsdLux.DistantLight):
        usd_light = UsdLux.DistantLight(prim)
    elif prim.IsA(UsdLux.SphereLight):
        usd_light = UsdLux.SphereLight(prim)
    else:
        return False
    world = _world(usd_light, time)
    direction = world[:3, :3] @ [0.0, 0.0, -1.0]
    radius = float(_shadowgeo(prim, "range", math.inf))
    beam = _shadowgeo(prim, "beamWidth")
    if isinstance(usd_light, UsdLux.DistantLight):
        light = DirectionalLight(direction)
    else:
        shaping = UsdLux.ShapingAPI(prim)
        cone = (
            shaping.GetShapingConeAngleAttr().Get(time) if prim.HasAPI(UsdLux.ShapingAPI) else None
        )
        if cone is not None and 0 < cone <= 90:
            cut_off = math.radians(cone)
            exact = _shadowgeo(prim, "cutOffAngle")
            if exact is not None and abs(exact - cut_off) <= 1e-6 * cut_off:
                cut_off = float(exact)
            light = SpotLight(world[:3, 3], direction, min(cut_off, math.pi / 2), radius)
            if beam is None:
                softness = shaping.GetShapingConeSoftnessAttr().Get(time) or 0.0
                beam = (1.0 - softness) * light.cut_off_angle
        else:
            light = PointLight(world[:3, 3], radius)
    shadow = UsdLux.ShadowAPI(prim).GetShadowEnableAttr().Get(time)
    visibility = usd_light.ComputeVisibility(time)
    scene.lights.append(
        SceneLight(
            light,
            name=_name(prim, "global"),
            color=tuple(float(c) for c in (usd_light.GetColorAttr().Get(time) or (1, 1, 1))),
            intensity=float(usd_light.GetIntensityAttr().Get(time) or 0.0),
            ambient_intensity=float(_shadowgeo(prim, "ambientIntensity", 0.0)),
            attenuation=tuple(float(a) for a in _shadowgeo(prim, "attenuation", (1.0, 0.0, 0.0))),
            beam_width=float(beam if beam is not None else math.pi / 4),
            on=visibility != UsdGeom.Tokens.invisible,
            global_=bool(_shadowgeo(prim, "global", True)),
            shadows=bool(shadow),
            shadow_intensity=float(_shadowgeo(prim, "shadowIntensity", 1.0)),
        )
    )
    return True


def read(path, **options) -> Scene:
    """Read a USD file into a :class:`Scene`.

    Parameters
    ----------
    path : str or Path
        ``.usda``, ``.usdc`` or ``.usd``.

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
        Missing or corrupt file, a layer outside the file's folder, or a mesh
        whose indices do not match its points.
    """
    path = Path(path)
    if options:
        raise SceneError(f"USD reader takes no options, got {sorted(options)}", path=str(path))
    if not path.is_file():
        raise SceneError("no such file", path=str(path))
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = _pxr()
    _check_layers(path)
    try:
        stage = Usd.Stage.Open(str(path))
    except Tf.ErrorException as error:
        raise SceneError(f"cannot open: {_first_line(error)}", path=str(path)) from None
    if stage is None:
        raise SceneError("cannot open", path=str(path))
    up = UsdGeom.GetStageUpAxis(stage)
    scene = Scene(
        path=str(path),
        up_axis="Z" if up == UsdGeom.Tokens.z else "Y",
        meters_per_unit=float(UsdGeom.GetStageMetersPerUnit(stage)),
    )
    # An animated stage reads at its first time sample; a static one at its defaults.
    time = Usd.TimeCode.EarliestTime()
    indices: list[int | None] = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        where = f"{prim.GetTypeName()} <{prim.GetPath()}>"
        if prim.IsA(UsdGeom.Mesh):
            imageable = UsdGeom.Imageable(prim)
            if imageable.ComputeVisibility(time) == UsdGeom.Tokens.invisible:
                continue
            if imageable.ComputePurpose() == UsdGeom.Tokens.guide:
                continue
            _read_mesh(scene, prim, path, time)
            indices.append(_shadowgeo(prim, "index"))
        elif prim.IsA(UsdGeom.Gprim):
            scene.warnings.append(f"{path.name}: skipped {where}: only meshes are read")
        elif prim.HasAPI(UsdLux.LightAPI) or prim.IsA(UsdLux.BoundableLightBase):
            if not _read_light(scene, prim, time):
                scene.warnings.append(f"{path.name}: skipped {where}: not a point, spot or sun")
    # Shapes shadowgeo wrote carry their place in the scene; others follow in file order.
    keys = [(0, index) if index is not None else (1, 0) for index in indices]
    order = sorted(range(len(keys)), key=keys.__getitem__)
    scene.shapes = [scene.shapes[i] for i in order]
    return scene
