"""Compatibility path: ``toolpoint.identify`` is now :mod:`toolpoint.identification.identify`.

``from toolpoint.identify import identify`` keeps working. The module is also
callable, so ``toolpoint.identify(model, measured)`` is the function whether
this module has been imported or not.
"""

import sys
import types

from .identification.identify import *  # noqa: F401,F403
from .identification.identify import __all__  # noqa: F401
from .identification.identify import identify as _identify


class _CallableModule(types.ModuleType):
    def __call__(self, *args, **kwargs):
        return _identify(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
