"""A tool library: the CSV a shop keeps of its end mills and the cut each one is meant for.

Columns (one tool per row; lengths in mm, speeds in rpm):

* ``id``: tool identifier (unique, non-empty)
* ``diameter_mm``: tool diameter D, mm
* ``overhang_mm``: overhang (gauge length out of the holder) L, mm
* ``teeth``: number of teeth N
* ``holder``: holder name: one of the campaign's ``[holders]``
* ``tangential_coeff_n_mm2``, ``radial_ratio``: cutting coefficients K_t (N/mm²) and K_r = K_n/K_t; or leave
  them empty and name a preset in ``material`` (:mod:`~toolpoint.recommend.materials`)
* ``radial_immersion``: a_e/D in (0, 1] (1 = slotting)
* ``milling``: ``down`` or ``up``
* ``rpm_min``, ``rpm_max``: the spindle's usable speed range, rpm
* ``flute_length_mm``: optional: flute length, mm (default: the campaign's tool family rule)
* ``material``: optional: work material (a preset name when the coefficients are empty)
* ``tangential_coeff_sigma_pct``, ``radial_ratio_sigma_pct``: optional: one standard deviation of K_t and K_r,
  % (default: the preset's, or 10 % and 15 % for coefficients given in the row; :mod:`.materials`)

A file that cannot be read, has no header or no rows, or lacks a required
column is an :class:`~toolpoint.errors.InputError`. A bad *row* (a missing
or non-numeric value, no cutting data, an unknown preset) does not stop the
others: :func:`read_library` returns it as a :class:`BadRow` naming the id and
the problem.

Examples
--------
>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "tools.csv"
>>> _ = p.write_text("id,diameter_mm,overhang_mm,teeth,holder,tangential_coeff_n_mm2,radial_ratio,"
...                  "radial_immersion,milling,rpm_min,rpm_max,material\\n"
...                  "E1,16,50,3,ER40,,,0.5,down,3000,20000,al7075\\n"
...                  "E2,12,40,2,ER40,,,1,up,3000,20000,\\n")
>>> tools, bad = read_library(p)
>>> tools[0].id, tools[0].cutting.tangential_coeff, [b.id for b in bad]
('E1', 796000000.0, ['E2'])
>>> bad[0].error
'E2: no cutting data: give tangential_coeff_n_mm2 and radial_ratio, or a material preset (al7075, aluminium, steel)'
"""

from __future__ import annotations

import hashlib
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from ..io.table import read_table
from ..stability.cutting import CuttingConditions
from .materials import LIBRARY_UNCERTAINTY, PRESETS, preset, uncertainty

__all__ = ["REQUIRED", "OPTIONAL", "LibraryTool", "BadRow", "read_library"]

#: Required columns.
REQUIRED = ("id", "diameter_mm", "overhang_mm", "teeth", "holder", "radial_immersion", "milling", "rpm_min",
            "rpm_max")
#: Optional columns (the cutting coefficients are needed unless ``material`` names a preset).
OPTIONAL = ("tangential_coeff_n_mm2", "radial_ratio", "flute_length_mm", "material", "tangential_coeff_sigma_pct",
            "radial_ratio_sigma_pct")


@dataclass(frozen=True)
class LibraryTool:
    """One valid row of a tool library (SI inside except D, L in mm as the models take them).

    Attributes
    ----------
    id, holder, material : str
        Tool id, holder name, work material ('' if not given).
    diameter_mm, overhang_mm : float
        D and L, mm.
    flute_length_mm : float or None
        Flute length, mm (None: the campaign's tool family rule).
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r, immersion, milling.
    rpm_min, rpm_max : float
        Speed range, rpm.
    cutting_source : str
        Where K_t, K_r come from (``library`` or the preset's source).
    line : int
        Line in the file.
    cutting_sigma_ln : (float, float)
        One standard deviation of ln K_t and ln K_r (:mod:`.materials`; the row's ``*_sigma_pct`` columns
        override it).
    """

    id: str
    holder: str
    material: str
    diameter_mm: float
    overhang_mm: float
    flute_length_mm: float | None
    cutting: CuttingConditions
    rpm_min: float
    rpm_max: float
    cutting_source: str
    line: int
    cutting_sigma_ln: tuple = LIBRARY_UNCERTAINTY


@dataclass(frozen=True)
class BadRow:
    """A library row that cannot be used, and why (one line starting with its id).

    Attributes
    ----------
    id : str
        The row's id (``line N`` if it has none).
    error : str
        One line: ``<id>: <problem>``.
    line : int
        Line in the file.
    """

    id: str
    error: str
    line: int


def _number(row: dict, name: str, *, positive=True, required=True) -> float | None:
    cell = (row.get(name) or "").strip()
    if not cell:
        if required:
            raise ValueError(f"{name}: missing value")
        return None
    try:
        v = float(cell)
    except ValueError:
        raise ValueError(f"{name}: {cell!r} is not a number") from None
    if not math.isfinite(v) or (positive and v <= 0):
        raise ValueError(f"{name}: must be a finite number > 0, got {cell}")
    return v


def _tool(row: dict, line: int, tid: str) -> LibraryTool:
    D, L = _number(row, "diameter_mm"), _number(row, "overhang_mm")
    flute = _number(row, "flute_length_mm", required=False)
    teeth_v = _number(row, "teeth")
    if teeth_v != int(teeth_v):
        raise ValueError(f"teeth: must be a whole number, got {row['teeth'].strip()}")
    holder = (row.get("holder") or "").strip()
    if not holder:
        raise ValueError("holder: missing value")
    material = (row.get("material") or "").strip()
    kt = _number(row, "tangential_coeff_n_mm2", required=False)
    kr = _number(row, "radial_ratio", positive=False, required=False)
    sigma = LIBRARY_UNCERTAINTY
    if kt is not None and kr is not None:
        kt_si, source = kt * 1e6, "library"
    elif kt is None and kr is None and material and preset(material) is not None:
        kt_si, kr, source = preset(material)
        sigma = uncertainty(material)
    elif kt is None and kr is None:
        known = ", ".join(PRESETS)
        if material:
            raise ValueError(f"no cutting data: material {material!r} is not a preset ({known}); give "
                             "tangential_coeff_n_mm2 and radial_ratio")
        raise ValueError(f"no cutting data: give tangential_coeff_n_mm2 and radial_ratio, or a material preset "
                         f"({known})")
    else:
        raise ValueError("give both tangential_coeff_n_mm2 and radial_ratio (or neither, with a material preset)")
    ri = _number(row, "radial_immersion")
    milling = (row.get("milling") or "").strip().lower()
    try:
        cut = CuttingConditions(int(teeth_v), kt_si, kr, ri, milling)
    except InputError as e:
        raise ValueError(str(e)) from None
    lo, hi = _number(row, "rpm_min"), _number(row, "rpm_max")
    if not lo < hi:
        raise ValueError(f"rpm_min ({lo:g}) must be below rpm_max ({hi:g})")
    given = [_number(row, f"{c}_sigma_pct", positive=False, required=False)
             for c in ("tangential_coeff", "radial_ratio")]
    for name, g in zip(("tangential_coeff_sigma_pct", "radial_ratio_sigma_pct"), given):
        if g is not None and not 0 <= g <= 100:
            raise ValueError(f"{name}: must be a percentage in [0, 100], got {g:g}")
    sigma = tuple(math.log1p(g / 100) if g is not None else s for g, s in zip(given, sigma))
    return LibraryTool(tid, holder, material, D, L, flute, cut, lo, hi, source, line, sigma)


def read_library(path: str | os.PathLike) -> tuple[list[LibraryTool], list[BadRow]]:
    """Read a tool library CSV (module docstring).

    Parameters
    ----------
    path : path-like
        The CSV file.

    Returns
    -------
    tools : list of LibraryTool
        The usable rows, in file order.
    bad : list of BadRow
        The rows that are not (one line each, naming the id).

    Raises
    ------
    InputError
        The file is missing or unreadable, has no header, lacks a required
        column, or has no data rows.
    """
    path = Path(path)
    header, rows = read_table(path, what="the tool library")
    if not header:
        raise InputError("empty file (no header row)", file=path)
    for name in REQUIRED:
        if name not in header:
            raise InputError(f"no such column (columns: {', '.join(header)})", file=path, field=name)
    if not rows:
        raise InputError("no tools (a header but no rows)", file=path)
    tools, bad, seen = [], [], set()
    for line, row in rows:
        tid = (row.get("id") or "").strip()
        try:
            if not tid:
                tid = f"line {line}"
                raise ValueError("empty id")
            if tid in seen:
                raise ValueError(f"id appears more than once (line {line})")
            if None in row:
                raise ValueError(f"line {line} has more cells than the header")
            seen.add(tid)
            tools.append(_tool(row, line, tid))
        except ValueError as e:
            bad.append(BadRow(tid, f"{tid}: {' '.join(str(e).split())}", line))
    return tools, bad


_SAFE_ID = re.compile(r"[A-Z0-9][A-Z0-9._-]{0,63}")
_HASHED = re.compile(r".*-[0-9a-fA-F]{10}")  # what a hashed stem looks like: such an id is hashed too
_RESERVED = {"con", "prn", "aux", "nul", *(f"com{i}" for i in range(10)), *(f"lpt{i}" for i in range(10))}


def tool_file_stem(tool_id: str) -> str:
    """The file name stem of a tool's result files: a tool id from a library never becomes a path as it is.

    An id of at most 64 capital letters, digits, ``.``, ``_``, ``-`` (starting with a letter or digit, not a
    reserved device name such as ``CON`` or ``NUL.x``, not ending with ``.`` or with ``-`` and 10 hex digits) is its
    own stem, so ``EM10-45`` gives ``tools/EM10-45.json``. Any other id — lower-case letters, path separators,
    ``..``, NUL, newlines, 300 characters, a leading ``=`` — gives its safe characters (at most 40) and a hash of
    the whole id: safe, bounded (≤ 64 characters), inside the folder, and unique even where the file system
    ignores case (``em10`` and ``EM10`` are two tools on macOS and Windows too) and whatever ids the library
    holds (an id never equals another id's hashed stem). The tool's JSON records the id itself.

    Examples
    --------
    >>> tool_file_stem("EM10-45")
    'EM10-45'
    >>> tool_file_stem("../../x")
    'x-9bdbf20b56'
    >>> tool_file_stem("x-9bdbf20b56") != tool_file_stem("../../x"), tool_file_stem("em10-45")
    (True, 'em10-45-53a2595e41')
    >>> len(tool_file_stem("a" * 300)), tool_file_stem("CON").startswith("CON-"), tool_file_stem("CON.x")
    (51, True, 'CON_x-eb2aca898c')
    """
    def reserved(stem: str) -> bool:  # Windows takes ``stem.<ext>`` for a device (``CON``, ``nul.x``)
        return stem.split(".")[0].lower() in _RESERVED

    tool_id = str(tool_id)
    if (_SAFE_ID.fullmatch(tool_id) and not reserved(tool_id) and not tool_id.endswith(".")
            and not _HASHED.fullmatch(tool_id)):
        return tool_id
    slug = re.sub(r"[^A-Za-z0-9._-]+", "_", tool_id).strip("._-")[:40]
    if reserved(slug):
        slug = slug.replace(".", "_", 1)  # "CON.x-…" would still be the device CON
    digest = hashlib.sha1(tool_id.encode("utf-8", "surrogatepass")).hexdigest()[:10]
    return f"{slug}-{digest}" if slug else f"tool-{digest}"
