"""The frequency response function type used everywhere in toolpoint.

An :class:`FRF` holds frequencies in Hz and complex response values, in the
spirit of python-control's ``FRD``. The values are either one response per
frequency, shape (F,) (single input, single output), or a matrix per
frequency, shape (F, n, m) (e.g. the 2×2 holder-tip receptance
[[h, l], [n, p]] of :class:`~toolpoint.dynamics.subassembly.Subassembly`).
The *quantity* says what the values are:

* ``"receptance"``  displacement / force, m/N
* ``"mobility"``    velocity / force, m/(N s)
* ``"accelerance"`` acceleration / force, m/(N s²)

With ω = 2π f, mobility = iω · receptance and accelerance = −ω² · receptance.
:func:`check_freq_hz` is the one place where frequency grids are checked.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .errors import InputError

__all__ = ["FRF", "QUANTITIES", "check_freq_hz"]

QUANTITIES = {"receptance": "m/N", "mobility": "m/(N·s)", "accelerance": "m/(N·s²)"}
"""Unit of each FRF quantity (per unit force; moments and rotations keep the same name)."""

# Relative tolerance of FRF.at at the band edges: a query this close outside the band (relative to
# max(1 Hz, f_max)) is round-off of the grid, not extrapolation, and is read as the edge value.
AT_RTOL = 1e-9


def check_freq_hz(freq_hz, *, file=None, field: str = "freq_hz", positive: bool = False,
                  min_points: int = 1, where: Callable[[int], str] | None = None) -> np.ndarray:
    """A frequency grid as a 1-D float array, checked.

    The one place frequency grids are checked: finite, ≥ 0 Hz (> 0 Hz with
    ``positive``), strictly increasing, at least ``min_points`` long.

    Parameters
    ----------
    freq_hz : array_like
        Frequencies, Hz (any shape; flattened).
    file, field : str, optional
        Where the grid came from, for the error message.
    positive : bool
        Refuse 0 Hz (a free–free receptance, mobility or accelerance is singular there).
    min_points : int
        Fewest points accepted.
    where : callable, optional
        ``where(i)`` describes the location of point ``i`` (e.g. ``"line 7"`` of a file);
        appended to the message.

    Returns
    -------
    numpy.ndarray
        (F,) float frequencies, Hz.

    Raises
    ------
    InputError
        One line naming ``file`` and ``field``.

    Examples
    --------
    >>> check_freq_hz([0, 1, 2]).tolist()
    [0.0, 1.0, 2.0]
    >>> check_freq_hz([3, 1, 2], file="m.csv")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: m.csv: freq_hz: frequencies must be strictly increasing (3 Hz is followed by 1 Hz)
    """
    def fail(message: str, i: int | None = None):
        at = f" at {where(i)}" if where is not None and i is not None else ""
        return InputError(message + at, file=file, field=field)

    try:
        f = np.asarray(freq_hz, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError("frequencies must be numbers", file=file, field=field) from None
    if f.size < min_points:
        raise fail(f"needs at least {min_points} frequencies, got {f.size}")
    bad = np.flatnonzero(~np.isfinite(f))
    if bad.size:
        raise fail(f"frequencies must be finite, got {f[bad[0]]}", int(bad[0]))
    if f.size and (f[0] <= 0 if positive else f[0] < 0):
        raise fail(f"frequencies must be {'> 0' if positive else '≥ 0'} Hz, got {f[0]:.10g}", 0)
    bad = np.flatnonzero(np.diff(f) <= 0)
    if bad.size:
        k = int(bad[0])
        what = f"{f[k]:.10g} Hz repeated" if f[k] == f[k + 1] else f"{f[k]:.10g} Hz is followed by {f[k + 1]:.10g} Hz"
        raise fail(f"frequencies must be strictly increasing ({what})", k + 1)
    return f


def _interp(fq: np.ndarray, f: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Piecewise-linear interpolation of v (F, ...) at fq (Q,) inside [f[0], f[-1]], all entries at once.

    The same formula as :func:`numpy.interp` (slope × (x − f_j) + v_j, exact at the
    grid points), applied to every entry of the trailing axes in one vectorised pass.
    """
    if f.size == 1:
        return np.broadcast_to(v[:1], (fq.size,) + v.shape[1:]).copy()
    j = np.clip(np.searchsorted(f, fq, side="right") - 1, 0, f.size - 2)
    extra = (slice(None),) + (None,) * (v.ndim - 1)
    slope = (v[j + 1] - v[j]) / (f[j + 1] - f[j])[extra]
    out = slope * (fq - f[j])[extra] + v[j]
    node = fq == f[j]
    out[node] = v[j[node]]
    last = fq == f[-1]
    out[last] = v[-1]
    return out


@dataclass(frozen=True)
class FRF:
    """A frequency response: complex values on a grid of frequencies (Hz).

    Invariants (checked on construction; a violation raises
    :class:`~toolpoint.errors.InputError` naming the field): frequencies finite,
    ≥ 0 Hz and strictly increasing (:func:`check_freq_hz`); values finite, of
    shape (F,) (SISO) or (F, n, m) (a matrix FRF); ``quantity`` one of
    :data:`QUANTITIES`.

    Parameters
    ----------
    freq_hz : array_like
        (F,) frequencies, Hz.
    values : array_like
        (F,) or (F, n, m) complex values in the unit of ``quantity``.
    quantity : str
        ``"receptance"`` (m/N), ``"mobility"`` (m/(N s)) or ``"accelerance"`` (m/(N s²)).
    label : str
        Free text (e.g. ``"tool point"``, a file name).
    meta : dict
        Free-form provenance (source file, format, UFF node/direction, ...);
        not compared.

    Examples
    --------
    A single-degree-of-freedom receptance H = 1 / (k (1 − r² + 2iζr)), r = f/fn,
    k = 1e7 N/m, fn = 600 Hz, ζ = 0.05: at resonance H = −i/(2ζk) = −1e-6i m/N,
    and |H| peaks at fn √(1 − 2ζ²) ≈ 598.5 Hz (on this 1 Hz grid: 598 Hz).

    >>> import numpy as np
    >>> f = np.linspace(100.0, 1000.0, 901)
    >>> r = f / 600.0
    >>> h = FRF(f, 1 / (1e7 * (1 - r**2 + 0.1j * r)), label="sdof")
    >>> h.peak()[0]
    598.0
    >>> complex(h.at([600.0]).values[0] * 1e6)
    -1j
    >>> len(h.band(500.0, 700.0)), h.unit
    (201, 'm/N')
    >>> FRF([3, 1, 2], [1, 2, 3])
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: freq_hz: frequencies must be strictly increasing (3 Hz is followed by 1 Hz)
    """

    freq_hz: np.ndarray
    values: np.ndarray
    quantity: str = "receptance"
    label: str = ""
    meta: dict = field(default_factory=dict, compare=False)

    # Extra invariants of specialisations (class attributes, not fields).
    _positive_freq = False  # refuse 0 Hz
    _entry_shape = None  # required (n, m) of a matrix FRF (a tuple), or None

    def __post_init__(self):
        f = check_freq_hz(self.freq_hz, positive=self._positive_freq, min_points=0)
        try:
            v = np.array(self.values, dtype=complex)  # a copy: the FRF owns its values
        except (TypeError, ValueError):
            raise InputError("values must be complex numbers", field="values") from None
        if v.ndim not in (1, 3) or v.shape[0] != f.size:
            raise InputError(f"shape {v.shape} does not match {f.size} frequencies: need ({f.size},) or "
                             f"({f.size}, n, m)", field="values")
        if self._entry_shape is not None and v.shape[1:] != self._entry_shape:
            raise InputError(f"shape {v.shape}, expected ({f.size}, {', '.join(map(str, self._entry_shape))})",
                             field="values")
        if not np.all(np.isfinite(v)):
            k = int(np.flatnonzero(~np.isfinite(v.reshape(f.size, -1)).any(1))[0])
            raise InputError(f"values must be finite (first non-finite value at {f[k]:g} Hz)", field="values")
        if self.quantity not in QUANTITIES:
            raise InputError(f"unknown quantity {self.quantity!r} (one of {', '.join(QUANTITIES)})",
                             field="quantity")
        object.__setattr__(self, "freq_hz", f)
        object.__setattr__(self, "values", v)

    def _new(self, freq_hz, values, quantity: str | None = None, meta: dict | None = None) -> "FRF":
        """An object of the same type and label on new data (checked like any other)."""
        out = object.__new__(type(self))
        FRF.__init__(out, freq_hz, values, quantity or self.quantity, self.label, dict(self.meta if meta is None
                                                                                      else meta))
        return out

    # ------------------------------------------------------------------ basics
    def __len__(self) -> int:
        """Number of frequencies F."""
        return self.freq_hz.size

    @property
    def omega(self) -> np.ndarray:
        """Angular frequency ω = 2π f, rad/s, (F,)."""
        return 2.0 * np.pi * self.freq_hz

    @property
    def unit(self) -> str:
        """Unit of the values, e.g. ``"m/N"`` for receptance."""
        return QUANTITIES[self.quantity]

    @property
    def is_siso(self) -> bool:
        """True for one response per frequency (values (F,)), False for a matrix FRF (F, n, m)."""
        return self.values.ndim == 1

    def entry(self, i: int, j: int) -> "FRF":
        """Entry (i, j) of a matrix FRF as a SISO :class:`FRF` (label ``"<label>[i, j]"``)."""
        if self.is_siso:
            raise InputError("entry() is for a matrix FRF (F, n, m); this one is SISO", field="values")
        return FRF(self.freq_hz, self.values[:, i, j], self.quantity, f"{self.label}[{i}, {j}]", dict(self.meta))

    def to_receptance(self) -> "FRF":
        """Convert to receptance (m/N): mobility / (iω), accelerance / (−ω²).

        Works entry by entry for a matrix FRF.

        Raises
        ------
        InputError
            For a mobility or accelerance point at 0 Hz (no receptance there).
        """
        if self.quantity == "receptance":
            return self
        w = self.omega
        if np.any(w == 0):
            raise InputError(f"FRF {self.label!r}: cannot convert {self.quantity} at 0 Hz to receptance",
                             field="values")
        factor = 1j * w if self.quantity == "mobility" else -(w**2)
        return self._new(self.freq_hz, self.values / factor.reshape((-1,) + (1,) * (self.values.ndim - 1)),
                         "receptance")

    def at(self, freq_hz) -> "FRF":
        """Linear interpolation of every entry (real and imaginary parts) at ``freq_hz`` (Hz).

        Between grid points f_j ≤ f ≤ f_{j+1}:
        H(f) = H_j + (H_{j+1} − H_j)(f − f_j)/(f_{j+1} − f_j), exact at the grid
        points; the same as :func:`numpy.interp` entry by entry, vectorised over
        frequencies and entries. ``freq_hz`` is a grid like any other (finite,
        ≥ 0, strictly increasing). Only inside the band [f_min, f_max], widened by
        ``AT_RTOL`` · max(1 Hz, f_max) for round-off: extrapolating an FRF invents
        dynamics. An empty query gives an empty FRF.

        Raises
        ------
        InputError
            For a query outside the band (field ``freq_hz``).
        """
        fq = check_freq_hz(freq_hz, min_points=0)
        if fq.size == self.freq_hz.size and np.array_equal(fq, self.freq_hz):
            return self
        if fq.size == 0:
            return self._new(fq, self.values[:0], meta=self._meta_per_freq(lambda v: v[:0]))
        if len(self) == 0:
            raise InputError(f"FRF {self.label!r} is empty; asked for {fq.min():g}–{fq.max():g} Hz", field="freq_hz")
        lo, hi = self.freq_hz[0], self.freq_hz[-1]
        tol = AT_RTOL * max(1.0, hi)
        if fq.min() < lo - tol or fq.max() > hi + tol:
            raise InputError(f"{self.label or 'FRF'!r} covers {lo:g}–{hi:g} Hz; asked for {fq.min():g}–{fq.max():g} "
                             "Hz (no extrapolation outside the measured band)", field="freq_hz")
        fc = np.clip(fq, lo, hi)
        return self._new(fq, _interp(fc, self.freq_hz, self.values),
                         meta=self._meta_per_freq(lambda v: _interp(fc, self.freq_hz, v)))

    def _meta_per_freq(self, f) -> dict:
        """``meta`` with ``f`` applied to every per-frequency array (first axis one entry per frequency)."""
        n = len(self)
        return {k: (f(v) if isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == n else v)
                for k, v in self.meta.items()}

    def band(self, fmin: float | None = None, fmax: float | None = None) -> "FRF":
        """The points with fmin ≤ f ≤ fmax (Hz), no interpolation; same type and shape per point.

        Per-frequency arrays in ``meta`` (NumPy arrays whose first axis has one
        entry per frequency, e.g. ``meta["coherence"]``) are cut to the same points.
        """
        m = np.ones(len(self), bool)
        if fmin is not None:
            m &= self.freq_hz >= fmin
        if fmax is not None:
            m &= self.freq_hz <= fmax
        return self._new(self.freq_hz[m], self.values[m], meta=self._meta_per_freq(lambda v: v[m]))

    def peak(self) -> tuple[float, float]:
        """Dominant peak of a SISO FRF: (frequency Hz, magnitude in :attr:`unit`) of max |values|.

        Raises
        ------
        InputError
            For a matrix FRF (take an entry with :meth:`entry`) or an empty one.
        """
        if not self.is_siso:
            raise InputError("peak() is for a SISO FRF; take an entry first, e.g. .entry(0, 0)", field="values")
        if len(self) == 0:
            raise InputError("peak() of an empty FRF", field="values")
        k = int(np.argmax(np.abs(self.values)))
        return float(self.freq_hz[k]), float(abs(self.values[k]))

    # ------------------------------------------------------------------ plotting
    def plot(self, ax=None, *, kind: str = "bode", **line_kw):
        """Plot a SISO FRF: magnitude (log axis) and phase, or real and imaginary parts.

        Parameters
        ----------
        ax : pair of matplotlib axes, optional
            Overlay several FRFs on the same pair; a new figure if None.
        kind : str
            ``"bode"`` (default: |H| in :attr:`unit` and phase in degrees) or ``"reim"``.
        **line_kw
            Passed to matplotlib's ``plot`` (``label`` defaults to :attr:`label`).

        Returns
        -------
        tuple
            The pair of axes.
        """
        import matplotlib.pyplot as plt

        if not self.is_siso:
            raise InputError("plot() is for a SISO FRF; take an entry first, e.g. .entry(0, 0)", field="values")
        if kind not in ("bode", "reim"):
            raise ValueError(f"FRF.plot: kind must be 'bode' or 'reim', not {kind!r}")
        if ax is None:
            _, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5), constrained_layout=True)
        a0, a1 = ax
        label = line_kw.pop("label", self.label or None)
        f, v = self.freq_hz, self.values
        if kind == "bode":
            a0.semilogy(f, np.abs(v), label=label, **line_kw)
            a1.plot(f, np.degrees(np.angle(v)), **line_kw)
            a0.set_ylabel(f"|{self.quantity}| [{self.unit}]")
            a1.set_ylabel("phase [deg]")
            a1.set_ylim(-185, 185)
        else:
            a0.plot(f, v.real, label=label, **line_kw)
            a1.plot(f, v.imag, **line_kw)
            a0.set_ylabel(f"real [{self.unit}]")
            a1.set_ylabel(f"imaginary [{self.unit}]")
        a1.set_xlabel("frequency [Hz]")
        for a in ax:
            a.grid(True, which="both", alpha=0.3)
        if label:
            a0.legend(loc="best", fontsize="small")
        return ax
