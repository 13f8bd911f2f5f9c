"""Seed files per encoding: the corpus's and the examples' scenes, and the
X3D ones written in the other formats."""

from __future__ import annotations

import gzip
import shutil
from collections import defaultdict
from pathlib import Path
from typing import TYPE_CHECKING

import shadowgeo

from .inputs import CITY_SEED_OBJECTS, ENCODINGS, EXAMPLES, MESH_SUFFIXES, SHARED, WRITTEN
from .mutate_city import subset

if TYPE_CHECKING:
    from .pool import Pool


def collect_seeds(pool: Pool, max_bytes: int, encodings=ENCODINGS) -> dict[str, list]:
    """Seed files per encoding: (name, content). Missing folders are skipped.
    City files (``.city.json``, ``.geojson``) seed their own encodings, a big
    one cut to its first objects.
    glb, glTF, USD and mesh (OBJ, STL, PLY, OFF) seeds are the X3D ones written by
    shadowgeo (meshes by trimesh), in a worker
    (the parent never starts USD's threads, so forking stays safe)."""
    seeds: dict[str, list[tuple[str, bytes]]] = defaultdict(list)
    roots = [p for p in (SHARED / "corpus", EXAMPLES) if p.is_dir()]
    for root in roots:
        for path in sorted(root.rglob("*")):
            suffix = path.suffix.lower().lstrip(".")
            if path.is_file() and suffix in ENCODINGS and path.stat().st_size <= max_bytes:
                seeds[suffix].append((str(path), path.read_bytes()))
    seeds.update(_city_seeds(roots, max_bytes, encodings))
    for name, data in seeds["x3d"]:
        seeds["x3dz"].append((name + ".gz", gzip.compress(data, mtime=0)))
    for name, data in seeds["json"]:
        seeds["x3dj"].append((name, data))
    tasks = [
        {"kind": "seed", "path": name, "suffix": ENCODINGS[encoding], "encoding": encoding}
        for name, _ in seeds["x3d"]
        for encoding in WRITTEN
        if encoding in encodings
    ]
    for task, result in pool.run(tasks):
        if result.get("data"):
            seeds[task["encoding"]].append((f"{task['path']} as {task['suffix']}", result["data"]))
    for encoding in WRITTEN:  # made in completion order: sort, to replay
        seeds[encoding] = sorted(seeds[encoding])
    return dict(seeds)


def _city_seeds(roots: list[Path], max_bytes: int, encodings) -> dict[str, list]:
    """Seeds of the city encodings asked for: (name, content) per encoding."""
    seeds: dict[str, list[tuple[str, bytes]]] = defaultdict(list)
    for root in roots:
        for path in sorted(root.rglob("*")):
            city = _city_seed(path, max_bytes)
            if city is not None and city[0] in encodings:
                seeds[city[0]].append((str(path), city[1]))
    return seeds


def _city_seed(path: Path, max_bytes: int) -> tuple[str, bytes] | None:
    """(encoding, seed) of a city file: the file, or a big one's first objects."""
    name = path.name.lower()
    encoding = "cityjson" if name.endswith(".city.json") else None
    encoding = "geojson" if name.endswith(".geojson") else encoding
    if encoding is None or not path.is_file():
        return None
    data = path.read_bytes()
    if len(data) > max_bytes:
        data = subset(data, encoding, CITY_SEED_OBJECTS) or b""
    return (encoding, data) if 0 < len(data) <= max_bytes else None


def run_seed(task: dict, scratch: Path) -> dict:
    """An X3D seed written in another format: its bytes when it loads, has
    shapes and fits in one file (an external .bin would not be mutated)."""
    folder = scratch / "run"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    target = folder / f"seed{task['suffix']}"
    try:
        scene = shadowgeo.load(task["path"])
        if scene.shapes and task["suffix"] in MESH_SUFFIXES:
            import trimesh

            meshes = [
                trimesh.Trimesh(shape.world_vertices, shape.faces, process=False)
                for shape in scene.shapes
                if len(shape.faces)
            ]
            trimesh.util.concatenate(meshes).export(target)
        elif scene.shapes:
            shadowgeo.save(scene, target)
    except (shadowgeo.SceneError, shadowgeo.GeometryError, OSError):
        pass
    files = list(folder.iterdir())
    data = target.read_bytes() if files == [target] else None
    return {"ok": True, "signature": None, "detail": "", "data": data}
