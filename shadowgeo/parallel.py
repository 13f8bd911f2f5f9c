"""Dask, for jobs bigger than one process: sun studies and batch conversion.

Nothing here schedules work itself: :func:`client_for` only hands back a
``dask.distributed.Client`` for what the caller named, and closes what it
started. Dask is an extra: ``pip install "shadowgeo[dask]"``.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

__all__ = ["client_for", "results_as_they_finish"]

Key = TypeVar("Key", bound=Hashable)


def _distributed() -> Any:
    try:
        import dask.distributed as distributed
    except ImportError:
        raise ImportError('parallel runs need Dask: pip install "shadowgeo[dask]"') from None
    return distributed


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
        cluster = distributed.LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=40,  # logging.ERROR: a run's output is its progress and results
        )
        try:
            with distributed.Client(cluster) as client:
                yield client
        finally:
            cluster.close()
        return
    if not isinstance(scheduler, str) or not scheduler:
        raise ValueError(f"scheduler must be a Client, an address or 'local', got {scheduler!r}")
    with distributed.Client(scheduler) as client:
        yield client


def results_as_they_finish(
    futures: dict[Key, Any], progress: Callable[[int, int], None] | None = None
) -> dict[Key, Any]:
    """Each of ``futures``' results, fetched as it finishes and released at
    once (so the workers let go of it), keyed and ordered as ``futures``;
    ``progress(done, total)`` is called after each."""
    as_completed = _distributed().as_completed
    key_of = {future.key: key for key, future in futures.items()}
    finished: dict[Key, Any] = {}
    for future in as_completed(list(futures.values())):
        finished[key_of[future.key]] = future.result()
        future.release()
        if progress:
            progress(len(finished), len(futures))
    return {key: finished[key] for key in futures}
