"""Silhouettes and shadow volumes: cost next to manifold3d's ingest, one run.

Run from the repository root::

    python benchmarks/bench_volume.py            # full size (81,920 faces)
    python benchmarks/bench_volume.py --quick    # small meshes, for a smoke test

For each mesh, on the same input and in the same process, it times

* ``shadowgeo.silhouette`` and ``shadowgeo.shadow_volume`` with a point light,
  cold (a fresh mesh: the topology is built in the call) and warm (topology
  cached on the mesh, as for a second light);
* manifold3d's ingest of the same caster, ``Manifold(Mesh(...))``, which
  builds its own half-edge topology: the yardstick for "a warm volume costs
  no more than ingesting the caster";
* the planar shadow: ``project_shadow``'s automatic path (the silhouette loops
  of a closed caster) against ``method="triangles"`` (every triangle united),
  both warm, with their areas compared.

Each volume is checked as it is timed: manifold3d accepts it (``NoError``)
and trimesh finds it watertight. Times are medians.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import platform
import sys
from pathlib import Path

import manifold3d
import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from common import median_time, meshes  # noqa: E402

import shadowgeo  # noqa: E402
from shadowgeo import Plane, PointLight, project_shadow, shadow_volume, silhouette  # noqa: E402


def manifold_ingest(mesh: trimesh.Trimesh):
    return manifold3d.Manifold(
        manifold3d.Mesh(
            vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
            tri_verts=np.asarray(mesh.faces, dtype=np.uint32),
        )
    )


def volume_is_closed(volume: trimesh.Trimesh) -> bool:
    manifold = manifold3d.Manifold(
        manifold3d.Mesh64(
            vert_properties=np.ascontiguousarray(volume.vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(volume.faces, dtype=np.uint64),
        )
    )
    return bool(
        manifold.status() == manifold3d.Error.NoError
        and volume.is_watertight
        and volume.is_winding_consistent
        and volume.volume > 0
    )


def run(quick: bool, repeat: int) -> list[dict]:
    light = PointLight([0.4, 4.0, 0.3])
    plane = Plane([0.15, 1.0, -0.1], 2.5)  # tilted, about 2.5 below the meshes
    rows = []
    for name, mesh in list(meshes(quick).items())[:2]:  # icosphere, bumpy sphere
        label = f"{name}, {len(mesh.faces):,} faces"

        def fresh(mesh=mesh):
            return trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)

        shadow_volume(mesh, light)  # fill the topology cache
        ingest, _ = median_time(lambda m=mesh: manifold_ingest(m), repeat)
        volume_warm, volume = median_time(lambda m=mesh: shadow_volume(m, light), repeat)
        volume_cold, _ = median_time(lambda: shadow_volume(fresh(), light), repeat)
        outline_warm, outline = median_time(lambda m=mesh: silhouette(m, light), repeat)
        outline_cold, _ = median_time(lambda: silhouette(fresh(), light), repeat)
        fast, fast_shadow = median_time(lambda m=mesh: project_shadow(m, light, plane), repeat)
        union, union_shadow = median_time(
            lambda m=mesh: project_shadow(m, light, plane, method="triangles"),
            1 if not quick else repeat,
        )
        closed = volume_is_closed(volume)
        area_difference = abs(union_shadow.area - fast_shadow.area) / union_shadow.area
        details = f"{len(outline.edges):,} silhouette edges, {len(outline.loops)} loops"
        rows += [
            dict(mesh=label, method="manifold3d Manifold(Mesh) ingest", seconds=ingest, note=""),
            dict(
                mesh=label,
                method="shadowgeo silhouette (warm)",
                seconds=outline_warm,
                note=details,
            ),
            dict(mesh=label, method="shadowgeo silhouette (cold)", seconds=outline_cold, note=""),
            dict(
                mesh=label,
                method="shadowgeo shadow_volume (warm)",
                seconds=volume_warm,
                note=f"{len(volume.faces):,} faces, closed: {closed}",
                ratio=volume_warm / ingest,
            ),
            dict(
                mesh=label,
                method="shadowgeo shadow_volume (cold)",
                seconds=volume_cold,
                note="",
                ratio=volume_cold / ingest,
            ),
            dict(
                mesh=label,
                method="project_shadow, silhouette fast path (warm)",
                seconds=fast,
                note=f"area {fast_shadow.area:.12g}",
            ),
            dict(
                mesh=label,
                method='project_shadow method="triangles" (warm)',
                seconds=union,
                note=f"area rel. diff {area_difference:.1e}",
                speedup=union / fast,
            ),
        ]
    return rows


def table(rows: list[dict]) -> str:
    lines = [
        "| mesh | method | median ms | vs manifold3d ingest | fast path speed-up | notes |",
        "|---|---|---:|---:|---:|---|",
    ]
    for row in rows:
        ratio = f"{row['ratio']:.2f}x" if "ratio" in row else ""
        speedup = f"{row['speedup']:.0f}x" if "speedup" in row else ""
        lines.append(
            f"| {row['mesh']} | {row['method']} | {row['seconds'] * 1e3:.1f} | {ratio} "
            f"| {speedup} | {row['note']} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small meshes")
    parser.add_argument("--repeat", type=int, default=7, help="runs per timing (median)")
    args = parser.parse_args(argv)
    rows = run(args.quick, args.repeat)
    print(
        f"shadowgeo {shadowgeo.__version__}, "
        f"manifold3d {importlib.metadata.version('manifold3d')}, trimesh {trimesh.__version__}, "
        f"numpy {np.__version__}, Python {platform.python_version()}, {platform.machine()}"
    )
    print()
    print(table(rows))
    print()
    print(
        "vs manifold3d ingest: time / the ingest time of the same caster (target for the "
        "warm volume: <= 1). Fast path speed-up: triangle union time / fast path time "
        "(target >= 10)."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
