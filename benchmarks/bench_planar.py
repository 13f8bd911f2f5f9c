"""Planar shadows: shadowgeo against its peers, time and area error, one run.

Run from the repository root::

    python benchmarks/bench_planar.py            # full size (81,920 faces)
    python benchmarks/bench_planar.py --quick    # small meshes, for a smoke test

For each mesh it times, on the same input and in the same process:

* ``shadowgeo.project_shadow`` with a point light on a tilted plane, cold (the
  mesh's topology computed in the call) and warm (topology cached);
* manifold3d: ``Manifold(Mesh)`` ingest, perspective ``warp`` onto the plane's
  frame, then ``project()`` -- the peer path that handles a point light -- timed
  with the ingest (to compare with shadowgeo cold) and with the mesh ingested
  once beforehand (to compare with shadowgeo warm);
* the textbook way: every triangle through the shadow matrix, ``shapely.union_all``;
* orthographic peers, which cannot do a point light, against shadowgeo with a
  directional light along the plane normal: ``trimesh.path.polygons.projected``
  and manifold3d's ``project()`` of the mesh rotated so the plane is XY.

Area error is relative to an exact reference: the convex hull of the vertex
images for a convex mesh, otherwise the union of every projected triangle by
shapely (GEOS, float64), which is exact to rounding. Times are medians.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import platform
import sys
from pathlib import Path

import manifold3d
import numpy as np
import shapely
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common import median_time, meshes  # noqa: E402

import shadowgeo  # noqa: E402
from shadowgeo import DirectionalLight, Plane, PointLight, project_shadow  # noqa: E402


def frame(plane: Plane) -> np.ndarray:
    """4x4 rotation taking the plane frame (u, v, normal) to (x, y, z)."""
    u, v = plane.basis
    rotation = np.eye(4)
    rotation[:3, :3] = np.vstack([u, v, plane.normal])
    return rotation


def project_points(points, light: PointLight, plane: Plane) -> np.ndarray:
    """Ray/plane intersection from the light through each point, in plane 2-D."""
    direction = points - light.position
    t = -(plane.signed_distance(light.position[None])[0]) / (direction @ plane.normal)
    return plane.to_2d(light.position + t[:, None] * direction)


def reference_area(mesh, convex: bool, light, plane) -> float:
    if isinstance(light, PointLight):
        uv = project_points(mesh.vertices, light, plane)
    else:
        uv = plane.to_2d(mesh.vertices)
    if convex:
        return shapely.MultiPoint(uv).convex_hull.area
    return shapely.union_all(shapely.polygons(uv[mesh.faces])).area


def textbook(mesh, light, plane):
    matrix = shadowgeo.shadow_matrix(plane, light)
    image = np.column_stack([mesh.vertices, np.ones(len(mesh.vertices))]) @ matrix.T
    uv = plane.to_2d(image[:, :3] / image[:, 3:])
    return shapely.union_all(shapely.polygons(uv[mesh.faces])).area


def manifold_ingest(mesh) -> manifold3d.Manifold:
    return manifold3d.Manifold(
        manifold3d.Mesh(
            vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
            tri_verts=np.asarray(mesh.faces, dtype=np.uint32),
        )
    )


def manifold_perspective(mesh, light, plane, manifold=None):
    """Ingest (unless ``manifold`` is given, as warm), warp, project."""
    manifold = manifold_ingest(mesh) if manifold is None else manifold
    position = light.position
    height = plane.signed_distance(position[None])[0]
    foot2d = plane.to_2d(position[None])[0]

    def warp(points):
        points = np.asarray(points, dtype=np.float64)
        distance = plane.signed_distance(points)
        image = position + (points - position) * (height / (height - distance))[:, None]
        uv = plane.to_2d(image) - foot2d
        return np.column_stack([uv, distance])

    warped = manifold.warp_batch(warp)
    return warped.project().area()


def manifold_orthographic(mesh, plane, manifold=None):
    manifold = manifold_ingest(mesh) if manifold is None else manifold
    return manifold.transform(frame(plane)[:3, :]).project().area()


def trimesh_orthographic(mesh, plane):
    polygon = trimesh.path.polygons.projected(mesh, normal=plane.normal, precise=True)
    return polygon.area


def run(quick: bool, repeat: int) -> list[dict]:
    plane = Plane([0.15, 1.0, -0.1], 2.5)  # tilted, about 2.5 below the meshes
    light = PointLight([0.4, 4.0, 0.3])
    ortho = DirectionalLight(-plane.normal)
    rows = []
    for name, mesh in meshes(quick).items():
        convex = name == "icosphere"
        exact = reference_area(mesh, convex, light, plane)
        exact_ortho = reference_area(mesh, convex, ortho, plane)

        def ours_cold(mesh=mesh):
            fresh = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
            return project_shadow(fresh, light, plane).area

        def ours_warm(mesh=mesh):
            return project_shadow(mesh, light, plane).area

        def ours_ortho(mesh=mesh):
            return project_shadow(mesh, ortho, plane).area

        project_shadow(mesh, light, plane)  # fill the topology cache
        ingested = manifold_ingest(mesh)  # manifold3d's own warm start
        entries = [
            ("shadowgeo project_shadow (warm)", "point", ours_warm, exact),
            ("shadowgeo project_shadow (cold)", "point", ours_cold, exact),
            (
                "manifold3d ingest+warp+project",
                "point",
                lambda m=mesh: manifold_perspective(m, light, plane),
                exact,
            ),
            (
                "manifold3d warp+project (ingested once)",
                "point",
                lambda m=mesh, g=ingested: manifold_perspective(m, light, plane, g),
                exact,
            ),
            (
                "textbook matrix + shapely.union_all",
                "point",
                lambda m=mesh: textbook(m, light, plane),
                exact,
            ),
            ("shadowgeo project_shadow (warm)", "ortho", ours_ortho, exact_ortho),
            (
                "manifold3d ingest+project",
                "ortho",
                lambda m=mesh: manifold_orthographic(m, plane),
                exact_ortho,
            ),
            (
                "manifold3d project (ingested once)",
                "ortho",
                lambda m=mesh, g=ingested: manifold_orthographic(m, plane, g),
                exact_ortho,
            ),
            (
                "trimesh polygons.projected",
                "ortho",
                lambda m=mesh: trimesh_orthographic(m, plane),
                exact_ortho,
            ),
        ]
        for method, kind, function, reference in entries:
            slow = "union_all" in method or "projected" in method
            seconds, area = median_time(function, 1 if slow and not quick else repeat)
            rows.append(
                {
                    "mesh": f"{name}, {len(mesh.faces):,} faces",
                    "light": kind,
                    "method": method,
                    "seconds": seconds,
                    "error": abs(area - reference) / reference,
                }
            )
    return rows


def table(rows: list[dict]) -> str:
    lines = [
        "| mesh | light | method | time (ms) | relative area error | time / shadowgeo warm |",
        "|---|---|---|---:|---:|---:|",
    ]
    baseline = {}
    for row in rows:
        if row["method"] == "shadowgeo project_shadow (warm)":
            baseline[(row["mesh"], row["light"])] = row["seconds"]
    for row in rows:
        ratio = row["seconds"] / baseline[(row["mesh"], row["light"])]
        lines.append(
            f"| {row['mesh']} | {row['light']} | {row['method']} | {1e3 * row['seconds']:.1f} "
            f"| {row['error']:.1e} | {ratio:.1f}x |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small meshes, fewer repeats")
    parser.add_argument("--repeat", type=int, default=7, help="runs per method (median)")
    args = parser.parse_args()
    print(
        f"shadowgeo {shadowgeo.__version__}, numpy {np.__version__}, "
        f"trimesh {trimesh.__version__}, "
        f"manifold3d {importlib.metadata.version('manifold3d')}, shapely {shapely.__version__}, "
        f"Python {platform.python_version()}, {platform.machine()}"
    )
    rows = run(args.quick, 3 if args.quick else args.repeat)
    print(table(rows))


if __name__ == "__main__":
    main()
