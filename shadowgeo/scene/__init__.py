"""Scene model: shapes with world transforms, materials, lights and names."""

from .model import Material, Scene, SceneLight, Semantics, Shape, Site, Viewpoint

__all__ = ["Material", "Scene", "SceneLight", "Semantics", "Shape", "Site", "Viewpoint"]
