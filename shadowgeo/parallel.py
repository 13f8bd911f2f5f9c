"""Dask, for jobs bigger than one process: sun studies and batch conversion.

Nothing here schedules work itself: :func:`client_for` only hands back a
``dask.distributed.Client`` for what the caller named, and closes what it
started. Dask is an extra: ``pip install "shadowgeo[dask]"``.
"""

from __future__ import annotations

import datetime as _dt
import logging
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from .sun import days

__all__ = ["client_for", "each_day"]


def _distributed() -> Any:
    try:
        import dask.distributed as distributed
    except ImportError:
        raise ImportError('parallel runs need Dask: pip install "shadowgeo[dask]"') from None
    return distributed


# The loggers a LocalCluster started here quiets, in its workers and, while it
# runs and shuts down, in this process: Dask's, and those of the event loop it
# runs on (tornado logs an exception in a callback at ERROR, as a traceback).
_QUIET_LOGGERS = ("distributed", "tornado", "tornado.application", "asyncio")


def _quiet() -> list[tuple[logging.Logger, int]]:
    """:data:`_QUIET_LOGGERS` set to CRITICAL in this process; each logger
    with the level it had."""
    loggers = [logging.getLogger(name) for name in _QUIET_LOGGERS]
    before = [(logger, logger.level) for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL)
    return before


@contextmanager
def _quiet_here() -> Iterator[None]:
    """:func:`_quiet` inside the block, the levels restored after it."""
    before = _quiet()
    try:
        yield
    finally:
        for logger, level in before:
            logger.setLevel(level)


def _quiet_workers(distributed: Any) -> Any:
    """A worker plugin that quiets (:func:`_quiet`) each worker process of a
    LocalCluster started here. ``silence_logs`` sets only the nanny's logger
    there, and when the cluster shuts down under an interrupt a worker's
    heartbeat can fail first, logging a traceback at ERROR that a user would
    read as a crash. A task's own error still reaches the caller through its
    future."""

    class QuietWorkers(distributed.WorkerPlugin):  # type: ignore[misc]
        name = "shadowgeo-quiet-workers"

        def setup(self, worker: Any) -> None:
            _quiet()

    return QuietWorkers()


@contextmanager
def client_for(scheduler: Any, *, workers: int | None = None) -> Iterator[Any]:
    """A Dask client for ``scheduler``, closed on exit if started here.

    ``scheduler`` is a ``Client`` (used as is, left open), a scheduler address
    such as ``"tcp://10.0.0.5:8786"`` (connected to, then disconnected), or
    ``"local"`` (a ``LocalCluster`` of ``workers`` single-threaded processes,
    one per core by default, started and shut down here).
    """
    distributed = _distributed()
    if isinstance(scheduler, distributed.Client):
        yield scheduler
        return
    if scheduler == "local":
        with _quiet_here():
            yield from _local_client(distributed, workers)
        return
    if not isinstance(scheduler, str) or not scheduler:
        raise ValueError(f"scheduler must be a Client, an address or 'local', got {scheduler!r}")
    with distributed.Client(scheduler) as client:
        yield client


def _local_client(distributed: Any, workers: int | None) -> Iterator[Any]:
    """A client of a LocalCluster of ``workers`` processes started here,
    its workers quieted (:func:`_quiet_workers`), shut down after."""
    cluster = distributed.LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        # a run's output is its progress and results: the nanny's loggers at the
        # level _quiet gives the others
        silence_logs=logging.CRITICAL,
    )
    try:
        with distributed.Client(cluster) as client:
            client.register_plugin(_quiet_workers(distributed))
            yield client
    finally:
        cluster.close()


def each_day(
    function: Callable[..., Any],
    shared: tuple[Any, ...],
    times: Sequence[_dt.datetime],
    *,
    tz: _dt.tzinfo | None,
    scheduler: Any,
    progress: Callable[[int, int], None] | None,
    name: str,
    options: dict[str, Any],
) -> dict[_dt.date, Any]:
    """``function(*shared, day_times, **options)`` for each calendar day of
    ``times`` (in ``tz``, UTC by default), in day order: one after another
    here when ``scheduler`` is None, else one Dask task a day (key
    ``name-day``) on :func:`client_for`'s client, ``shared`` sent to the
    workers once and each result fetched as it finishes and released at once
    (so the workers let go of it). ``progress(done, total)`` after each day."""
    chosen = {day: [times[i] for i in indices] for day, indices in days(times, tz).items()}
    if scheduler is None:
        results = {}
        for done, (day, day_times) in enumerate(chosen.items(), start=1):
            results[day] = function(*shared, day_times, **options)
            if progress:
                progress(done, len(chosen))
        return results
    as_completed = _distributed().as_completed
    with client_for(scheduler) as client:
        # each scattered as one object (a scattered tuple would travel as its items)
        # under keys of their own (hash=False): content-hashed keys are shared with an
        # earlier call of the same data, whose release as it returned lost them here
        sent = [client.scatter([value], broadcast=True, hash=False)[0] for value in shared]
        futures = {
            day: client.submit(function, *sent, day_times, key=f"{name}-{day}", **options)
            for day, day_times in chosen.items()
        }
        day_of = {future.key: day for day, future in futures.items()}
        finished: dict[_dt.date, Any] = {}
        for future in as_completed(list(futures.values())):
            finished[day_of[future.key]] = future.result()
            future.release()
            if progress:
                progress(len(finished), len(futures))
        return {day: finished[day] for day in futures}
