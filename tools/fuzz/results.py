"""What a run gives back: its result record, the signature a failure is
grouped by, and the exception the CPU-time alarm raises."""

from __future__ import annotations

import traceback
from pathlib import Path

from .inputs import ROOT


class BudgetExceeded(BaseException):
    """Raised by the alarm in a worker when a run exceeds its CPU-time budget."""


def signature_of(error: BaseException) -> str:
    """Exception type and the innermost frame inside shadowgeo or cli."""
    frames = traceback.extract_tb(error.__traceback__)
    where = "outside shadowgeo"
    for frame in reversed(frames):
        path = Path(frame.filename)
        for package in ("shadowgeo", "cli"):
            if package in path.parts and str(ROOT) in str(path):
                where = f"{path.relative_to(ROOT)}:{frame.name}"
                break
        else:
            continue
        break
    name = "timeout" if isinstance(error, BudgetExceeded) else type(error).__name__
    if isinstance(error, MemoryError):
        name = "memory budget (MemoryError)"
    return f"{name} @ {where}"


def failure(signature: str, detail: str = "", **extra) -> dict:
    return {"ok": False, "signature": signature, "detail": detail, **extra}
