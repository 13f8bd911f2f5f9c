"""USD writer (``.usda`` text, ``.usdc`` binary, ``.usd`` binary) with usd-core.

The layout written, which :mod:`.usd_read` reads back, is described in
:mod:`.usd_layout`.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SceneError
from ..lights import DirectionalLight, DiskLight, PointLight, RectLight, SpotLight
from ..scene import Material, Scene, SceneLight, Shape
from ..scene.model import overview, rotate
from . import check_face_indices, look_rotation, up_and_units
from .atomic import atomic_path
from .usd_layout import error_text, pxr, set_custom, usd_text

__all__ = ["write"]


class _Names:
    """Valid, unique prim names per parent path."""

    def __init__(self) -> None:
        self.taken: dict[str, set[str]] = {}
        # the next suffix to try for each (parent, base): 10,000 shapes of one
        # name would otherwise each walk past every suffix taken before
        self.next: dict[tuple[str, str], int] = {}

    def child(self, parent: str, wanted: str | None, fallback: str) -> str:
        from pxr import Tf

        base = Tf.MakeValidIdentifier(usd_text(wanted)) if wanted else fallback
        taken = self.taken.setdefault(parent, set())
        name, count = base, self.next.get((parent, base), 1)
        while name in taken:
            name = f"{base}_{count}"
            count += 1
        self.next[parent, base] = count
        taken.add(name)
        return f"{parent}/{name}"


def _face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(3 m, 3) float32 unit normal of each face, once per corner (zero for a
    face without area)."""
    corners = vertices[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0)
    return np.repeat(normals, 3, axis=0).astype(np.float32)


def _matrix(transform: np.ndarray) -> Any:
    """Gf.Matrix4d of a (4, 4) column-vector transform (USD uses row vectors)."""
    from pxr import Gf

    return Gf.Matrix4d(np.asarray(transform, dtype=np.float64).T.tolist())


class _Writer:
    def __init__(self, scene: Scene) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        up, meters_per_unit = up_and_units(scene)
        self.scene = scene
        self.stage = Usd.Stage.CreateInMemory()
        UsdGeom.SetStageUpAxis(self.stage, UsdGeom.Tokens.y if up == "Y" else UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(self.stage, meters_per_unit)
        world = UsdGeom.Xform.Define(self.stage, "/World")
        self.stage.SetDefaultPrim(world.GetPrim())
        self.names = _Names()
        self.names.taken["/World"] = {"Looks"}
        self.looks: dict[tuple[Any, ...], object] = {}
        self.groups: dict[object, str] = {}

    def write_shapes(self) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        places = []
        for index, shape in enumerate(self.scene.shapes):
            parent = "/World"
            if shape.role != "geometry" or shape.group:
                parent = self._group_path(shape)
            places.append((parent, self.names.child(parent, shape.name, f"Shape_{index}")))
        self._declare(places)
        filled = {"/World"}
        for index, (shape, (parent, path)) in enumerate(
            zip(self.scene.shapes, places, strict=True)
        ):
            if parent not in filled:
                filled.add(parent)
                self._fill_group(shape, parent)
            # Group Xforms change the traversal order; keep the scene's.
            set_custom(self._mesh(shape, path), "index", Sdf.ValueTypeNames.Int, index)

    def _declare(self, places: list[tuple[str, str]]) -> None:
        """Every group's Xform and every shape's Mesh (``(parent, path)``
        each) declared in the layer first, in the order they come, in one
        change block. Defining them one by one through the stage recomposes
        the parent's children each time, so 10,000 meshes under one parent
        took seconds just to be defined (quadratic); the stage API that
        fills them in afterwards finds them defined, and the layer holds
        the same specs in the same order."""
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        layer, declared = self.stage.GetRootLayer(), set()
        with Sdf.ChangeBlock():
            for number, (parent, path) in enumerate(places):
                if parent != "/World" and parent not in declared:
                    declared.add(parent)
                    _declared(layer, parent, "Xform")
                _declared(layer, path, "Mesh")
                if number == 0:  # the first shape's look makes the scope of looks
                    _declared(layer, "/World/Looks", "Scope")

    def _group_path(self, shape: Shape) -> str:
        """The path of the Xform holding ``shape``'s light group, named at
        the group's first shape."""
        key = shape.group or (None, shape.role)
        if key not in self.groups:
            self.groups[key] = self.names.child("/World", _group_label(shape), "Group")
        return self.groups[key]

    def _fill_group(self, shape: Shape, path: str) -> None:
        """The Xform at ``path`` holding ``shape``'s light group's shadows;
        unnamed groups (one per role) get a display name but no
        ``shadowgeo:group``, so read back as None."""
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        prim = UsdGeom.Xform.Define(self.stage, path).GetPrim()
        prim.SetDisplayName(usd_text(_group_label(shape)))
        if shape.group:
            set_custom(prim, "group", Sdf.ValueTypeNames.String, usd_text(shape.group))

    def _mesh(self, shape: Shape, path: str) -> Any:
        """Define the shape's Mesh prim at ``path`` and return the prim."""
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        vertices = np.ascontiguousarray(shape.vertices, dtype=np.float64)
        faces = np.asarray(shape.faces, dtype=np.int64)
        if not np.all(np.isfinite(vertices)) or not np.all(np.isfinite(shape.transform)):
            raise SceneError("non-finite vertex or transform", node=f"shape {shape.name!r}")
        check_face_indices(shape)
        with np.errstate(over="ignore"):
            single = vertices.astype(np.float32)
        if not np.all(np.isfinite(single)):  # a float64 past ~3.4e38 becomes inf
            raise SceneError(
                "vertex past float32's range (about 3.4e38), which USD points hold",
                node=f"shape {shape.name!r}",
            )
        mesh = UsdGeom.Mesh.Define(self.stage, path)
        prim = mesh.GetPrim()
        if shape.name:
            prim.SetDisplayName(usd_text(shape.name))
        points = Vt.Vec3fArray.FromNumpy(single)
        mesh.CreatePointsAttr(points)
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
        indices = np.ascontiguousarray(faces.reshape(-1), dtype=np.int32)
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
        mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
        mesh.CreateDoubleSidedAttr(not shape.solid)
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        if len(vertices):
            mesh.CreateExtentAttr(UsdGeom.PointBased.ComputeExtent(points))
        if len(faces):
            # Flat shading, as glTF draws a mesh without normals and X3D a face
            # set with creaseAngle 0; renderers would otherwise smooth the corners.
            mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(_face_normals(vertices, faces)))
            mesh.SetNormalsInterpolation(UsdGeom.Tokens.faceVarying)
        set_custom(
            prim, "points", Sdf.ValueTypeNames.Point3dArray, Vt.Vec3dArray.FromNumpy(vertices)
        )
        set_custom(prim, "role", Sdf.ValueTypeNames.String, shape.role)
        if not shape.casts_shadow or shape.receives_shadow:
            set_custom(prim, "castsShadow", Sdf.ValueTypeNames.Bool, bool(shape.casts_shadow))
            set_custom(prim, "receivesShadow", Sdf.ValueTypeNames.Bool, bool(shape.receives_shadow))
        if not np.array_equal(shape.transform, np.eye(4)):
            mesh.AddTransformOp(UsdGeom.XformOp.PrecisionDouble).Set(_matrix(shape.transform))
        look = shape.material
        mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(
            Vt.Vec3fArray([Gf.Vec3f(*_float3(look.diffuse_color))])
        )
        mesh.CreateDisplayOpacityPrimvar(UsdGeom.Tokens.constant).Set(
            Vt.FloatArray([_float(1.0 - look.transparency)])
        )
        UsdShade.MaterialBindingAPI.Apply(prim).Bind(self._look(look))
        return prim

    def _look(self, look: Material) -> Any:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
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
                material.GetPrim().SetDisplayName(usd_text(look.name))
            shader = UsdShade.Shader.Define(self.stage, f"{path}/PreviewSurface")
            shader.CreateIdAttr("UsdPreviewSurface")
            color = Sdf.ValueTypeNames.Color3f
            shader.CreateInput("diffuseColor", color).Set(Gf.Vec3f(*_float3(look.diffuse_color)))
            shader.CreateInput("emissiveColor", color).Set(Gf.Vec3f(*_float3(look.emissive_color)))
            shader.CreateInput("opacity", Sdf.ValueTypeNames.Float).Set(
                _float(1.0 - look.transparency)
            )
            roughness = min(max(1.0 - look.shininess, 0.0), 1.0)
            shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(roughness)
            shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(0.0)
            output = shader.CreateOutput("surface", Sdf.ValueTypeNames.Token)
            material.CreateSurfaceOutput().ConnectToSource(output)
            self.looks[key] = material
        return self.looks[key]

    def write_lights(self) -> None:
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        for index, scene_light in enumerate(self.scene.lights):
            light = scene_light.light
            path = self.names.child("/World", scene_light.name, f"Light_{index}")
            usd_light, transform = _light_shape(self.stage, path, scene_light)
            prim = usd_light.GetPrim()
            if scene_light.name:
                prim.SetDisplayName(usd_text(scene_light.name))
            if isinstance(light, SpotLight) and scene_light.area is None:
                shaping = UsdLux.ShapingAPI.Apply(prim)
                shaping.CreateShapingConeAngleAttr(math.degrees(light.cut_off_angle))
                beam = min(max(scene_light.beam_width / light.cut_off_angle, 0.0), 1.0)
                shaping.CreateShapingConeSoftnessAttr(1.0 - beam)
                set_custom(prim, "beamWidth", Sdf.ValueTypeNames.Double, scene_light.beam_width)
                # The cone angle is float32 degrees; keep the exact radians too.
                set_custom(prim, "cutOffAngle", Sdf.ValueTypeNames.Double, light.cut_off_angle)
            if not isinstance(light, DirectionalLight) and math.isfinite(light.radius):
                set_custom(prim, "range", Sdf.ValueTypeNames.Double, float(light.radius))
            usd_light.CreateIntensityAttr(_float(scene_light.intensity))
            usd_light.CreateColorAttr(Gf.Vec3f(*_float3(scene_light.color)))
            shadow = UsdLux.ShadowAPI.Apply(prim)
            shadow.CreateShadowEnableAttr(bool(scene_light.runtime_shadows))
            if scene_light.baked:  # shadowgeo baked them and turned them off
                set_custom(prim, "shadowsBaked", Sdf.ValueTypeNames.Bool, True)
            set_custom(
                prim, "shadowIntensity", Sdf.ValueTypeNames.Double, scene_light.shadow_intensity
            )
            set_custom(
                prim, "ambientIntensity", Sdf.ValueTypeNames.Double, scene_light.ambient_intensity
            )
            attenuation = Gf.Vec3d(*scene_light.attenuation)
            set_custom(prim, "attenuation", Sdf.ValueTypeNames.Double3, attenuation)
            set_custom(prim, "global", Sdf.ValueTypeNames.Bool, bool(scene_light.global_))
            if not scene_light.on:
                usd_light.CreateVisibilityAttr(UsdGeom.Tokens.invisible)
            if not np.array_equal(transform, np.eye(4)):
                usd_light.AddTransformOp(UsdGeom.XformOp.PrecisionDouble).Set(_matrix(transform))

    def write_cameras(self) -> None:
        """A ``UsdGeom.Camera`` for each viewpoint (else the overview), in
        the stage's own frame; its vertical aperture gives the field of view
        at the default focal length (X3D's smaller angle: the vertical one)."""
        Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
        size = float(np.linalg.norm(np.subtract(*self.scene.bounds))) or 1.0
        for index, view in enumerate(self.scene.viewpoints or [overview(self.scene)]):
            path = self.names.child("/World", view.name, f"Camera_{index}")
            camera = UsdGeom.Camera.Define(self.stage, path)
            camera.CreateProjectionAttr(UsdGeom.Tokens.perspective)
            focal = camera.GetFocalLengthAttr().Get()
            vertical = 2 * focal * math.tan(view.field_of_view / 2)
            camera.CreateVerticalApertureAttr(vertical)
            camera.CreateHorizontalApertureAttr(vertical * _ASPECT)
            # a float2: a scene past 3.4e35 across would make its far end inf
            camera.CreateClippingRangeAttr(Gf.Vec2f(_float(size / 1000), _float(size * 1000)))
            transform = np.eye(4)
            transform[:3, :3] = np.column_stack(
                [rotate(view.orientation, axis) for axis in np.eye(3)]
            )
            transform[:3, 3] = view.position
            if not np.all(np.isfinite(transform)):
                raise SceneError(f"cannot write viewpoint {view.name!r}: not finite")
            camera.AddTransformOp(UsdGeom.XformOp.PrecisionDouble).Set(_matrix(transform))
            if view.name:
                camera.GetPrim().SetDisplayName(usd_text(view.name))
            if view.description:
                camera.GetPrim().SetDocumentation(usd_text(view.description))


# The picture's width over its height: usd-core's default apertures' (20.955 / 15.2908).
_ASPECT = 20.955 / 15.2908
# The largest finite float32 (USD float attributes).
_FLOAT32_MAX = float(np.finfo(np.float32).max)


def _float(value: float) -> float:
    """``value`` for a USD float (float32) attribute, held inside float32's
    finite range: a finite double past it (a light's intensity of -1e308 in
    a glTF) would be written as inf, which no reader takes back."""
    return min(max(float(value), -_FLOAT32_MAX), _FLOAT32_MAX)


def _float3(values: tuple[float, float, float]) -> tuple[float, float, float]:
    """:func:`_float` of each of three (a colour)."""
    return (_float(values[0]), _float(values[1]), _float(values[2]))


def _group_label(shape: Shape) -> str:
    """The display name of ``shape``'s light group: its name, or one per role."""
    return shape.group or f"shadowgeo {shape.role}s"


def write(scene: Scene, path: str | os.PathLike[str], **options: Any) -> None:
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
        writer.write_cameras()
    except SceneError as error:
        raise SceneError(error.message, path=str(path), node=error.node) from None
    Tf = pxr()[2]
    with atomic_path(path) as temporary:
        try:
            saved = writer.stage.GetRootLayer().Export(str(temporary))
        except Tf.ErrorException as error:  # a full disk: hundreds of lines, one kept
            message = error_text(error, first=True).rsplit(": '", 1)[-1].rstrip("'")
            raise SceneError(f"cannot write: {message}", path=str(path)) from None
        if not saved:
            raise SceneError("usd-core could not save the stage", path=str(path))


def _declared(layer: Any, path: str, kind: str) -> None:
    """A ``def`` prim spec of type ``kind`` at ``path`` in ``layer``."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    spec = Sdf.CreatePrimInLayer(layer, path)
    spec.specifier = Sdf.SpecifierDef
    spec.typeName = kind


def _light_shape(stage: Any, path: str, scene_light: SceneLight) -> tuple[Any, np.ndarray]:
    """The UsdLux light at ``path`` of the kind and size of ``scene_light``
    (a DistantLight, a SphereLight, or a RectLight or DiskLight), and its
    (4, 4) transform (UsdLux's lights shine along their local -Z)."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    light = scene_light.light
    if scene_light.area is not None:
        return _area_light(stage, path, scene_light.area)
    transform = np.eye(4)
    if isinstance(light, DirectionalLight):
        usd_light = UsdLux.DistantLight.Define(stage, path)
        usd_light.CreateAngleAttr(math.degrees(light.angle))  # (not the 0.53 default)
        if light.angle:  # float32 degrees: the exact radians too
            set_custom(usd_light.GetPrim(), "angle", Sdf.ValueTypeNames.Double, light.angle)
    else:
        usd_light = UsdLux.SphereLight.Define(stage, path)
        usd_light.CreateTreatAsPointAttr(light.source_radius == 0)
        usd_light.CreateRadiusAttr(_float(light.source_radius))
        if light.source_radius:  # float32: the exact value too
            set_custom(
                usd_light.GetPrim(), "sourceRadius", Sdf.ValueTypeNames.Double, light.source_radius
            )
        transform[:3, 3] = light.position
    if not isinstance(light, PointLight):
        transform[:3, :3] = look_rotation(light.direction)
    return usd_light, transform


def _area_light(stage: Any, path: str, light: RectLight | DiskLight) -> tuple[Any, np.ndarray]:
    """A UsdLux ``RectLight`` or ``DiskLight`` at ``path`` for ``light`` and its
    (4, 4) transform: UsdLux's lights emit along their local -Z, a
    rectangle's width along local X and its height along local Y, so local
    +Y is the light's ``up`` and -Z its ``direction``. The sizes are float32
    there: the exact values go beside them as custom attributes."""
    Gf, Sdf, Tf, Usd, UsdGeom, UsdLux, UsdShade, Vt = pxr()
    transform = np.eye(4)
    transform[:3, 3] = light.position
    if isinstance(light, RectLight):
        usd_light = UsdLux.RectLight.Define(stage, path)
        usd_light.CreateWidthAttr(float(light.width))
        usd_light.CreateHeightAttr(float(light.height))
        set_custom(usd_light.GetPrim(), "width", Sdf.ValueTypeNames.Double, light.width)
        set_custom(usd_light.GetPrim(), "height", Sdf.ValueTypeNames.Double, light.height)
        back = -light.direction
        transform[:3, :3] = np.column_stack([np.cross(light.up, back), light.up, back])
    else:
        usd_light = UsdLux.DiskLight.Define(stage, path)
        usd_light.CreateRadiusAttr(float(light.radius))
        set_custom(usd_light.GetPrim(), "sourceRadius", Sdf.ValueTypeNames.Double, light.radius)
        transform[:3, :3] = look_rotation(light.direction)
    return usd_light, transform
