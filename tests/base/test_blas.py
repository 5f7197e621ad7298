"""``single_thread_blas`` keeps one threadpoolctl controller per process: it must still limit every BLAS the
process has loaded (numpy's and scipy's are separate OpenBLAS builds in the wheels) and give the limits back."""


def _blas_threads():
    from threadpoolctl import threadpool_info

    return {d["filepath"]: d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas"}


def test_single_thread_blas_limits_every_loaded_blas_and_restores_the_limits():
    import scipy.linalg  # noqa: F401  (scipy's own BLAS loaded, as in any toolpoint computation)
    from threadpoolctl import threadpool_limits

    from toolpoint.blas import single_thread_blas

    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        for _ in range(2):  # the second call reuses the controller
            with single_thread_blas():
                inside = _blas_threads()
            assert inside.keys() == before.keys() and set(inside.values()) == {1}, (before, inside)
            assert _blas_threads() == before
