"""asekit.util.blas: the one-BLAS-thread context and decorator restore the caller's setting."""

from threadpoolctl import threadpool_info, threadpool_limits

from asekit.util.blas import blas_threads_for, one_blas_thread, small_dense


def _blas_threads():
    return {m["filepath"]: m["num_threads"] for m in threadpool_info() if m["user_api"] == "blas"}


def test_small_dense_runs_on_one_thread_and_restores():
    import scipy.linalg  # noqa: F401  (scipy's own OpenBLAS loaded too)

    @small_dense
    def inside():
        return _blas_threads()

    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert set(inside().values()) == {1}
        with one_blas_thread():                                   # nests
            assert set(inside().values()) == {1}
        assert _blas_threads() == before
        with blas_threads_for(10, threshold=2000):
            assert set(_blas_threads().values()) == {1}
        with blas_threads_for(5000, threshold=2000):              # large: left alone
            assert _blas_threads() == before
    assert inside.__name__ == "inside"                           # functools.wraps
