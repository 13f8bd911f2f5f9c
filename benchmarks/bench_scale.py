"""Scenes at scale: reading, shadowing and writing big scenes, next to trimesh and lxml.

Run from the repository root::

    python benchmarks/bench_scale.py            # full size, writes its REPORT.md section
    python benchmarks/bench_scale.py --quick    # small scenes, a smoke test (prints only)
    python benchmarks/bench_scale.py --scene "one mesh"   # one scene only (prints only)

It generates two scenes into a temporary folder, each as ``.x3d`` (one
IndexedTriangleSet per shape, written by lxml) and ``.glb`` (written by
trimesh):

* **one mesh**: an icosphere subdivided 8 times, 1,310,720 triangles;
* **many shapes**: 10,000 cylinders of 104 triangles (1,040,000 triangles)
  on a 100 x 100 grid.

Each case -- ``.x3d`` or ``.glb`` in, ``.glb`` or ``.x3d`` out -- runs in a
subprocess of its own (so that peak RSS, the process's VmHWM, is the
case's alone) and times ``shadowgeo.load``, ``add_shadows`` as ``shadowgeo
convert IN OUT`` calls it (no options: the default sun, receivers found
automatically, here the ground plane under the scene) and ``shadowgeo.save``
of the shadowed scene, and also the save of the scene without shadows and,
apart, ``add_shadows`` with the receiving plane y = 0 given (no search). The
peers run the same way on the same files, in the same run:

* **trimesh**: ``trimesh.load`` of the ``.glb`` + ``export`` to ``.glb`` --
  the yardstick for the end-to-end time;
* **lxml + numpy**: ``etree.parse`` of the ``.x3d`` (huge_tree) and every
  number attribute converted by ``np.fromstring`` -- the yardstick for the
  X3D load -- then the same numbers written back as X3D text (shortest
  round-trip digits, by orjson): with trimesh's load and export timed apart,
  the *format yardstick* of each case (read its input, write its output).

Times are CPU seconds of the process (the tools are single-threaded in these
steps), each step timed from a collected heap (:func:`started`), the least
of ``--repeat`` runs (3) of each case, taken in rounds (every case once,
peers among them, then again) so that a drift in the machine's speed weighs
on all alike. Ratios are shadowgeo
over peer, from one run: the machine may be shared, so absolute times are noisy
but the ratios are measured side by side. The memory
yardstick is the raw float64 vertex + int64 face arrays of the scene.
"""

from __future__ import annotations

import argparse
import gc
import json
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh
from common import write_section
from lxml import etree

ROOT = Path(__file__).resolve().parents[1]
TITLE = "## Scenes at scale: big files in and out"
PLANE = (0.0, 1.0, 0.0, 0.0)
# CPU time of the process (every thread): on a shared machine it wanders far
# less than wall time, and every tool measured is single-threaded in these
# steps, so for them it is the wall time of an idle machine.
clock = time.process_time


def started() -> float:
    """The clock at the start of a timed step, after a full collection: a
    collection of every object the imports made (30-40 ms here, found with
    ``gc.callbacks``) otherwise falls in whichever step first crosses the
    collector's threshold, by chance of what was allocated before it."""
    gc.collect()
    return clock()


def scenes(quick: bool) -> dict[str, list[trimesh.Trimesh]]:
    """The two scenes as lists of meshes in world coordinates."""
    sphere = trimesh.creation.icosphere(subdivisions=5 if quick else 8, radius=1.0)
    sphere.apply_translation([0.0, 2.0, 0.0])
    side = 10 if quick else 100
    cylinders = []
    for index in range(side * side):
        cylinder = trimesh.creation.cylinder(radius=0.3, height=1.0, sections=26)
        cylinder.apply_translation([index % side, 1.0, index // side])
        cylinders.append(cylinder)
    return {"one mesh": [sphere], "many shapes": cylinders}


def write_x3d(meshes: list[trimesh.Trimesh], path: Path) -> None:
    """One Shape with an IndexedTriangleSet per mesh (text written by numpy)."""
    root = etree.Element("X3D", version="4.0", profile="Interchange")
    scene = etree.SubElement(root, "Scene")
    for index, mesh in enumerate(meshes):
        shape = etree.SubElement(scene, "Shape", DEF=f"shape{index}")
        appearance = etree.SubElement(shape, "Appearance")
        etree.SubElement(appearance, "Material", diffuseColor="0.8 0.6 0.4")
        triangles = etree.SubElement(
            shape, "IndexedTriangleSet", index=" ".join(map(str, mesh.faces.ravel().tolist()))
        )
        etree.SubElement(
            triangles, "Coordinate", point=" ".join(map(repr, mesh.vertices.ravel().tolist()))
        )
    etree.ElementTree(root).write(str(path), xml_declaration=True, encoding="UTF-8")


def write_glb(meshes: list[trimesh.Trimesh], path: Path) -> None:
    scene = trimesh.Scene()
    for index, mesh in enumerate(meshes):
        scene.add_geometry(mesh, geom_name=f"shape{index}", node_name=f"shape{index}")
    scene.export(str(path))


# -- the cases, each run in a subprocess of its own ------------------------------------


def peak_mb() -> float:
    """This process's peak RSS in MB: VmHWM, which execve resets (Linux keeps
    ``getrusage``'s ru_maxrss across exec, so a child would report its
    parent's peak); ru_maxrss where /proc is missing."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def run_shadowgeo(source: str, target: str) -> dict:
    sys.path.insert(0, str(ROOT))
    import shadowgeo
    import shadowgeo.io.gltf_read  # noqa: F401  (the readers and writers imported up front,
    import shadowgeo.io.gltf_write  # noqa: F401  so that "base MB" holds all the code)
    try:
        import shadowgeo.io.x3d.read  # noqa: F401
        import shadowgeo.io.x3d.write  # noqa: F401
    except ImportError:  # (before the X3D modules were grouped: side_by_side's old commit)
        import shadowgeo.io.x3d_read  # noqa: F401
        import shadowgeo.io.x3d_write  # noqa: F401

    times = {"base MB": peak_mb()}
    start = started()
    scene = shadowgeo.load(source)
    times["load"] = clock() - start
    start = started()
    shadowgeo.save(scene, target)
    times["save (no shadows)"] = clock() - start
    times["peak MB (no shadows)"] = peak_mb()
    start = started()
    shadowed = shadowgeo.add_shadows(scene)  # as `shadowgeo convert IN OUT` does
    times["add_shadows"] = clock() - start
    start = started()
    shadowgeo.save(shadowed, target)
    times["save"] = clock() - start
    times["shadow shapes"] = sum(shape.role == "shadow" for shape in shadowed.shapes)
    times["peak MB"] = peak_mb()
    del shadowed
    start = started()
    shadowgeo.add_shadows(scene, plane=PLANE)  # the receiver given: no search
    times["add_shadows, plane given"] = clock() - start
    return times


def run_trimesh(source: str, target: str) -> dict:
    start = started()
    loaded = trimesh.load(source, force="scene")
    middle = clock()
    loaded.export(target)
    end = clock()
    return {"load + export": end - start, "load": middle - start, "export": end - middle}


def run_lxml(source: str, target: str) -> dict:
    """lxml's parse and numpy's reading of every number attribute, then the
    same numbers written back as X3D text (the shortest round-trip digits, by
    orjson when installed, else repr) into ``target``: what reading and
    writing the format costs at least."""
    start = started()
    parser = etree.XMLParser(huge_tree=True, resolve_entities=False, no_network=True)
    tree = etree.parse(source, parser)
    count = 0
    arrays = []
    for element in tree.iter("Coordinate", "IndexedTriangleSet"):
        text = element.get("point") if element.tag == "Coordinate" else element.get("index")
        numbers = np.fromstring(text.replace(",", " "), sep=" ")
        if element.tag == "IndexedTriangleSet":
            numbers = numbers.astype(np.int64)
        arrays.append((element.tag, numbers))
        count += numbers.size
    middle = clock()
    with open(target, "wb") as handle:
        handle.write(b"<X3D><Scene>")
        for tag, numbers in arrays:
            name = b"point" if tag == "Coordinate" else b"index"
            handle.write(b"<%s %s='%s'/>" % (tag.encode(), name, _number_text(numbers)))
        handle.write(b"</Scene></X3D>")
    end = clock()
    return {"parse + numbers": middle - start, "write numbers": end - middle, "numbers": count}


def _number_text(numbers: np.ndarray) -> bytes:
    try:
        import orjson
    except ImportError:
        return " ".join(map(repr, numbers.tolist())).encode()
    return orjson.dumps(numbers, option=orjson.OPT_SERIALIZE_NUMPY)[1:-1].replace(b",", b" ")


RUNNERS = {"shadowgeo": run_shadowgeo, "trimesh": run_trimesh, "lxml": run_lxml}


def best_of(runs: list[dict]) -> dict:
    """The least of each time over ``runs`` of one case, and the peak RSS (MB)
    of the run with the least total time."""
    best = min(runs, key=lambda run: sum(v for k, v in run.items() if "MB" not in k))
    for key in best:
        if "MB" not in key and isinstance(best[key], float):
            best[key] = min(run[key] for run in runs)
    return best


def _case(tool: str, source: Path, target: Path) -> dict:
    """Run one case in a fresh interpreter; its times and peak RSS (MB)."""
    code = (
        "import json, sys; sys.path.insert(0, sys.argv[1]); import bench_scale as b; "
        "r = b.RUNNERS[sys.argv[2]](sys.argv[3], sys.argv[4]); "
        "r.setdefault('peak MB', b.peak_mb()); "
        "print(json.dumps(r))"
    )
    here = str(Path(__file__).resolve().parent)
    done = subprocess.run(
        [sys.executable, "-c", code, here, tool, str(source), str(target)],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure(quick: bool, repeat: int = 1, only: str | None = None) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for name, meshes in scenes(quick).items():
            if only is not None and name != only:
                continue
            stem = folder / name.replace(" ", "_")
            write_x3d(meshes, stem.with_suffix(".x3d"))
            write_glb(meshes, stem.with_suffix(".glb"))
            raw = sum(mesh.vertices.nbytes + mesh.faces.astype(np.int64).nbytes for mesh in meshes)
            facts = {
                "scene": name,
                "shapes": len(meshes),
                "triangles": sum(len(mesh.faces) for mesh in meshes),
                "raw MB": raw / 2**20,
                "x3d MB": stem.with_suffix(".x3d").stat().st_size / 2**20,
                "glb MB": stem.with_suffix(".glb").stat().st_size / 2**20,
            }
            # Every case once a round, the peers among them: a machine whose
            # speed drifts over the minutes of a run weighs on all alike (run
            # one case's repeats after another's, and the ratios wandered by
            # 0.5 between runs of the same code).
            cases = {
                "trimesh": ("trimesh", stem.with_suffix(".glb"), folder / "peer.glb"),
                "lxml": ("lxml", stem.with_suffix(".x3d"), folder / "numbers.x3d"),
                **{
                    (source, target): (
                        "shadowgeo", stem.with_suffix(source), folder / f"out{target}"
                    )
                    for source in (".x3d", ".glb")
                    for target in (".glb", ".x3d")
                },
            }  # fmt: skip
            runs: dict = {key: [] for key in cases}
            for _ in range(repeat):
                for key, (tool, source_path, target_path) in cases.items():
                    runs[key].append(_case(tool, source_path, target_path))
            best = {key: best_of(each) for key, each in runs.items()}
            for source in (".x3d", ".glb"):
                for target in (".glb", ".x3d"):
                    rows.append(
                        {**facts, "in": source, "out": target, "ours": best[(source, target)],
                         "trimesh": best["trimesh"], "lxml": best["lxml"]}
                    )  # fmt: skip
                    print(_line(rows[-1]), flush=True)
    return rows


def _end_to_end(row: dict) -> float:
    ours = row["ours"]
    return ours["load"] + ours["add_shadows"] + ours["save"]


def _yardstick(row: dict) -> float:
    """What the peers take to read the input's format and write the output's:
    lxml's parse + numbers or trimesh's load, then the numbers written as X3D
    text or trimesh's export."""
    read = row["lxml"]["parse + numbers"] if row["in"] == ".x3d" else row["trimesh"]["load"]
    write = row["lxml"]["write numbers"] if row["out"] == ".x3d" else row["trimesh"]["export"]
    return float(read + write)


def _line(row: dict) -> str:
    ours = row["ours"]
    return (
        f"{row['scene']} {row['in']}->{row['out']}: load {ours['load']:.2f}s shadows "
        f"{ours['add_shadows']:.2f}s (plane given {ours['add_shadows, plane given']:.2f}s) "
        f"save {ours['save']:.2f}s, peak {ours['peak MB']:.0f} MB; "
        f"trimesh {row['trimesh']['load + export']:.2f}s, "
        f"lxml {row['lxml']['parse + numbers']:.2f}s, yardstick {_yardstick(row):.2f}s"
    )


def table(rows: list[dict]) -> str:
    lines = [
        "| scene | in → out | load (s) | add_shadows (s) | plane given (s) | save (s) "
        "| end-to-end (s) "
        "| without shadows (s) | trimesh load+export (s) | × trimesh | × trimesh, no shadows "
        "| lxml parse+numbers (s) | X3D load × lxml | format yardstick (s) | × yardstick "
        "| peak RSS (MB) | peak, no shadows (MB) | no shadows, above imports (MB) "
        "| × raw arrays |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        "---:|",
    ]
    for row in rows:
        ours, peer = row["ours"], row["trimesh"]["load + export"]
        plain = ours["load"] + ours["save (no shadows)"]
        parse = row["lxml"]["parse + numbers"]
        above = ours["peak MB (no shadows)"] - ours["base MB"]
        x3d_ratio = f"{ours['load'] / parse:.2f}" if row["in"] == ".x3d" else "—"
        lines.append(
            f"| {row['scene']} | {row['in']} → {row['out']} | {ours['load']:.2f} "
            f"| {ours['add_shadows']:.2f} | {ours['add_shadows, plane given']:.2f} "
            f"| {ours['save']:.2f} | {_end_to_end(row):.2f} "
            f"| {plain:.2f} | {peer:.2f} | {_end_to_end(row) / peer:.2f} | {plain / peer:.2f} "
            f"| {parse:.2f} | {x3d_ratio} | {_yardstick(row):.2f} "
            f"| {_end_to_end(row) / _yardstick(row):.2f} | {ours['peak MB']:.0f} "
            f"| {ours['peak MB (no shadows)']:.0f} | {above:.0f} | {above / row['raw MB']:.1f} |"
        )
    return "\n".join(lines)


def section(rows: list[dict], command: str) -> str:
    facts = {}
    for row in rows:
        facts.setdefault(row["scene"], row)
    scenes_text = "; ".join(
        f"**{name}**: {row['shapes']:,} shape(s), {row['triangles']:,} triangles, "
        f".x3d {row['x3d MB']:.0f} MB, .glb {row['glb MB']:.0f} MB, raw float64 vertices + "
        f"int64 faces {row['raw MB']:.0f} MB; trimesh peak {row['trimesh']['peak MB']:.0f} MB, "
        f"lxml peak {row['lxml']['peak MB']:.0f} MB"
        for name, row in facts.items()
    )
    return (
        f"{TITLE}\n\n"
        f"`{command}` (Python {platform.python_version()}, numpy {np.__version__}, "
        f"trimesh {trimesh.__version__}, lxml {etree.__version__}; times are CPU seconds of "
        "the process, the least of each case's runs, each run in a subprocess of its own, "
        "every case once a round, peers among them; the machine is shared, so read the "
        "ratios). "
        f"{scenes_text}.\n\n"
        "End-to-end = load + add_shadows + save of the shadowed scene, add_shadows as "
        "`shadowgeo convert IN OUT` calls it (default sun, receivers found automatically: "
        "here the ground plane under the scene); *plane given* is add_shadows onto y = 0, "
        "no search, timed apart; *without shadows* = load + save of the scene as read. "
        "The trimesh peer is "
        "`trimesh.load` + `export` of the same geometry's .glb; the X3D load yardstick is "
        "lxml's parse (huge_tree) plus `np.fromstring` of every number attribute. The *format "
        "yardstick* of a row is what the peers take to read its input and write its output: "
        "lxml's parse + numbers (.x3d) or trimesh's load (.glb), then the same numbers "
        "written back as X3D text with their shortest round-trip digits (.x3d; orjson) or "
        "trimesh's export (.glb); for .glb → .glb it is the trimesh peer. Peak RSS is the "
        "shadowgeo subprocess's: overall, and up to the save without shadows; *above imports* "
        "subtracts the RSS once shadowgeo and its readers and writers are imported, and "
        "*× raw arrays* divides that by the raw float64 vertex + int64 face arrays.\n\n"
        f"{table(rows)}\n"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small scenes; print only")
    parser.add_argument("--repeat", type=int, default=3, help="runs per case; the least time")
    parser.add_argument(
        "--scene", choices=["one mesh", "many shapes"], help="that scene only; print only"
    )
    arguments = parser.parse_args()
    rows = measure(arguments.quick, arguments.repeat, arguments.scene)
    command = "python benchmarks/bench_scale.py" + (" --quick" if arguments.quick else "")
    if arguments.repeat != 3:
        command += f" --repeat {arguments.repeat}"
    text = section(rows, command)
    print(text)
    if not arguments.quick and arguments.scene is None:
        write_section(TITLE, text)


if __name__ == "__main__":
    main()
