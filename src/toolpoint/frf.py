"""The frequency response function type used everywhere in toolpoint.

An :class:`FRF` holds frequencies in Hz and complex response values, in the
spirit of python-control's ``FRD``. The *quantity* says what the values are:

* ``"receptance"``  displacement / force, m/N
* ``"mobility"``    velocity / force, m/(N s)
* ``"accelerance"`` acceleration / force, m/(N s²)

With ω = 2π f, mobility = iω · receptance and accelerance = −ω² · receptance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import InputError

QUANTITIES = {"receptance": "m/N", "mobility": "m/(N·s)", "accelerance": "m/(N·s²)"}


def check_freq_hz(freq_hz, *, file=None, field: str = "freq_hz", positive: bool = False,
                  min_points: int = 1) -> np.ndarray:
    """A frequency grid as a 1-D float array, checked: finite, ≥ 0 (> 0 with
    ``positive``), strictly increasing, at least ``min_points`` long.

    The one place frequency grids are checked; problems raise
    :class:`~toolpoint.errors.InputError` naming ``file`` and ``field``.

    Examples
    --------
    >>> check_freq_hz([0, 1, 2]).tolist()
    [0.0, 1.0, 2.0]
    >>> check_freq_hz([3, 1, 2], file="m.csv")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: m.csv: freq_hz: frequencies must be strictly increasing (3 Hz is followed by 1 Hz)
    """
    try:
        f = np.asarray(freq_hz, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError("frequencies must be numbers", file=file, field=field) from None
    if f.size < min_points:
        raise InputError(f"needs at least {min_points} frequencies, got {f.size}", file=file, field=field)
    if not np.all(np.isfinite(f)):
        raise InputError("frequencies must be finite", file=file, field=field)
    if f.size and (f[0] <= 0 if positive else f[0] < 0):
        raise InputError(f"frequencies must be {'> 0' if positive else '≥ 0'} Hz, got {f[0]:g}", file=file, field=field)
    d = np.diff(f)
    if np.any(d <= 0):
        k = int(np.argmax(d <= 0))
        raise InputError(f"frequencies must be strictly increasing ({f[k]:g} Hz is followed by {f[k + 1]:g} Hz)",
                         file=file, field=field)
    return f


@dataclass(frozen=True)
class FRF:
    """A single-input single-output frequency response.

    Attributes
    ----------
    freq_hz : (n,) float array, strictly increasing, Hz.
    values : (n,) complex array, in the unit of ``quantity``.
    quantity : one of ``QUANTITIES``.
    label : free text (e.g. ``"tool point"``, a file name).
    """

    freq_hz: np.ndarray
    values: np.ndarray
    quantity: str = "receptance"
    label: str = ""
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        f = np.asarray(self.freq_hz, dtype=float).reshape(-1)
        v = np.asarray(self.values, dtype=complex).reshape(-1)
        if f.shape != v.shape:
            raise ValueError(f"FRF: {f.size} frequencies but {v.size} values")
        if self.quantity not in QUANTITIES:
            raise ValueError(f"FRF: unknown quantity {self.quantity!r} (one of {', '.join(QUANTITIES)})")
        object.__setattr__(self, "freq_hz", f)
        object.__setattr__(self, "values", v)

    # ------------------------------------------------------------------ basics
    def __len__(self) -> int:
        return self.freq_hz.size

    @property
    def omega(self) -> np.ndarray:
        """Angular frequency ω = 2π f, rad/s."""
        return 2.0 * np.pi * self.freq_hz

    @property
    def unit(self) -> str:
        return QUANTITIES[self.quantity]

    def to_receptance(self) -> "FRF":
        """Convert to receptance (m/N): divide mobility by iω, accelerance by −ω².

        A point at 0 Hz cannot be converted from mobility or accelerance and
        raises ``ValueError``.
        """
        if self.quantity == "receptance":
            return self
        w = self.omega
        if np.any(w == 0):
            raise ValueError(f"FRF {self.label!r}: cannot convert {self.quantity} at 0 Hz to receptance")
        factor = 1j * w if self.quantity == "mobility" else -(w**2)
        return FRF(self.freq_hz, self.values / factor, "receptance", self.label, dict(self.meta))

    def at(self, freq_hz) -> "FRF":
        """Linear interpolation (real and imaginary parts) at ``freq_hz``.

        Only inside the band [f_min, f_max]: asking outside raises ``ValueError``
        (extrapolating an FRF invents dynamics).
        """
        fq = np.asarray(freq_hz, dtype=float).reshape(-1)
        lo, hi = self.freq_hz[0], self.freq_hz[-1]
        tol = 1e-9 * max(1.0, abs(hi))
        if fq.size and (fq.min() < lo - tol or fq.max() > hi + tol):
            raise ValueError(
                f"FRF {self.label!r} covers {lo:g}–{hi:g} Hz; asked for {fq.min():g}–{fq.max():g} Hz "
                "(no extrapolation outside the measured band)"
            )
        re = np.interp(fq, self.freq_hz, self.values.real)
        im = np.interp(fq, self.freq_hz, self.values.imag)
        return FRF(fq, re + 1j * im, self.quantity, self.label, dict(self.meta))

    def band(self, fmin: float | None = None, fmax: float | None = None) -> "FRF":
        """The points with fmin ≤ f ≤ fmax (no interpolation)."""
        m = np.ones(len(self), bool)
        if fmin is not None:
            m &= self.freq_hz >= fmin
        if fmax is not None:
            m &= self.freq_hz <= fmax
        return FRF(self.freq_hz[m], self.values[m], self.quantity, self.label, dict(self.meta))

    def peak(self) -> tuple[float, float]:
        """Dominant peak: (frequency Hz, magnitude) of max |values|."""
        k = int(np.argmax(np.abs(self.values)))
        return float(self.freq_hz[k]), float(abs(self.values[k]))

    # ------------------------------------------------------------------ plotting
    def plot(self, ax=None, *, kind: str = "bode", **line_kw):
        """Plot magnitude (log axis) and phase, or real and imaginary parts.

        ``kind="bode"`` (default) or ``"reim"``. Pass ``ax`` as a pair of axes to
        overlay several FRFs; returns the pair.
        """
        import matplotlib.pyplot as plt

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
        elif kind == "reim":
            a0.plot(f, v.real, label=label, **line_kw)
            a1.plot(f, v.imag, **line_kw)
            a0.set_ylabel(f"real [{self.unit}]")
            a1.set_ylabel(f"imaginary [{self.unit}]")
        else:
            raise ValueError(f"FRF.plot: kind must be 'bode' or 'reim', not {kind!r}")
        a1.set_xlabel("frequency [Hz]")
        for a in ax:
            a.grid(True, which="both", alpha=0.3)
        if label:
            a0.legend(loc="best", fontsize="small")
        return ax
