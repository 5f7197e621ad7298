"""Read and write FRF files (the format follows the file extension).

* ``.csv`` — toolpoint's own format: the header ``freq_hz,real,imag``, then one
  row per frequency: Hz, real and imaginary part of the receptance in m/N.
  Written with ``%.17g``, so a write/read round trip is exact.
* ``.uff`` / ``.unv`` / ``.uf`` — Universal File Format dataset 58 (function at
  nodal DOF), read and written with pyuff. Written as a complex double
  precision (ordinate data type 6) frequency response function (function type
  4): abscissa frequency in Hz (18), ordinate displacement in m (8) over
  excitation force in N (13). ASCII UFF keeps 12 significant digits of each
  value (pyuff writes ``%20.11e``: relative error ≤ 5e-12) and 6 significant
  digits of the abscissa (``%13.5e``: the minimum and increment of an even
  grid, or every frequency of an uneven one). ``binary=True`` (dataset 58b)
  stores values and uneven frequencies as exact doubles.
* ``.frf`` — CutPro text: whitespace (normally tab) separated columns Freq (Hz),
  Real, Imag (m/N); an optional header line ``Freq  Real  Imag`` and comment
  lines starting with ``%`` or ``#`` are skipped.

Every reader returns a receptance :class:`~toolpoint.frf.FRF` in m/N (a
mobility or accelerance file is converted with :meth:`FRF.to_receptance`) and
raises :class:`~toolpoint.errors.InputError` naming the file and field for bad
input. Every writer writes receptance, through :mod:`toolpoint.io.atomic`, so a
failure never leaves a half-written file.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pyuff

from .atomic import atomic_open, atomic_path
from ..errors import InputError
from ..frf import FRF, QUANTITIES

__all__ = [
    "read_frf", "write_frf", "read_csv_frf", "write_csv_frf", "read_uff58", "read_uff58_all",
    "write_uff58", "read_cutpro", "write_cutpro",
]

G0 = 9.80665  # standard gravity, m/s² per g
CSV_HEADER = ("freq_hz", "real", "imag")
CUTPRO_COLUMNS = ("Freq", "Real", "Imag")


# ---------------------------------------------------------------- dispatch
def read_frf(path, *, quantity: str | None = None, min_points: int = 1, label: str | None = None) -> FRF:
    """Read an FRF file (``.csv``, ``.uff``/``.unv``/``.uf``, ``.frf``) as receptance in m/N.

    ``quantity`` ("receptance", "mobility" or "accelerance") says what the file
    holds and overrides what the file says; mobility/accelerance points at 0 Hz
    are dropped with a warning. ``label`` defaults to the file stem. Fewer than
    ``min_points`` points raises :class:`InputError`.
    """
    return _pick(path, _READERS)(path, quantity=quantity, min_points=min_points, label=label)


def write_frf(path, frf: FRF) -> None:
    """Write ``frf`` as receptance (m/N) in the format given by the extension of ``path``."""
    _pick(path, _WRITERS)(path, frf)


def _pick(path, table):
    ext = Path(path).suffix.lower()
    if ext not in table:
        raise InputError(f"unknown FRF file extension {ext!r} (use one of {', '.join(table)})", file=path, field="extension")
    return table[ext]


# ---------------------------------------------------------------- CSV
def read_csv_frf(path, *, quantity: str | None = None, min_points: int = 1, label: str | None = None) -> FRF:
    """Read a toolpoint CSV file: header ``freq_hz,real,imag``, then Hz, real, imaginary (m/N)."""
    q = _quantity(path, quantity)
    lines = [(n, s) for n, s in enumerate(_read_lines(path), 1) if s.strip()]
    if not lines:
        raise InputError("empty file", file=path, field="header")
    head = lines[0][1]
    if tuple(c.strip() for c in head.split(",")) != CSV_HEADER:
        raise InputError(f"expected {','.join(CSV_HEADER)!r}, found {head.strip()!r}", file=path, field="header")
    rows = [(n, s.split(",")) for n, s in lines[1:]]
    return _table_frf(path, rows, CSV_HEADER, q, min_points, label, "csv")


def write_csv_frf(path, frf: FRF) -> None:
    """Write ``frf`` as receptance to a toolpoint CSV file (``%.17g``: exact round trip)."""
    _write_table(path, frf, ",".join(CSV_HEADER) + "\n", ",")


# ---------------------------------------------------------------- CutPro
def read_cutpro(path, *, quantity: str | None = None, min_points: int = 1, label: str | None = None) -> FRF:
    """Read a CutPro ``.frf`` text file: columns Freq (Hz), Real, Imag (m/N).

    Columns may be separated by tabs or any whitespace; lines starting with
    ``%`` or ``#`` and one header line before the data are skipped.
    """
    q = _quantity(path, quantity)
    rows, header_seen = [], False
    for n, line in enumerate(_read_lines(path), 1):
        cells = line.split()
        if not cells or cells[0][0] in "%#":
            continue
        if not rows and not header_seen and not _is_number(cells[0]):
            header_seen = True
            continue
        rows.append((n, cells))
    return _table_frf(path, rows, CUTPRO_COLUMNS, q, min_points, label, "cutpro")


def write_cutpro(path, frf: FRF) -> None:
    """Write ``frf`` as receptance to a CutPro ``.frf`` file: tab-separated Hz, real, imaginary (m/N).

    No header line is written (CutPro-style plain three-column data).
    """
    _write_table(path, frf, "", "\t")


# ---------------------------------------------------------------- UFF 58
_UFF_QUANTITY = {8: "receptance", 11: "mobility", 12: "accelerance"}  # ordinate specific data type
_FUNC_TYPES = {
    0: "general or unknown", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
    4: "frequency response function", 5: "transmissibility", 6: "coherence", 7: "auto correlation",
    8: "cross correlation", 9: "power spectral density", 12: "spectrum",
}


def read_uff58(path, *, index: int | None = None, quantity: str | None = None, min_points: int = 1,
               label: str | None = None) -> FRF:
    """Read one FRF from a Universal File Format dataset 58 (ASCII or binary 58b).

    ``index`` picks among the datasets 58 of the file (0 = first); by default
    the first whose function type is 4 (frequency response function). The
    quantity comes from the ordinate specific data type (8 displacement, 11
    velocity, 12 acceleration, over force) unless ``quantity`` is given; an
    ordinate units label ``g`` is converted to m/s² (×9.80665) with a warning.
    Values are assumed SI (m, N, s).
    """
    q = _quantity(path, quantity) if quantity is not None else None
    uff, sets, heads = _uff_headers(path)
    if index is None:
        k = next((k for k, h in enumerate(heads) if h.get("func_type") == 4), 0)
    else:
        try:
            k = range(len(heads))[index]
        except (IndexError, TypeError):
            raise InputError(f"index {index!r} out of range: the file has {len(heads)} datasets 58",
                             file=path, field="index") from None
    return _uff_frf(path, uff, sets[k], k, q, min_points, label)


def read_uff58_all(path, *, quantity: str | None = None, min_points: int = 1) -> list[FRF]:
    """Every FRF (dataset 58 with function type 4) of a UFF file, as receptance in m/N.

    Other datasets 58 (coherence, spectra, ...) are skipped; labels are
    ``"<stem>#<k>"`` with k the position among the datasets 58.
    """
    q = _quantity(path, quantity) if quantity is not None else None
    uff, sets, heads = _uff_headers(path)
    ks = [k for k, h in enumerate(heads) if h.get("func_type") == 4] or [0]  # [0]: report its type
    return [_uff_frf(path, uff, sets[k], k, q, min_points, f"{Path(path).stem}#{k}") for k in ks]


def write_uff58(path, frf: FRF, *, binary: bool = False) -> None:
    """Write ``frf`` as one UFF dataset 58 (receptance m/N, complex double), replacing ``path``.

    An evenly spaced grid is written as abscissa minimum and increment when
    those survive pyuff's 6-digit ``%13.5e`` header format; otherwise every
    frequency is stored (uneven spacing). ASCII keeps uneven frequencies to 6
    significant digits: a warning gives the rounding, and frequencies that
    would collide raise :class:`InputError`; ``binary=True`` keeps them exact.
    """
    r = _for_write(path, frf)
    f, v = r.freq_hz, r.values
    if len(f) < 2:
        raise InputError("a UFF dataset 58 needs at least 2 points", file=path, field="freq_hz")
    f0, df = _fmt13([f[0], f[1] - f[0]])
    tol = 1e-9 * f[-1]
    even = bool(np.max(np.abs(f0 + np.arange(len(f)) * df - f)) <= tol)
    if not even and not binary:
        fr = _fmt13(f)
        if np.any(np.diff(fr) <= 0):
            raise InputError("frequencies closer than ASCII UFF's 6 significant digits can separate; "
                             "use binary=True or CSV", file=path, field="freq_hz")
        err = np.max(np.abs(fr - f))
        if err > tol:
            warnings.warn(f"{path}: ASCII UFF keeps 6 significant digits of uneven frequencies "
                          f"(max rounding {err:.3g} Hz); binary=True keeps them exact", stacklevel=2)
    m = r.meta
    ds = pyuff.prepare_58(
        binary=int(bool(binary)), id1=(" ".join(r.label.split()) or "NONE")[:80],
        func_type=4, rsp_node=_dof(m, "rsp_node"), rsp_dir=_dof(m, "rsp_dir"),
        ref_node=_dof(m, "ref_node"), ref_dir=_dof(m, "ref_dir"),
        ord_data_type=6, abscissa_spacing=int(even),
        abscissa_spec_data_type=18, abscissa_axis_units_lab="Hz",
        ordinate_spec_data_type=8, ordinate_axis_units_lab="m",
        orddenom_spec_data_type=13, orddenom_axis_units_lab="N",
        data=v.copy(), x=f.copy(),
    )
    with atomic_path(path) as tmp, warnings.catch_warnings():
        # tmp is a new, empty file, so "add" writes exactly one dataset. Not "overwrite":
        # pyuff 2.5.8 reopens the file with "wb" for binary data and truncates the header.
        # For binary data it also leaves its last handle to be closed (and flushed) when its
        # writer returns, which CPython does at once, with a ResourceWarning.
        warnings.simplefilter("ignore", ResourceWarning)
        pyuff.UFF(tmp).write_sets(ds, mode="add")


def _uff_headers(path):
    """(pyuff.UFF, file set numbers of the datasets 58, their header dicts)."""
    _check_readable(path)
    try:
        uff = pyuff.UFF(os.fspath(path))
        types = [int(t) for t in uff.get_set_types()]
        sets = [i for i, t in enumerate(types) if t == 58]
        heads = [uff.read_sets(i, header_only=True) for i in sets]
    except Exception as exc:  # pyuff raises bare Exception
        raise InputError(f"not a readable universal file ({exc})", file=path) from exc
    if not sets:
        found = ", ".join(str(t) for t in sorted(set(types))) or "none"
        raise InputError(f"no dataset 58 found (dataset types in file: {found})", file=path, field="dataset")
    return uff, sets, heads


def _uff_frf(path, uff, setno: int, k: int, quantity, min_points, label) -> FRF:
    try:
        ds = uff.read_sets(setno)
    except Exception as exc:
        raise InputError(f"dataset 58 #{k} cannot be read ({exc})", file=path, field="data") from exc
    tag = f"dataset 58 #{k}"
    ft = ds.get("func_type")
    if ft != 4:
        raise InputError(f"{tag} has function type {ft} ({_FUNC_TYPES.get(ft, 'other')}); "
                         "need 4 (frequency response function)", file=path, field="func_type")
    if ds.get("ord_data_type") not in (5, 6):
        raise InputError(f"{tag} has real ordinate data (type {ds.get('ord_data_type')}); "
                         "an FRF needs complex (5 or 6)", file=path, field="ord_data_type")
    ab = ds.get("abscissa_spec_data_type")
    if ab == 0:
        warnings.warn(f"{path}: {tag} abscissa data type 0 (unknown): assuming frequency in Hz", stacklevel=3)
    elif ab != 18:
        raise InputError(f"{tag} abscissa data type {ab}; need 18 (frequency)", file=path,
                         field="abscissa_spec_data_type")
    unit = _label(ds, "abscissa_axis_units_lab")
    if unit.lower() not in ("", "hz", "1/s"):
        raise InputError(f"{tag} abscissa units {unit!r}; need Hz", file=path, field="abscissa_axis_units_lab")
    q = quantity or _uff_quantity(path, ds, tag)
    f = np.asarray(ds["x"], dtype=float)
    v = np.asarray(ds["data"], dtype=complex)
    if v.size != ds.get("num_pts") or f.size != v.size:
        raise InputError(f"{tag} declares {ds.get('num_pts')} points but holds {v.size} values "
                         "(truncated file?)", file=path, field="num_pts")
    _validate(path, f, v.real, v.imag, lambda i: f"{tag} point {i + 1}", ("abscissa", "real", "imag"))
    num_unit = _label(ds, "ordinate_axis_units_lab")
    if num_unit.split("/")[0].strip().lower() == "g":
        warnings.warn(f"{path}: {tag} ordinate units {num_unit!r}: converted g to m/s² (×{G0})", stacklevel=3)
        v = v * G0
    meta = {key: ds.get(key) for key in ("id1", "rsp_node", "rsp_dir", "ref_node", "ref_dir")}
    meta.update(index=k, binary=ds.get("binary"))
    return _finish(path, f, v, q, min_points, label, "uff58", meta)


def _uff_quantity(path, ds, tag) -> str:
    num, den = ds.get("ordinate_spec_data_type"), ds.get("orddenom_spec_data_type")
    if num in _UFF_QUANTITY and den in (0, 9, 13):
        return _UFF_QUANTITY[num]
    if num in (9, 13):
        raise InputError(f"{tag} is force over data type {den} (dynamic stiffness or similar); "
                         "need response over force", file=path, field="ordinate_spec_data_type")
    warnings.warn(f"{path}: {tag} ordinate data type {num} over {den} is not displacement, velocity or "
                  "acceleration over force; assuming receptance (m/N) — pass quantity= to say", stacklevel=4)
    return "receptance"


def _dof(meta, key) -> int:
    """Node or direction kept in ``meta`` by :func:`read_uff58` (default 1 = node 1, +X)."""
    v = meta.get(key)
    return int(v) if isinstance(v, (int, np.integer)) and not isinstance(v, bool) else 1


def _label(ds, key) -> str:
    s = str(ds.get(key) or "").strip()
    return "" if s.upper() == "NONE" else s


def _fmt13(a) -> np.ndarray:
    """Values as pyuff's ``%13.5e`` header/abscissa format stores them."""
    return np.array([float("%13.5e" % x) for x in a])


# ---------------------------------------------------------------- shared
def _quantity(path, quantity) -> str:
    q = "receptance" if quantity is None else quantity
    if q not in QUANTITIES:
        raise InputError(f"unknown quantity {q!r} (one of {', '.join(QUANTITIES)})", file=path, field="quantity")
    return q


def _check_readable(path) -> None:
    try:
        with open(path, "rb"):
            pass
    except FileNotFoundError:
        raise InputError("file not found", file=path) from None
    except OSError as exc:
        raise InputError(f"cannot read file ({exc.strerror or exc})", file=path) from None


def _read_lines(path) -> list[str]:
    _check_readable(path)
    try:
        return Path(path).read_text(encoding="utf-8-sig").splitlines()
    except UnicodeDecodeError:
        raise InputError("not a UTF-8 text file", file=path) from None
    except OSError as exc:
        raise InputError(f"cannot read file ({exc.strerror or exc})", file=path) from None


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return False


def _table_frf(path, rows, names, quantity, min_points, label, fmt) -> FRF:
    """FRF from text rows ``[(line number, [freq, real, imag]), ...]``."""
    a = np.empty((len(rows), 3))
    for i, (n, cells) in enumerate(rows):
        if len(cells) != 3:
            raise InputError(f"line {n}: expected 3 columns, found {len(cells)}", file=path, field="columns")
        for j, cell in enumerate(cells):
            try:
                a[i, j] = float(cell)
            except ValueError:
                raise InputError(f"line {n}: {cell.strip()!r} is not a number", file=path, field=names[j]) from None
    _validate(path, a[:, 0], a[:, 1], a[:, 2], lambda i: f"line {rows[i][0]}", names)
    v = np.empty(len(rows), dtype=complex)
    v.real, v.imag = a[:, 1], a[:, 2]
    return _finish(path, a[:, 0], v, quantity, min_points, label, fmt, {})


def _validate(path, f, re, im, where, names) -> None:
    """Finite values, non-negative and strictly increasing frequencies."""
    for name, col in zip(names, (f, re, im)):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise InputError(f"non-finite value {col[bad[0]]} at {where(bad[0])}", file=path, field=name)
    if f.size and f[0] < 0:
        raise InputError(f"negative frequency {f[0]:.10g} Hz at {where(0)}", file=path, field=names[0])
    bad = np.flatnonzero(np.diff(f) <= 0)
    if bad.size:
        i = bad[0] + 1
        what = "duplicate" if f[i] == f[i - 1] else f"non-increasing (after {f[i - 1]:.10g} Hz)"
        raise InputError(f"{what} frequency {f[i]:.10g} Hz at {where(i)}", file=path, field=names[0])


def _finish(path, f, v, quantity, min_points, label, fmt, meta) -> FRF:
    """Drop an unconvertible 0 Hz point, check the count, convert to receptance."""
    if quantity != "receptance" and f.size and f[0] == 0:
        warnings.warn(f"{path}: dropped the 0 Hz point ({quantity} cannot be converted to receptance at 0 Hz)",
                      stacklevel=4)
        f, v = f[1:], v[1:]
    if f.size == 0:
        raise InputError("no data points", file=path, field="data")
    if f.size < min_points:
        raise InputError(f"{f.size} points, need at least {min_points}", file=path, field="data")
    meta = {"source": os.fspath(path), "format": fmt, "file_quantity": quantity, **meta}
    return FRF(f, v, quantity, Path(path).stem if label is None else label, meta).to_receptance()


def _for_write(path, frf: FRF) -> FRF:
    """``frf`` as receptance, checked for writing."""
    try:
        r = frf.to_receptance()
    except ValueError as exc:
        raise InputError(str(exc), file=path, field="values") from None
    if len(r) == 0:
        raise InputError("no data points to write", file=path, field="values")
    _validate(path, r.freq_hz, r.values.real, r.values.imag, lambda i: f"point {i + 1}",
              ("freq_hz", "values.real", "values.imag"))
    return r


def _write_table(path, frf, header: str, sep: str) -> None:
    r = _for_write(path, frf)
    rows = "".join(f"{f:.17g}{sep}{z.real:.17g}{sep}{z.imag:.17g}\n" for f, z in zip(r.freq_hz, r.values))
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(header + rows)


_READERS = {".csv": read_csv_frf, ".uff": read_uff58, ".unv": read_uff58, ".uf": read_uff58, ".frf": read_cutpro}
_WRITERS = {".csv": write_csv_frf, ".uff": write_uff58, ".unv": write_uff58, ".uf": write_uff58, ".frf": write_cutpro}
