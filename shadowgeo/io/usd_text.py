"""usd-core's text parser held to a memory and time budget.

A malformed ``.usda`` can make usd-core's parser take gigabytes and minutes
before it reports the error: the fuzzing campaign found a 725 KB file (a few
bytes inserted into a long ``normals`` array) that took 7.8 GB and 71 CPU
seconds. The parser cannot be interrupted from Python, so each text layer is
first parsed by a fresh Python process whose address space and CPU time are
limited (:data:`~shadowgeo.limits.USD_TEXT_MEMORY` and friends); only a layer
it parsed within them is opened by the caller. A fresh process, not a fork:
usd-core's worker threads, once started, would leave a forked child waiting
on locks for ever. A text layer of at most
:data:`~shadowgeo.limits.USD_TEXT_CHECK_BYTES` is not checked (the child
costs about 0.35 s to start).

A crate (``.usdc``) layer is checked whatever its size: its values are read
lazily, and fuzzing found single corrupt bytes in a 3 KB crate that make
usd-core abort the whole process (SIGABRT) when a value is unpacked. The
child unpacks every value (``ExportToString``); a crate it could not read is
refused, and the caller never touches one that would abort it. Without the
``resource`` module (Windows) the check is skipped.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from .. import limits
from ..errors import SceneError

__all__ = ["parse_within_budget"]

# Exit codes of the child: parsed, usd-core refused the file, out of memory.
_PARSED, _REFUSED, _EXHAUSTED = 0, 3, 4
_CHILD = r"""
import os, resource, sys
from pxr import Sdf, Tf
memory, seconds, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
pages = int(open("/proc/self/statm").read().split()[0]) if os.path.exists("/proc/self/statm") else 0
mapped = pages * os.sysconf("SC_PAGE_SIZE")
resource.setrlimit(resource.RLIMIT_AS, (mapped + memory, mapped + memory))
resource.setrlimit(resource.RLIMIT_CPU, (seconds, seconds + 1))
try:
    layer = Sdf.Layer.OpenAsAnonymous(path)
    if layer and sys.argv[4] == "crate":
        layer.ExportToString()  # unpacks every value: a corrupt one aborts here
except Tf.ErrorException as error:
    lines = []
    for item in error.args:
        try:
            text = str(getattr(item, "commentary", item))
        except UnicodeDecodeError as problem:
            text = bytes(problem.object).decode("utf-8", "replace")
        lines += [line.strip() for line in text.splitlines() if line.strip()]
    sys.stdout.write(lines[-1] if lines else "")
    sys.exit(3)
except MemoryError:
    sys.exit(4)
sys.exit(0 if layer else 3)
"""


def _kind(path: Path) -> str:
    """``"text"`` or ``"crate"`` from the layer's first bytes, else ``""``."""
    try:
        with path.open("rb") as stream:
            start = stream.read(8)
    except OSError:
        return ""
    return "text" if start[:5] == b"#usda" else "crate" if start == b"PXR-USDC" else ""


def parse_within_budget(path: Path) -> None:
    """Read the layer ``path`` in a child process held to the budget: a text
    layer over :data:`~shadowgeo.limits.USD_TEXT_CHECK_BYTES`, and any crate
    with every value unpacked; other files are left to the caller's open.

    Returns when it parsed. Raises :class:`SceneError` naming ``path`` with
    usd-core's own message when the parser refused the layer (within the
    budget usd-core may report running out of memory as such an error), and
    when the parse ran past the budget; the caller then never parses it
    unbounded."""
    kind = _kind(path)
    if sys.platform == "win32" or not kind:
        return
    size = path.stat().st_size
    if kind == "text" and size <= limits.USD_TEXT_CHECK_BYTES:
        return
    memory = limits.USD_TEXT_MEMORY + limits.USD_TEXT_MEMORY_PER_BYTE * size
    seconds = limits.USD_TEXT_SECONDS + size // limits.USD_TEXT_BYTES_PER_SECOND
    command = [sys.executable, "-c", _CHILD, str(memory), str(seconds), str(path), kind]
    try:
        # one work thread: under the address-space limit, usd-core's thread
        # pool could not reserve its stacks and the child crashed on a sound crate
        child = subprocess.run(
            command,
            capture_output=True,
            timeout=4 * seconds + 30,
            env={**os.environ, "PXR_WORK_THREAD_LIMIT": "1"},
        )
    except subprocess.TimeoutExpired:
        code = -1
    else:
        code = child.returncode
    if code == _PARSED:
        return
    if code == _REFUSED:
        said = child.stdout.decode("utf-8", "replace").strip()
        raise SceneError(f"not a USD file: {said}" if said else "not a USD file", path=str(path))
    if code > 0 and code != _EXHAUSTED:
        return  # the check itself could not run (no usd-core there): the caller's open decides
    budget = f"{memory / 2**30:.1f} GiB or {seconds} CPU seconds"
    why = (
        f"usd-core stopped with signal {-code} (a corrupt file, or past {budget})"
        if code < -1
        else f"usd-core needs more than {budget}"
    )
    raise SceneError(
        f"{why} to read this {size:,}-byte {kind} layer: refused (a malformed layer can "
        "make usd-core take gigabytes or abort; shadowgeo.limits.USD_TEXT_MEMORY)",
        path=str(path),
    )
