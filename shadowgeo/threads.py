"""One BLAS thread for the scene pipeline.

numpy hands matrix products to its BLAS (OpenBLAS in numpy's wheels), which
starts a thread per core for a product of many rows. The products here are
thin, ``(n, 3) @ (3,)`` or ``(n, 4) @ (4, 4)``: memory-bound, so the extra
threads spin without shortening the call. Measured on a 2-core machine, the
shadows of a 1.3M-triangle mesh (``benchmarks/bench_scale.py``'s sphere)
took the same wall time either way and 0.2 s more CPU time with them; on a
Dask worker or beside other conversions those threads take cores that other
work needs. :func:`one_blas_thread` limits BLAS to one thread for the length
of a call and restores the caller's setting after it.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread"]


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS on one thread inside the ``with`` block (about 0.2 ms to enter;
    for scene-sized calls, not for every small product)."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
