"""usd-core's text parser held to a memory and time budget.

A malformed ``.usda`` can make usd-core's parser take gigabytes and minutes
before it reports the error: the fuzzing campaign found a 725 KB file (a few
bytes inserted into a long ``normals`` array) that took 7.8 GB and 71 CPU
seconds. The parser cannot be interrupted from Python, so each text layer is
first parsed in a forked child process whose address space and CPU time are
limited (:data:`~shadowgeo.limits.USD_TEXT_MEMORY` and friends); only a layer
the child parsed within them is opened by the caller. A crate (``.usdc``)
layer is read by offsets and is not checked. Where there is no ``fork``
(Windows), the check is skipped.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

from .. import limits
from ..errors import SceneError

_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
# Exit codes of the child: parsed, usd-core refused the file, out of budget.
_PARSED, _REFUSED, _EXHAUSTED = 0, 3, 4


def is_text_layer(path: Path) -> bool:
    """Whether ``path`` starts as a USD text layer does (``#usda``)."""
    try:
        with path.open("rb") as stream:
            return stream.read(5) == b"#usda"
    except OSError:
        return False


def parse_within_budget(path: Path) -> None:
    """Parse the text layer ``path`` in a child process held to the budget.

    Returns when it parsed. Raises :class:`SceneError` naming ``path`` with
    usd-core's own message when the parser refused the layer (within the
    budget usd-core reports running out of memory as such an error), and
    when the parse ran past the budget; the caller then never parses it
    unbounded."""
    if not hasattr(os, "fork") or not is_text_layer(path):
        return
    size = path.stat().st_size
    memory = limits.USD_TEXT_MEMORY + limits.USD_TEXT_MEMORY_PER_BYTE * size
    seconds = limits.USD_TEXT_SECONDS + size // limits.USD_TEXT_BYTES_PER_SECOND
    try:  # the address space the child starts with, which its limit adds to
        mapped = int(Path("/proc/self/statm").read_bytes().split()[0]) * _PAGE
    except (OSError, ValueError, IndexError):
        mapped = 0
    reading, writing = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        code = _EXHAUSTED
        try:
            os.close(reading)
            import resource

            from pxr import Sdf, Tf

            from .usd_layout import error_text

            resource.setrlimit(resource.RLIMIT_AS, (mapped + memory, mapped + memory))
            resource.setrlimit(resource.RLIMIT_CPU, (seconds, seconds + 1))
            try:
                code = _PARSED if Sdf.Layer.OpenAsAnonymous(str(path)) else _REFUSED
            except Tf.ErrorException as error:
                os.write(writing, error_text(error).encode("utf-8", "replace")[:4000])
                code = _REFUSED
            except MemoryError:
                code = _EXHAUSTED
        finally:
            os._exit(code)
    os.close(writing)
    with os.fdopen(reading, "rb") as stream:
        said = stream.read().decode("utf-8", "replace")
    _, status = os.waitpid(pid, 0)
    if os.WIFEXITED(status) and os.WEXITSTATUS(status) == _PARSED:
        return
    if os.WIFEXITED(status) and os.WEXITSTATUS(status) == _REFUSED:
        raise SceneError(f"not a USD file: {said}" if said else "not a USD file", path=str(path))
    if os.WIFSIGNALED(status) and os.WTERMSIG(status) not in (
        signal.SIGXCPU,
        signal.SIGKILL,
        signal.SIGABRT,
        signal.SIGSEGV,
    ):
        return  # interrupted from outside: the caller's own open decides
    raise SceneError(
        f"usd-core needs more than {memory / 2**30:.1f} GiB or {seconds} CPU seconds to "
        f"parse this {size:,}-byte text layer: refused (a malformed layer can make its "
        "parser take gigabytes; shadowgeo.limits.USD_TEXT_MEMORY)",
        path=str(path),
    )
