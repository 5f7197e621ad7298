"""One BLAS thread for small dense linear algebra.

The least-squares solves, SVDs and matrix exponentials in toolpoint are small
(tens to hundreds of rows): a threaded BLAS only adds synchronisation there
(and oversubscribes when worker processes run side by side). Measurements:
``docs/design/dynamics.md``.
"""

from __future__ import annotations


def single_thread_blas():
    """Context manager limiting BLAS to one thread (threadpoolctl).

    Returns
    -------
    threadpoolctl.threadpool_limits
        Use in a ``with`` statement; the previous limits come back on exit.

    Examples
    --------
    >>> import numpy as np
    >>> from toolpoint.blas import single_thread_blas
    >>> with single_thread_blas():
    ...     s = np.linalg.svd(np.eye(3), compute_uv=False)
    >>> s.tolist()
    [1.0, 1.0, 1.0]
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")
