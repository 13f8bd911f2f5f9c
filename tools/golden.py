"""Golden outputs of today's code, to check a refactoring changes no byte.

Run from the repository root::

    python tools/golden.py record tests/data/golden/manifest.json   # at the old commit
    python tools/golden.py compare tests/data/golden/manifest.json  # at the new one
    python tools/golden.py record /tmp/g.json --keep /tmp/g --check-determinism

``record`` computes every case (the bundled example scenes and 30 corpus
scenes converted to .x3d, .glb and .usda; the benchmark scenes and the pyramid
under a point, a spot and a directional light through ``project_shadow``, its
many-lights form, ``shadow_on_surface``, ``shadow_volume``, ``silhouette``; a
tiny ``sun_study``) and writes the manifest: the commit, and per case the
sha256 of each output file, or the area and the sha256 of each array of the
result. Each conversion runs twice and a case whose two runs differ is
reported; ``--check-determinism`` runs every case twice here and once more in
a fresh process with another hash seed. ``--keep DIR`` also writes each
case's files and an .npz of its arrays under DIR/<case id>/ for diffing.
``compare`` recomputes and prints, per case, identical, different (with the
area's change), not run (the corpus, ../shared/corpus, is absent) or new;
exit code 1 when any differs. The cases live in tools/golden/.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

# this repository's shadowgeo, not another checkout's installed in the environment
sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]

from golden import manifest  # noqa: E402


def computed(args: argparse.Namespace, repeat: bool) -> tuple[list, manifest.Run, Path | None]:
    corpus = manifest.corpus_folder()
    if corpus is None:
        print(
            "golden: no corpus at ../shared/corpus: the corpus cases are not run",
            file=sys.stderr,
        )
    cases = manifest.all_cases(corpus)
    if args.only:
        cases = [case for case in cases if any(part in case.id for part in args.only)]
    done = manifest.run(cases, corpus, repeat=repeat, keep=args.keep, progress=not args.quiet)
    return cases, done, corpus


def other_process(args: argparse.Namespace) -> dict:
    """The manifest of the same cases computed by a fresh process with another hash seed."""
    with tempfile.TemporaryDirectory(prefix="golden-") as folder:
        out = Path(folder) / "manifest.json"
        command = [sys.executable, __file__, "record", str(out), "--quiet"]
        for part in args.only or []:
            command += ["--only", part]
        environment = {**os.environ, "PYTHONHASHSEED": "4242"}
        subprocess.run(command, check=True, env=environment)
        return json.loads(out.read_text())


def record(args: argparse.Namespace) -> int:
    cases, done, corpus = computed(args, repeat=args.check_determinism)
    data = manifest.manifest(cases, done, corpus)
    unstable = [f"{case_id}: differs between two runs in one process" for case_id in done.unstable]
    if args.check_determinism:
        again = other_process(args)["cases"]
        unstable += [
            f"{case_id}: differs in another process ({manifest.difference(record, again[case_id])})"
            for case_id, record in data["cases"].items()
            if case_id in again and not manifest.same(record, again[case_id])
        ]
    data["nondeterministic"] = unstable
    manifest.write(args.manifest, data)
    dirty = ", dirty tree" if data["commit"]["dirty"] else ""
    print(
        f"golden: {len(data['cases'])} cases in {done.seconds:.1f} s, written to {args.manifest}"
        f" (commit {data['commit']['head'][:10]}{dirty})"
    )
    for line in unstable:
        print(f"golden: NONDETERMINISTIC {line}")
    return 1 if unstable else 0


def compare(args: argparse.Namespace) -> int:
    old = json.loads(args.manifest.read_text())
    cases, done, corpus = computed(args, repeat=False)
    new = manifest.manifest(cases, done, corpus)
    if args.only:
        old = {**old, "cases": {k: v for k, v in old["cases"].items() if k in new["cases"]}}
    lines, tally = manifest.table(old, new)
    print(
        f"old: {old['commit']['head'][:10]}  new: {new['commit']['head'][:10]}"
        f"{' (dirty tree)' if new['commit']['dirty'] else ''}"
    )
    for change in manifest.environment_changes(old, new):
        print(f"environment: {change}")
    print("\n".join(lines))
    print(", ".join(f"{count} {status}" for status, count in sorted(tally.items())))
    return 1 if tally.get("different", 0) else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="golden", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    for name, function, help_text in (
        ("record", record, "compute every case and write the manifest"),
        ("compare", compare, "recompute and compare with a manifest; exit 1 if any differs"),
    ):
        command = commands.add_parser(name, help=help_text)
        command.add_argument("manifest", type=Path, metavar="MANIFEST.json")
        command.add_argument(
            "--keep",
            type=Path,
            metavar="DIR",
            help="also write each case's files and arrays (.npz) under DIR",
        )
        command.add_argument(
            "--only",
            action="append",
            metavar="TEXT",
            help="only the cases whose id contains TEXT (repeatable)",
        )
        command.add_argument("--quiet", action="store_true", help="no line per case")
        command.set_defaults(func=function)
    commands.choices["record"].add_argument(
        "--check-determinism",
        action="store_true",
        help="run every case twice here and once more in a fresh process; report any that differ",
    )
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
