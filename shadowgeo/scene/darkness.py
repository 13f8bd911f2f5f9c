"""How dark a baked shadow is drawn: the light's share of the receiver's lighting.

A browser darkens a shadow by taking away only the shadowing light's diffuse
light (X3D 4, and X_ITE's shader: the light's diffuse and specular term is
mixed towards black by ``shadowIntensity``); the other lights, the headlight,
every light's ambient term and the material's emissive colour still light the
receiver. A baked shadow is a black shape drawn over the receiver with opacity
``alpha``, so it shows as the browser's would when

    alpha = 1 - Y(min(S, 1)) / Y(min(L, 1))

at the receiver, with, per colour channel (``D`` the receiver's diffuse
colour, ``a`` its ambient intensity, ``E`` its emissive colour; for each light
``i`` that is on: colour ``c_i``, ``intensity I_i``, ``ambientIntensity A_i``,
``w_i`` its attenuation ``1 / max(k0 + k1 d + k2 d^2, 1)`` at distance ``d``
times a spot light's cone factor (1 inside ``beamWidth``, 0 beyond
``cutOffAngle``, linear between), 0 past its ``radius``; ``l_i`` the unit
vector towards it, ``n`` the receiver's normal facing the shadowing light ``k``;
the headlight ``H`` = 1 when on, ``v`` the first Viewpoint's direction, or
``|n . v|`` = 1 when the scene has none)::

    L = E + sum_i w_i c_i (A_i a D + I_i max(0, n . l_i) D) + H |n . v| D
    S = L - s_k w_k c_k I_k max(0, n . l_k) D

(``s_k`` the light's ``shadowIntensity``, ``Y`` the Rec. 709 luminance, the
``min(., 1)`` the display's clamp). Below the clamp this is the light's share
of the receiver's lighting::

    alpha = s_k * Y(w_k c_k I_k (n . l_k) D) / Y(L)

so a scene with exactly one light, no headlight, no ambient and no emissive
colour keeps ``alpha = s_k``. It is averaged over the shadow's triangles,
weighted by area. Specular light is left out (X3D's default material has
none). Every light that is on counts where it lights the receiver: a
non-global light (X3D's ``global="false"``) only within its scope
(:attr:`~.model.SceneLight.scope`, :func:`~.model.lights`), the headlight
everywhere. A light the scene does not hold (an extra light,
the default sun) lights nothing the browser draws; its shadows keep
``alpha = s_k``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..lights import DirectionalLight, SpotLight
from .model import Material, Scene, SceneLight, lights

__all__ = ["LUMINANCE", "Lighting", "Scopes", "shadow_darkness"]

# Where a shadow lies, for which lights reach it: the scopes
# (:attr:`~.model.Shape.scopes`) of its receiver, or of each triangle's
# receiving shape; None: every light reaches it.
Scopes = frozenset[int] | Sequence[frozenset[int]] | None

# Rec. 709 luminance weights of linear R, G, B.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
# A shadow's triangles are sampled evenly down to at most _MAX_POINTS, and to
# at most _PAIRS light-and-point pairs over the scene's lights (at least
# _MIN_POINTS): every shadow of every light is weighed, so each stays cheap.
_MAX_POINTS = 1024
_PAIRS = 1 << 18
_MIN_POINTS = 16


def shadow_darkness(
    scene_light: SceneLight,
    vertices: ArrayLike,
    faces: ArrayLike,
    lights: Sequence[SceneLight],
    *,
    headlight: bool = False,
    view: ArrayLike | None = None,
    material: Material | None = None,
    scopes: Scopes = None,
) -> float:
    """The opacity, in [0, 1], a black shadow of ``scene_light`` is drawn with
    (the formula is in the module notes).

    Parameters
    ----------
    scene_light : SceneLight
        The shadowing light.
    vertices : (n, 3) float64
        The shadow's vertices, world coordinates.
    faces : (m, 3) int64
        Its triangles.
    lights : sequence of SceneLight
        Every light of the scene (those off count nothing). When
        ``scene_light`` is not among them, its ``shadow_intensity``.
    headlight : bool
        The viewer carries X3D's headlight.
    view : (3,) float64, optional
        The direction the viewer looks along; None: straight onto the receiver.
    material : Material, optional
        The receiver's; default: X3D's default Material.
    scopes : frozenset of int, or (m,) sequence of them, optional
        The receiver's :attr:`~.model.Shape.scopes`, or each triangle's: a
        light with a scope counts only where it is among them. None: every
        light counts everywhere.

    Returns
    -------
    float

    Examples
    --------
    Two lights straight above a floor, intensities 0.25 and 0.75: each one's
    shadow takes away its share of the light, 1/4 and 3/4. With intensities
    1 and 3 the floor is lit past white by either alone: the browser shows
    the dimmer one's shadow not at all.

    >>> from shadowgeo import DirectionalLight
    >>> floor = [[0, 0, 0], [1, 0, 0], [0, 0, 1]], [[0, 2, 1]]
    >>> dim = SceneLight(DirectionalLight([0, -1, 0]), intensity=0.25)
    >>> bright = SceneLight(DirectionalLight([0, -1, 0]), intensity=0.75)
    >>> round(shadow_darkness(dim, *floor, [dim, bright]), 12)
    0.25
    >>> round(shadow_darkness(bright, *floor, [dim, bright]), 12)
    0.75

    Out of the bright light's scope, the dim one is the floor's only light:

    >>> bright.scope = 7
    >>> round(shadow_darkness(dim, *floor, [dim, bright], scopes=frozenset()), 12)
    1.0
    """
    shadow = float(np.clip(scene_light.shadow_intensity, 0.0, 1.0))
    if not any(light is scene_light for light in lights) or not scene_light.on:
        return shadow
    shining = [light for light in lights if light.on]
    points, normals, areas, picked = _samples(vertices, faces, scene_light, len(shining))
    if not areas.sum() > 0:
        return shadow
    material = material or Material()
    diffuse = np.asarray(material.diffuse_color, dtype=np.float64)
    lit = np.tile(np.asarray(material.emissive_color, dtype=np.float64), (len(points), 1))
    own = np.zeros_like(lit)
    for light, inside in zip(shining, _in_scope(shining, scopes, picked), strict=True):
        weight, facing = _reach(light, points, normals)
        weight = weight * inside
        color = np.asarray(light.color, dtype=np.float64)
        ambient = light.ambient_intensity * material.ambient_intensity
        direct = weight * light.intensity * facing
        lit += np.outer(weight * ambient + direct, color * diffuse)
        if light is scene_light:
            own = np.outer(direct, color * diffuse)
    if headlight:
        toward = (
            np.ones(len(points))
            if view is None
            else np.abs(normals @ _unit(np.asarray(view, dtype=np.float64)))
        )
        lit += np.outer(toward, diffuse)
    shadowed = lit - shadow * own
    shown = np.minimum(lit, 1.0) @ LUMINANCE
    dark = np.minimum(np.maximum(shadowed, 0.0), 1.0) @ LUMINANCE
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(shown > 0, 1.0 - dark / shown, shadow)
    return float(np.clip((alpha * areas).sum() / areas.sum(), 0.0, 1.0))


@dataclass(frozen=True)
class Lighting:
    """What lights a scene's receivers in the browser: its lights, whether the
    viewer carries a headlight, and the direction of its first Viewpoint
    (None when it has none)."""

    lights: tuple[SceneLight, ...]
    headlight: bool
    view: np.ndarray | None

    @classmethod
    def of(cls, scene: Scene) -> Lighting:
        view = scene.viewpoints[0].direction if scene.viewpoints else None
        return cls(tuple(scene.lights), scene.headlight, view)

    def darkness(
        self,
        scene_light: SceneLight,
        vertices: ArrayLike,
        faces: ArrayLike,
        material: Material | None = None,
        scopes: Scopes = None,
    ) -> float:
        """:func:`shadow_darkness` of a shadow under this lighting."""
        return shadow_darkness(
            scene_light,
            vertices,
            faces,
            self.lights,
            headlight=self.headlight,
            view=self.view,
            material=material,
            scopes=scopes,
        )


def _unit(vector: np.ndarray) -> np.ndarray:
    length = float(np.linalg.norm(vector))
    return vector / length if length > 0 else vector


def _in_scope(
    shining: Sequence[SceneLight], scopes: Scopes, picked: np.ndarray
) -> list[np.ndarray]:
    """For each light, (k,) 1.0 where it lights the sampled triangles
    ``picked`` (indices into the shadow's), 0.0 where they lie outside its
    scope."""
    if scopes is None or isinstance(scopes, frozenset):
        return [np.full(len(picked), float(lights(light, scopes))) for light in shining]
    distinct: dict[frozenset[int], int] = {}
    which = np.array([distinct.setdefault(scopes[int(i)], len(distinct)) for i in picked])
    return [
        np.array([float(lights(light, known)) for known in distinct])[which]
        if len(which)
        else np.zeros(0)
        for light in shining
    ]


def _samples(
    vertices: ArrayLike, faces: ArrayLike, scene_light: SceneLight, n_lights: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Centroids (k, 3), unit normals facing ``scene_light`` (k, 3), areas
    (k,) and indices (k,) of the shadow's triangles, evenly sampled so that
    ``k`` times the number of lights stays within the budget."""
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    count = max(_MIN_POINTS, min(_MAX_POINTS, _PAIRS // max(n_lights, 1)))
    picked = np.arange(len(faces))
    if len(faces) > count:
        picked = np.linspace(0, len(faces) - 1, count).astype(np.int64)
        faces = faces[picked]
    corners = np.asarray(vertices, dtype=np.float64)[faces]
    points = corners.mean(axis=1)
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    doubled = np.linalg.norm(normals, axis=1)
    normals = normals / np.where(doubled > 0, doubled, 1.0)[:, None]
    light = scene_light.light
    if isinstance(light, DirectionalLight):
        toward = np.broadcast_to(-light.direction, points.shape)
    else:
        toward = light.position - points
    normals *= np.where(np.einsum("ij,ij->i", normals, toward) < 0, -1.0, 1.0)[:, None]
    return points, normals, doubled / 2, picked


def _reach(
    scene_light: SceneLight, points: np.ndarray, normals: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """For each point: the light's attenuation times its cone factor (0 past
    its radius), and ``max(0, n . l)``."""
    light = scene_light.light
    if isinstance(light, DirectionalLight):
        facing = np.maximum(normals @ -light.direction, 0.0)
        return np.ones(len(points)), facing
    offset = light.position - points
    distance = np.linalg.norm(offset, axis=1)
    towards = offset / np.where(distance > 0, distance, 1.0)[:, None]
    facing = np.maximum(np.einsum("ij,ij->i", normals, towards), 0.0)
    k0, k1, k2 = scene_light.attenuation
    weight = 1.0 / np.maximum(k0 + k1 * distance + k2 * distance**2, 1.0)
    weight = np.where(distance <= light.radius, weight, 0.0)
    if isinstance(light, SpotLight):
        angle = np.arccos(np.clip(-towards @ light.direction, -1.0, 1.0))
        cut_off = float(light.cut_off_angle)
        beam = min(float(scene_light.beam_width), cut_off)
        span = cut_off - beam
        with np.errstate(divide="ignore", invalid="ignore"):
            cone = np.where(angle <= beam, 1.0, (cut_off - angle) / span if span > 0 else 0.0)
        weight = weight * np.where(angle >= cut_off, 0.0, np.clip(cone, 0.0, 1.0))
    return weight, facing
