"""Small helpers shared by the CLI commands."""

from __future__ import annotations

import math
import os
import warnings
from contextlib import contextmanager
from pathlib import Path

from ..io.atomic import atomic_path
from ..errors import InputError


def out_path(value: str, flag: str, *, inputs=()) -> Path:
    """An output file path, checked before any work is done.

    Refused (:class:`~toolpoint.errors.InputError` naming the path and ``flag``):
    an existing folder; a path under a file; a folder that cannot be written;
    one of the command's ``inputs`` (it would be overwritten); for a figure
    (``flag`` ``--plot``/``--plots``), an extension matplotlib cannot write.
    """
    p = Path(value)
    if p.is_dir():
        raise InputError("is a folder, expected a file name", file=p, field=flag)
    for q in inputs:
        if q is not None and Path(q).exists() and p.exists() and p.resolve() == Path(q).resolve():
            raise InputError("is one of this command's inputs: choose another output file", file=p, field=flag)
    _check_parent(p.parent, p, flag)
    if flag in ("--plot", "--plots"):
        check_figure_suffix(p, flag)
    return p


def out_folder(value: str, flag: str) -> Path:
    """An output folder path, checked before any work is done.

    Refused (:class:`~toolpoint.errors.InputError` naming the path and ``flag``): an
    existing file; a path under a file; a first existing ancestor that cannot be written.
    """
    out = Path(value)
    if out.exists() and not out.is_dir():
        raise InputError("exists and is not a folder", file=out, field=flag)
    _check_parent(out, out, flag)
    return out


def _check_parent(parent: Path, p: Path, flag: str) -> None:
    """The first existing ancestor of ``parent`` (itself included) must be a writable folder."""
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"cannot write under {parent}: it is a file, not a folder", file=p, field=flag)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"folder {parent} is not writable", file=p, field=flag)


def check_number(value, flag: str, *, minimum: float | None = None, above: float | None = None,
                 unit: str = "", maximum: float | None = None, why: str = "") -> float:
    """A numeric command-line value that must be finite and ≥ ``minimum`` (or > ``above``), and ≤ ``maximum``
    where given (``why``: what the bound is, said in the message).

    Python's ``float`` accepts ``nan`` and ``inf``; they would reach the numerics
    (a NaN noise level writes a campaign of NaNs), so every numeric option is judged here.
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {value!r}", file="command line", field=flag) from None
    bound = ""
    if minimum is not None:
        bound = f" ≥ {minimum:g}"
    elif above is not None:
        bound = f" > {above:g}"
    ok = math.isfinite(v) and (minimum is None or v >= minimum) and (above is None or v > above)
    if not ok:
        raise InputError(f"must be a finite number{bound}{(' ' + unit) if unit else ''}, got {value!r}",
                         file="command line", field=flag)
    if maximum is not None and v > maximum:
        raise InputError(f"must be ≤ {maximum:g}{(' ' + unit) if unit else ''}{f' ({why})' if why else ''}, "
                         f"got {value}", file="command line", field=flag)
    return v


def check_whole(value, flag: str, *, minimum: int | None = None) -> int:
    """A whole-number command-line value (a channel, a count), ≥ ``minimum`` where given."""
    try:
        v = int(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a whole number, got {value!r}", file="command line", field=flag) from None
    if minimum is not None and v < minimum:
        raise InputError(f"must be ≥ {minimum}, got {v}", file="command line", field=flag)
    return v


def check_figure_suffix(path: Path, flag: str) -> None:
    """Refuse a figure path whose extension matplotlib cannot write (before any work)."""
    from matplotlib.figure import Figure

    formats = Figure().canvas.get_supported_filetypes()
    fmt = path.suffix.lstrip(".").lower()
    if fmt not in formats:
        raise InputError(f"cannot write a figure as {fmt or 'a file without extension'!r} "
                         f"(use one of {', '.join(sorted(formats))})", file=path, field=flag)


def save_figure(fig, path: Path) -> None:
    """Save a matplotlib figure atomically (format from the extension)."""
    import matplotlib.pyplot as plt

    fmt = path.suffix.lstrip(".").lower() or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=130)
    plt.close(fig)


@contextmanager
def warnings_to_stderr():
    """Show library warnings as one line each: 'warning: …'."""
    import sys

    def show(message, category, filename, lineno, file=None, line=None):
        print(f"warning: {message}", file=sys.stderr)

    old = warnings.showwarning
    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = old


def use_agg() -> None:
    """Headless plotting backend for the CLI."""
    import matplotlib

    matplotlib.use("Agg")


def parse_band(text: str | None, flag: str = "--band") -> tuple[float, float] | None:
    """``"LO:HI"`` → (LO, HI) Hz with 0 ≤ LO < HI finite; None → None; otherwise an InputError naming ``flag``.

    The one parser of a frequency band on the command line (``lobes``, ``identify``, ``modal``).

    Examples
    --------
    >>> parse_band("200:5000")
    (200.0, 5000.0)
    >>> parse_band("200-5000")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: command line: --band: expected LO:HI in Hz with 0 ≤ LO < HI, got '200-5000'
    """
    if text is None:
        return None
    lo, sep, hi = text.partition(":")
    try:
        band = (float(lo), float(hi))
    except ValueError:
        band = None
    if not sep or band is None or not (all(math.isfinite(b) for b in band) and 0 <= band[0] < band[1]):
        raise InputError(f"expected LO:HI in Hz with 0 ≤ LO < HI, got {text!r}", file="command line", field=flag)
    return band
