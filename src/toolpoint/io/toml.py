"""TOML input files: reading and a field-path-aware schema reader.

Every problem raises :class:`~toolpoint.errors.InputError` naming the file and
the field (``spindle.segments[1].od_mm``), so the CLI can print one line.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

from ..errors import InputError

__all__ = ["TomlReader", "load_toml"]


class TomlReader:
    """Accessors for a parsed TOML document that raise ``InputError(file, field)``.

    Parameters
    ----------
    file : str
        The file name used in error messages.

    Examples
    --------
    >>> r = TomlReader("a.toml")
    >>> r.number({"E": 2.1e11}, "E", "materials.steel", positive=True)
    210000000000.0
    >>> r.number({"E": -1}, "E", "materials.steel", positive=True)
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: a.toml: materials.steel.E: must be > 0, got -1
    """

    def __init__(self, file: str):
        self.file = str(file)

    def err(self, field: str, msg: str) -> InputError:
        """An :class:`InputError` for ``field`` of this file."""
        return InputError(msg, file=self.file, field=field)

    def table(self, parent: dict, key: str, path: str, required: bool = True) -> dict | None:
        """``parent[key]`` as a table; None if absent and not ``required``."""
        if key not in parent:
            if required:
                raise self.err(path, "missing section")
            return None
        val = parent[key]
        if not isinstance(val, dict):
            raise self.err(path, f"must be a table, got {type(val).__name__}")
        return val

    def number(self, d: dict, key: str, path: str, *, default=None, positive=False, nonneg=False) -> float:
        """``d[key]`` as a finite float (``default`` if absent and given)."""
        if key not in d:
            if default is None:
                raise self.err(f"{path}.{key}", "missing value")
            return float(default)
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.err(f"{path}.{key}", f"must be a number, got {v!r}")
        v = float(v)
        if not math.isfinite(v):
            raise self.err(f"{path}.{key}", f"must be finite, got {v}")
        if positive and v <= 0:
            raise self.err(f"{path}.{key}", f"must be > 0, got {v:g}")
        if nonneg and v < 0:
            raise self.err(f"{path}.{key}", f"must be ≥ 0, got {v:g}")
        return v

    def unknown_keys(self, d: dict, allowed: set[str], path: str) -> None:
        """Refuse keys of ``d`` not in ``allowed`` (typos would otherwise be ignored)."""
        extra = sorted(set(d) - allowed)
        if extra:
            raise self.err(f"{path}.{extra[0]}", f"unknown key (allowed: {', '.join(sorted(allowed))})")


def load_toml(path: str | Path) -> dict:
    """Read a TOML file; unreadable, undecodable or malformed files raise InputError."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        from .table import check_regular_file

        check_regular_file(path, what="TOML file")
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise InputError("file not found", file=path) from None
    except IsADirectoryError:
        raise InputError("is a folder, expected a TOML file", file=path) from None
    except OSError as e:
        raise InputError(f"cannot read file ({e.strerror})", file=path) from None
    except UnicodeDecodeError:
        raise InputError("not UTF-8 text (a TOML file must be UTF-8)", file=path) from None
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"malformed TOML ({e})", file=path, field="syntax") from None
