"""``identified.csv``: one identified holder–tool joint per tool assembly of a campaign.

The one home of the file's schema: ``campaign run`` appends rows
(:func:`resume`, :class:`Appender`), ``campaign learn`` and ``predict`` read
them (:func:`read_identified`, :class:`IdentifiedRows`).

Columns (:data:`COLUMNS`), one row per measurement:

* ``id``, ``holder``; ``diameter_mm``, ``overhang_mm`` (mm);
* ``kt`` N/m, ``ct`` N s/m, ``kr`` N m/rad, ``cr`` N m s/rad (SI, ``repr`` of
  the float) and their 95 % intervals ``<p>_lo``, ``<p>_hi`` (same units);
* ``objective`` (the fit's objective), ``evaluations``, ``seconds`` (wall time);
* ``status`` (``ok`` or ``failed``), ``warnings`` (identifiability, ``; ``
  separated), ``error`` (one line, failed rows only).

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "identified.csv"
>>> resume(path, set())
set()
>>> with Appender(path) as append:
...     append(new_row("T001", "ER40", 16.0, 50.0, status="ok", kt=repr(2.1e7), kt_lo="2e7", kt_hi="2.2e7"))
>>> rows = read_identified(path, required=["kt"]).ok()
>>> rows.ids(), rows.column("kt").tolist(), rows.identified("kt").tolist()
(['T001'], [21000000.0], [True])
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..identification.params import PARAMS, interval_ratio, is_identified, sigma_ln_from_interval
from ..io.atomic import atomic_open
from ..io.table import read_table

__all__ = ["COLUMNS", "FILE_NAME", "new_row", "resume", "Appender", "read_identified", "IdentifiedRows"]

FILE_NAME = "identified.csv"
#: Largest tool diameter or overhang accepted, mm (a 10 m tool: beyond it the number is not a tool size).
MAX_LENGTH_MM = 1e4
#: Smallest tool diameter or overhang accepted, mm (a 1 µm tool: below it D⁴ and the beam model underflow).
MIN_LENGTH_MM = 1e-3
#: Largest magnitude of any other required number (squares and sums of squares stay finite).
MAX_ABS_VALUE = 1e100
COLUMNS = (
    ["id", "holder", "diameter_mm", "overhang_mm", *PARAMS]
    + [f"{p}_{s}" for p in PARAMS for s in ("lo", "hi")]
    + ["objective", "evaluations", "seconds", "status", "warnings", "error"]
)


def new_row(item_id: str, holder: str, diameter_mm, overhang_mm, **cells) -> dict:
    """A row of :data:`COLUMNS` (empty cells where not given).

    Parameters
    ----------
    item_id, holder : str
        Measurement id and holder name.
    diameter_mm, overhang_mm : float
        Tool diameter D and overhang L, mm.
    **cells
        Further columns by name (values written as ``str(value)``).

    Returns
    -------
    dict
        Column → cell.
    """
    row = dict.fromkeys(COLUMNS, "")
    row.update(id=item_id, holder=holder, diameter_mm=diameter_mm, overhang_mm=overhang_mm, **cells)
    return row


def _is_ok(row: dict) -> bool:
    return (row.get("status") or "").strip().lower() == "ok"


def _read_rows(path: Path) -> tuple[list[str], list[tuple[int, dict]]]:
    """Header and (line number, row) of every data row; InputError if unreadable."""
    return read_table(path, what="identified.csv")


def resume(path: str | os.PathLike, ids: set[str]) -> set[str]:
    """Start or continue a run's ``identified.csv``: keep the finished ``ok`` rows of ``ids``.

    A new file gets the header. An existing one is rewritten atomically with only
    its ``ok`` rows whose id is in ``ids`` and whose four parameters are present
    (a row cut short by a killed run, failed rows and ids no longer in the
    campaign go; they are run again).

    Parameters
    ----------
    path : path-like
        The ``identified.csv`` to start or continue.
    ids : set of str
        Ids of the campaign's measurements.

    Returns
    -------
    set of str
        Ids already done (to skip).
    """
    path = Path(path)
    rows = [] if not path.exists() else [row for _, row in _read_rows(path)[1]]
    keep = [r for r in rows if _is_ok(r) and r.get("id") in ids and all(r.get(p) not in (None, "") for p in PARAMS)]
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, COLUMNS, extrasaction="ignore")
        w.writeheader()
        w.writerows(keep)
    return {r["id"] for r in keep}


class Appender:
    """Append rows to ``identified.csv`` as items finish, each flushed and synced to disk.

    A killed run loses at most the row being written (:func:`resume` drops it).
    Use as a context manager, or call :meth:`close`.

    Parameters
    ----------
    path : path-like
        The file, already holding the header (:func:`resume`).
    """

    def __init__(self, path: str | os.PathLike):
        self.fh = open(path, "a", newline="", encoding="utf-8")
        self.w = csv.DictWriter(self.fh, COLUMNS)

    def __call__(self, row: dict) -> None:
        """Write one row of :data:`COLUMNS` and sync it."""
        self.w.writerow(row)
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def close(self) -> None:
        """Close the file."""
        self.fh.close()

    def __enter__(self) -> "Appender":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def read_identified(path: str | os.PathLike, required=()) -> "IdentifiedRows":
    """Read ``identified.csv`` (every row; :meth:`IdentifiedRows.ok` selects the finished ones).

    Parameters
    ----------
    path : path-like
        The file.
    required : iterable of str
        Columns that must be in the header.

    Returns
    -------
    IdentifiedRows

    Raises
    ------
    InputError
        Missing or unreadable file, no header, a missing ``required`` column
        (naming the file and the column).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found (run 'toolpoint campaign run' first)", file=path)
    header, rows = _read_rows(path)
    if not header:
        raise InputError("empty file (no header row)", file=path)
    for name in required:
        if name not in header:
            raise InputError(f"no such column (columns: {', '.join(header)})", file=path, field=name)
    return IdentifiedRows(path, tuple(header), tuple(rows))


@dataclass(frozen=True)
class IdentifiedRows:
    """Rows of an ``identified.csv`` with their line numbers, and typed columns of them.

    Attributes
    ----------
    path : Path
        The file (named in errors).
    header : tuple of str
        Column names.
    rows : tuple of (int, dict)
        (line number, column → cell text) per data row.
    """

    path: Path
    header: tuple[str, ...]
    rows: tuple[tuple[int, dict], ...]

    def __len__(self) -> int:
        return len(self.rows)

    def ok(self) -> "IdentifiedRows":
        """The rows with status ``ok``, ordered by id.

        ``campaign run`` appends rows as items finish: ordering by id makes
        everything downstream (a seeded split, training) independent of which
        identification finished first.
        """
        ok = sorted((lr for lr in self.rows if _is_ok(lr[1])), key=lambda lr: (lr[1].get("id") or "").strip())
        return IdentifiedRows(self.path, self.header, tuple(ok))

    def ids(self) -> list[str]:
        """The ids, in row order; InputError (with the line) for an empty or repeated id."""
        out, seen = [], set()
        for line, row in self.rows:
            i = (row.get("id") or "").strip()
            if not i:
                raise InputError(f"line {line}: empty id", file=self.path, field="id")
            if i in seen:
                raise InputError(f"line {line}: id {i!r} appears more than once", file=self.path, field="id")
            seen.add(i)
            out.append(i)
        return out

    def has(self, name: str) -> bool:
        """Whether the file has the column ``name``."""
        return name in self.header

    def column(self, name: str, *, required: bool = True) -> np.ndarray:
        """A numeric column, in the file's units (mm for D and L, SI for the joint).

        Parameters
        ----------
        name : str
            Column name.
        required : bool, default True
            True: every row must hold a finite number, within ±:data:`MAX_ABS_VALUE`
            (diameter and overhang: in [:data:`MIN_LENGTH_MM`, :data:`MAX_LENGTH_MM`] mm) — an InputError
            naming the line and the cell otherwise; False: NaN where it is not a finite number.

        Returns
        -------
        ndarray of float, shape (len(self),)
        """
        out = np.empty(len(self.rows))
        for k, (line, row) in enumerate(self.rows):
            out[k] = self._number(line, row, name, required)
        return out

    def check_numbers(self, name: str) -> None:
        """InputError naming the first row whose ``name`` is not a finite number."""
        self.column(name, required=True)

    def _number(self, line: int, row: dict, name: str, required: bool) -> float:
        cell = (row.get(name) or "").strip()
        try:
            v = float(cell)
        except ValueError:
            if required:
                raise InputError(f"line {line}: {cell!r} is not a number (status ok)", file=self.path,
                                 field=name) from None
            return math.nan
        if not math.isfinite(v):
            if required:
                raise InputError(f"line {line}: {cell!r} is not a finite number (status ok)", file=self.path,
                                 field=name)
            return math.nan
        if required and name in ("diameter_mm", "overhang_mm") and not MIN_LENGTH_MM <= v <= MAX_LENGTH_MM:
            raise InputError(f"line {line}: {cell!r} mm is not a tool size ({MIN_LENGTH_MM:g} to {MAX_LENGTH_MM:g} mm)",
                             file=self.path, field=name)
        if required and abs(v) > MAX_ABS_VALUE:
            raise InputError(f"line {line}: {cell!r} is beyond ±{MAX_ABS_VALUE:g} (models square it)",
                             file=self.path, field=name)
        return v

    def has_interval(self, param: str) -> bool:
        """Whether the file has the 95 % interval columns of ``param``."""
        return self.has(f"{param}_lo") and self.has(f"{param}_hi")

    def interval(self, param: str) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of the 95 % intervals of ``param`` (its unit; NaN where not a number or not an interval of a
        positive parameter: lo < 0, hi ≤ 0 or hi < lo — then the row has no interval)."""
        lo, hi = self.column(f"{param}_lo", required=False), self.column(f"{param}_hi", required=False)
        bad = (lo < 0) | (hi <= 0) | (hi < lo)
        lo[bad] = hi[bad] = np.nan
        return lo, hi

    def identified(self, param: str) -> np.ndarray:
        """Per row: whether ``param`` was identified (:func:`~toolpoint.identification.params.is_identified`).

        Returns
        -------
        ndarray of bool
            False where the interval is missing, not finite, or wider than the
            factor :data:`~toolpoint.identification.params.IDENTIFIED_RATIO`.
        """
        return is_identified(*self.interval(param))

    def interval_ratio(self, param: str) -> np.ndarray:
        """Per row: hi/lo of the 95 % interval of ``param`` (inf where there is none)."""
        return interval_ratio(*self.interval(param))

    def sigma_ln(self, param: str) -> np.ndarray:
        """Per row: standard error of ln ``param`` from its 95 % interval (inf where there is none).

        σ_ln = ln(hi/lo) / (2 · 1.96) (:func:`~toolpoint.identification.params.sigma_ln_from_interval`).
        """
        return sigma_ln_from_interval(*self.interval(param))
