"""shadowgeo: exact shadow geometry.

The public API is re-exported here and nowhere else.
"""

from __future__ import annotations

from .errors import GeometryError, SceneError
from .io import load, save
from .lights import DirectionalLight, DiskLight, Light, PointLight, RectLight, SpotLight
from .plane import Plane
from .projection import project_shadow, shadow_matrix
from .scene import Material, Scene, SceneLight, Semantics, Shape, Site, Viewpoint
from .scene.shadows import add_shadows
from .shadow import Shadow, ShadowDiagnostics
from .silhouette import Silhouette, silhouette
from .soft import SoftShadow, soft_shadow
from .soft_surface import SoftSurfaceShadow, soft_shadow_on_surface
from .sun import sun_direction
from .sunlight_surfaces import (
    SurfaceSunlight,
    surface_sun_study,
    surface_sun_study_by_day,
    surface_sunlight,
)
from .sunstudy import (
    DaySummary,
    SunStudies,
    SunStudy,
    sun_study,
    sun_study_by_day,
    sun_summaries_by_day,
)
from .surface import SurfaceShadow, shadow_on_surface
from .tolerance import Tolerance
from .topology import Caster, MeshLike, as_caster
from .viz import plot
from .volume import shadow_volume

__all__ = [
    "Caster",
    "DaySummary",
    "DirectionalLight",
    "DiskLight",
    "GeometryError",
    "Light",
    "Material",
    "MeshLike",
    "Plane",
    "PointLight",
    "RectLight",
    "Scene",
    "SceneError",
    "SceneLight",
    "Semantics",
    "Shadow",
    "ShadowDiagnostics",
    "Shape",
    "Silhouette",
    "Site",
    "SoftShadow",
    "SoftSurfaceShadow",
    "SpotLight",
    "SunStudies",
    "SunStudy",
    "SurfaceShadow",
    "SurfaceSunlight",
    "Tolerance",
    "Viewpoint",
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
    "soft_shadow",
    "soft_shadow_on_surface",
    "sun_direction",
    "sun_study",
    "sun_study_by_day",
    "sun_summaries_by_day",
    "surface_sun_study",
    "surface_sun_study_by_day",
    "surface_sunlight",
]

__version__ = "0.1.0"
