"""Every surface receives in the converter: the bundled terrain scene (an
ElevationGrid under a low sun, with a tower, a boulder and a pole) baked with no
flags, checked against rays cast to the sun and by the three validators."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from reference import segment_hits_mesh
from validators import gltf_problems, gltf_report, usd_errors
from x3d_schema import x3d_schema_errors

import shadowgeo as sg
from cli.main import main

ROOT = Path(__file__).resolve().parents[1]
TERRAIN = ROOT / "examples" / "scenes" / "terrain.x3d"


@pytest.fixture(scope="module")
def baked():
    scene = sg.load(TERRAIN)
    return scene, sg.add_shadows(scene)


def _surface_shadow(result: sg.Scene) -> sg.Shape:
    (shape,) = [s for s in result.shapes_with_role("shadow") if s.name.endswith("_surfaces")]
    return shape


def test_terrain_and_objects_receive(baked):
    scene, result = baked
    shadow = _surface_shadow(result)
    geometry = [s for s in scene.shapes if s.n_faces]
    names = [s.name for s in geometry]
    # Which shape each shadow triangle lies on: the nearest surface, by centroid.
    centroids = shadow.world_vertices[shadow.faces].mean(axis=1)
    meshes = [trimesh.Trimesh(s.world_vertices, s.faces, process=False) for s in geometry]
    distances = np.column_stack(
        [np.abs(trimesh.proximity.signed_distance(mesh, centroids)) for mesh in meshes]
    )
    on = np.argmin(distances, axis=1)
    lift = 1e-3 * sg.Tolerance.for_points(result.bounds).scale
    assert distances.min(axis=1).max() < 3 * lift  # every triangle lies on a surface
    received = set(on.tolist())
    terrain = int(np.argmax([s.n_faces for s in geometry]))
    assert terrain in received  # the hills
    assert len(received) >= 2, [names[i] for i in received]  # and at least one object


def test_shadowed_points_are_blocked_and_lit_points_are_not(baked):
    """Ray reference: the centre of each shadow triangle, pushed back onto its
    surface, sees the sun blocked by the scene; random terrain points outside
    the shadow see it (points near a shadow edge are left out)."""
    scene, result = baked
    sun = scene.lights[0].light
    geometry = [s for s in scene.shapes if s.n_faces]
    triangles = np.concatenate([s.world_vertices[s.faces] for s in geometry])
    far = 1e3 * sg.Tolerance.for_points(result.bounds).scale
    shadow = _surface_shadow(result)
    mesh = trimesh.Trimesh(shadow.world_vertices, shadow.faces, process=False)
    big = mesh.area_faces > np.percentile(mesh.area_faces, 50)
    inner = mesh.triangles_center[big]
    pushed = inner - mesh.face_normals[big] * 2e-3 * far / 1e3
    rng = np.random.default_rng(3)
    sample = rng.choice(len(pushed), size=min(300, len(pushed)), replace=False)
    # each ray: from the point towards the sun, far past the scene
    blocked = [
        segment_hits_mesh(pushed[[i]], pushed[i] - sun.direction * far, triangles)[0]
        for i in sample
    ]
    assert np.mean(blocked) > 0.97, np.mean(blocked)

    terrain = next(s for s in geometry if len(s.faces) > 500)
    ground = trimesh.Trimesh(terrain.world_vertices, terrain.faces, process=False)
    points, faces = trimesh.sample.sample_surface(ground, 1500, seed=5)
    facing = ground.face_normals[faces] @ -sun.direction > 0.05
    points = points[facing] + ground.face_normals[faces][facing] * 1e-6
    closest, distance, _ = trimesh.proximity.closest_point(mesh, points)
    clear = distance > 0.05  # away from the shadow mesh and its edges
    lit = [
        not segment_hits_mesh(points[[i]], points[i] - sun.direction * far, triangles)[0]
        for i in np.flatnonzero(clear)[:300]
    ]
    assert len(lit) > 100 and np.mean(lit) > 0.97, (len(lit), np.mean(lit))


def test_no_face_is_shadowed_twice(tmp_path):
    # The courtyard's ground is a planar receiver: the surface path leaves it out.
    scene = sg.load(ROOT / "examples" / "scenes" / "courtyard.x3d")
    result = sg.add_shadows(scene)
    planar = [s for s in result.shapes_with_role("shadow") if not s.name.endswith("_surfaces")]
    surface = [s for s in result.shapes_with_role("shadow") if s.name.endswith("_surfaces")]
    assert planar
    ground_height = 0.0
    for shape in surface:
        heights = shape.world_vertices[:, 1]
        assert not np.all(np.abs(heights - ground_height) < 0.05)


def test_a_plane_or_receiver_narrows_to_the_planar_path():
    scene = sg.load(TERRAIN)
    narrowed = sg.add_shadows(scene, plane=sg.Plane([0, 1, 0], 0.9))
    assert not [s for s in narrowed.shapes_with_role("shadow") if s.name.endswith("_surfaces")]
    off = sg.add_shadows(scene, surfaces=False)
    assert not [s for s in off.shapes_with_role("shadow") if s.name.endswith("_surfaces")]


def test_converted_terrain_passes_the_three_validators(tmp_path, x3d_schema, capsys):
    outputs = {}
    for suffix in (".x3d", ".glb", ".usda"):
        out = tmp_path / f"terrain{suffix}"
        assert main(["convert", str(TERRAIN), str(out)]) == 0
        outputs[suffix] = out
    capsys.readouterr()
    text = outputs[".x3d"].read_text()
    assert "shadow_sun_surfaces" in text
    assert x3d_schema_errors(outputs[".x3d"], x3d_schema) == []
    assert usd_errors(outputs[".usda"]) == []
    assert gltf_problems(gltf_report(outputs[".glb"]), warnings=False) == []
