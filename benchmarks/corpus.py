"""What the converter does with every file of the shared corpus, as a table.

Each X3D file is read, given the shadows of its own lights (or, when it has
none, of a sun as ``--sun 0.3,-1,0.2`` gives) on the receivers found in it (or,
when none is found, on the plane y = 0: ``--plane 0,1,0,0``),
written back as X3D, and validated against the X3D 4.0 schema next to the
input (the corpus has X3D 3.x files with errors of their own: the output must
add none). Run from the repository root:

    python benchmarks/corpus.py [CORPUS] [--schema X3D_XSD]

CORPUS defaults to ../shared/corpus/castle-demo-models, the schema to
../shared/schemas/x3d/x3d-4.0.xsd.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from x3d_schema import new_schema_errors, x3d_schema_errors  # noqa: E402

import shadowgeo as sg  # noqa: E402

GROUND = (0.0, 1.0, 0.0, 0.0)
SUN = sg.SceneLight(sg.DirectionalLight([0.3, -1.0, 0.2]), name="sun", shadows=True)


def convert(path: Path, out: Path, schema: Path | None) -> dict:
    """Convert one file; returns the row of the table."""
    row = {"file": path, "shapes": "-", "lights": "-", "receivers": "-", "shadows": "-"}
    start = time.perf_counter()
    try:
        scene = sg.load(path)
        row["shapes"] = f"{len(scene.shapes)} ({sum(s.n_faces for s in scene.shapes)} tri)"
        row["lights"] = str(len(scene.lights))
        extra = [] if any(light.on for light in scene.lights) else [SUN]
        if extra:
            row["lights"] += " (--sun)"
        try:
            result = sg.add_shadows(scene, extra_lights=extra)
            row["receivers"] = "found"
        except sg.SceneError as error:
            if "no receiver found" not in error.message:
                raise
            result = sg.add_shadows(scene, plane=GROUND, extra_lights=extra)
            row["receivers"] = "plane y=0"
        added = result.shapes_with_role("shadow")
        row["shadows"] = f"{len(added)} ({sum(s.n_faces for s in added)} tri)"
        sg.save(result, out)
    except (sg.SceneError, sg.GeometryError) as error:
        row["outcome"] = f"fails: {getattr(error, 'message', str(error))}"
    else:
        row["outcome"] = "converts"
    row["seconds"] = f"{time.perf_counter() - start:.2f}"  # without the validation
    if row["outcome"] == "converts" and schema is not None:
        before = x3d_schema_errors(path, schema)
        new = new_schema_errors(before, x3d_schema_errors(out, schema))
        row["outcome"] += f", {len(new)} new schema errors (input has {len(before)})"
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    shared = ROOT.parent / "shared"
    parser.add_argument(
        "corpus", nargs="?", type=Path, default=shared / "corpus" / "castle-demo-models"
    )
    parser.add_argument("--schema", type=Path, default=shared / "schemas" / "x3d" / "x3d-4.0.xsd")
    args = parser.parse_args(argv)
    files = sorted(args.corpus.rglob("*.x3d")) + sorted(args.corpus.rglob("*.x3dz"))
    if not files:
        print(f"no X3D files under {args.corpus}", file=sys.stderr)
        return 1
    schema = args.schema if args.schema.is_file() else None
    columns = ["file", "shapes", "lights", "receivers", "shadows", "outcome", "seconds"]
    print("| " + " | ".join(columns) + " |")
    print("|" + "|".join("---" for _ in columns) + "|")
    with tempfile.TemporaryDirectory() as folder:
        for path in files:
            row = convert(path, Path(folder) / "out.x3d", schema)
            row["file"] = f"`{path.relative_to(args.corpus)}`"
            print("| " + " | ".join(str(row[c]) for c in columns) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
