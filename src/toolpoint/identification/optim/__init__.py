"""Optimisers for joint identification: GA, SA, PSO (ours), DE (scipy) and the hybrid.

Every optimiser takes all its options, the stopping rules included, in ``__init__`` (scipy's names:
``maxiter``, ``maxfev``, ``popsize``, ``tol``; GA/SA/PSO share ``stall_iter``, ``tol`` and ``f_target``
with one meaning) and returns a ``scipy.optimize.OptimizeResult`` with ``x`` in log10 space and a truthful
``success``/``status`` (codes in :data:`STATUS_MESSAGES`, see :mod:`.base`).
"""

from .base import STATUS_MESSAGES, Termination
from .de import DE
from .ga import GA
from .hybrid import Hybrid
from .pso import PSO
from .sa import SA

#: Method name → optimiser class.
METHODS = {"hybrid": Hybrid, "ga": GA, "sa": SA, "pso": PSO, "de": DE}

__all__ = ["DE", "GA", "METHODS", "PSO", "SA", "STATUS_MESSAGES", "Hybrid", "Termination", "check_method"]


def check_method(name, *, file: str | None = "command line", field: str | None = "--method") -> str:
    """Check an optimiser name (the one place it is checked).

    Parameters
    ----------
    name : str
        One of :data:`METHODS`: ``hybrid``, ``ga``, ``sa``, ``pso``, ``de``.
    file, field : str or None
        Where the name came from, for the error message.

    Returns
    -------
    str
        ``name`` in lower case (``"GA"`` and ``"ga"`` are the same method).

    Raises
    ------
    toolpoint.errors.InputError
        ``"file: field: unknown method …"`` when ``name`` is not a method.

    Examples
    --------
    >>> check_method("GA")
    'ga'
    >>> check_method("magic", file=None, field="method")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: method: unknown method 'magic' (one of hybrid, ga, sa, pso, de)
    """
    from ...errors import InputError

    if not isinstance(name, str) or name.strip().lower() not in METHODS:
        raise InputError(f"unknown method {name!r} (one of {', '.join(METHODS)})", file=file, field=field)
    return name.strip().lower()
