"""One mutant through ``shadowgeo convert`` or ``info`` (``cli.main``), and
the checks on what it did: its exit code, its input untouched, no file left
after a failure and one after a success, no NaN or inf written
(:mod:`fuzz.check_output`), and with ``--sun`` and ``--plane`` the textbook
shadow area (:mod:`fuzz.check_area`). And a known finding's reproducer
script, run for its signature."""

from __future__ import annotations

import contextlib
import hashlib
import io
import shutil
import traceback
import warnings
from pathlib import Path

from cli.main import main as cli_main

from .check_area import reference_area_problem
from .check_output import non_finite_in_output
from .results import BudgetExceeded, failure, signature_of


def run_script(source: str) -> dict:
    """A known finding's reproducer script, for its signature."""
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(source, "<finding>", "exec"), {"__name__": "__finding__"})
    except (BudgetExceeded, MemoryError):
        raise
    except Exception as error:  # noqa: BLE001 - the signature is what we want
        return failure(signature_of(error), traceback.format_exc(limit=-8))
    return {"ok": True, "signature": None, "detail": ""}


def run_converter(task: dict, scratch: Path) -> dict:
    folder = scratch / "run"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    source = folder / f"input{task['suffix']}"
    source.write_bytes(task["data"])
    before = hashlib.sha256(task["data"]).hexdigest()
    argv = [str(source) if a == "IN" else a for a in task["argv"]]
    target = None
    for index, argument in enumerate(argv):
        if argument.startswith("OUT"):
            target = folder / "out" / ("output" + argument[3:])
            argv[index] = str(target)
    stdout, stderr = io.StringIO(), io.StringIO()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                code = cli_main(argv)
        except SystemExit as error:
            code = error.code if isinstance(error.code, int) else 1
        except (BudgetExceeded, MemoryError):
            raise
        except Exception as error:  # noqa: BLE001 - any other exception is the finding
            return failure(signature_of(error), traceback.format_exc(limit=-8))
    numeric = sum(1 for w in caught if issubclass(w.category, RuntimeWarning))
    extra = {"code": code, "runtime_warnings": numeric}
    if hashlib.sha256(source.read_bytes()).hexdigest() != before:
        return failure("check:input-modified", **extra)
    if code not in (0, 1, 2):
        return failure(f"check:exit-code-{code}", stderr.getvalue()[-2000:], **extra)
    left = sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())
    left = [p for p in left if p != source.name]
    if code != 0 and left:
        return failure("check:output-after-failure", f"left behind: {left}", **extra)
    if code == 0 and target is not None:
        if left != [str(target.relative_to(folder))]:
            return failure("check:output-files", f"after success: {left}", **extra)
        problem = non_finite_in_output(target)
        if problem:
            return failure("check:non-finite-in-output", problem, **extra)
        if task.get("reference"):
            try:
                problem = reference_area_problem(source, task["argv"])
            except (BudgetExceeded, MemoryError):
                raise
            except Exception as error:  # noqa: BLE001 - the CLI passed, the library did not
                return failure(signature_of(error), traceback.format_exc(limit=-8), **extra)
            if problem:
                return failure("check:shadow-area-vs-reference", problem, **extra)
    return {"ok": True, "signature": None, "detail": stderr.getvalue()[-300:], **extra}
