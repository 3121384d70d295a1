"""BLAS threads around loops of small dense problems.

Multithreaded OpenBLAS stalls on small matrices when the cores are shared: on the project's
2-core machine, the ASE chapter of ``python -m asekit reproduce`` took 8.4 s with two BLAS threads
and 2.5 s with one (issue 12), and a 140-box GAF database rebuild 2.4-5.5 s against 0.8-0.9 s.
The functions that loop over many small solves, matrix exponentials or eigenproblems
(frequency responses, closed-loop and free-response integration, p-k and root-locus sweeps,
rational-function fits, harmonic balance) therefore run on one BLAS thread, through
threadpoolctl; large single factorisations (a DLM matrix of 2000+ boxes) keep the user's
setting. One thread also makes those results independent of the thread count, bit for bit.
"""

from __future__ import annotations

import contextlib
import functools


def one_blas_thread():
    """A context in which BLAS / LAPACK run on one thread (threadpoolctl); the previous limits
    are restored on exit (contexts nest)."""
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=1, user_api="blas")


def blas_threads_for(size: int, threshold: int):
    """:func:`one_blas_thread` for a problem of ``size`` below ``threshold``, else a no-op
    context (large factorisations may use every thread)."""
    return one_blas_thread() if size < threshold else contextlib.nullcontext()


def small_dense(func):
    """Decorator: run ``func`` inside :func:`one_blas_thread` (about 0.5 ms per call)."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with one_blas_thread():
            return func(*args, **kwargs)
    return wrapper
