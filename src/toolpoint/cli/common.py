"""Small helpers shared by the CLI commands."""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from pathlib import Path

from ..io.atomic import atomic_path
from ..errors import InputError


def out_path(value: str, flag: str) -> Path:
    """An output path whose folder exists or can be made."""
    p = Path(value)
    if p.exists() and p.is_dir():
        raise InputError("is a folder, expected a file name", file=p, field=flag)
    return p


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
