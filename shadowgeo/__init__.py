"""shadowgeo: exact shadow geometry.

The public API is re-exported here and nowhere else.
"""

from __future__ import annotations

from .errors import GeometryError, SceneError
from .io import load, save
from .lights import DirectionalLight, PointLight, SpotLight
from .plane import Plane
from .projection import Shadow, ShadowDiagnostics, project_shadow, shadow_matrix
from .scene import Material, Scene, SceneLight, Shape
from .scene.shadows import add_shadows
from .silhouette import Silhouette, silhouette
from .surface import SurfaceShadow, shadow_on_surface
from .tolerance import Tolerance
from .topology import Caster, as_caster
from .viz import plot
from .volume import shadow_volume

__all__ = [
    "Caster",
    "DirectionalLight",
    "GeometryError",
    "Material",
    "Plane",
    "PointLight",
    "Scene",
    "SceneError",
    "SceneLight",
    "Shadow",
    "ShadowDiagnostics",
    "Shape",
    "Silhouette",
    "SpotLight",
    "SurfaceShadow",
    "Tolerance",
    "add_shadows",
    "as_caster",
    "load",
    "plot",
    "project_shadow",
    "save",
    "shadow_matrix",
    "shadow_on_surface",
    "shadow_volume",
    "silhouette",
]

__version__ = "0.1.0"
