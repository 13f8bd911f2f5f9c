"""Scene model: shapes with world transforms, materials, lights and names."""

from .model import Material, Scene, SceneLight, Shape, Viewpoint

__all__ = ["Material", "Scene", "SceneLight", "Shape", "Viewpoint"]
