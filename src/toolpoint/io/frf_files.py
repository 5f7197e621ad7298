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
  lines starting with ``%`` or ``#`` are skipped. Exports with more columns
  (e.g. 9: several FRFs side by side) need a header naming them and may have a
  unit line after it: the first frequency, real and imaginary columns are read
  (and a coherence column if one is named so); m/N, mm/N and µm/N are known.
* ``.txt`` / ``.tsv`` / ``.dat`` — the same reader: whitespace, tab or comma
  separated Hz, real, imaginary (m/N), header optional (a lab export of three
  tab-separated columns without a header reads as is).

Coherence, when a file has it (a ``coherence`` column of CSV or text, a UFF
dataset 58 of function type 6 for the same response and reference), is kept as
an array on ``frf.meta["coherence"]`` (checked to lie in [0, 1]); the CSV and
UFF writers write it back.

Every reader returns a receptance :class:`~toolpoint.frf.FRF` in m/N (a
mobility or accelerance file is converted with :meth:`FRF.to_receptance`) and
raises :class:`~toolpoint.errors.InputError` naming the file and field for bad
input. Besides finite numbers and a strictly increasing frequency grid, the
readers refuse values no structure's FRF has, so that nothing overflows
downstream (squares in the fits, ω⁴ in conversions, 1/H in inverse RCSA):

* an FRF magnitude ``|H|`` above :data:`MAX_ABS_VALUE` (1e100, in the file's
  unit) or, unless it is exactly 0, below :data:`MIN_ABS_VALUE` (1e-100);
* a frequency above :data:`MAX_FREQ_HZ` (1e9 Hz);
* in a text file that does not end with a line break (a copy or export cut
  short), a last number with a missing or shorter exponent than every other
  number of its column (``1.2345e-08`` cut to ``1.2345e-0`` or ``1.23`` reads
  as 1.2345 or 1.23 m/N), or, in a column without exponents, with fewer digits
  than each of them; in an export of more columns than are read, a last line
  with fewer columns than the first or a cut number in a column not read: the
  message names the line and says to end the file with a line break if it is
  complete. A file cut exactly at a line break cannot be told from a shorter
  one (none of the text formats states its number of lines).

Every writer writes receptance, through :mod:`toolpoint.io.atomic`, so a
failure never leaves a half-written file.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pyuff

from .atomic import atomic_open, atomic_path
from ..errors import InputError
from ..frf import FRF, QUANTITIES, check_freq_hz

__all__ = [
    "read_frf", "write_frf", "read_csv_frf", "write_csv_frf", "read_uff58", "read_uff58_all",
    "write_uff58", "read_cutpro", "write_cutpro", "read_text_frf",
]

G0 = 9.80665  # standard gravity, m/s² per g
CSV_HEADER = ("freq_hz", "real", "imag")
COHERENCE_TOL = 1e-6  # round-off allowed outside [0, 1] before a coherence is refused
CUTPRO_COLUMNS = ("Freq", "Real", "Imag")
MAX_ABS_VALUE = 1e100  # largest |H| accepted from a file (file's unit); its square, summed, stays finite
MIN_ABS_VALUE = 1e-100  # smallest non-zero |H| accepted; 1/H stays finite
MAX_FREQ_HZ = 1e9  # largest frequency accepted from a file, Hz; (2πf)⁴ stays finite


# ---------------------------------------------------------------- dispatch
def read_frf(path, *, quantity: str | None = None, min_points: int = 1, label: str | None = None,
             response=None, reference=None) -> FRF:
    """Read an FRF file (``.csv``, ``.uff``/``.unv``/``.uf``, ``.frf``, ``.txt``/``.tsv``/``.dat``) as receptance.

    Parameters
    ----------
    path : str or Path
        The file; its extension picks the format.
    quantity : str, optional
        ``"receptance"``, ``"mobility"`` or ``"accelerance"``: what the file holds
        (overrides what a UFF file says). Mobility/accelerance points at 0 Hz are
        dropped with a warning.
    min_points : int
        Fewest points accepted.
    label : str, optional
        Defaults to the file stem.
    response, reference : int, str or tuple, optional
        UFF only: pick the FRF by response / reference node (``7``), or node and
        direction (``"7:3"``, ``"7:-2"`` or ``(7, 3)``). Needed when the file holds
        several FRFs; the error lists them.

    Returns
    -------
    FRF
        Receptance (m/N), SISO; ``meta`` holds the source, format, file quantity
        and, when the file has one, ``coherence`` (array on the FRF's grid).

    Raises
    ------
    InputError
        One line naming the file and field (and the line of a text file).

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from toolpoint.frf import FRF
    >>> frf = FRF([10.0, 20.0, 30.0], [1e-8 - 2e-8j, 3e-8j, -1e-9 + 0j], label="tool")
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_frf(os.path.join(d, "tp.csv"), frf)
    ...     got = read_frf(os.path.join(d, "tp.csv"))
    >>> got.label, bool(np.array_equal(got.values, frf.values))
    ('tp', True)
    """
    reader = _pick(path, _READERS)
    if reader is read_uff58:
        return reader(path, quantity=quantity, min_points=min_points, label=label, response=response,
                      reference=reference)
    if response is not None or reference is not None:
        raise InputError("response=/reference= pick among the FRFs of a UFF file; this file holds one",
                         file=path, field="response")
    return reader(path, quantity=quantity, min_points=min_points, label=label)


def write_frf(path, frf: FRF, *, as_measured: bool = False) -> None:
    """Write a SISO ``frf`` as receptance (m/N) in the format given by the extension of ``path``.

    ``.csv`` and ``.frf`` are exact (``%.17g``); ``.uff``/``.unv``/``.uf`` is UFF
    dataset 58 (see :func:`write_uff58`). The file is replaced atomically: a
    failure leaves any old file untouched. A coherence on ``frf.meta["coherence"]``
    (same length as the FRF) is written as a fourth CSV column or a second UFF
    dataset (function type 6); CutPro files hold no coherence. With
    ``as_measured`` the FRF is written in its own quantity (mobility,
    accelerance) instead of receptance (UFF says which; CSV and CutPro do not).

    Raises
    ------
    InputError
        Unknown extension, an empty or matrix FRF, or a mobility/accelerance at 0 Hz.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from toolpoint.frf import FRF
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_frf(Path(d) / "h.csv", FRF([0.0, 5.0], [1e-8 + 0j, 2e-8 - 1e-8j]))
    ...     print(Path(d, "h.csv").read_text(), end="")
    freq_hz,real,imag
    0,1e-08,0
    5,2e-08,-1e-08
    """
    _pick(path, _WRITERS)(path, frf, as_measured=as_measured)


def _pick(path, table):
    ext = Path(path).suffix.lower()
    if ext not in table:
        raise InputError(f"unknown FRF file extension {ext!r} (use one of {', '.join(table)})", file=path,
                         field="extension")
    return table[ext]


# ---------------------------------------------------------------- CSV
def read_csv_frf(path, *, quantity: str | None = None, min_points: int = 1, label: str | None = None) -> FRF:
    """Read a toolpoint CSV file: header ``freq_hz,real,imag``, then Hz, real, imaginary (m/N)."""
    q = _quantity(path, quantity)
    text, open_end = _read_text(path)
    lines = [(n, s) for n, s in enumerate(text, 1) if s.strip()]
    if not lines:
        raise InputError("empty file", file=path, field="header")
    head = lines[0][1]
    names = tuple(c.strip() for c in head.split(","))
    if names not in (CSV_HEADER, CSV_HEADER + ("coherence",)):
        raise InputError(f"expected {','.join(CSV_HEADER)!r} (optionally ',coherence'), found {head.strip()!r}",
                         file=path, field="header")
    rows = [(n, s.split(",")) for n, s in lines[1:]]
    return _table_frf(path, rows, names, q, min_points, label, "csv", open_end)


def write_csv_frf(path, frf: FRF, *, as_measured: bool = False) -> None:
    """Write ``frf`` as receptance to a toolpoint CSV file (``%.17g``: exact round trip).

    A coherence on ``frf.meta["coherence"]`` becomes a fourth column ``coherence``.
    """
    _write_table(path, frf, ",".join(CSV_HEADER), ",", as_measured)


# ---------------------------------------------------------------- CutPro
def read_cutpro(path, *, quantity: str | None = None, min_points: int = 1, label: str | None = None) -> FRF:
    """Read a CutPro ``.frf`` (or ``.txt``/``.tsv``/``.dat``) text file: columns Freq (Hz), Real, Imag (m/N).

    Columns may be separated by tabs, any whitespace or commas; lines starting
    with ``%`` or ``#`` are skipped. A header line is optional for three
    columns and required for more: it names the columns (``Freq``/``Hz``,
    ``Real``/``Re``, ``Imag``/``Im``, ``Coherence``), the first of each is read.
    A line of units may follow the header (``Hz``, ``m/N``, ``mm/N``, ``um/N``).
    """
    q = _quantity(path, quantity)
    rows, head, units = [], None, None
    text, open_end = _read_text(path)
    for n, line in enumerate(text, 1):
        cells = _split(line)
        if not cells or cells[0].startswith(("%", "#")):
            continue
        if not rows and not _is_number(cells[0]):
            if head is None:
                head = (n, cells)
            elif units is None:
                units = (n, cells)
            else:
                raise InputError(f"line {n}: {cells[0]!r} is not a number (a third header line?)", file=path,
                                 field="header")
            continue
        rows.append((n, cells))
    cols, names, scale = _columns(path, head, units, rows)
    if cols is not None:
        width = max(cols) + 1
        if open_end and len(rows) > 1 and len(rows[-1][1]) < len(rows[0][1]):  # columns not read are cut too
            n, cells = rows[-1]
            raise InputError(f"line {n}: {len(cells)} columns, the first data line has {len(rows[0][1])} (the file "
                             "ends without a line break: cut short?); if the file is complete, end it with a line "
                             "break", file=path, field="columns")
        _check_not_cut(path, rows, head[1], open_end)  # the last cell may be of a column not read
        picked = []
        for n, cells in rows:
            if len(cells) < width:
                raise InputError(f"line {n}: expected {len(head[1])} columns, found {len(cells)}", file=path,
                                 field="columns")
            picked.append((n, [cells[c] for c in cols]))
        rows = picked
    frf = _table_frf(path, rows, names, q, min_points, label, Path(path).suffix.lower().lstrip(".") or "text",
                     open_end)
    if scale != 1.0:
        frf = FRF(frf.freq_hz, frf.values * scale, frf.quantity, frf.label, frf.meta)
    return frf


read_text_frf = read_cutpro
"""Whitespace/tab/comma separated Hz, real, imaginary (m/N); header optional (see :func:`read_cutpro`)."""

_NAMES = {"freq": ("freq", "frequency", "f", "hz", "freq_hz"), "real": ("real", "re"),
          "imag": ("imag", "im", "imaginary"), "coherence": ("coherence", "coh", "gamma2", "γ²")}
_LENGTH_UNITS = {"m/n": 1.0, "mm/n": 1e-3, "um/n": 1e-6, "µm/n": 1e-6, "μm/n": 1e-6}


def _kind(name: str) -> str | None:
    """What a header cell names: 'freq', 'real', 'imag', 'coherence' or None (``Re(H11)`` → real)."""
    s = name.strip().lower()
    base = s.split("(")[0].split("[")[0].strip(" _-") or s
    for k, words in _NAMES.items():
        if base in words or (k != "freq" and base.startswith(words[0])) or (k == "freq" and base.startswith("freq")):
            return k
    return None


def _columns(path, head, units, rows):
    """(column indices or None, names, value scale to m/N) from the header and unit lines."""
    ncol = len(rows[0][1]) if rows else 3
    if head is None:
        if ncol != 3:
            n = rows[0][0]
            raise InputError(f"line {n}: {ncol} columns and no header naming them; expected 3 (Hz, real, imag) "
                             "or a header line", file=path, field="columns")
        return None, CUTPRO_COLUMNS, 1.0
    n, cells = head
    kinds = [_kind(c) for c in cells]
    if len(cells) == 3 and ncol == 3 and kinds == [None] * 3:
        return None, CUTPRO_COLUMNS, 1.0  # an unlabelled header such as "Freq Re Im" of another language
    pos = {}
    for i, k in enumerate(kinds):
        if k is not None and k not in pos:
            pos[k] = i
    missing = [k for k in ("freq", "real", "imag") if k not in pos]
    if missing:
        raise InputError(f"line {n}: header {' '.join(cells)!r} names no {' or '.join(missing)} column",
                         file=path, field="header")
    order = ["freq", "real", "imag"] + (["coherence"] if "coherence" in pos else [])
    cols = [pos[k] for k in order]
    names = tuple(cells[c] for c in cols)
    scale = 1.0
    if units is not None:
        un, ucells = units
        if len(ucells) != len(cells):
            raise InputError(f"line {un}: {len(ucells)} unit labels for {len(cells)} columns", file=path,
                             field="units")
        fu, vu = ucells[pos["freq"]].strip("[]()").lower(), ucells[pos["real"]].strip("[]()").lower()
        if fu not in ("hz", "1/s"):
            raise InputError(f"line {un}: frequency unit {ucells[pos['freq']]!r}; need Hz", file=path,
                             field="units")
        if vu not in _LENGTH_UNITS:
            raise InputError(f"line {un}: FRF unit {ucells[pos['real']]!r}; known: m/N, mm/N, um/N", file=path,
                             field="units")
        scale = _LENGTH_UNITS[vu]
    return cols, names, scale


def _split(line: str) -> list[str]:
    """Cells of a text line: comma separated, else tab separated (a header cell may hold spaces), else whitespace."""
    s = line.strip()
    if "," in s:
        return [c.strip() for c in s.split(",")]
    if "\t" in s:
        return [c.strip() for c in s.split("\t") if c.strip()]
    return s.split()


def write_cutpro(path, frf: FRF, *, as_measured: bool = False) -> None:
    """Write ``frf`` as receptance to a CutPro ``.frf`` file: tab-separated Hz, real, imaginary (m/N).

    No header line is written (CutPro-style plain three-column data); a coherence is not written.
    """
    _write_table(path, frf, None, "\t", as_measured)


# ---------------------------------------------------------------- UFF 58
_UFF_QUANTITY = {8: "receptance", 11: "mobility", 12: "accelerance"}  # ordinate specific data type
_UFF_TYPE = {q: t for t, q in _UFF_QUANTITY.items()}
_UFF_UNIT = {"receptance": "m", "mobility": "m/s", "accelerance": "m/s^2"}
_FUNC_TYPES = {
    0: "general or unknown", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
    4: "frequency response function", 5: "transmissibility", 6: "coherence", 7: "auto correlation",
    8: "cross correlation", 9: "power spectral density", 12: "spectrum",
}


def read_uff58(path, *, index: int | None = None, quantity: str | None = None, min_points: int = 1,
               label: str | None = None, response=None, reference=None) -> FRF:
    """Read one FRF from a Universal File Format dataset 58 (ASCII or binary 58b).

    The FRF is a dataset 58 of function type 4. ``index`` picks among the
    datasets 58 of the file (0 = first); otherwise ``response`` / ``reference``
    (node ``7``, or node and direction ``"7:3"`` / ``(7, 3)``) pick among the
    FRFs, and a file with one FRF needs neither; several candidates raise
    :class:`InputError` listing them. The quantity comes from the ordinate
    specific data type (8 displacement, 11 velocity, 12 acceleration, over
    force), else from the ordinate unit label (``m/s²``…), unless ``quantity``
    is given; a unit ``g`` is converted to m/s² (×9.80665) with a warning.
    Values are assumed SI (m, N, s). A coherence dataset (function type 6) with
    the same response and reference goes to ``meta["coherence"]``.
    """
    q = _quantity(path, quantity) if quantity is not None else None
    uff, sets, heads = _uff_headers(path)
    if index is None:
        k = _pick_frf(path, heads, response, reference)
    else:
        try:
            k = range(len(heads))[index]
        except (IndexError, TypeError):
            raise InputError(f"index {index!r} out of range: the file has {len(heads)} datasets 58",
                             file=path, field="index") from None
    frf = _uff_frf(path, uff, sets[k], k, q, min_points, label)
    coh = [j for j, h in enumerate(heads) if h.get("func_type") == 6 and _dofs(h) == _dofs(heads[k])]
    if coh:
        c = _uff_coherence(path, uff, sets[coh[0]], coh[0], frf)
        frf = FRF(frf.freq_hz, frf.values, frf.quantity, frf.label, {**frf.meta, "coherence": c})
    return frf


def _dofs(h) -> tuple:
    return (h.get("rsp_node"), h.get("rsp_dir"), h.get("ref_node"), h.get("ref_dir"))


def _parse_dof(path, value, name):
    """(node, direction or None) from 7, "7", "7:3", (7, 3)."""
    try:
        if isinstance(value, (tuple, list)):
            node, d = value
            return int(node), int(d)
        s = str(value).strip()
        if ":" in s:
            node, d = s.split(":")
            return int(node), int(d)
        return int(s), None
    except (TypeError, ValueError):
        raise InputError(f"{value!r} is not a node or node:direction (e.g. 7 or 7:3)", file=path,
                         field=name) from None


def _pick_frf(path, heads, response, reference) -> int:
    """Index of the one FRF (function type 4) matching ``response`` / ``reference``."""
    frfs = [k for k, h in enumerate(heads) if h.get("func_type") == 4]
    if not frfs:
        return 0  # _uff_frf reports its function type
    want = {}
    for name, value, keys in (("response", response, ("rsp_node", "rsp_dir")),
                              ("reference", reference, ("ref_node", "ref_dir"))):
        if value is not None:
            want[name] = (_parse_dof(path, value, name), keys)

    def ok(h):
        return all(h.get(keys[0]) == node and (d is None or h.get(keys[1]) == d)
                   for (node, d), keys in want.values())

    found = [k for k in frfs if ok(heads[k])]
    if len(found) == 1:
        return found[0]
    choices = "; ".join(f"#{k}: response {heads[k].get('rsp_node')}:{heads[k].get('rsp_dir')} reference "
                        f"{heads[k].get('ref_node')}:{heads[k].get('ref_dir')}" for k in frfs)
    field = "response" if response is not None or reference is None else "reference"
    if not found:
        asked = ", ".join(f"{n} {v}" for n, v in (("response", response), ("reference", reference)) if v is not None)
        raise InputError(f"no FRF with {asked}; the file has {choices}", file=path, field=field)
    raise InputError(f"{len(found)} FRFs match; pick one with response=/reference= (--response/--reference): "
                     f"{choices}", file=path, field=field)


def _uff_coherence(path, uff, setno, k, frf) -> np.ndarray:
    """Coherence dataset 58 #k on the FRF's grid, checked to lie in [0, 1]."""
    try:
        ds = uff.read_sets(setno)
    except Exception as exc:  # pyuff raises bare Exception
        raise InputError(f"dataset 58 #{k} cannot be read ({exc})", file=path, field="coherence") from exc
    x = np.asarray(ds["x"], dtype=float)
    c = np.asarray(ds["data"])
    if np.iscomplexobj(c):
        if np.any(c.imag != 0):
            raise InputError(f"coherence dataset 58 #{k} has imaginary values", file=path, field="coherence")
        c = c.real
    c = np.asarray(c, dtype=float)
    sel = np.isin(x, frf.freq_hz) if x.size != len(frf) else np.ones(x.size, bool)
    if np.count_nonzero(sel) != len(frf):
        raise InputError(f"coherence dataset 58 #{k} has {x.size} points, the FRF {len(frf)}", file=path,
                         field="coherence")
    return _check_coherence(path, c[sel], lambda i: f"dataset 58 #{k} point {i + 1}")


def read_uff58_all(path, *, quantity: str | None = None, min_points: int = 1) -> list[FRF]:
    """Every FRF (dataset 58 with function type 4) of a UFF file, as receptance in m/N.

    Other datasets 58 (coherence, spectra, ...) are skipped; labels are
    ``"<stem>#<k>"`` with k the position among the datasets 58.
    """
    q = _quantity(path, quantity) if quantity is not None else None
    uff, sets, heads = _uff_headers(path)
    ks = [k for k, h in enumerate(heads) if h.get("func_type") == 4] or [0]  # [0]: report its type
    return [_uff_frf(path, uff, sets[k], k, q, min_points, f"{Path(path).stem}#{k}") for k in ks]


def write_uff58(path, frf: FRF, *, binary: bool = False, as_measured: bool = False) -> None:
    """Write ``frf`` as a UFF dataset 58 (receptance m/N, complex double), replacing ``path``.

    A coherence on ``frf.meta["coherence"]`` is written as a second dataset 58
    (function type 6, real double) with the same nodes. ``as_measured`` keeps a
    mobility or accelerance as it is (ordinate data type 11 or 12).

    An evenly spaced grid is written as abscissa minimum and increment when
    those survive pyuff's 6-digit ``%13.5e`` header format; otherwise every
    frequency is stored (uneven spacing). ASCII keeps uneven frequencies to 6
    significant digits: a warning gives the rounding, and frequencies that
    would collide raise :class:`InputError`; ``binary=True`` keeps them exact.
    """
    r = _for_write(path, frf, as_measured)
    coh = _coherence_of(path, r)
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
        ordinate_spec_data_type=_UFF_TYPE[r.quantity], ordinate_axis_units_lab=_UFF_UNIT[r.quantity],
        orddenom_spec_data_type=13, orddenom_axis_units_lab="N",
        data=v.copy(), x=f.copy(),
    )
    sets = [ds]
    if coh is not None:
        cs = dict(ds, func_type=6, ord_data_type=4, ordinate_spec_data_type=0, ordinate_axis_units_lab="NONE",
                  orddenom_spec_data_type=0, orddenom_axis_units_lab="NONE", data=coh.copy(), x=f.copy())
        cs["id1"] = ("coherence " + ds["id1"])[:80]
        sets.append(cs)
    with atomic_path(path) as tmp, warnings.catch_warnings():
        # tmp is a new, empty file, so "add" writes exactly one dataset. Not "overwrite":
        # pyuff 2.5.8 reopens the file with "wb" for binary data and truncates the header.
        # For binary data it also leaves its last handle to be closed (and flushed) when its
        # writer returns, which CPython does at once, with a ResourceWarning.
        warnings.simplefilter("ignore", ResourceWarning)
        pyuff.UFF(tmp).write_sets(sets, mode="add")


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
    by_unit = _quantity_from_unit(_label(ds, "ordinate_axis_units_lab"))
    if by_unit is not None:
        return by_unit
    warnings.warn(f"{path}: {tag} ordinate data type {num} over {den} is not displacement, velocity or "
                  "acceleration over force; assuming receptance (m/N) — pass quantity= to say", stacklevel=4)
    return "receptance"


def _quantity_from_unit(unit: str) -> str | None:
    """Quantity named by an ordinate unit label such as ``(1/N)*(m/s²)`` or ``m/s^2/N`` (None if unclear).

    Vendors write the square as ``²``, ``^2`` or ``2``; a non-UTF-8 ``²`` reads as a replacement character.
    """
    u = "".join(unit.lower().split()).replace("(", "").replace(")", "").replace("*", "")
    u = u.replace("1/n", "").replace("/n", "")
    u = u.replace("\ufffd", "²").replace("^2", "²").replace("s2", "s²")
    return {"m": "receptance", "m/s": "mobility", "m/s²": "accelerance"}.get(u)


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
    from .table import check_regular_file

    if os.path.exists(path):
        check_regular_file(path)  # a FIFO would block the open below for ever
    try:
        with open(path, "rb"):
            pass
    except FileNotFoundError:
        raise InputError("file not found", file=path) from None
    except OSError as exc:
        raise InputError(f"cannot read file ({exc.strerror or exc})", file=path) from None


def _read_lines(path) -> list[str]:
    return _read_text(path)[0]


def _read_text(path) -> tuple[list[str], bool]:
    """(lines of a UTF-8 (or UTF-16 with its byte-order mark) text file, whether it ends without a line break: its
    last line may be cut)."""
    from .table import text_encoding

    _check_readable(path)
    try:
        raw = Path(path).read_bytes()
        enc = text_encoding(raw)
        text = raw.decode(enc)
    except UnicodeDecodeError:
        raise InputError(f"not a {'UTF-16' if enc == 'utf-16' else 'UTF-8'} text file", file=path) from None
    except OSError as exc:
        raise InputError(f"cannot read file ({exc.strerror or exc})", file=path) from None
    return text.splitlines(), bool(text) and text[-1] not in "\r\n"


def _digits(cell: str) -> tuple[int, int | None]:
    """(digits of the mantissa, digits of the exponent or None) of a number as written."""
    s = cell.strip().lower().lstrip("+-")
    mant, _, exp = s.partition("e")
    return sum(ch.isdigit() for ch in mant), (sum(ch.isdigit() for ch in exp) if _ else None)


def _check_not_cut(path, rows, names, open_end: bool) -> None:
    """Refuse a last number that looks cut short, in a text file that ends without a line break.

    ``rows`` are ``[(line number, cells), ...]`` of numbers. A cut removes the end of the file, so only
    the last cell of the last row can lose digits (a cut elsewhere leaves too few columns). Compared
    with the other numbers of its column it is refused when

    * they all have an exponent and it has none (and is not 0), or a shorter one (one other number is enough:
      a file cut in its second data line is refused too);
    * none of them has an exponent and it has fewer digits than each of them (at least 2 of them).
    """
    if not open_end or len(rows) < 2:
        return
    n, cells = rows[-1]
    j = len(cells) - 1
    others = [_digits(c[j]) for _, c in rows[:-1] if len(c) > j]
    if not others:
        return
    m, e = _digits(cells[j])
    exps = [x for _, x in others if x is not None]
    if not _is_number(cells[j]):  # a column not read ("-7.1e-" in the 6th column of a 3-column pick)
        cut = True
    elif len(exps) == len(others):
        cut = (e is None and float(cells[j]) != 0) or (e is not None and e < min(exps))
    else:
        cut = not exps and e is None and len(others) >= 2 and m < min(d for d, _ in others)
    if cut:
        raise InputError(f"line {n}: {cells[j].strip()!r} looks cut short (the file ends without a line break, "
                         "mid-number?); if the file is complete, end it with a line break", file=path,
                         field=names[min(j, len(names) - 1)])


def _is_number(s: str) -> bool:
    """Whether ``s`` is a number as data files write them (Python's ``1_000`` is not)."""
    try:
        float(s)
        return "_" not in s
    except ValueError:
        return False


def _table_frf(path, rows, names, quantity, min_points, label, fmt, open_end=False) -> FRF:
    """FRF from text rows ``[(line number, [freq, real, imag(, coherence)]), ...]``; ``names`` name the columns."""
    k = len(names)
    a = np.empty((len(rows), k))
    for i, (n, cells) in enumerate(rows):
        if len(cells) != k:
            raise InputError(f"line {n}: expected {k} columns, found {len(cells)}", file=path, field="columns")
        for j, cell in enumerate(cells):
            try:
                if "_" in cell:  # Python's float() reads "1_000" as 1000; no data file writes that
                    raise ValueError(cell)
                a[i, j] = float(cell)
            except ValueError:
                raise InputError(f"line {n}: {cell.strip()!r} is not a number", file=path, field=names[j]) from None
    _check_not_cut(path, rows, names, open_end)
    where = lambda i: f"line {rows[i][0]}"  # noqa: E731
    _validate(path, a[:, 0], a[:, 1], a[:, 2], where, names)
    v = np.empty(len(rows), dtype=complex)
    v.real, v.imag = a[:, 1], a[:, 2]
    meta = {} if k == 3 else {"coherence": _check_coherence(path, a[:, 3], where, names[3])}
    return _finish(path, a[:, 0], v, quantity, min_points, label, fmt, meta)


def _check_coherence(path, c, where, name="coherence") -> np.ndarray:
    """A coherence column: finite and in [0, 1] (round-off of ``COHERENCE_TOL`` clipped)."""
    c = np.asarray(c, dtype=float)
    bad = np.flatnonzero(~np.isfinite(c) | (c < -COHERENCE_TOL) | (c > 1 + COHERENCE_TOL))
    if bad.size:
        raise InputError(f"coherence {c[bad[0]]:.6g} outside [0, 1] at {where(bad[0])}", file=path, field=name)
    return np.clip(c, 0.0, 1.0)


def _validate(path, f, re, im, where, names) -> None:
    """Finite values of a plausible magnitude and a valid frequency grid (:func:`check_freq_hz`), located in the file.

    ``|H|`` must be 0 or within [:data:`MIN_ABS_VALUE`, :data:`MAX_ABS_VALUE`] and frequencies at most
    :data:`MAX_FREQ_HZ`: a value such as 1e300 is finite but overflows downstream.
    """
    for name, col in zip(names[1:], (re, im)):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            raise InputError(f"non-finite value {col[bad[0]]} at {where(bad[0])}", file=path, field=name)
    mag = np.hypot(re, im)
    bad = np.flatnonzero((mag > MAX_ABS_VALUE) | ((mag < MIN_ABS_VALUE) & (mag != 0)))
    if bad.size:
        i = bad[0]
        name = names[1] if abs(re[i]) >= abs(im[i]) else names[2]
        raise InputError(f"|H| = {mag[i]:.3g} at {where(i)} is not a plausible FRF value (accepted: 0 or "
                         f"{MIN_ABS_VALUE:g} to {MAX_ABS_VALUE:g} in the file's unit)", file=path, field=name)
    check_freq_hz(f, file=path, field=names[0], min_points=0, where=where)
    bad = np.flatnonzero(f > MAX_FREQ_HZ)
    if bad.size:
        raise InputError(f"frequency {f[bad[0]]:.3g} Hz at {where(bad[0])} is above {MAX_FREQ_HZ:g} Hz",
                         file=path, field=names[0])


def _finish(path, f, v, quantity, min_points, label, fmt, meta) -> FRF:
    """Drop an unconvertible 0 Hz point, check the count, convert to receptance."""
    if quantity != "receptance" and f.size and f[0] == 0:
        warnings.warn(f"{path}: dropped the 0 Hz point ({quantity} cannot be converted to receptance at 0 Hz)",
                      stacklevel=4)
        f, v = f[1:], v[1:]
        if "coherence" in meta:
            meta = {**meta, "coherence": meta["coherence"][1:]}
    if f.size == 0:
        raise InputError("no data points", file=path, field="data")
    if f.size < min_points:
        raise InputError(f"{f.size} points, need at least {min_points}", file=path, field="data")
    meta = {"source": os.fspath(path), "format": fmt, "file_quantity": quantity, **meta}
    return FRF(f, v, quantity, Path(path).stem if label is None else label, meta).to_receptance()


def _for_write(path, frf: FRF, as_measured: bool = False) -> FRF:
    """``frf`` as receptance (or as it is, ``as_measured``), checked for writing."""
    try:
        r = frf if as_measured else frf.to_receptance()
    except InputError as exc:
        raise InputError(exc.message, file=path, field="values") from None
    if len(r) == 0:
        raise InputError("no data points to write", file=path, field="values")
    if not r.is_siso:
        raise InputError("an FRF file holds one response; write each entry (.entry(i, j)) to its own file",
                         file=path, field="values")
    return r


def _coherence_of(path, frf: FRF):
    """``frf.meta["coherence"]`` checked for writing, or None when there is none."""
    c = frf.meta.get("coherence")
    if c is None:
        return None
    c = np.asarray(c, dtype=float).reshape(-1)
    if c.size != len(frf):
        raise InputError(f"meta['coherence'] has {c.size} values for {len(frf)} frequencies (an FRF cut with "
                         "band()/at() keeps the old coherence: drop or cut it too)", file=path, field="coherence")
    return _check_coherence(path, c, lambda i: f"{frf.freq_hz[i]:g} Hz")


def _write_table(path, frf, header: str | None, sep: str, as_measured: bool = False) -> None:
    r = _for_write(path, frf, as_measured)
    coh = _coherence_of(path, r) if header is not None else None
    cols = [r.freq_hz, r.values.real, r.values.imag] + ([coh] if coh is not None else [])
    head = "" if header is None else header + (f"{sep}coherence" if coh is not None else "") + "\n"
    fmt = sep.join(["{:.17g}"] * len(cols)) + "\n"
    rows = "".join(fmt.format(*row) for row in zip(*cols))
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(head + rows)


_READERS = {".csv": read_csv_frf, ".uff": read_uff58, ".unv": read_uff58, ".uf": read_uff58, ".frf": read_cutpro,
            ".txt": read_cutpro, ".tsv": read_cutpro, ".dat": read_cutpro}
_WRITERS = {".csv": write_csv_frf, ".uff": write_uff58, ".unv": write_uff58, ".uf": write_uff58, ".frf": write_cutpro}


def header_cells(text: list[str], first: int) -> list[list[str]]:
    """The header lines just above the first data line (line ``first``, 1-based), nearest first, split as
    ``numeric_lines`` splits the data; comments and blank lines skipped."""
    out = []
    for line in reversed(text[:first - 1]):
        s = line.strip()
        if not s or s[0] in "#%":
            continue
        sep = ";" if ";" in s else "\t" if "\t" in s else "," if "," in s else None
        out.append([c.strip().strip('"') for c in (s.split(sep) if sep else s.split())])
    return out


def _is_unit_row(cells: list[str]) -> bool:
    """A DAQ's units row under the names (``s;g;g``, ``[s] [m/s^2]``): short cells without a space."""
    return all(0 < len(c) <= 8 and " " not in c for c in cells)


def column_names(text: list[str], first: int, width: int) -> list[str] | None:
    """The columns' names from the header above the data: the names line, with a units row under it (a DAQ's
    export: ``Time;AI 1`` over ``s;g``) as "AI 1 (g)"; None where the header holds another number of cells."""
    head = [c for c in header_cells(text, first)[:2] if len(c) == width]
    if not head:
        return None
    if len(head) == 2 and _is_unit_row(head[0]):
        return [f"{n} ({u.strip('[]()')})" if u else n for n, u in zip(head[1], head[0])]
    return head[0]


# the units a column's header may carry (lower case, spaces removed): (quantity, factor to SI); a voltage is no
# physical quantity until divided by the sensor's sensitivity (factor None)
UNITS = {**{u: ("time", f) for u, f in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("µs", 1e-6), ("μs", 1e-6))},
         **{u: ("force", f) for u, f in (("n", 1.0), ("kn", 1e3), ("lbf", 4.4482216), ("lb", 4.4482216))},
         **{u: ("acceleration", 1.0) for u in ("m/s^2", "m/s²", "m/s2", "ms2", "ms^-2", "m/s/s", "ms-2")},
         **{u: ("acceleration", f) for u, f in (("g", G0), ("mm/s^2", 1e-3), ("mm/s²", 1e-3), ("mm/s2", 1e-3),
                                                 ("in/s^2", 0.0254), ("in/s²", 0.0254), ("in/s2", 0.0254))},
         **{u: ("velocity", f) for u, f in (("m/s", 1.0), ("mm/s", 1e-3), ("in/s", 0.0254), ("ips", 0.0254))},
         **{u: ("displacement", f) for u, f in (("m", 1.0), ("mm", 1e-3), ("um", 1e-6), ("µm", 1e-6), ("μm", 1e-6),
                                                 ("in", 0.0254), ("mil", 2.54e-5))},
         "v": ("voltage", None), "mv": ("voltage", None)}
_UNIT_IN_BRACKETS = re.compile(r"[\[(]\s*([^\[\]()]+?)\s*[\])]\s*$")
_UNIT_AFTER_UNDERSCORE = re.compile(r"_([^_\s]+)$")


def column_unit(name: str) -> tuple | None:
    """(unit, quantity, factor to SI or None) that a column's header names: in brackets at its end (``Accel (g)``,
    ``t [ms]``), after its last underscore (``time_s``, ``acceleration_ms2``) or as the whole cell (a units row's
    ``g``); None where it names no unit of :data:`UNITS`.

    Examples
    --------
    >>> column_unit("Accel (g)"), column_unit("time_ms"), column_unit("Accel_X"), column_unit("mV")
    (('g', 'acceleration', 9.80665), ('ms', 'time', 0.001), None, ('mv', 'voltage', None))
    """
    for m in (_UNIT_IN_BRACKETS.search(name), _UNIT_AFTER_UNDERSCORE.search(name)):
        if m and (u := m.group(1).replace(" ", "").lower()) in UNITS:
            return (u, *UNITS[u])
    u = name.strip().strip("[]()").replace(" ", "").lower()
    return (u, *UNITS[u]) if u in UNITS else None


def drop_empty_columns(rows: list) -> tuple[list, list]:
    """(``rows`` [(line number, cells)] without the columns that are empty on every row, the kept columns' indices):
    a LabVIEW export's Comment column, a separator closing each line, are no data. A cell empty on some rows only
    stays (a missing value, refused by the reader that checks the numbers). Rows of unequal width are returned as
    they are, for the reader to refuse.

    Examples
    --------
    >>> drop_empty_columns([(2, ["0", "1.5", ""]), (3, ["0.1", "-2", ""])])
    ([(2, ['0', '1.5']), (3, ['0.1', '-2'])], [0, 1])
    """
    if not rows or len({len(c) for _, c in rows}) != 1:
        return rows, list(range(max((len(c) for _, c in rows), default=0)))
    keep = [j for j in range(len(rows[0][1])) if any(c[j] for _, c in rows)]
    if len(keep) == len(rows[0][1]):
        return rows, keep
    return [(n, [c[j] for j in keep]) for n, c in rows], keep


def numeric_lines(text: list[str]):
    """(line number, cells) of a text table's data lines: comments (``#``, ``%``) and blank lines skipped, cells split
    at semicolons (a spreadsheet's export where the comma is the decimal mark: ``0,5;1,25`` is 0.5 and 1.25) or, where
    a line holds both tabs and commas, at tabs (the same, as "Unicode text"), else at commas, else at white space;
    header lines before the first number skipped. The one line splitter of the column readers (impact records, cut
    records).

    Examples
    --------
    >>> list(numeric_lines(["t;acc", "0,0;1,5", "0,1;-2"])), list(numeric_lines(["0.0, 1.5", "0.1\\t-2"]))
    ([(2, ['0.0', '1.5']), (3, ['0.1', '-2'])], [(1, ['0.0', '1.5']), (2, ['0.1', '-2'])])
    >>> list(numeric_lines(["t\\tacc", "0,0\\t1,5"]))
    [(2, ['0.0', '1.5'])]
    """
    started = False
    for n, line in enumerate(text, 1):
        s = line.strip()
        if not s or s[0] in "#%":
            continue
        if ";" in s or ("\t" in s and "," in s):  # a spreadsheet's cells: ',' there is the decimal mark
            cells = [c.strip().replace(",", ".") for c in s.split(";" if ";" in s else "\t")]
        else:
            cells = [c.strip() for c in (s.split(",") if "," in s else s.split())]
        if not started and not _is_number(cells[0]):
            continue  # a header line
        started = True
        yield n, cells
