"""One BLAS thread for small dense linear algebra.

The least-squares solves, SVDs and matrix exponentials in toolpoint are small
(tens to hundreds of rows): a threaded BLAS only adds synchronisation there
(and oversubscribes when worker processes run side by side). Measurements:
``docs/design/dynamics.md``.
"""

from __future__ import annotations

_CONTROLLER = None  # one threadpoolctl controller per process (see single_thread_blas)


def single_thread_blas():
    """Context manager limiting BLAS to one thread (threadpoolctl).

    Returns
    -------
    threadpoolctl limiter
        Use in a ``with`` statement; the previous limits come back on exit. The libraries are looked up once per
        process (numpy's and scipy's BLAS).

    Examples
    --------
    >>> import numpy as np
    >>> from toolpoint.blas import single_thread_blas
    >>> with single_thread_blas():
    ...     s = np.linalg.svd(np.eye(3), compute_uv=False)
    >>> s.tolist()
    [1.0, 1.0, 1.0]
    """
    global _CONTROLLER
    if _CONTROLLER is None:
        # threadpool_limits() looks for the loaded libraries on every call (it reads the process's shared objects):
        # 2.3 s of a 9.2 s prior update on the example tool went there, one call per SDM multiplier evaluation.
        # One controller per process, made after scipy.linalg has loaded its own BLAS, so that both are limited.
        import scipy.linalg  # noqa: F401
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER.limit(limits=1, user_api="blas")
