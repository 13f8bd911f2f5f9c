"""What ``shadowgeo convert IN OUT`` (no flags) does with every file of the
shared corpus: one table per encoding, each with a summary line.

Every file under the corpus folders (``../shared/corpus/*``) is listed,
grouped by its extension (``.x3d``, ``.x3dv``, ``.wrl``, ``.json``, ...; a
``.gz`` keeps the extension before it), except documentation and media. Each
is converted exactly as ``shadowgeo convert IN OUT.x3d`` does (in this
process, through the command line's own ``main``), and the output is validated
against the X3D 4.0 schema: an X3D XML input's own schema errors do not count
(the corpus has X3D 3.x files with errors of their own), the output must add
none; other inputs' outputs must have none. Outcomes:

converted
    exit code 0, an output written;
clear error
    exit code 1 with one line naming the file (an encoding there is no reader
    for yet counts here);
crash
    any traceback, or more than ``--timeout`` seconds;
validator failure
    converted, but the output has schema errors the input does not have.

Run from the repository root (no arguments needed)::

    python benchmarks/corpus.py [FOLDER ...] [--schema X3D_XSD] [--timeout SECONDS]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import signal
import sys
import tempfile
import time
import traceback
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from x3d_schema import new_schema_errors, x3d_schema_errors  # noqa: E402

import shadowgeo as sg  # noqa: E402
from cli.main import main as shadowgeo_main  # noqa: E402

SHARED = ROOT.parent / "shared"
# Not scenes: documentation, licences and media that scenes refer to.
NOT_SCENES = {
    ".md", ".txt", ".html", ".htm", ".css", ".license", ".png", ".jpg", ".jpeg", ".gif",
    ".bmp", ".dds", ".ktx", ".ktx2", ".wav", ".ogg", ".mp3", ".mp4", ".bin",
}  # fmt: skip
COLUMNS = ["file", "shapes", "lights", "shadows", "notes", "outcome", "seconds"]


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


def _alarm(signum, frame):
    raise _Timeout


def convert(path: Path, out: Path, schema: Path | None, timeout: float) -> dict:
    """Run ``shadowgeo convert path out`` in this process; the row of the table."""
    row = dict.fromkeys(COLUMNS, "-")
    stdout, stderr = io.StringIO(), io.StringIO()
    out.unlink(missing_ok=True)
    start = time.perf_counter()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            code = shadowgeo_main(["convert", str(path), str(out)])
    except _Timeout:
        code, row["outcome"], row["kind"] = None, f"crash: more than {timeout:g} s", "crash"
    except BaseException as error:  # noqa: BLE001 -- a traceback is what is measured
        code, row["kind"] = None, "crash"
        last = traceback.format_exception_only(type(error), error)[-1].strip()
        row["outcome"] = f"crash: {last[:160]}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    row["seconds"] = f"{time.perf_counter() - start:.2f}"  # without the validation
    lines = stderr.getvalue().splitlines()
    if code is None:
        return row
    if code != 0:
        message = lines[-1] if lines else f"exit code {code}, no message"
        clear = code == 1 and len(lines) == 1 and path.name in message
        row["kind"] = "error" if clear else "crash"
        row["outcome"] = ("error: " if clear else "crash: ") + message.split(": ", 2)[-1][:160]
        return row
    row["kind"] = "converted"
    row["notes"] = str(sum(line.startswith("note: ") for line in lines))
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
    if schema is not None:
        before = x3d_schema_errors(path, schema) if encoding(path) in (".x3d", ".x3dz") else []
        new = new_schema_errors(before, x3d_schema_errors(out, schema))
        if new:
            row["kind"] = "invalid"
            row["outcome"] += f"; {len(new)} new schema errors: {new[0][:100]}"
    return row


def summary(name: str, rows: list[dict]) -> str:
    count = defaultdict(int)
    for row in rows:
        count[row["kind"]] += 1
    converted = count["converted"] + count["invalid"]
    return (
        f"**{name}**: {len(rows)} files, {converted} converted, {count['error']} clear errors, "
        f"{count['crash']} crashes, {count['invalid']} validator failures"
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "folders",
        nargs="*",
        type=Path,
        help="default: every folder of ../shared/corpus",
    )
    parser.add_argument("--schema", type=Path, default=SHARED / "schemas" / "x3d" / "x3d-4.0.xsd")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per file")
    args = parser.parse_args(argv)
    folders = args.folders or sorted(p for p in (SHARED / "corpus").glob("*") if p.is_dir())
    groups = scene_files(folders)
    if not groups:
        print(
            f"no files under {', '.join(map(str, folders)) or SHARED / 'corpus'}", file=sys.stderr
        )
        return 1
    schema = args.schema if args.schema.is_file() else None
    if schema is None:
        print(f"note: {args.schema} is absent: outputs are not validated", file=sys.stderr)
    totals = []
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "out.x3d"
        for name, files in groups.items():
            print(f"\n### {name}\n")
            print("| " + " | ".join(COLUMNS) + " |")
            print("|" + "|".join("---" for _ in COLUMNS) + "|")
            rows = []
            for path in files:
                row = convert(path, out, schema, args.timeout)
                base = next(f for f in folders if path.is_relative_to(f))
                row["file"] = f"`{base.name}/{path.relative_to(base)}`"
                rows.append(row)
                cells = [str(row[c]).replace("|", "\\|") for c in COLUMNS]
                print("| " + " | ".join(cells) + " |", flush=True)
            totals.append(summary(name, rows))
            print(f"\n{totals[-1]}", flush=True)
    print("\n### Summary\n")
    for line in totals:
        print(f"- {line}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
