"""The fuzz tool's modules and its mutants, made again in a test.

Import from any test::

    from fuzz_replay import corpus_seeds, fuzz_module, written_mutant

``tools/fuzz/`` is the package ``tools/fuzz.py`` runs (``tools/`` is not a
package), so :func:`fuzz_module` puts ``tools/`` on the path first. A mutant
of the campaign is made again from the same seed files, encoding, index and
seed (``tools/fuzz/campaign.converter_task``), so a test replays exactly the
run that failed.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

from needs import SHARED, absent

ROOT = Path(__file__).resolve().parents[1]


def fuzz_module(name: str) -> ModuleType:
    """The module ``fuzz.NAME`` of ``tools/fuzz/``."""
    folder = str(ROOT / "tools")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module(f"fuzz.{name}")


class _NoWorkers:
    """The seeds read from the corpus need no worker: none may be asked for."""

    def run(self, tasks):
        assert not list(tasks)
        return iter(())


def corpus_seeds(encodings: list[str]) -> dict[str, list]:
    """The campaign's seed files of ``encodings`` (those read from the corpus,
    not written by a worker), as ``--max-seed-bytes``' default takes them;
    the test skips (fails under SHADOWGEO_REQUIRE_ALL) without the corpus."""
    if not (SHARED / "corpus").is_dir():
        absent("the fuzz seeds come from ../shared/corpus, which is missing")
    return fuzz_module("seeds").collect_seeds(_NoWorkers(), 64 << 10, encodings)


def written_mutant(
    seeds: dict[str, list], encoding: str, index: int, seed: int, folder: Path
) -> tuple[Path, list[str], dict]:
    """Mutant ``index`` of ``encoding`` at ``seed`` written to ``folder``, the
    command line the campaign ran it with (its output under ``folder/out``),
    and the task itself."""
    task = fuzz_module("campaign").converter_task(seeds, encoding, index, seed)
    source = folder / f"input{task['suffix']}"
    source.write_bytes(task["data"])
    argv = [str(source) if a == "IN" else a for a in task["argv"]]
    argv = [str(folder / "out" / ("output" + a[3:])) if a.startswith("OUT") else a for a in argv]
    return source, argv, task
