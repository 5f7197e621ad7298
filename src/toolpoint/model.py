"""Compatibility path: ``toolpoint.model`` is now :mod:`toolpoint.dynamics.model`.

Kept because README and user code import ``AssemblyModel`` from here; new code
should import from :mod:`toolpoint.dynamics.model` or the top-level package.
"""

from .dynamics.model import *  # noqa: F401,F403
from .dynamics.model import __all__  # noqa: F401
