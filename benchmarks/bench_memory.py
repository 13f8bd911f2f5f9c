"""Peak memory of the worst inputs: each through ``shadowgeo`` in a fresh
process, its peak RSS (``resource.getrusage``) against its size and the
budget (issue 34 item 4; ``shadowgeo.limits.MEMORY_BUDGET``).

Run from the repository root::

    python benchmarks/bench_memory.py            # writes its REPORT.md section
    python benchmarks/bench_memory.py --quick    # smaller meshes; print only

The bombs (DEF/USE ten deep, prototypes of a big mesh, the outsider's USE
chain, a glTF accessor claiming 30M points) must be refused at about the
memory of an empty scene; the meshes measure what a triangle costs at the
peak of a conversion (read, shadows added, written), the figure behind
``BYTES_PER_TRIANGLE``.
"""

from __future__ import annotations

import argparse
import base64
import json
import os
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

from common import cpu_model, write_section  # noqa: E402

from shadowgeo import limits  # noqa: E402

TITLE = "## Peak memory of the worst inputs"
USE_CHAIN = (
    ROOT.parent / "shared" / "findings" / "outsider-2" / "budget_cpu_USE_chain_under_node_limit"
)
# The child: the CLI under a CPU-time guard, then its own peak RSS and CPU time.
CHILD = """
import json, resource, sys
resource.setrlimit(resource.RLIMIT_CPU, (300, 300))
from cli.main import main
try:
    code = main(sys.argv[2:])
except SystemExit as stop:
    code = stop.code
usage = resource.getrusage(resource.RUSAGE_SELF)
# ru_maxrss keeps the parent's high-water mark across fork and exec: VmHWM is this image's
peak = [line for line in open("/proc/self/status") if line.startswith("VmHWM:")]
rss = int(peak[0].split()[1]) * 1024 if peak else usage.ru_maxrss * 1024
with open(sys.argv[1], "w") as report:
    json.dump({"code": code, "rss": rss, "cpu": usage.ru_utime + usage.ru_stime}, report)
"""


def use_nest(levels: int, bottom: str = "<Shape><Box/></Shape>") -> str:
    lines = [f'<Transform DEF="L0">{bottom}</Transform>']
    for level in range(1, levels + 1):
        uses = f'<Transform USE="L{level - 1}"/>' * 10
        lines.append(f'<Transform DEF="L{level}">{uses}</Transform>')
    return x3d("\n".join(lines))


def x3d(body: str) -> str:
    return f'<X3D version="4.0"><Scene>\n{body}\n</Scene></X3D>\n'


def grid(n: int) -> str:
    points = " ".join(f"{i} 0 {j}" for i in range(n + 1) for j in range(n + 1))
    quads = " ".join(
        f"{i * (n + 1) + j} {i * (n + 1) + j + 1} {(i + 1) * (n + 1) + j + 1} "
        f"{(i + 1) * (n + 1) + j} -1"
        for i in range(n)
        for j in range(n)
    )
    return (
        f'<Shape><IndexedFaceSet coordIndex="{quads}">'
        f'<Coordinate point="{points}"/></IndexedFaceSet></Shape>'
    )


def claiming_gltf(points: int) -> str:
    """A glTF of one triangle whose accessor claims ``points`` points."""
    data = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 0, 1)
    document = {
        "asset": {"version": "2.0"},
        "buffers": [
            {
                "byteLength": len(data),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
            }
        ],
        "bufferViews": [{"buffer": 0, "byteLength": len(data)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": points, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    return json.dumps(document)


def terrain(path: Path, side: int) -> int:
    """A bumpy terrain of ``side`` x ``side`` quads under a box, as .glb; its triangles."""
    mesh = trimesh.creation.box(extents=[side / 4, 4, side / 4])
    mesh.apply_translation([side / 2, 6, side / 2])
    x, z = np.meshgrid(np.arange(side + 1.0), np.arange(side + 1.0), indexing="ij")
    heights = 0.3 * np.sin(x / 7) * np.cos(z / 5)
    vertices = np.column_stack([x.ravel(), heights.ravel(), z.ravel()])
    corner = (np.arange(side)[:, None] * (side + 1) + np.arange(side)[None, :]).ravel()
    faces = np.concatenate(
        [
            np.column_stack([corner, corner + 1, corner + side + 2]),
            np.column_stack([corner, corner + side + 2, corner + side + 1]),
        ]
    )
    ground = trimesh.Trimesh(vertices, faces, process=False)
    trimesh.Scene([ground, mesh]).export(path)
    return len(faces) + 12


def cases(folder: Path, quick: bool) -> list[tuple[str, Path, list[str], str]]:
    """(name, input, extra arguments, what it stands for)."""
    made = []

    def write(name: str, text: str) -> Path:
        path = folder / name
        path.write_text(text)
        return path

    made.append(
        (
            "DEF/USE nest ten deep (each level USEs the one before 10 times)",
            write("nest.x3d", use_nest(10)),
            [],
            f"{12 * sum(10**k for k in range(11)):.2g} triangles",
        )
    )
    body = f'<ProtoDeclare name="Big"><ProtoBody>{grid(200)}</ProtoBody></ProtoDeclare>\n'
    made.append(
        (
            "PROTO of an 80,000-triangle grid, 1,000 instances",
            write("protos.x3d", x3d(body + '<ProtoInstance name="Big"/>\n' * 1000)),
            [],
            "8e+07 triangles",
        )
    )
    if (USE_CHAIN / "repro.x3dv").is_file():
        made.append(
            (
                "outsider-2 USE chain (empty Transforms, 10 USEs x 6 levels)",
                USE_CHAIN / "repro.x3dv",
                [],
                "1,234,567 Transforms to walk",
            )
        )
    made.append(
        (
            "glTF accessor claiming 30M points (one triangle's buffer)",
            write("claims.gltf", claiming_gltf(30_000_000)),
            [],
            "1e+07 triangles",
        )
    )
    budget_side = 47  # 1111 copies of 2 x 47 x 47 triangles: 4.9M, just under the budget
    made.append(
        (
            "DEF/USE nest of a grid just under the budget (1,111 copies)",
            write("under.x3d", use_nest(3, grid(16 if quick else budget_side))),
            ["--method", "planar"],
            f"{1111 * 2 * (16 if quick else budget_side) ** 2:,} triangles",
        )
    )
    for side in (100, 300) if quick else (300, 700):
        path = folder / f"terrain{side}.glb"
        triangles = terrain(path, side)
        made.append(
            (
                f"terrain of {triangles:,} triangles under a box",
                path,
                [],
                f"{triangles:,} triangles",
            )
        )
    return made


def run(source: Path, extra: list[str], folder: Path) -> dict:
    report = folder / "usage.json"
    report.unlink(missing_ok=True)
    out = folder / "out" / "result.glb"
    argv = ["convert", str(source), str(out), *extra]
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(report), *argv],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"},
        timeout=1800,
    )
    usage = json.loads(report.read_text()) if report.is_file() else {"code": done.returncode}
    usage["seconds"] = time.perf_counter() - started
    usage["message"] = (done.stderr.strip().splitlines() or [""])[-1]
    return usage


def outcome(usage: dict) -> str:
    if usage.get("code") == 0:
        return "converted"
    message = usage["message"]
    for budget in ("MAX_TRIANGLES", "MAX_VISITS", "MAX_PROTO_EXPANSIONS", "MAX_NODES"):
        if budget in message:
            return f"refused ({budget})"
    return f"exit {usage.get('code')}: {message[-80:]}"


def section(
    rows: list[list[str]], baseline: float, per_triangle: str, command: str, quick: bool
) -> str:
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT
    ).stdout.strip()
    lines = [
        TITLE,
        "",
        f"`{command}` at {commit} on {cpu_model()} (2 cores shared with other work), "
        f"{time.strftime('%Y-%m-%d')}{' (quick)' if quick else ''}. Each input goes through "
        "`shadowgeo convert IN out.glb` in a fresh process; peak RSS is the process's "
        "`VmHWM` (its `getrusage` `ru_maxrss` would keep this script's own, inherited "
        "through fork and exec), CPU its user + system time (`getrusage`). The budget is "
        f"`limits.MEMORY_BUDGET` = {limits.MAX_TRIANGLES:,} triangles x "
        f"{limits.BYTES_PER_TRIANGLE} bytes = {limits.MEMORY_BUDGET / 1e9:.1f} GB, estimated "
        "before the work (`shadowgeo/io/x3d/budget.py`, glTF accessor counts); the bombs are "
        f"refused at about the {baseline / 1e6:.0f} MB an empty scene takes.",
        "",
        "| input | file size | stands for | outcome | peak RSS | CPU s |",
        "|---|---|---|---|---|---|",
        *["| " + " | ".join(row) + " |" for row in rows],
        "",
        f"What a triangle costs at the peak: {per_triangle}. "
        "`BYTES_PER_TRIANGLE` (400) is that figure, so the budget's 2 GB is what the "
        "5,000,000 triangles of the triangle budget take as separate meshes. Copies of one "
        "mesh (DEF/USE, glTF nodes) share its arrays and take less (the nest just under the "
        "budget), but the estimate counts them all: the work on shadows grows with each.",
        "",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller meshes; print only")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    rows: list[list[str]] = []
    costs: list[tuple[int, float]] = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        empty = folder / "empty.x3d"
        empty.write_text(x3d("<Shape><Box/></Shape>"))
        baseline = float(run(empty, [], folder)["rss"])
        for name, source, extra, stands_for in cases(folder, args.quick):
            print(name, file=sys.stderr, flush=True)
            usage = run(source, extra, folder)
            rss = usage.get("rss")
            rows.append(
                [
                    name,
                    f"{source.stat().st_size / 1e3:,.1f} KB",
                    stands_for,
                    outcome(usage),
                    f"{rss / 1e6:,.0f} MB" if rss else "-",
                    f"{usage.get('cpu', float('nan')):.2f}",
                ]
            )
            if usage.get("code") == 0 and name.startswith("terrain"):
                costs.append((int(stands_for.split()[0].replace(",", "")), float(rss)))
    (small, small_rss), (big, big_rss) = costs[0], costs[-1]
    per_triangle = (
        f"{(big_rss - small_rss) / (big - small):.0f} bytes (the two terrains' difference in "
        f"peak RSS over their difference in triangles; {big_rss / big:.0f} bytes a triangle "
        "for the bigger one whole)"
    )
    command = "python benchmarks/bench_memory.py" + (" --quick" if args.quick else "")
    text = section(rows, baseline, per_triangle, command, args.quick)
    print(text)
    if not (args.quick or args.no_write):
        write_section(TITLE, text)
        print(f"wrote the section {TITLE[3:]!r} of benchmarks/REPORT.md", file=sys.stderr)


if __name__ == "__main__":
    main()
