"""toolpoint — tool-point FRF prediction for milling.

Data flow, one sub-package per step (imports go one way, no cycle inside a sub-package; checked in CI)::

    frf, errors → trust → io → dynamics → identification → learning → campaign → stability → simulation
    → recommend → shop → cli

measured FRFs enter through ``io`` and the trusted band (``trust``), test cuts through ``io`` and ``shop``.

The names most used are importable from here (lazily, so that ``import
toolpoint`` stays fast): :class:`FRF`, :func:`load_assembly`,
:class:`AssemblyModel`, :func:`identify`, :class:`ANFIS`, :class:`InputError`.

Reference: Čiča et al., "Dynamical contact parameter identification of
spindle–holder–tool assemblies using soft computing techniques", Facta
Universitatis, Series: Mechanical Engineering, 2020, doi:10.22190/FUME191014012C.
"""

import importlib

__version__ = "0.1.0"

_LAZY = {
    "FRF": "toolpoint.frf",
    "InputError": "toolpoint.errors",
    "load_assembly": "toolpoint.dynamics.assembly",
    "AssemblyModel": "toolpoint.dynamics.model",
    "ToolPointModel": "toolpoint.dynamics.model",
    "ANFIS": "toolpoint.learning.anfis",
    "identify": "toolpoint.identification.identify",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'toolpoint' has no attribute {name!r}")
