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

Quality checks per hit: a *double hit* (the force rises above the threshold
again within ``min_gap_s`` of the trigger) warns; an *overload* (three or more
samples of a channel at its maximum magnitude: clipping) is an error. With
``drop_bad=True`` both are dropped from the average with a warning.

Bad input raises :class:`~toolpoint.errors.InputError` naming the file and field.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..frf import FRF

__all__ = ["RESPONSES", "Record", "Hit", "TapResult", "read_record", "find_hits", "impact_frf", "plot_tap",
           "corrected_damping"]

RESPONSES = {"acceleration": "accelerance", "velocity": "mobility", "displacement": "receptance"}
"""Response kind → the FRF quantity it gives over force."""

G0 = 9.80665  # standard gravity, m/s² per g
CLIP_SAMPLES = 3  # samples at a channel's maximum magnitude that mean clipping (pyFRF's rule)
PRETRIGGER_SAMPLES = 20  # default pretrigger
LEAK_TAIL, LEAK_LEVEL = 0.05, 0.02  # warn if the last 5 % of a block still reaches 2 % of its peak


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

    @property
    def bad(self) -> bool:
        """True for a double hit or an overload."""
        return self.double_at_s is not None or bool(self.clipped)

    def describe(self, source: str = "") -> str:
        """One line: which hit, where, and what is wrong with it."""
        what = []
        if self.double_at_s is not None:
            what.append(f"double hit (second pulse at {self.double_at_s:.6g} s)")
        if self.clipped:
            what.append(f"overload: {self.clipped} clipped")
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
        (F,) ordinary coherence γ² on ``frf.freq_hz``.
    hits : list of Hit
        Every hit found.
    used : list of int
        Numbers of the hits averaged.
    tau_s : float or None
        Time constant of the exponential window, s (None: no window).
    records : list of Record
        The input records (for plotting).
    """

    frf: FRF
    coherence: np.ndarray
    hits: list
    used: list
    tau_s: float | None
    records: list = field(default_factory=list)

    def added_damping(self, freq_hz) -> np.ndarray:
        """Damping ratio added by the exponential window to a mode at ``freq_hz`` (Hz): 1/(2π f τ); 0 without one."""
        f = np.asarray(freq_hz, dtype=float)
        return np.zeros_like(f) if self.tau_s is None else 1.0 / (2 * np.pi * f * self.tau_s)


def corrected_damping(fn_hz, zeta, tau_s: float | None):
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
    tuple of numpy.ndarray
        (fn_hz, zeta) of the structure without the window.

    Examples
    --------
    The pole of a 500 Hz, ζ = 0.02 mode seen through a τ = 0.1 s window, and back:

    >>> w = 2 * np.pi * 500.0
    >>> lam = -0.02 * w + 1j * w * np.sqrt(1 - 0.02**2) - 1 / 0.1
    >>> fn, z = corrected_damping(abs(lam) / (2 * np.pi), -lam.real / abs(lam), 0.1)
    >>> round(float(fn), 9), round(float(z), 9)
    (500.0, 0.02)
    """
    fn, z = np.asarray(fn_hz, dtype=float), np.asarray(zeta, dtype=float)
    if tau_s is None:
        return fn, z
    w = 2 * np.pi * fn
    sigma, wd = z * w - 1.0 / tau_s, w * np.sqrt(1 - z**2)
    w0 = np.hypot(sigma, wd)
    return w0 / (2 * np.pi), sigma / w0


# ---------------------------------------------------------------- reading
def read_record(path, *, response: str = "acceleration") -> Record:
    """Read an impact record: a text table (time s, force N, response) or UFF58 time histories.

    Text (any extension but ``.uff``/``.unv``/``.uf``): three columns separated
    by commas, tabs or spaces; an optional header line; lines starting with
    ``#`` or ``%`` are comments. UFF: the file's datasets 58 of function type 1
    (time response); the force is the one with ordinate data type 13 (force),
    the response the one with 8/11/12 (displacement/velocity/acceleration, which
    overrides ``response``; an ordinate unit ``g`` is converted to m/s²).

    Parameters
    ----------
    path : str or Path
        The file.
    response : str
        What the text file's third column is: ``"acceleration"`` (m/s²),
        ``"velocity"`` (m/s) or ``"displacement"`` (m).

    Returns
    -------
    Record

    Raises
    ------
    InputError
        One line naming the file and field (and the line of a text file).
    """
    if Path(path).suffix.lower() in (".uff", ".unv", ".uf"):
        return _read_uff_record(path)
    from .frf_files import _check_not_cut, _is_number, _read_text

    rows = []
    text, open_end = _read_text(path)
    for n, line in enumerate(text, 1):
        s = line.strip()
        if not s or s[0] in "#%":
            continue
        cells = [c.strip() for c in (s.split(",") if "," in s else s.split())]
        if not rows and not _is_number(cells[0]):
            continue  # a header line
        if len(cells) != 3:
            raise InputError(f"line {n}: expected 3 columns (time s, force N, response), found {len(cells)}",
                             file=path, field="columns")
        rows.append((n, cells))
    if not rows:
        raise InputError("no data rows", file=path, field="data")
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


_UFF_RESPONSE = {8: "displacement", 11: "velocity", 12: "acceleration"}


def _read_uff_record(path) -> Record:
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
    if len(force) != 1 or len(resp) != 1:
        raise InputError(f"need one force (ordinate type 13) and one response (8/11/12) time history, found "
                         f"{len(force)} and {len(resp)} among: {names}", file=path, field="ordinate_spec_data_type")
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
    f, x, n = record.force_n, record.response, record.force_n.size
    sign = 1.0 if f.max() >= -f.min() else -1.0
    fs_ = sign * f
    peak = fs_.max()
    noise = 1.4826 * np.median(np.abs(f - np.median(f)))
    if peak <= 0 or peak < 10 * noise:
        raise InputError(f"no hit: peak force {peak:.3g} N is not above the noise ({noise:.3g} N rms)",
                         file=src, field="force_n")
    gap = max(1, int(round(min_gap_s / record.dt)))
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
        hits.append(Hit(first_number + k, record_index, s, stop, float(record.time_s[t]), float(sign * pk),
                        t + int(above[-1]), width, double, " and ".join(clipped)))
    return hits


# ---------------------------------------------------------------- FRF
def impact_frf(records, *, estimator: str = "H1", output: str = "receptance", threshold: float = 0.1,
               min_gap_s: float = 0.05, pretrigger_s: float | None = None, force_window_s: float | None = None,
               exp_window_s: float | str | None = None, drop_bad: bool = False, fmax_hz: float | None = None,
               label: str = "tap") -> TapResult:
    """Average the hits of impact records into an FRF with coherence.

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
        Highest frequency kept, Hz (default: Nyquist).
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
    >>> len(res.used), float(res.coherence.min()) > 0.999
    (2, True)
    """
    recs = [records] if isinstance(records, Record) else list(records)
    if not recs:
        raise InputError("no records", field="records")
    if estimator not in ("H1", "H2"):
        raise InputError(f"estimator must be H1 or H2, not {estimator!r}", field="estimator")
    if output not in ("receptance", "measured"):
        raise InputError(f"output must be 'receptance' or 'measured', not {output!r}", field="output")
    dt, kind = recs[0].dt, recs[0].response_kind
    for r in recs[1:]:
        if abs(r.dt - dt) > 1e-6 * dt:
            raise InputError(f"sampling step {r.dt:.9g} s differs from {dt:.9g} s of {recs[0].source}",
                             file=r.source or None, field="time_s")
        if r.response_kind != kind:
            raise InputError(f"response is {r.response_kind}, {recs[0].source} has {kind}", file=r.source or None,
                             field="response")
    hits, number = [], 1
    for i, r in enumerate(recs):
        found = find_hits(r, threshold=threshold, min_gap_s=min_gap_s, pretrigger_s=pretrigger_s,
                          first_number=number, record_index=i)
        hits += found
        number += len(found)
    used = []
    for h in hits:
        src = recs[h.record].source
        if h.bad and drop_bad:
            warnings.warn(f"{h.describe(src)}: dropped", stacklevel=2)
            continue
        if h.clipped:
            raise InputError(f"{h.describe()}; use --drop-bad (drop_bad=True) to leave it out",
                             file=src or None, field="overload")
        if h.double_at_s is not None:
            warnings.warn(f"{h.describe(src)}: kept (use --drop-bad to leave it out)", stacklevel=2)
        used.append(h)
    if not used:
        raise InputError(f"all {len(hits)} hits were dropped as bad", file=recs[0].source or None, field="hits")
    n = min(h.stop - h.start for h in used)
    if n < 8:
        raise InputError(f"hit blocks of {n} samples are too short (hits too close: raise min_gap_s or record "
                         "longer)", file=recs[0].source or None, field="time_s")
    t = np.arange(n) * dt
    tau = None
    if exp_window_s is not None:
        tau = n * dt / np.log(100.0) if exp_window_s == "auto" else float(exp_window_s)
        if not tau > 0:
            raise InputError(f"exponential window time constant must be > 0 s, got {exp_window_s}",
                             field="exp_window_s")
    we = np.ones(n) if tau is None else np.exp(-t / tau)
    fblk = np.stack([recs[h.record].force_n[h.start:h.start + n] for h in used])
    xblk = np.stack([recs[h.record].response[h.start:h.start + n] for h in used])
    if force_window_s is None:
        ends = np.array([h.pulse_end - h.start + h.width for h in used])
    else:
        ends = np.full(len(used), int(round(force_window_s / dt)))
    wf = (np.arange(n)[None, :] <= ends[:, None]).astype(float)
    for h, x in zip(used, xblk):
        tail = np.abs(x[int((1 - LEAK_TAIL) * n):]).max()
        if tail > LEAK_LEVEL * np.abs(x).max() and tau is None:
            warnings.warn(f"{recs[h.record].source}: hit {h.number}: the response has not died out by the end of "
                          f"its {n * dt:.4g} s block ({tail / np.abs(x).max():.1%} of its peak): leakage; "
                          "use longer records or an exponential window", stacklevel=2)
    F = np.fft.rfft(fblk * wf * we, axis=1)
    X = np.fft.rfft(xblk * we, axis=1)
    freq = np.fft.rfftfreq(n, dt)
    sff = np.sum(np.abs(F) ** 2, axis=0)
    sxx = np.sum(np.abs(X) ** 2, axis=0)
    sxf = np.sum(X * np.conj(F), axis=0)
    keep = np.ones(freq.size, bool) if fmax_hz is None else freq <= fmax_hz
    quantity = RESPONSES[kind]
    if output == "receptance" and quantity != "receptance":
        keep &= freq > 0
    if not keep.any():
        raise InputError(f"no frequency line at or below {fmax_hz} Hz", field="fmax_hz")
    freq, sff, sxx, sxf = freq[keep], sff[keep], sxx[keep], sxf[keep]
    zero = np.flatnonzero((sff == 0) | (np.abs(sxf) == 0))
    if zero.size:
        raise InputError(f"force or cross spectrum is zero at {freq[zero[0]]:.6g} Hz: lower fmax",
                         field="force_n")
    with np.errstate(all="ignore"):
        h = sxf / sff if estimator == "H1" else sxx / np.conj(sxf)
        coh = np.clip(np.abs(sxf) ** 2 / (sff * sxx), 0.0, 1.0)
    if len(used) == 1:
        warnings.warn("one hit: the coherence is 1 by construction (average several hits to measure it)",
                      stacklevel=2)
    meta = {"coherence": coh, "estimator": estimator, "hits": [h.number for h in used], "tau_s": tau,
            "source": ", ".join(r.source for r in recs), "format": "tap", "file_quantity": quantity}
    frf = FRF(freq, h, quantity, label, meta)
    if output == "receptance" and tau is not None and quantity != "receptance":
        # The windowed record is that of the system h(t) e^{-t/τ}: its accelerance (mobility) is
        # H_a(s + 1/τ) = (s + 1/τ)² H_x(s + 1/τ), so dividing by (iω + 1/τ)² (not (iω)²) gives exactly the
        # receptance with every pole moved by −1/τ and the residues unchanged.
        power = 2 if quantity == "accelerance" else 1
        frf = FRF(freq, h / (2j * np.pi * freq + 1.0 / tau) ** power, "receptance", label, meta)
    elif output == "receptance":
        frf = frf.to_receptance()
    return TapResult(frf, coh, hits, [h.number for h in used], tau, recs)


def plot_tap(result: TapResult):
    """Figure of an impact test: records with hits marked, |FRF|, phase and coherence.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

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
    result.frf.plot(ax[1:3])
    ax[3].plot(result.frf.freq_hz, result.coherence)
    ax[3].set_ylim(0, 1.05)
    ax[3].set_ylabel("coherence γ²")
    ax[3].set_xlabel("frequency [Hz]")
    ax[3].grid(True, alpha=0.3)
    return fig
