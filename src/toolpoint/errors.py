"""Errors raised for bad user input.

The CLI turns an :class:`InputError` into one line on stderr and exit code 2;
the Python API lets it propagate (it is a ``ValueError``).
"""

from __future__ import annotations

from os import PathLike


class InputError(ValueError):
    """Bad input, located by file and field (a ``ValueError``).

    ``str(err)`` is a single line: ``"<file>: <field>: <message>"`` (parts that
    are unknown are left out).

    Parameters
    ----------
    message : str
        What is wrong; whitespace (newlines included) is collapsed to single spaces.
    file : str or PathLike, optional
        The file the input came from.
    field : str, optional
        The field inside it, e.g. ``spindle.segments[1].od_mm`` or ``freq_hz``.

    Examples
    --------
    >>> str(InputError("must be > 0,   got -1", file="a.toml", field="tool.segments[0].od_mm"))
    'a.toml: tool.segments[0].od_mm: must be > 0, got -1'
    """

    def __init__(self, message: str, *, file: str | PathLike | None = None, field: str | None = None):
        self.message = " ".join(str(message).split())  # keep it to one line
        self.file = None if file is None else str(file)
        self.field = field
        # a file name may hold a newline or other control characters: escaped, the error stays one line
        parts = [p.encode("unicode_escape").decode("ascii", "replace") if any(ord(c) < 32 for c in p) else p
                 for p in (self.file, self.field) if p]
        super().__init__(": ".join(parts + [self.message]))


class ExtrapolationWarning(UserWarning):
    """A prediction outside the range a model was trained on."""


class IdentifiabilityWarning(UserWarning):
    """A parameter that the data cannot pin down (wide confidence interval or at a bound)."""
