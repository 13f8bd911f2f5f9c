"""Atomic output: write to a temporary file beside the target, then rename.

A writer that fails half-way (a full disk, a folder it may not write, a bug)
or is interrupted (``KeyboardInterrupt``, or SIGTERM, which the command line
unwinds the same way) leaves no partial file and no temporary one, and an
existing file at the target stays as it was until the new one is complete and
on disk. Two processes writing one target each write their own temporary file
and rename it over the target: it ends up as one of them, whole.

The temporary file is ``.<name>.<host>-<pid>-<random><suffix>``. A writer
killed outright (SIGKILL, a lost Dask worker, a power cut) cannot remove its
own; the name says whose it was, so :func:`remove_stale` removes those of
writers no longer alive on this machine, never a live writer's.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import secrets
import socket
import stat
from collections.abc import Iterable, Iterator
from pathlib import Path

__all__ = ["atomic_path", "remove_stale"]

# What follows ".<name>" in a temporary file's name: host tag, pid, random,
# then the suffix; or usd-core's own sibling temporary file, which Export
# writes first and renames to ours, our name with 6 random characters for
# the suffix (strace of usd-core 26.11): the same owner, so swept too.
_OWNER = re.compile(r"\.(?P<host>[0-9a-f]{8})-(?P<pid>[0-9]+)-[0-9a-f]{8}(\.[^.]*)?$")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; on success flush it to
    disk and rename it to ``path``, on failure or interrupt delete it.

    ``suffix`` defaults to the target's own, for libraries that pick a format
    from the file name (usd-core, trimesh).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_path(target) as temporary:
    ...     _ = temporary.write_text("done")
    >>> target.read_text()
    'done'
    """
    path = Path(path)
    own_suffix = path.suffix if suffix is None else suffix
    temporary = path.with_name(
        f".{path.name}.{_host_tag()}-{os.getpid()}-{secrets.token_hex(4)}{own_suffix}"
    )
    try:
        # created inside the try: an interrupt at any point from here removes it
        os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        yield temporary
        _flush_to_disk(temporary)
        # private (0600) while written; the output gets the mode an ordinary
        # open() would give it, or keeps the mode of the file it replaces
        os.chmod(temporary, _mode_for(path))
        os.replace(temporary, path)
    except BaseException:
        # the pid in the name is ours, so whatever is there is ours to remove
        with contextlib.suppress(FileNotFoundError):
            temporary.unlink()
        raise
    _flush_folder(path.parent)


def remove_stale(paths: Iterable[str | os.PathLike[str]]) -> list[Path]:
    """Remove the temporary files that writers of ``paths`` on this machine
    left when killed outright, and return them.

    A temporary file is stale when the process its name names is gone; those
    of live processes (another conversion writing the same file) and of other
    machines (workers on a shared file system) are kept. Each folder is
    listed once, so call it once for a batch's outputs, not per file.
    """
    names_in: dict[Path, set[str]] = {}
    for path in map(Path, paths):
        names_in.setdefault(path.parent, set()).add(path.name)
    host = _host_tag()
    removed = []
    for folder, names in names_in.items():
        try:
            entries = list(os.scandir(folder))
        except OSError:  # no folder, or one we cannot read: nothing we wrote is there
            continue
        for entry in entries:
            pid = _owner(entry.name, names, host)
            if pid is not None and not _alive(pid):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(entry.path)
                    removed.append(Path(entry.path))
    return removed


def _owner(name: str, targets: set[str], host: str) -> int | None:
    """The pid of the writer on this host whose temporary file of one of
    ``targets`` is called ``name``, or None."""
    for target in targets:
        prefix = f".{target}"
        if name.startswith(prefix):
            match = _OWNER.fullmatch(name, len(prefix))
            if match and match["host"] == host:
                return int(match["pid"])
    return None


def _alive(pid: int) -> bool:
    if pid <= 0:  # os.kill would mean a process group
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's: alive
        return True
    return True


def _host_tag() -> str:
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


def _flush_to_disk(path: Path) -> None:
    # without it a crash soon after the rename can leave the new name on an
    # empty file (the rename reaches the disk before the data)
    descriptor = os.open(path, os.O_RDONLY)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)


def _flush_folder(folder: Path) -> None:
    # the rename itself on disk; some file systems cannot sync a folder
    with contextlib.suppress(OSError):
        _flush_to_disk(folder)


def _mode_for(path: Path) -> int:
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except FileNotFoundError:
        mask = os.umask(0)
        os.umask(mask)
        return 0o666 & ~mask
