"""Optimisers for joint identification: GA, SA, PSO (ours), DE (scipy) and the hybrid."""

from .base import Termination
from .de import DE
from .ga import GA
from .hybrid import Hybrid
from .pso import PSO
from .sa import SA

METHODS = {"hybrid": Hybrid, "ga": GA, "sa": SA, "pso": PSO, "de": DE}

__all__ = ["DE", "GA", "METHODS", "PSO", "SA", "Hybrid", "Termination", "check_method"]


def check_method(name, *, file: str | None = "command line", field: str | None = "--method") -> str:
    """``name`` if it is one of :data:`METHODS`, else an :class:`~toolpoint.errors.InputError`
    naming ``file`` and ``field`` (the one place the method name is checked)."""
    from ...errors import InputError

    if not isinstance(name, str) or name not in METHODS:
        raise InputError(f"unknown method {name!r} (one of {', '.join(METHODS)})", file=file, field=field)
    return name
