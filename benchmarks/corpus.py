"""What ``shadowgeo convert IN OUT`` (no flags) does with every file of the
shared corpus, and whether every output passes its validator: one table per
encoding, each with a summary line, then a summary table.

Every file under the corpus folders (``../shared/corpus/*``) is listed,
grouped by its extension (``.x3d``, ``.x3dv``, ``.wrl``, ``.json``, ...; a
``.gz`` keeps the extension before it), except documentation and media. Each
is converted exactly as ``shadowgeo convert IN OUT`` does (in this process,
through the command line's own ``main``), OUT in the input's own encoding
(``.x3d`` -> ``.x3d``, ``.x3dv`` -> ``.x3dv``, ``.wrl`` -> ``.wrl``, ``.json``
-> ``.x3dj``), and the output is validated:

- X3D XML against the X3D 4.0 XML schema;
- X3D JSON against the X3D 4.0 JSON schema (``iri`` formats asserted);
- ClassicVRML and VRML 97 read back with shadowgeo (the input's shapes and
  the shadows written, no more, no less), and their XML translation (the
  output loaded and saved as ``.x3d``) against the X3D 4.0 XML schema;
- for every ``--sample``-th file converted, also a ``.glb`` through the
  Khronos glTF validator and a ``.usda`` through ``pxr.UsdValidation``.

The fair rule for inputs that are invalid themselves (X3D 3.x files, Castle
Game Engine extensions such as ``Teapot`` or ``shadowCaster``): an output may
have the schema errors its input has (the input itself, or for ClassicVRML and
VRML 97 its XML translation), never a new one. Outcomes:

converted
    exit code 0, an output written;
clear error
    exit code 1 with one line naming the file (VRML 1.0 is refused so);
crash
    any traceback, an exit code 0 with no output, or more than ``--timeout``
    seconds;
validator failure
    converted, but an output fails its validator (as above).

Run from the repository root (no arguments needed; about 3 minutes)::

    python benchmarks/corpus.py [FOLDER ...] [--sample N] [--timeout SECONDS]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import re
import shutil
import signal
import sys
import tempfile
import time
import traceback
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from needs import TOOLS  # noqa: E402
from x3d_json_schema import json_schema_errors, json_validator  # noqa: E402
from x3d_schema import new_schema_errors, x3d_schema_errors  # noqa: E402

import shadowgeo as sg  # noqa: E402
from cli.main import main as shadowgeo_main  # noqa: E402
from shadowgeo.io.x3d.parse import read_bytes  # noqa: E402

SHARED = ROOT.parent / "shared"
XSD = ROOT / "tests" / "data" / "x3d-schema" / "x3d-4.0.xsd.gz"
JSON_SCHEMA = SHARED / "schemas" / "x3d" / "x3d-4.0-JSONSchema.json"
# Not scenes: documentation, licences and media that scenes refer to.
NOT_SCENES = {
    ".md", ".txt", ".html", ".htm", ".css", ".license", ".png", ".jpg", ".jpeg", ".gif",
    ".bmp", ".dds", ".ktx", ".ktx2", ".wav", ".ogg", ".mp3", ".mp4", ".bin",
}  # fmt: skip
# Each encoding's own output.
OUTPUT = {
    ".x3d": ".x3d", ".x3dz": ".x3d", ".x3d.gz": ".x3d", ".json": ".x3dj", ".x3dj": ".x3dj",
    ".x3dv": ".x3dv", ".x3dvz": ".x3dv", ".x3dv.gz": ".x3dv",
    ".wrl": ".wrl", ".wrz": ".wrl", ".wrl.gz": ".wrl",
}  # fmt: skip
COLUMNS = ["file", "shapes", "lights", "shadows", "notes", "outcome", "validated", "seconds"]
WROTE = re.compile(r"^wrote .*?: (\d+) planar shadow shape")


class _Timeout(Exception):
    pass


def encoding(path: Path) -> str:
    """The extension that names the file's encoding: ``.wrl.gz`` for a gzip
    file, else the last suffix (lower case)."""
    suffixes = [suffix.lower() for suffix in path.suffixes[-2:]]
    if len(suffixes) == 2 and suffixes[1] == ".gz":
        return "".join(suffixes)
    return path.suffix.lower() or "(none)"


def scene_files(folders: list[Path]) -> dict[str, list[Path]]:
    """Files under ``folders`` by encoding, sorted."""
    found: dict[str, list[Path]] = defaultdict(list)
    for folder in folders:
        for path in sorted(folder.rglob("*")):
            if path.is_file() and encoding(path) not in NOT_SCENES:
                found[encoding(path)].append(path)
    return dict(sorted(found.items()))


def is_vrml1(path: Path) -> bool:
    """Whether ``path`` is a VRML 1.0 file (outside X3D and VRML 97)."""
    try:
        return read_bytes(path).lstrip(b"\xef\xbb\xbf").startswith(b"#VRML V1.")
    except sg.SceneError:
        return False


def _alarm(signum, frame):
    raise _Timeout


def run_cli(argv: list[str], timeout: float) -> tuple[int | None, str, str]:
    """``shadowgeo ARGV`` in this process: (exit code, stdout, stderr); the
    code is None after a traceback (its last line in stderr) or a timeout."""
    stdout, stderr = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            code = shadowgeo_main(argv)
    except _Timeout:
        return None, stdout.getvalue(), f"more than {timeout:g} s"
    except BaseException as error:  # noqa: BLE001 -- a traceback is what is measured
        last = traceback.format_exception_only(type(error), error)[-1].strip()
        return None, stdout.getvalue(), last
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    return code, stdout.getvalue(), stderr.getvalue()


def convert(path: Path, out: Path, timeout: float) -> dict:
    """Run ``shadowgeo convert path out``; the row of the table (``kind`` is
    ``converted``, ``error`` or ``crash``)."""
    row = dict.fromkeys(COLUMNS, "-")
    out.unlink(missing_ok=True)
    start = time.perf_counter()
    code, stdout, stderr = run_cli(["convert", str(path), str(out)], timeout)
    row["seconds"] = f"{time.perf_counter() - start:.2f}"  # without the validation
    lines = stderr.splitlines()
    if code is None:
        row["kind"], row["outcome"] = "crash", f"crash: {stderr[:160]}"
        return row
    if code != 0 or not out.is_file():
        message = lines[-1] if lines else f"exit code {code}, no message"
        clear = code == 1 and len(lines) == 1 and path.name in message
        row["kind"] = "error" if clear else "crash"
        row["outcome"] = ("error: " if clear else "crash: ") + message.split(": ", 2)[-1][:160]
        return row
    row["kind"] = "converted"
    row["notes"] = str(sum(line.startswith("note: ") for line in lines))
    reported = WROTE.match(stdout.splitlines()[-1]) if stdout.strip() else None
    row["reported_shadows"] = int(reported.group(1)) if reported else None
    written = sg.load(out)
    geometry = written.shapes_with_role("geometry")
    shadows = written.shapes_with_role("shadow")
    row["shapes"] = f"{len(geometry)} ({sum(s.n_faces for s in geometry)} tri)"
    row["lights"] = str(len(written.lights))
    if any("a default sun casts" in line for line in lines):
        row["lights"] += " (+ default sun)"
    row["shadows"] = f"{len(shadows)} ({sum(s.n_faces for s in shadows)} tri)"
    row["outcome"] = "converts"
    if any("ground plane" in line for line in lines):
        row["outcome"] += " onto the ground"
    row["written"] = written
    return row


def _xsd_new(before: Path | None, after: Path) -> list[str]:
    errors_before = x3d_schema_errors(before, XSD) if before is not None else []
    return new_schema_errors(errors_before, x3d_schema_errors(after, XSD))


def validate(path: Path, out: Path, row: dict, scratch: Path) -> tuple[str, list[str]]:
    """Validate a converted file's output in its own encoding: (what was
    checked, problems)."""
    kind = OUTPUT.get(encoding(path), ".x3d")
    if kind == ".x3d":
        xml_input = path if encoding(path) in (".x3d", ".x3dz", ".x3d.gz") else None
        return "XSD", _xsd_new(xml_input, out)
    if kind == ".x3dj":
        validator = json_validator(str(JSON_SCHEMA))
        before = json_schema_errors(validator, path) if encoding(path) == ".json" else []
        return "JSON schema", new_schema_errors(before, json_schema_errors(validator, out))
    # ClassicVRML / VRML 97: read back, then its XML translation against the XSD.
    # The input copied beside the output, so both miss the same Inline files.
    problems, copy = [], scratch / ("input" + encoding(path))
    shutil.copyfile(path, copy)
    source = sg.load(copy)
    written = row["written"]
    n_geometry, n_shadows = (len(written.shapes_with_role(r)) for r in ("geometry", "shadow"))
    if n_geometry != len(source.shapes):
        problems.append(f"read back: {n_geometry} shapes, the input has {len(source.shapes)}")
    if row.get("reported_shadows") is not None and n_shadows != row["reported_shadows"]:
        problems.append(f"read back: {n_shadows} shadows, {row['reported_shadows']} written")
    translated_in, translated_out = scratch / "input.x3d", scratch / "output.x3d"
    sg.save(source, translated_in)
    sg.save(written, translated_out)
    problems += _xsd_new(translated_in, translated_out)
    return "read back, XSD of .x3d", problems


def sample_checks(path: Path, scratch: Path, timeout: float, gltf: bool) -> list[str]:
    """Convert ``path`` to ``.glb`` and ``.usda`` too and validate both."""
    from validators import gltf_problems, gltf_reports, usd_errors

    problems = []
    glb, usda = scratch / "sample.glb", scratch / "sample.usda"
    for target in (glb, usda):
        target.unlink(missing_ok=True)
        code, _, stderr = run_cli(["convert", str(path), str(target)], timeout)
        if code != 0:
            problems.append(f"{target.suffix}: exit code {code}: {stderr.strip()[-160:]}")
    if glb.is_file() and gltf:
        problems += [f"glTF: {p}" for p in gltf_problems(gltf_reports([glb])[0], warnings=False)]
    if usda.is_file():
        problems += [f"USD: {p}" for p in usd_errors(usda)]
    return problems


def summary(name: str, rows: list[dict]) -> dict:
    count = defaultdict(int)
    for row in rows:
        count[row["kind"]] += 1
    wrote = count["converted"] + count["invalid"]
    return {
        "encoding": name,
        "files": len(rows),
        "wrote output": wrote,
        "clear errors": count["error"],
        "crashes": count["crash"],
        "validator failures": count["invalid"],
        "%": f"{100 * wrote / max(len(rows), 1):.1f}",
    }


def print_table(columns: list[str], rows: list[dict]) -> None:
    print("| " + " | ".join(columns) + " |")
    print("|" + "|".join("---" for _ in columns) + "|")
    for row in rows:
        print("| " + " | ".join(str(row[c]).replace("|", "\\|") for c in columns) + " |")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "folders", nargs="*", type=Path, help="default: every folder of ../shared/corpus"
    )
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per file")
    parser.add_argument(
        "--sample", type=int, default=10, help="also .glb and .usda for every N-th file (0: none)"
    )
    args = parser.parse_args(argv)
    folders = args.folders or sorted(p for p in (SHARED / "corpus").glob("*") if p.is_dir())
    groups = scene_files(folders)
    if not groups:
        print(f"no files under {', '.join(map(str, folders))}", file=sys.stderr)
        return 1
    gltf = all(TOOLS[tool][0]() is not None for tool in ("node", "gltf-validator"))
    if not gltf:
        print("note: node or gltf-validator is absent: .glb samples are not validated")
    totals, all_rows, index = [], [], 0
    with tempfile.TemporaryDirectory() as folder:
        scratch = Path(folder)
        for name, files in groups.items():
            print(f"\n### {name}\n")
            print("| " + " | ".join(COLUMNS) + " |")
            print("|" + "|".join("---" for _ in COLUMNS) + "|")
            rows = []
            for path in files:
                out = scratch / ("out" + OUTPUT.get(name, ".x3d"))
                row = convert(path, out, args.timeout)
                base = next(f for f in folders if path.is_relative_to(f))
                row["file"] = f"`{base.name}/{path.relative_to(base)}`"
                row["vrml1"] = is_vrml1(path)
                if row["kind"] == "converted":
                    checked, problems = validate(path, out, row, scratch)
                    index += 1
                    if args.sample and index % args.sample == 1 % args.sample:
                        problems += sample_checks(path, scratch, args.timeout, gltf)
                        checked += ", .glb, .usda"
                    row["validated"] = checked
                    if problems:
                        row["kind"] = "invalid"
                        row["outcome"] += f"; {len(problems)} validator failures: {problems[0]}"
                row.pop("written", None)
                rows.append(row)
                cells = [str(row[c])[:220].replace("|", "\\|") for c in COLUMNS]
                print("| " + " | ".join(cells) + " |", flush=True)
            totals.append(summary(name, rows))
            all_rows += rows
            line = ", ".join(f"{value} {key}" for key, value in list(totals[-1].items())[1:-1])
            print(f"\n**{name}**: {line} ({totals[-1]['%']}% wrote an output)", flush=True)
    print("\n### Summary\n")
    print(
        "Validators: XSD (X3D 4.0) for .x3d and for the .x3d translation of .x3dv/.wrl outputs "
        "(no new error vs. the input's own), X3D 4.0 JSON schema for .x3dj, read back for "
        f".x3dv/.wrl; every {args.sample}-th converted file also to .glb (Khronos glTF "
        "validator) and .usda (pxr.UsdValidation).\n"
    )
    x3d_rows = [row for row in all_rows if not row["vrml1"]]
    totals.append(summary("all", all_rows))
    totals.append(summary("X3D + VRML 97 (no VRML 1.0)", x3d_rows))
    print_table(list(totals[0]), totals)
    last = totals[-1]
    print(
        f"\nX3D + VRML 97: {last['files']} files, {last['wrote output']} wrote an output "
        f"({last['%']}%), {last['clear errors']} clear errors, {last['crashes']} crashes, "
        f"{last['validator failures']} validator failures; "
        f"{len(all_rows) - len(x3d_rows)} VRML 1.0 files refused clearly"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
