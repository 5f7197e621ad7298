"""One BLAS thread for small dense linear algebra.

The least-squares solves, SVDs and matrix exponentials in toolpoint are small
(tens to hundreds of rows): a threaded BLAS only adds synchronisation there
(and oversubscribes when worker processes run side by side). Measurements:
``docs/design/dynamics.md``.
"""

from __future__ import annotations

import functools


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
    import sys

    return _controller(len(sys.modules)).limit(limits=1, user_api="blas")


@functools.lru_cache(maxsize=1)
def _controller(n_modules):
    # Inspecting the loaded libraries costs ~2 ms (it reads /proc/self/maps): not at every call — the SDM calls
    # this once per model in the shop update's per-sample loop. Built again when modules were imported since
    # (``n_modules``), which is when a new BLAS can have been loaded.
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()
