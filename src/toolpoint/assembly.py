"""Compatibility path: ``toolpoint.assembly`` is now :mod:`toolpoint.dynamics.assembly`.

Kept because README and user code import ``load_assembly`` from here; new code
should import from :mod:`toolpoint.dynamics.assembly` or the top-level package.
"""

from .dynamics.assembly import *  # noqa: F401,F403
from .dynamics.assembly import __all__  # noqa: F401
