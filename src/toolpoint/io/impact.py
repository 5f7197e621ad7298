"""Impact (tap) tests: time records of hammer force and response → hits → FRF with coherence.

A *record* is a uniformly sampled time history of the hammer force (N) and of
the response (acceleration m/s², velocity m/s or displacement m). A record may
hold one hit or several (one long record); :func:`find_hits` cuts it into
*hits* at the force threshold, and :func:`impact_frf` averages the hits of one
or several records into the H1 (default) or H2 estimate of the FRF, with the
ordinary coherence.

Per hit k, with F_k and X_k the DFTs of the windowed force and response blocks,

    S_ff = Σ_k |F_k|²,  S_xx = Σ_k |X_k|²,  S_xf = Σ_k X_k F_k*,
    H1 = S_xf / S_ff,   H2 = S_xx / S_xf*,  γ² = |S_xf|² / (S_ff S_xx).

Windows (all start at the block start, ``pretrigger_s`` before the trigger):

* force window: 1 from the block start to the end of the force pulse(s) plus
  one pulse width, 0 after (removes the force channel's noise between hits);
* exponential window e^{-t/τ} on both channels, off by default
  (``exp_window_s=None``). Because e^{-t/τ} multiplies the convolution
  x = h * f exactly when both channels share the time origin, the estimated FRF
  is exactly that of the impulse response h(t) e^{-t/τ}: every pole s_r moves
  to s_r − 1/τ (residues unchanged), which adds Δζ = 1/(ω_r τ) to the damping
  ratio of a mode at ω_r. A windowed accelerance (mobility) is converted to
  receptance by dividing by (iω + 1/τ)² ((iω + 1/τ)), which keeps that exact
  form; dividing by (iω)² would distort it by about 2/(ωτ). The FRF is
  reported with the window; the added damping is returned
  (:meth:`TapResult.added_damping`) and :func:`corrected_damping` removes it
  from modal parameters fitted downstream.

Offsets and drift (``detrend="auto"``, the default) are removed per block
before any window. The force: its baseline (median of the block outside the
force window) is subtracted. The acceleration: the least-squares straight line
over the block is subtracted. This removes a DC offset and a linear drift of
the channel and nothing of a grounded structure's response, whose acceleration
has zero 0th and 1st moments once it is at rest again before the block ends:
∫ẍ dt = ẋ(T) − ẋ(0) = 0 and ∫t ẍ dt = T ẋ(T) − (x(T) − x(0)) = 0. Divided by
−ω² a drift b·t becomes an artefact b T/(iω · ω² F(ω)) ∝ f⁻³ in the receptance,
which is what a real record shows below ≈ 60 Hz (issue 20). A velocity
response loses only its mean (∫ẋ dt = 0; its 1st moment is −∫x dt ≠ 0), a
displacement only its pre-trigger mean (its mean is the static response).
What is left below a few tens of Hz (the conditioner's high-pass settling,
sensor noise × 1/ω²) is cut downstream by :func:`toolpoint.trust.trusted_band`.

Band. The FRF is kept only where the hammer excited the structure: up to the
first line where the force auto-spectrum S_ff has dropped by ``force_drop_db``
(default :data:`FORCE_DROP_DB` = 15 dB, the middle of the 10–20 dB of test
practice) below its low-frequency level (median of S_ff from 0 Hz to
0.1/T_pulse, T_pulse the force pulse width). A half-sine pulse of contact time
T_c drops by 15 dB at ≈ 1.17/T_c (steel tip, 0.15 ms: 7.8 kHz; plastic, 0.4 ms:
2.9 kHz; rubber, 1.5 ms: 0.78 kHz); its first zero is at 1.5/T_c. Above the
band the FRF is noise over a vanishing force and is not written; the note
(:attr:`TapResult.notes`) says where and why the band ends.

One hit: the coherence of a single average is 1 at every frequency by
construction (|S_xf|² = S_ff S_xx for one block), so it says nothing about the
quality of the FRF. It is then not reported (no ``meta["coherence"]``, no
coherence column in the file) and a warning names the record as a single hit.

Quality checks per hit: a *double hit* (the force rises above the threshold
again within ``min_gap_s`` of the trigger) warns; an *overload* (three or more
samples of a channel at its maximum magnitude: clipping) is an error. With
``drop_bad=True`` both are dropped from the average with a warning. A hit *cut
off* by the end of the record (less than ``min_gap_s`` of record after its
trigger, or its pulse still above the threshold at the last sample) is always
dropped with a warning; a record whose only hits are cut off is refused.

Bad input raises :class:`~toolpoint.errors.InputError` naming the file and field.
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..frf import FRF

__all__ = ["RESPONSES", "Record", "Hit", "TapResult", "read_record", "find_hits", "impact_frf", "plot_tap",
           "corrected_damping", "CorrectedDamping"]

RESPONSES = {"acceleration": "accelerance", "velocity": "mobility", "displacement": "receptance"}
"""Response kind → the FRF quantity it gives over force."""

G0 = 9.80665  # standard gravity, m/s² per g
CLIP_SAMPLES = 3  # samples at a channel's maximum magnitude that mean clipping (pyFRF's rule)
PRETRIGGER_SAMPLES = 20  # default pretrigger
LEAK_TAIL, LEAK_LEVEL = 0.05, 0.02  # warn if the last 5 % of a block still reaches 2 % of its peak
FORCE_DROP_DB = 15.0
"""Default drop of the force auto-spectrum below its low-frequency level that ends the band, dB (10–20 dB practice)."""
DT_RANGE_S = (1e-9, 1.0)
"""Sampling steps accepted, s (1 GHz … 1 Hz): outside, the time column is not in seconds or not a tap record."""
DETRENDS = ("auto", "none")


@dataclass(frozen=True)
class Record:
    """A uniformly sampled impact record (checked on construction).

    Parameters
    ----------
    time_s : array_like
        (N,) sample times, s, strictly increasing and uniform (to half a step).
    force_n : array_like
        (N,) hammer force, N.
    response : array_like
        (N,) response in SI units of ``response_kind``.
    response_kind : str
        ``"acceleration"`` (m/s², default), ``"velocity"`` (m/s) or ``"displacement"`` (m).
    source : str
        File the record came from (for messages).
    """

    time_s: np.ndarray
    force_n: np.ndarray
    response: np.ndarray
    response_kind: str = "acceleration"
    source: str = ""

    def __post_init__(self):
        src = self.source or None
        if self.response_kind not in RESPONSES:
            raise InputError(f"unknown response kind {self.response_kind!r} (one of {', '.join(RESPONSES)})",
                             file=src, field="response")
        arrays = {}
        for name in ("time_s", "force_n", "response"):
            try:
                a = np.asarray(getattr(self, name), dtype=float).reshape(-1)
            except (TypeError, ValueError):
                raise InputError("must be numbers", file=src, field=name) from None
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                raise InputError(f"non-finite value at sample {bad[0] + 1}", file=src, field=name)
            arrays[name] = a
        t, f, x = arrays["time_s"], arrays["force_n"], arrays["response"]
        if not (t.size == f.size == x.size):
            raise InputError(f"lengths differ: time {t.size}, force {f.size}, response {x.size} samples",
                             file=src, field="length")
        if t.size < 8:
            raise InputError(f"{t.size} samples; need at least 8", file=src, field="time_s")
        d = np.diff(t)
        bad = np.flatnonzero(d <= 0)
        if bad.size:
            k = int(bad[0])
            raise InputError(f"time must increase: sample {k + 2} ({t[k + 1]:.10g} s) follows {t[k]:.10g} s",
                             file=src, field="time_s")
        dt = (t[-1] - t[0]) / (t.size - 1)
        if not DT_RANGE_S[0] <= dt <= DT_RANGE_S[1]:
            raise InputError(f"time step {dt:.3g} s is outside {DT_RANGE_S[0]:g}–{DT_RANGE_S[1]:g} s (sampling "
                             "1 GHz … 1 Hz): is the time column in seconds?", file=src, field="time_s")
        dev = np.abs(t - (t[0] + dt * np.arange(t.size)))
        if dev.max() > 0.5 * dt:
            k = int(np.argmax(dev))
            raise InputError(f"sampling is not uniform (sample {k + 1} at {t[k]:.10g} s is {dev[k] / dt:.3g} steps "
                             f"off the mean step {dt:.6g} s)", file=src, field="time_s")
        for name, a in arrays.items():
            object.__setattr__(self, name, a)

    @property
    def dt(self) -> float:
        """Mean sampling step, s."""
        return float((self.time_s[-1] - self.time_s[0]) / (self.time_s.size - 1))

    @property
    def fs(self) -> float:
        """Sampling frequency, Hz."""
        return 1.0 / self.dt


@dataclass(frozen=True)
class Hit:
    """One hit found in a record.

    Attributes
    ----------
    number : int
        1-based over all records, in order (what messages and ``--drop-bad`` name).
    record : int
        Index of its record.
    start, stop : int
        Sample range [start, stop) of its block in the record (start = trigger − pretrigger).
    trigger_s : float
        Time of the first threshold crossing, s.
    peak_n : float
        Peak force, N.
    pulse_end : int
        Last sample (record index) of its force pulse(s) above the threshold.
    width : int
        Samples of its first pulse above the threshold.
    double_at_s : float or None
        Time of a second force pulse within ``min_gap_s`` (a double hit), s.
    clipped : str
        ``""`` or the clipped channel(s), e.g. ``"force"``.
    cut_s : float or None
        Record left after the trigger, s, when the record's end cuts the hit off (None: not cut).
    """

    number: int
    record: int
    start: int
    stop: int
    trigger_s: float
    peak_n: float
    pulse_end: int
    width: int
    double_at_s: float | None = None
    clipped: str = ""
    cut_s: float | None = None

    @property
    def bad(self) -> bool:
        """True for a double hit, an overload or a hit cut off by the record's end."""
        return self.double_at_s is not None or bool(self.clipped) or self.cut_s is not None

    def describe(self, source: str = "") -> str:
        """One line: which hit, where, and what is wrong with it."""
        what = []
        if self.double_at_s is not None:
            what.append(f"double hit (second pulse at {self.double_at_s:.6g} s)")
        if self.clipped:
            what.append(f"overload: {self.clipped} clipped")
        if self.cut_s is not None:
            what.append(f"cut off by the end of the record ({self.cut_s:.3g} s after its trigger)")
        at = f"{source}: " if source else ""
        return f"{at}hit {self.number} at {self.trigger_s:.6g} s: {'; '.join(what) or 'ok'}"


@dataclass(frozen=True)
class TapResult:
    """FRF of an impact test and what went into it.

    Attributes
    ----------
    frf : FRF
        The averaged estimate (receptance by default); ``meta["coherence"]`` holds γ² on its grid.
    coherence : numpy.ndarray
        (F,) ordinary coherence γ² on ``frf.freq_hz`` (all 1 for a single hit: not a quality measure, and then
        not in ``frf.meta``).
    hits : list of Hit
        Every hit found.
    used : list of int
        Numbers of the hits averaged.
    tau_s : float or None
        Time constant of the exponential window, s (None: no window).
    records : list of Record
        The input records (for plotting).
    band_hz : tuple of float or None
        (first, last) frequency kept, Hz.
    notes : tuple of str
        One-line notes: where the band ends and why, what the detrend did.
    """

    frf: FRF
    coherence: np.ndarray
    hits: list
    used: list
    tau_s: float | None
    records: list = field(default_factory=list)
    band_hz: tuple | None = None
    notes: tuple = ()

    @property
    def single_hit(self) -> bool:
        """One hit averaged: the coherence is 1 by construction and says nothing."""
        return len(self.used) == 1

    def added_damping(self, freq_hz) -> np.ndarray:
        """Damping ratio added by the exponential window to a mode at ``freq_hz`` (Hz): 1/(2π f τ); 0 without one."""
        f = np.asarray(freq_hz, dtype=float)
        return np.zeros_like(f) if self.tau_s is None else 1.0 / (2 * np.pi * f * self.tau_s)


@dataclass(frozen=True)
class CorrectedDamping:
    """Modal frequency and damping with an exponential window's added damping removed (:func:`corrected_damping`).

    Attributes
    ----------
    fn_hz : numpy.ndarray
        Natural frequency, Hz.
    zeta : numpy.ndarray
        Damping ratio.
    """

    fn_hz: np.ndarray
    zeta: np.ndarray


def corrected_damping(fn_hz, zeta, tau_s: float | None) -> CorrectedDamping:
    """Modal frequency and damping with the exponential window's added damping removed.

    The window e^{-t/τ} moves each pole s = −ζω + iω_d to s − 1/τ (ω_d is
    unchanged). Given (fn, ζ) fitted to a windowed FRF, this returns those of
    the pole s + 1/τ: σ = ζω − 1/τ, ω = √(σ² + ω_d²), ζ = σ/ω (to first order
    ζ − 1/(ω τ)).

    Parameters
    ----------
    fn_hz, zeta : array_like
        Natural frequency (Hz) and damping ratio fitted to the windowed FRF.
    tau_s : float or None
        Window time constant, s (None: returned unchanged).

    Returns
    -------
    CorrectedDamping
        ``fn_hz`` and ``zeta`` of the structure without the window.

    Examples
    --------
    The pole of a 500 Hz, ζ = 0.02 mode seen through a τ = 0.1 s window, and back:

    >>> w = 2 * np.pi * 500.0
    >>> lam = -0.02 * w + 1j * w * np.sqrt(1 - 0.02**2) - 1 / 0.1
    >>> c = corrected_damping(abs(lam) / (2 * np.pi), -lam.real / abs(lam), 0.1)
    >>> round(float(c.fn_hz), 9), round(float(c.zeta), 9)
    (500.0, 0.02)
    """
    fn, z = np.asarray(fn_hz, dtype=float), np.asarray(zeta, dtype=float)
    if tau_s is None:
        return CorrectedDamping(fn, z)
    w = 2 * np.pi * fn
    sigma, wd = z * w - 1.0 / tau_s, w * np.sqrt(1 - z**2)
    w0 = np.hypot(sigma, wd)
    return CorrectedDamping(w0 / (2 * np.pi), sigma / w0)


# ---------------------------------------------------------------- reading
def read_record(path, *, response: str = "acceleration", channel: int | None = None) -> Record:
    """Read an impact record: a text table (time s, force N, response) or UFF58 time histories.

    Text (any extension but ``.uff``/``.unv``/``.uf``): three columns separated
    by commas, tabs or spaces, or more — time, force and several responses (a
    triaxial accelerometer, two directions), of which ``channel`` picks one; an
    optional header line; lines starting with ``#`` or ``%`` are comments. The
    force is the second column, or the one column the header names a force (a
    unit of force, or "force"/"hammer" in its name) wherever it stands.
    Where the header names units (``Accel (g)``,
    ``Time (ms)``, ``force_kn``, a DAQ's units row under the names) they are
    converted to s, N and SI; a voltage, or a response of another kind than
    ``response``, is refused. UFF: the file's datasets 58 of function type 1
    (time response); the force is the one with ordinate data type 13 (force),
    the response the one with 8/11/12 (displacement/velocity/acceleration, which
    overrides ``response``; an ordinate unit ``g`` is converted to m/s²).

    Parameters
    ----------
    path : str or Path
        The file.
    response : str
        What the text file's response column is: ``"acceleration"`` (m/s²),
        ``"velocity"`` (m/s) or ``"displacement"`` (m).
    channel : int, optional
        Which response, 0-based (the text file's columns after the force, the
        UFF file's response time histories in file order), where the record
        holds several; with one it may be omitted. Several without it are
        refused, naming them.

    Returns
    -------
    Record

    Raises
    ------
    InputError
        One line naming the file and field (and the line of a text file).
    """
    if Path(path).suffix.lower() in (".uff", ".unv", ".uf"):
        return _read_uff_record(path, channel)
    from .frf_files import (_check_not_cut, _is_number, _read_text, column_names, column_unit, drop_empty_columns,
                             numeric_lines)
    from .records import channel_index

    rows = []
    text, open_end = _read_text(path)
    numbered = list(numeric_lines(text))
    kept, keep = drop_empty_columns(numbered)
    names = column_names(text, numbered[0][0], len(numbered[0][1])) if numbered else None
    width = len(kept[0][1]) if kept else 0
    for n, cells in kept:
        if len(cells) < 3 or len(cells) != width:
            raise InputError(f"line {n}: expected {'3 columns' if width < 3 else f'{width} columns as on line '}"
                             f"{'' if width < 3 else kept[0][0]} (time s, force N, response"
                             f"{'' if width <= 3 else 's'}), found {len(cells)}", file=path, field="columns")
        if "" in cells:  # a cell empty on some rows only (a column empty on all is dropped above): a missing value
            raise InputError(f"line {n}: column {cells.index('') + 1} is empty", file=path, field="columns")
        rows.append((n, cells))
    if not rows:
        raise InputError("no data rows", file=path, field="data")
    # the force: the second column, unless the header puts it elsewhere (a DAQ orders its channels by number, and the
    # hammer's need not be the first: "Time (s), Accel (g), Force (N)"): the one column whose unit is a force or
    # whose name says force or hammer
    force = 1
    if names:
        said = [j for j in range(1, width) if (column_unit(names[keep[j]]) or ("", ""))[1] == "force"
                or re.search(r"force|hammer", names[keep[j]], re.I)]
        force = said[0] if len(said) == 1 else 1
    # the response: one of the other columns (a triaxial accelerometer), chosen as `cut` chooses
    resp = [j for j in range(1, width) if j != force]
    k = resp[channel_index(len(resp), channel, path, "the record", [names[keep[j]] for j in resp] if names else None,
                           kind="response columns")]
    rows = [(n, [cells[0], cells[force], cells[k]]) for n, cells in rows]
    keep = [keep[0], keep[force], keep[k]]
    try:
        if any("_" in c for _, cells in rows for c in cells):  # float() reads "1_000"; no data file writes it
            raise ValueError("_")
        a = np.array([c for _, c in rows], dtype=float)
    except ValueError:
        for n, cells in rows:
            for name, c in zip(("time_s", "force_n", "response"), cells):
                if not _is_number(c):
                    raise InputError(f"line {n}: {c!r} is not a number", file=path, field=name) from None
        raise
    _check_not_cut(path, rows, ("time_s", "force_n", "response"), open_end)
    if names:  # the header's units, where it names them: a response in g read as m/s² was an FRF 9.8 × too small
        a, response = _to_si(a, [names[j] for j in keep], response, path)
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        i, j = bad[0]
        raise InputError(f"line {rows[i][0]}: non-finite value {a[i, j]}", file=path,
                         field=("time_s", "force_n", "response")[j])
    d = np.diff(a[:, 0])
    if np.any(d <= 0):
        k = int(np.flatnonzero(d <= 0)[0]) + 1
        raise InputError(f"line {rows[k][0]}: time must increase ({a[k, 0]:.10g} s follows {a[k - 1, 0]:.10g} s)",
                         file=path, field="time_s")
    return Record(a[:, 0], a[:, 1], a[:, 2], response, os.fspath(path))


def _to_si(a: np.ndarray, names: list, response: str, path) -> tuple:
    """(the columns time, force, response in s, N and SI, the response's kind) from the units their header names
    (``Time (ms)``, ``Force (kN)``, ``Accel (g)``, ``force_n``, a DAQ's units row; :func:`~toolpoint.io.frf_files.
    column_unit`); a column without a unit keeps it (s, N, SI). Refused: a unit of another quantity than the column's
    (a force in g), a voltage (not yet divided by the sensor's sensitivity), a response of another kind than
    ``response`` (a velocity in mm/s read as acceleration)."""
    from .frf_files import column_unit

    def an(word):
        return f"{'an' if word[0] in 'aeiou' else 'a'} {word}"

    a = a.copy()
    for j, (name, want) in enumerate((("time_s", ("time",)), ("force_n", ("force",)),
                                       ("response", ("acceleration", "velocity", "displacement")))):
        u = column_unit(names[j])
        if u is None:
            continue
        _, qty, factor = u
        if qty == "voltage":
            raise InputError(f"column '{names[j]}' is a voltage: divide it by the sensor's sensitivity (V per "
                             f"{'N' if name == 'force_n' else 'm/s²'}) first", file=path, field=name)
        if qty not in want:
            raise InputError(f"column '{names[j]}' holds {an(qty)}, where {an(' or '.join(want))} is expected "
                             "(columns: time, force, response)", file=path, field=name)
        if name == "response" and qty != response:
            raise InputError(f"column '{names[j]}' holds {an(qty)} and the record is read as {response}: give "
                             f"--response {qty}", file=path, field="response")
        a[:, j] *= factor
    return a, response


_UFF_RESPONSE = {8: "displacement", 11: "velocity", 12: "acceleration"}


def _read_uff_record(path, channel: int | None = None) -> Record:
    from .frf_files import _uff_headers

    uff, sets, heads = _uff_headers(path)
    th = [(s, h) for s, h in zip(sets, heads) if h.get("func_type") == 1]
    if not th:
        types = ", ".join(str(h.get("func_type")) for h in heads)
        raise InputError(f"no time history (dataset 58 of function type 1; function types here: {types})",
                         file=path, field="func_type")
    force = [(s, h) for s, h in th if h.get("ordinate_spec_data_type") == 13]
    resp = [(s, h) for s, h in th if h.get("ordinate_spec_data_type") in _UFF_RESPONSE]
    names = "; ".join(f"#{k}: {h.get('id1', '')!s} (ordinate type {h.get('ordinate_spec_data_type')})"
                      for k, (_, h) in enumerate(th))
    if len(force) != 1 or not resp:
        raise InputError(f"need one force (ordinate type 13) and one response (8/11/12) time history, found "
                         f"{len(force)} and {len(resp)} among: {names}", file=path, field="ordinate_spec_data_type")
    from .records import channel_index

    resp = [resp[channel_index(len(resp), channel, path, "the record",
                               [f"dataset {s} {h.get('id1', '')!s}".strip() for s, h in resp],
                               kind="response time histories")]]
    data = []
    for s, _ in (force[0], resp[0]):
        try:
            ds = uff.read_sets(s)
        except Exception as exc:  # pyuff raises bare Exception
            raise InputError(f"dataset {s} cannot be read ({exc})", file=path, field="data") from exc
        data.append(ds)
    fd, rd = data
    if fd.get("num_pts") != rd.get("num_pts") or np.size(fd["data"]) != np.size(rd["data"]):
        raise InputError(f"force has {np.size(fd['data'])} samples, response {np.size(rd['data'])}",
                         file=path, field="num_pts")
    tf, tr = np.asarray(fd["x"], float), np.asarray(rd["x"], float)
    if tf.size > 1 and (abs(tf[1] - tf[0] - (tr[1] - tr[0])) > 1e-9 * abs(tf[1] - tf[0]) or abs(tf[0] - tr[0]) >
                        1e-9 * abs(tf[1] - tf[0])):
        raise InputError(f"force and response sampling differ (steps {tf[1] - tf[0]:.6g} s and "
                         f"{tr[1] - tr[0]:.6g} s)", file=path, field="abscissa_inc")
    if np.iscomplexobj(fd["data"]) or np.iscomplexobj(rd["data"]):
        raise InputError("time histories must be real (ordinate data type 2 or 4)", file=path, field="ord_data_type")
    x = np.asarray(rd["data"], float)
    if str(rd.get("ordinate_axis_units_lab", "")).strip().lower() == "g":
        warnings.warn(f"{path}: response units 'g': converted to m/s² (×{G0})", stacklevel=3)
        x = x * G0
    return Record(tf, np.asarray(fd["data"], float), x, _UFF_RESPONSE[rd["ordinate_spec_data_type"]],
                  os.fspath(path))


# ---------------------------------------------------------------- hits
def _pulses(y: np.ndarray, level: float) -> np.ndarray:
    """Rising edges (indices) of y above ``level``, with hysteresis: a new pulse needs y < level/2 first."""
    ev = np.where(y > level, 1, np.where(y < level / 2, -1, 0))
    idx = np.where(ev != 0, np.arange(y.size), 0)
    state = ev[np.maximum.accumulate(idx)] == 1
    state[ev[np.maximum.accumulate(idx)] == 0] = False  # before any event
    return np.flatnonzero(state & ~np.concatenate(([False], state[:-1])))


def find_hits(record: Record, *, threshold: float = 0.1, min_gap_s: float = 0.05,
              pretrigger_s: float | None = None, first_number: int = 1, record_index: int = 0) -> list[Hit]:
    """Cut a record into hits at the force threshold.

    A hit starts where the force (with the sign of its largest peak) rises above
    ``threshold`` × the record's peak force; force pulses within ``min_gap_s``
    of a trigger belong to that hit (a second one makes it a double hit). Each
    block runs from ``pretrigger_s`` before its trigger to the start of the next
    block (or the end of the record).

    Parameters
    ----------
    record : Record
    threshold : float
        Fraction (0, 1) of the peak force that triggers a hit.
    min_gap_s : float
        Shortest time between two hits, s; closer pulses are one (double) hit.
    pretrigger_s : float, optional
        Samples kept before the trigger, s (default 20 samples).
    first_number, record_index : int
        Numbering of the hits across several records.

    Returns
    -------
    list of Hit

    Raises
    ------
    InputError
        For a record without a hit (field ``force_n``) or a bad parameter.
    """
    src = record.source or None
    if not 0 < threshold < 1:
        raise InputError(f"threshold must be in (0, 1), got {threshold}", file=src, field="threshold")
    duration = record.dt * (record.time_s.size - 1)
    if not 0 < min_gap_s < np.inf:
        raise InputError(f"min_gap_s must be a finite time > 0 s, got {min_gap_s}", file=src, field="min_gap_s")
    if pretrigger_s is not None and not 0 <= pretrigger_s < min(min_gap_s, duration):
        raise InputError(f"pretrigger {pretrigger_s:g} s must be ≥ 0 and shorter than min_gap_s ({min_gap_s:g} s) "
                         f"and the record ({duration:.6g} s)", file=src, field="pretrigger_s")
    f, x, n = record.force_n, record.response, record.force_n.size
    sign = 1.0 if f.max() >= -f.min() else -1.0
    fs_ = sign * f
    peak = fs_.max()
    noise = 1.4826 * np.median(np.abs(f - np.median(f)))
    if peak <= 0 or peak < 10 * noise:
        raise InputError(f"no hit: peak force {peak:.3g} N is not above the noise ({noise:.3g} N rms)",
                         file=src, field="force_n")
    if np.ptp(x) == 0:
        raise InputError(f"the response is {x[0]:g} at every sample: no signal (sensor, cable or column?)",
                         file=src, field="response")
    gap = max(1, int(round(min(min_gap_s, 2 * duration) / record.dt)))
    pre = PRETRIGGER_SAMPLES if pretrigger_s is None else int(round(pretrigger_s / record.dt))
    edges = _pulses(fs_, threshold * peak)
    triggers = []
    for e in edges:  # a handful of pulses: group those within min_gap of a trigger
        if not triggers or e - triggers[-1] >= gap:
            triggers.append(int(e))
    starts = [max(0, t - pre) for t in triggers]
    hits = []
    for k, (t, s) in enumerate(zip(triggers, starts)):
        stop = starts[k + 1] if k + 1 < len(starts) else n
        seg = fs_[t:min(stop, t + gap)]
        pk = seg.max()
        level = threshold * pk
        own = _pulses(seg, level)
        above = np.flatnonzero(seg > level)
        first_end = int(above[np.searchsorted(above, own[1]) - 1]) if own.size > 1 else int(above[-1])
        width = first_end + 1
        double = float(record.time_s[t + own[1]]) if own.size > 1 else None
        clipped = [name for name, y in (("force", f[s:stop]), ("response", x[s:stop]))
                   if np.count_nonzero(np.abs(y) >= np.abs(y).max()) >= CLIP_SAMPLES and np.abs(y).max() > 0]
        # cut off: the record ends within min_gap of the trigger, or while the pulse is still above the threshold
        left = (n - 1 - t) * record.dt
        cut = left if stop == n and (n - t < gap or t + int(above[-1]) == n - 1) else None
        hits.append(Hit(first_number + k, record_index, s, stop, float(record.time_s[t]), float(sign * pk),
                        t + int(above[-1]), width, double, " and ".join(clipped), cut))
    return hits


# ---------------------------------------------------------------- FRF
def impact_frf(records, *, estimator: str = "H1", output: str = "receptance", threshold: float = 0.1,
               min_gap_s: float = 0.05, pretrigger_s: float | None = None, force_window_s: float | None = None,
               exp_window_s: float | str | None = None, drop_bad: bool = False, fmax_hz: float | None = None,
               force_drop_db: float | None = FORCE_DROP_DB, detrend: str = "auto", label: str = "tap") -> TapResult:
    """Average the hits of impact records into an FRF with coherence, over the band the hammer excited.

    Parameters
    ----------
    records : Record or list of Record
        Same sampling step (and response kind) for all.
    estimator : str
        ``"H1"`` (default; noise on the response averages out) or ``"H2"``.
    output : str
        ``"receptance"`` (m/N, default) or ``"measured"`` (the response's own
        quantity: accelerance, mobility or receptance).
    threshold, min_gap_s, pretrigger_s
        Hit finding (see :func:`find_hits`).
    force_window_s : float, optional
        Force window length from the block start, s; default: to the end of the
        last force pulse plus one pulse width.
    exp_window_s : float or "auto", optional
        Exponential window time constant τ, s; ``"auto"`` decays to 1 % at the
        block end (τ = T / ln 100); None (default): no window.
    drop_bad : bool
        Drop double hits and overloads (with a warning) instead of averaging a
        double hit (warning) or refusing an overload (error).
    fmax_hz : float, optional
        Highest frequency kept, Hz (default: the end of the force band, at most Nyquist).
    force_drop_db : float or None
        The band ends where the force auto-spectrum has dropped this much below its
        low-frequency level, dB (default :data:`FORCE_DROP_DB`; None: no force band).
    detrend : str
        ``"auto"`` (default: force baseline; acceleration line, velocity mean,
        displacement pre-trigger mean removed per block — see the module notes) or ``"none"``.
    label : str
        Label of the FRF.

    Returns
    -------
    TapResult

    Raises
    ------
    InputError
        No hit, an overload without ``drop_bad``, different sampling, every hit dropped, ...

    Examples
    --------
    Two hits of a half-sine force on a 1-DOF oscillator (fn = 200 Hz, ζ = 0.05),
    displacement response from the exact impulse response:

    >>> import numpy as np
    >>> fs, wn, z = 2000.0, 2 * np.pi * 200.0, 0.05
    >>> t = np.arange(4000) / fs
    >>> wd = wn * np.sqrt(1 - z**2)
    >>> h = np.exp(-z * wn * t) * np.sin(wd * t) / (wd * 1.0)  # m/(N s), mass 1 kg
    >>> f = np.zeros(t.size); f[[100, 2100]] = [fs * 1.0, fs * 0.5]  # 1 N s and 0.5 N s impulses
    >>> x = np.convolve(f, h)[: t.size] / fs
    >>> res = impact_frf(Record(t, f, x, "displacement"), min_gap_s=0.1)
    >>> len(res.used), float(res.coherence.min()) > 0.999, [round(f, 6) for f in res.band_hz]
    (2, True, [0.0, 1000.0])
    """
    recs, dt, kind = _check_inputs(records, estimator, output, detrend, force_drop_db)
    hits, used = _hits_to_average(recs, threshold, min_gap_s, pretrigger_s, drop_bad)
    n, tau, fblk, xblk = _hit_blocks(recs, used, dt, exp_window_s)
    we = np.ones(n) if tau is None else np.exp(-np.arange(n) * dt / tau)
    fblk, xblk, wf = _windowed(recs, used, fblk, xblk, dt, force_window_s, detrend, kind, tau)
    freq, sff, sxx, sxf = _spectra(fblk * wf * we, xblk * we, dt)
    quantity = RESPONSES[kind]
    keep, notes = _band(freq, sff, used, dt, fmax_hz, force_drop_db, output == "receptance" and
                        quantity != "receptance", recs[0].source)
    freq, sff, sxx, sxf = freq[keep], sff[keep], sxx[keep], sxf[keep]
    h, coh = _estimate(freq, sff, sxx, sxf, estimator, recs[0].source)
    if detrend == "auto":
        notes.append({"acceleration": "offset and linear drift of the acceleration removed per block "
                                      "(least-squares line) before the FFT",
                      "velocity": "velocity offset (block mean) removed before the FFT",
                      "displacement": "displacement offset (pre-trigger mean) removed before the FFT"}[kind])
    frf = _tap_frf(freq, h, coh, recs, used, estimator, tau, quantity, output, label)
    return TapResult(frf, coh, hits, [h.number for h in used], tau, recs, (float(freq[0]), float(freq[-1])),
                     tuple(notes))


def _check_inputs(records, estimator, output, detrend, force_drop_db):
    """(records as a list, sampling step s, response kind), after checking the options and the records agree."""
    recs = [records] if isinstance(records, Record) else list(records)
    if not recs:
        raise InputError("no records", field="records")
    if estimator not in ("H1", "H2"):
        raise InputError(f"estimator must be H1 or H2, not {estimator!r}", field="estimator")
    if output not in ("receptance", "measured"):
        raise InputError(f"output must be 'receptance' or 'measured', not {output!r}", field="output")
    if detrend not in DETRENDS:
        raise InputError(f"detrend must be one of {', '.join(DETRENDS)}, not {detrend!r}", field="detrend")
    if force_drop_db is not None and not 0 < force_drop_db < np.inf:
        raise InputError(f"force_drop_db must be a finite number > 0 dB, got {force_drop_db}", field="force_drop_db")
    dt, kind = recs[0].dt, recs[0].response_kind
    for r in recs[1:]:
        if abs(r.dt - dt) > 1e-6 * dt:
            raise InputError(f"sampling step {r.dt:.9g} s differs from {dt:.9g} s of {recs[0].source}",
                             file=r.source or None, field="time_s")
        if r.response_kind != kind:
            raise InputError(f"response is {r.response_kind}, {recs[0].source} has {kind}", file=r.source or None,
                             field="response")
    return recs, dt, kind


def _hits_to_average(recs, threshold, min_gap_s, pretrigger_s, drop_bad):
    """(every hit found, the hits to average): cut-short hits dropped, bad ones dropped or refused.

    The warnings name the caller of :func:`impact_frf` (stacklevel 3).
    """
    hits, number = [], 1
    for i, r in enumerate(recs):
        found = find_hits(r, threshold=threshold, min_gap_s=min_gap_s, pretrigger_s=pretrigger_s,
                          first_number=number, record_index=i)
        hits += found
        number += len(found)
    used = []
    for h in hits:
        src = recs[h.record].source
        if h.cut_s is not None:  # always: its short block would shorten every other block to its length
            if all(g.cut_s is not None for g in hits):
                raise InputError(f"{h.describe()}: no complete hit to average (min_gap_s = {min_gap_s:g} s of "
                                 "record is needed after a trigger)", file=src or None, field="hits")
            warnings.warn(f"{h.describe(src)}: dropped", stacklevel=3)
            continue
        if h.bad and drop_bad:
            warnings.warn(f"{h.describe(src)}: dropped", stacklevel=3)
            continue
        if h.clipped:
            raise InputError(f"{h.describe()}; use --drop-bad (drop_bad=True) to leave it out",
                             file=src or None, field="overload")
        if h.double_at_s is not None:
            warnings.warn(f"{h.describe(src)}: kept (use --drop-bad to leave it out)", stacklevel=3)
        used.append(h)
    if not used:
        raise InputError(f"all {len(hits)} hits were dropped as bad", file=recs[0].source or None, field="hits")
    return hits, used


def _hit_blocks(recs, used, dt, exp_window_s):
    """(block length n, exponential window τ s or None, force blocks, response blocks), each (hits, n)."""
    n = min(h.stop - h.start for h in used)
    if n < 8:
        raise InputError(f"hit blocks of {n} samples are too short (hits too close: raise min_gap_s or record "
                         "longer)", file=recs[0].source or None, field="time_s")
    tau = None
    if exp_window_s is not None:
        tau = n * dt / np.log(100.0) if exp_window_s == "auto" else float(exp_window_s)
        if not tau > 0:
            raise InputError(f"exponential window time constant must be > 0 s, got {exp_window_s}",
                             field="exp_window_s")
    fblk = np.stack([recs[h.record].force_n[h.start:h.start + n] for h in used])
    xblk = np.stack([recs[h.record].response[h.start:h.start + n] for h in used])
    for h, x in zip(used, xblk):
        if np.ptp(x) == 0:
            raise InputError(f"hit {h.number}: the response is {x[0]:g} throughout its block: no signal",
                             file=recs[h.record].source or None, field="response")
    return n, tau, fblk, xblk


def _windowed(recs, used, fblk, xblk, dt, force_window_s, detrend, kind, tau):
    """(force blocks, response blocks, force windows): detrended, and a warning where a response leaks."""
    n = fblk.shape[1]
    if force_window_s is None:
        ends = np.array([h.pulse_end - h.start + h.width for h in used])
    else:
        ends = np.full(len(used), int(round(min(force_window_s / dt, n))))
    inside = np.arange(n)[None, :] <= ends[:, None]
    wf = inside.astype(float)
    pre = np.array([int(round((h.trigger_s - recs[h.record].time_s[h.start]) / dt)) for h in used])
    if detrend == "auto":
        fblk, xblk = _detrend(fblk, xblk, inside, pre, kind)
    for h, x in zip(used, xblk):
        tail = np.abs(x[int((1 - LEAK_TAIL) * n):]).max()
        if tail > LEAK_LEVEL * np.abs(x).max() and tau is None:
            warnings.warn(f"{recs[h.record].source}: hit {h.number}: the response has not died out by the end of "
                          f"its {n * dt:.4g} s block ({tail / np.abs(x).max():.1%} of its peak): leakage; "
                          "use longer records or an exponential window", stacklevel=3)
    return fblk, xblk, wf


def _spectra(fw, xw, dt):
    """(frequencies Hz, S_ff, S_xx, S_xf) summed over the windowed blocks ``fw``, ``xw``."""
    F = np.fft.rfft(fw, axis=1)
    X = np.fft.rfft(xw, axis=1)
    freq = np.fft.rfftfreq(fw.shape[1], dt)
    return freq, np.sum(np.abs(F) ** 2, axis=0), np.sum(np.abs(X) ** 2, axis=0), np.sum(X * np.conj(F), axis=0)


def _band(freq, sff, used, dt, fmax_hz, force_drop_db, positive, source):
    """(mask of the lines kept, notes): up to ``fmax_hz`` and the end of the force band; only f > 0 if ``positive``."""
    notes = []
    keep = np.ones(freq.size, bool) if fmax_hz is None else freq <= fmax_hz
    if force_drop_db is not None:
        pulse_s = float(np.median([h.width for h in used])) * dt
        f_end, level_note = _force_band(freq, sff, pulse_s, force_drop_db)
        if f_end is not None:
            if not np.any(keep & (freq < f_end)):
                raise InputError(f"{level_note}; no frequency line is left below it (fmax {fmax_hz} Hz)",
                                 file=source or None, field="force_n")
            if fmax_hz is None or f_end <= fmax_hz:
                notes.append(f"band ends at {freq[freq < f_end][-1]:.6g} Hz: {level_note}; nothing written above "
                             "(force_drop_db / --force-drop)")
            keep &= freq < f_end
    if positive:
        keep &= freq > 0
    if not keep.any():
        raise InputError(f"no frequency line at or below {fmax_hz} Hz", field="fmax_hz")
    return keep, notes


def _estimate(freq, sff, sxx, sxf, estimator, source):
    """(H1 or H2 estimate, coherence γ²) from the spectra; refused where S_ff or S_xf is zero."""
    zero = np.flatnonzero((sff == 0) | (np.abs(sxf) == 0))
    if zero.size:
        what = "force spectrum" if sff[zero[0]] == 0 else "cross spectrum (response × force)"
        raise InputError(f"the {what} is zero at {freq[zero[0]]:.6g} Hz: lower fmax", file=source or None,
                         field="force_n" if sff[zero[0]] == 0 else "response")
    with np.errstate(all="ignore"):
        h = sxf / sff if estimator == "H1" else sxx / np.conj(sxf)
        coh = np.clip(np.abs(sxf) ** 2 / (sff * sxx), 0.0, 1.0)
    return h, coh


def _tap_frf(freq, h, coh, recs, used, estimator, tau, quantity, output, label):
    """The FRF with its metadata, as receptance (exact under an exponential window) or the measured quantity."""
    meta = {"estimator": estimator, "hits": [h.number for h in used], "tau_s": tau,
            "source": ", ".join(r.source for r in recs), "format": "tap", "file_quantity": quantity}
    if len(used) == 1:
        src = recs[used[0].record].source
        warnings.warn(f"{src + ': ' if src else ''}one hit: its coherence is 1 by construction (one average) and "
                      "says nothing about the FRF's quality, so none is reported; average 3–5 hits to measure it",
                      stacklevel=3)
    else:
        meta["coherence"] = coh
    frf = FRF(freq, h, quantity, label, meta)
    if output == "receptance" and tau is not None and quantity != "receptance":
        # The windowed record is that of the system h(t) e^{-t/τ}: its accelerance (mobility) is
        # H_a(s + 1/τ) = (s + 1/τ)² H_x(s + 1/τ), so dividing by (iω + 1/τ)² (not (iω)²) gives exactly the
        # receptance with every pole moved by −1/τ and the residues unchanged.
        power = 2 if quantity == "accelerance" else 1
        frf = FRF(freq, h / (2j * np.pi * freq + 1.0 / tau) ** power, "receptance", label, meta)
    elif output == "receptance":
        frf = frf.to_receptance()
    return frf


def _detrend(fblk, xblk, inside, pre, kind):
    """Blocks with the force baseline and the response's offset/drift removed (see the module notes)."""
    fblk = fblk - np.array([np.median(f[~m]) if (~m).any() else 0.0 for f, m in zip(fblk, inside)])[:, None]
    n = xblk.shape[1]
    if kind == "acceleration":  # least-squares line per block, vectorised over hits
        u = np.arange(n) - (n - 1) / 2.0
        slope = (xblk @ u) / (u @ u)
        return fblk, xblk - xblk.mean(axis=1, keepdims=True) - slope[:, None] * u[None, :]
    if kind == "velocity":
        return fblk, xblk - xblk.mean(axis=1, keepdims=True)
    base = np.array([x[:p].mean() if p > 0 else x[0] for x, p in zip(xblk, pre)])
    return fblk, xblk - base[:, None]


def _force_band(freq, sff, pulse_s, drop_db):
    """(First frequency where S_ff is ``drop_db`` below its low-frequency level or None, a note on it)."""
    f_ref = max(0.1 / pulse_s, freq[1] if freq.size > 1 else 0.0)
    level = float(np.median(sff[freq <= f_ref]))
    low = np.flatnonzero((freq > f_ref) & (sff < level * 10 ** (-drop_db / 10)))
    if not low.size:
        return None, ""
    f_end = float(freq[low[0]])
    return f_end, (f"the hammer's force spectrum is {drop_db:g} dB below its level at 0–{f_ref:.3g} Hz from "
                   f"{f_end:.6g} Hz (pulse {pulse_s * 1e3:.3g} ms)")


def plot_tap(result: TapResult):
    """Figure of an impact test: records with hits marked, |FRF|, phase and coherence.

    Only the band the FRF was computed over is drawn. Where the coherence of
    several hits is below :data:`toolpoint.trust.COHERENCE_MIN` the magnitude and
    phase are drawn in light grey (not trusted); a single hit has no coherence
    to show, and its panel says so.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    from ..trust import COHERENCE_MIN

    fig, ax = plt.subplots(4, 1, figsize=(8, 10), constrained_layout=True)
    used = set(result.used)
    for i, r in enumerate(result.records):
        ax[0].plot(r.time_s, r.force_n, lw=0.8, label=f"force [N] {Path(r.source).name}" if r.source else "force [N]")
        scale = np.abs(r.force_n).max() / max(np.abs(r.response).max(), 1e-300)
        ax[0].plot(r.time_s, r.response * scale, lw=0.6, alpha=0.7, label=f"response × {scale:.3g}")
    for h in result.hits:
        color = "tab:green" if h.number in used else "tab:red"
        ax[0].axvline(h.trigger_s, color=color, ls="--", lw=0.8)
        ax[0].annotate(str(h.number) + ("" if h.number in used else " ✗"), (h.trigger_s, h.peak_n), color=color)
    ax[0].set_xlabel("time [s]")
    ax[0].legend(loc="upper right", fontsize="small")
    frf = result.frf
    f, v = frf.freq_hz, frf.values
    good = np.ones(f.size, bool) if result.single_hit else result.coherence >= COHERENCE_MIN
    mag, ph = np.abs(v), np.degrees(np.angle(v))
    for a, y in ((ax[1], mag), (ax[2], ph)):
        a.plot(f, np.where(good, np.nan, y), color="0.8", lw=0.8,
               label=f"γ² < {COHERENCE_MIN:g} (not trusted)" if not good.all() else None)
        a.plot(f, np.where(good, y, np.nan), color="tab:blue", lw=1.0, label=frf.label or None)
        a.grid(True, alpha=0.3)
    ax[1].set_yscale("log")
    ax[1].set_ylabel(f"|{frf.quantity}| [{frf.unit}]")
    ax[1].legend(loc="upper right", fontsize="small")
    ax[1].set_title(f"band {f[0]:.6g}–{f[-1]:.6g} Hz (force spectrum; nothing computed outside)", fontsize="small")
    ax[2].set_ylabel("phase [deg]")
    ax[2].set_ylim(-185, 185)
    if result.single_hit:
        ax[3].text(0.5, 0.5, "one hit: coherence is 1 by construction — not measured", ha="center", va="center",
                   transform=ax[3].transAxes)
    else:
        ax[3].plot(f, result.coherence)
        ax[3].axhline(COHERENCE_MIN, color="0.5", ls=":", lw=0.8)
    ax[3].set_ylim(0, 1.05)
    ax[3].set_ylabel("coherence γ²")
    ax[3].set_xlabel("frequency [Hz]")
    ax[3].grid(True, alpha=0.3)
    for a in ax[1:]:
        a.set_xlim(f[0], f[-1])
    return fig
