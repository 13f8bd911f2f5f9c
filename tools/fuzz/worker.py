"""A worker process: it runs tasks one at a time under a CPU-time alarm and
an address-space limit, with its output to /dev/null, and sends back each
result."""

from __future__ import annotations

import contextlib
import ctypes
import os
import resource
import shutil
import signal
import tempfile
import time
import traceback
from pathlib import Path

from .converter import run_converter, run_script
from .geometry import run_geometry
from .results import BudgetExceeded, failure, signature_of
from .seeds import run_seed


def _alarm(signum, frame):
    raise BudgetExceeded()


def _die_with(parent: int) -> None:
    """Have the kernel kill this worker when the campaign dies (Linux's
    PR_SET_PDEATHSIG), so a campaign killed with SIGKILL, which cannot stop
    its workers itself, leaves none behind; elsewhere, nothing."""
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # it died before the call took hold
        os._exit(1)


_PR_SET_PDEATHSIG = 1


def worker_main(connection, memory_bytes: int, time_budget: float, parent: int) -> None:
    """Serve runs from ``connection`` until it sends None (or the campaign,
    process ``parent``, dies)."""
    _die_with(parent)
    # Its own process group: a Ctrl-C at the terminal reaches the campaign,
    # which stops and kills its workers, not the run in flight (the command
    # line would exit 130, a false finding).
    os.setpgid(0, 0)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    signal.signal(signal.SIGPROF, _alarm)
    scratch = Path(tempfile.mkdtemp(prefix="shadowgeo-fuzz-", dir=_scratch_root()))
    try:
        while True:
            task = connection.recv()
            if task is None:
                break
            if memory_bytes:  # the budget is per run, on top of what the process holds now
                limit = _vm_size() + memory_bytes
                resource.setrlimit(resource.RLIMIT_AS, (limit, resource.RLIM_INFINITY))
            started, cpu_started = time.perf_counter(), time.process_time()
            children_started = _children_cpu_seconds()
            signal.setitimer(signal.ITIMER_PROF, time_budget)  # CPU seconds
            try:
                if task["kind"] == "geometry":
                    result = run_geometry(task["case"])
                elif task["kind"] == "seed":
                    result = run_seed(task, scratch)
                elif task["kind"] == "script":
                    result = run_script(task["source"])
                else:
                    result = run_converter(task, scratch)
            except BudgetExceeded as error:
                result = failure(signature_of(error), traceback.format_exc(limit=-8))
            except MemoryError as error:
                result = failure(signature_of(error), traceback.format_exc(limit=-8))
            finally:
                signal.setitimer(signal.ITIMER_PROF, 0)
            result["seconds"] = time.perf_counter() - started
            # The alarm counts this process only; CPU spent by child processes
            # the run started and waited for (the USD text check) counts too.
            children = _children_cpu_seconds() - children_started
            result["cpu_seconds"] = time.process_time() - cpu_started + children
            if result["ok"] and result["cpu_seconds"] > time_budget:
                result = {
                    **failure(
                        "timeout (CPU with child processes)",
                        f"{result['cpu_seconds']:.1f} CPU-s, {children:.1f} of them in children",
                    ),
                    "seconds": result["seconds"],
                    "cpu_seconds": result["cpu_seconds"],
                }
            shutil.rmtree(scratch / "run", ignore_errors=True)
            connection.send(result)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _scratch_root() -> str | None:
    """Where runs write: /dev/shm (memory) when there is one, for the
    converter's atomic writes sync each output to disk, a wait on a real disk
    that is no part of what a run tests; else the usual temporary folder."""
    shm = Path("/dev/shm")
    return str(shm) if shm.is_dir() and os.access(shm, os.W_OK | os.X_OK) else None


def _children_cpu_seconds() -> float:
    """User and system CPU seconds of this process's waited-for children."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def cpu_seconds(pid: int) -> float:
    """User and system CPU seconds of process ``pid`` so far (0 when unknown)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _vm_size() -> int:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0
