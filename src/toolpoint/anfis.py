"""Compatibility path: ``toolpoint.anfis`` is now :mod:`toolpoint.learning.anfis`.

Kept because README and user code import ``ANFIS`` from here; new code
should import from :mod:`toolpoint.learning.anfis` or the top-level package.
"""

from .learning.anfis import *  # noqa: F401,F403
from .learning.anfis import __all__  # noqa: F401
