"""The trusted band of a measured FRF: where its data can be believed.

A measured FRF is not equally good everywhere. Two regions are found from the
data alone and excluded, one rule each:

* **Noise above the signal at low frequency.** A tool-point receptance is
  usually derived from an accelerance (an accelerometer and a hammer), whose
  noise is roughly white; dividing by −ω² multiplies that noise by 1/ω², so
  towards 0 Hz it grows without bound while the structure's receptance tends to
  its finite static compliance. Below some frequency the file holds noise, up
  to 1e4–1e6 times the real response, and a stability lobe computed from it
  finds "chatter" there. The noise is measured point by point: the difference
  between each value and the straight line through its two neighbours,
  r_k = H_k − (h₂H_{k−1} + h₁H_{k+1})/(h₁ + h₂) (h₁, h₂ the two frequency
  steps), is ≈ 0 for a smooth FRF and, for complex white noise of standard
  deviation σ, a complex Gaussian of variance σ²(1 + (h₁² + h₂²)/(h₁ + h₂)²).
  Over a sliding window of :data:`WINDOW` points the noise estimate is
  σ̂ = median|r̃|/√(ln 2) (r̃ = r normalised to variance σ²; √(ln 2) σ is the median of the
  modulus of a complex Gaussian) and the signal Ŝ = median|H|. The trusted band
  starts at the first point from which Ŝ ≥ :data:`SNR_MIN` · σ̂ holds for
  :data:`WINDOW` points in a row (pure noise gives Ŝ/σ̂ ≈ √(ln 2) ≈ 0.83).
  Only the low end is cut this way: a dip of the signal higher up (an
  anti-resonance) is not a reason to cut the band. Unless the FRF is known to
  be converted from accelerance or mobility (``quantity_measured``, or
  ``meta["file_quantity"]`` set by the readers), the cut is made only when the
  noise estimate below the edge grows towards 0 Hz (log–log slope of σ̂ against
  f ≤ −1 over at least :data:`MIN_SLOPE_POINTS` points): noise white in the
  receptance itself over a small static compliance is not the conversion's
  junk, and a fit can weigh it. The note says whether the excluded noise grows
  like 1/ω² (slope between −2.5 and −1.5: "looks like accelerance noise ×1/ω²").
* **Low coherence at either end.** When ``frf.meta["coherence"]`` holds the
  ordinary coherence γ² (e.g. from ``toolpoint tap`` or a file with a
  coherence column), the band starts at the first point from which
  γ² ≥ :data:`COHERENCE_MIN` holds for :data:`WINDOW` points in a row and ends
  at the last such point. Dips inside the band (anti-resonances, where γ²
  drops because the response is small) are kept.

Neither rule cuts a clean FRF: its neighbour residual is the curvature of the
FRF over two frequency steps, far below the FRF itself unless a mode is
narrower than a few steps. An explicit band (``--band LO:HI`` or a config key
such as ``band_hz``) replaces the detection; a band with fewer than two data
points inside is an :class:`~toolpoint.errors.InputError` naming the file and
field. The measured figures (a synthetic noisy receptance, the example
assembly) are in ``docs/design/measurements.md``, section "Trusted band".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .errors import InputError
from .frf import FRF

__all__ = ["COHERENCE_MIN", "SNR_MIN", "WINDOW", "MIN_SLOPE_POINTS", "TrustedBand", "check_band", "trusted_band",
           "edge_hits"]

COHERENCE_MIN = 0.8
"""Lowest ordinary coherence γ² trusted at the band ends (γ² = 0.8: noise-to-signal power ratio 0.25)."""

SNR_MIN = 2.0
"""Signal-to-noise ratio Ŝ/σ̂ (median |H| over the windowed noise estimate) from which the low end is trusted."""

WINDOW = 15
"""Points of the sliding window of the noise estimate, and of a run that starts (or ends) the trusted band."""

MIN_SLOPE_POINTS = 5
"""Fewest points (> 0 Hz) below the edge to judge whether the noise grows towards 0 Hz."""


class TrustedBand(NamedTuple):
    """The band of an FRF to use, and why.

    Attributes
    ----------
    lo_hz, hi_hz : float
        First and last trusted frequency, Hz (grid points of the FRF).
    reason : str
        What was excluded and why; ``""`` when nothing was.
    given : bool
        True when the band was given (``--band`` or a config key), not detected.
    noise_quantity : str
        The quantity the FRF's noise looks white in, when the noise rule found it:
        ``"accelerance"`` (noise ∝ 1/ω² in receptance: known converted from accelerance,
        or log–log slope of the noise between −2.5 and −1.5), ``"mobility"`` (∝ 1/ω: known
        converted from mobility, or slope above −1.5); ``""`` when not found (a modal
        fit then weighs the FRF as white in its own quantity).
    """

    lo_hz: float
    hi_hz: float
    reason: str = ""
    given: bool = False
    noise_quantity: str = ""

    def note(self, name: str = "", hint: str = "--band LO:HI") -> str:
        """The one-line note for stderr (``""`` when a detected band excludes nothing).

        Examples
        --------
        >>> TrustedBand(187.0, 5000.0, "below 187 Hz the noise exceeds the signal").note("tp.csv")
        'note: tp.csv: trusted band 187–5000 Hz (below 187 Hz the noise exceeds the signal); override with --band LO:HI'
        >>> TrustedBand(200.0, 4000.0, "given by --band", given=True).note("tp.csv")
        'note: tp.csv: band 200–4000 Hz given by --band (no automatic trimming)'
        """
        where = f"{name}: " if name else ""
        if self.given:
            return f"note: {where}band {self.lo_hz:g}–{self.hi_hz:g} Hz {self.reason} (no automatic trimming)"
        if not self.reason:
            return ""
        return f"note: {where}trusted band {self.lo_hz:g}–{self.hi_hz:g} Hz ({self.reason}); override with {hint}"


def check_band(band, *, file=None, field: str = "--band") -> tuple[float, float]:
    """A band (LO, HI) in Hz with 0 ≤ LO < HI, both finite; otherwise an InputError naming ``file`` and ``field``.

    Examples
    --------
    >>> check_band([200, 5000])
    (200.0, 5000.0)
    >>> check_band([5000, 200], file="a.toml", field="identify.band_hz")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: a.toml: identify.band_hz: expected [LO, HI] in Hz with 0 ≤ LO < HI, got [5000, 200]
    """
    try:
        lo, hi = (float(v) for v in band)
    except (TypeError, ValueError):
        lo = hi = math.nan
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
        raise InputError(f"expected [LO, HI] in Hz with 0 ≤ LO < HI, got {band!r}", file=file, field=field)
    return lo, hi


def _neighbour_residual(f: np.ndarray, h: np.ndarray) -> np.ndarray:
    """|r̃_k| for the interior points: the value minus the line through its neighbours, scaled to noise σ."""
    h1, h2 = np.diff(f)[:-1], np.diff(f)[1:]
    r = h[1:-1] - (h2 * h[:-2] + h1 * h[2:]) / (h1 + h2)
    return np.abs(r) / np.sqrt(1.0 + (h1**2 + h2**2) / (h1 + h2) ** 2)


def _running_median(x: np.ndarray, n: int) -> np.ndarray:
    """Median over a centred window of ``n`` (odd) points, the ends padded with the edge values.

    The same as ``scipy.ndimage.median_filter(x, n, mode="nearest")``, written with NumPy because
    scipy 1.15.0's 1-D median filter (our floor) returns wrong, run-to-run different values.
    """
    pad = np.pad(x, n // 2, mode="edge")
    return np.median(np.lib.stride_tricks.sliding_window_view(pad, n), axis=1)


def _first_run(ok: np.ndarray, n: int) -> int | None:
    """Index of the first point that starts ``n`` True values in a row, or None."""
    if ok.size < n:
        return 0 if ok.all() and ok.size else None
    runs = np.convolve(ok.astype(int), np.ones(n, int), "valid") == n
    hit = np.flatnonzero(runs)
    return int(hit[0]) if hit.size else None


def _noise_edge(frf: FRF, quantity_measured: str | None) -> tuple[int, str, str]:
    """Index of the first trusted point by the noise rule, the reason ("" when nothing is cut) and the
    quantity the noise looks white in ("" when not found)."""
    f, h = frf.freq_hz, frf.values
    if f.size < 3 * WINDOW:
        return 0, "", ""
    resid = np.concatenate([[np.nan], _neighbour_residual(f, h), [np.nan]])
    resid[0], resid[-1] = resid[1], resid[-2]
    sigma = _running_median(resid, WINDOW) / math.sqrt(math.log(2.0))
    signal = _running_median(np.abs(h), WINDOW)
    ok = signal >= SNR_MIN * sigma  # a zero FRF with zero noise is exact data, not noise
    i = _first_run(ok, WINDOW)
    if i is None:
        return 0, (f"no part of the FRF stands clearly above its noise (signal < {SNR_MIN:g}× the point-to-point "
                   "noise everywhere): nothing trimmed, check the data"), ""
    if i == 0:
        return 0, "", ""
    lo = f[i]
    if quantity_measured in ("accelerance", "mobility"):
        how = f"the {quantity_measured}'s noise ×1/ω{'²' if quantity_measured == 'accelerance' else ''} " \
              "exceeds the signal"
        return i, f"below {lo:g} Hz {how}", quantity_measured
    # Not known to be converted: cut only where the noise grows towards 0 Hz (log–log slope ≤ −1), the
    # signature of a division by ω or ω². Flat noise over a small signal is left to the fit's weighting.
    below = (f[:i] > 0) & (sigma[:i] > 0)
    if below.sum() < MIN_SLOPE_POINTS:
        return 0, "", ""
    slope = np.polyfit(np.log(f[:i][below]), np.log(sigma[:i][below]), 1)[0]
    if slope > -1.0:
        return 0, "", ""
    accel = -2.5 <= slope <= -1.5
    how = ("the receptance looks like accelerance noise ×1/ω²" if accel else
           f"the noise, growing towards 0 Hz as f^{slope:.1f}, exceeds the signal")
    return i, f"below {lo:g} Hz {how}", "accelerance" if accel else ("mobility" if slope > -1.5 else "")


def _coherence_edges(frf: FRF, coherence_min: float) -> tuple[int, int, str]:
    """First and last trusted index by the coherence rule, and the reason ("" when nothing is cut)."""
    g = np.asarray(frf.meta["coherence"], float).reshape(-1)
    if g.size != len(frf):
        raise InputError(f"coherence has {g.size} points, the FRF {len(frf)}", file=frf.meta.get("source"),
                         field="coherence")
    ok = g >= coherence_min
    i = _first_run(ok, min(WINDOW, ok.size))
    if i is None:
        return 0, len(frf) - 1, (f"coherence γ² < {coherence_min:g} almost everywhere: nothing trimmed, "
                                 "check the data")
    j = ok.size - 1 - _first_run(ok[::-1], min(WINDOW, ok.size))
    f = frf.freq_hz
    parts = ([f"below {f[i]:g} Hz"] if i > 0 else []) + ([f"above {f[j]:g} Hz"] if j < ok.size - 1 else [])
    return i, j, (f"coherence γ² < {coherence_min:g} {' and '.join(parts)}" if parts else "")


def trusted_band(frf: FRF, *, quantity_measured: str | None = None, coherence_min: float = COHERENCE_MIN,
                 band=None, file=None, field: str = "--band") -> TrustedBand:
    """The band of a measured SISO FRF to trust: given, or found from its data (module docstring).

    Parameters
    ----------
    frf : FRF
        The measured FRF (receptance or any quantity; judged as it is).
    quantity_measured : str, optional
        What the instrument measured when ``frf`` was converted from it
        (``"accelerance"``, ``"mobility"``); default ``frf.meta["file_quantity"]``.
        Cuts below the noise edge without the slope test, and sets ``noise_quantity``.
    coherence_min : float
        Lowest coherence γ² trusted at the band ends (:data:`COHERENCE_MIN`).
    band : (float, float), optional
        A band given by the user, Hz: used as it is (clipped to the data), no detection.
    file, field : optional
        Named by the error for a band outside the data (default: ``frf.meta["source"]``, ``--band``).

    Returns
    -------
    TrustedBand
        ``lo_hz``, ``hi_hz`` (grid points of ``frf``), ``reason``, ``given`` and ``noise_quantity``.

    Raises
    ------
    InputError
        A given band with fewer than two points of the FRF inside, or a matrix FRF.

    Examples
    --------
    A clean one-mode receptance keeps its whole band; white noise in
    accelerance (σ = 0.042 m/(N s²), 0.05 % of the peak accelerance), divided by −ω²,
    equals the static compliance 1e-7 m/N at 103 Hz; the band then starts where the
    signal is twice the noise, ≈ √2 × 103 Hz.

    >>> import numpy as np
    >>> f = np.arange(0.0, 3001.0)
    >>> r = f / 900.0
    >>> h = 1 / (1e7 * (1 - r**2 + 0.04j * r))
    >>> trusted_band(FRF(f, h))
    TrustedBand(lo_hz=0.0, hi_hz=3000.0, reason='', given=False, noise_quantity='')
    >>> rng = np.random.default_rng(0)
    >>> w = 2 * np.pi * np.maximum(f, 0.5)
    >>> noise = 0.03 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / w**2
    >>> tb = trusted_band(FRF(f, h + noise))
    >>> 120 < tb.lo_hz < 170, tb.hi_hz
    (True, 3000.0)
    >>> tb.reason[tb.reason.index("Hz") + 3:], tb.noise_quantity
    ('the receptance looks like accelerance noise ×1/ω²', 'accelerance')
    """
    if not frf.is_siso:
        raise InputError("a trusted band is found for one response at a time; take an entry first",
                         field="values")
    file = frf.meta.get("source") if file is None else file
    f = frf.freq_hz
    if band is not None:
        lo, hi = check_band(band, file=file, field=field)
        inside = f[(f >= lo) & (f <= hi)]
        if inside.size < 2:
            span = f"{f[0]:g}–{f[-1]:g} Hz" if f.size else "no frequencies"
            raise InputError(f"band {lo:g}–{hi:g} Hz holds {inside.size} of the data's points (the data cover "
                             f"{span})", file=file, field=field)
        return TrustedBand(float(inside[0]), float(inside[-1]), f"given by {field}", True)
    if f.size == 0:
        raise InputError("no data points", file=file, field="freq_hz")
    q = quantity_measured or frf.meta.get("file_quantity")
    i, why, noise_q = _noise_edge(frf, q)
    j, reasons = f.size - 1, [why] if why else []
    if frf.meta.get("coherence") is not None:
        ic, jc, cwhy = _coherence_edges(frf, coherence_min)
        if cwhy:
            reasons.append(cwhy)
        i, j = max(i, ic), min(j, jc)
    if j - i < 1:
        return TrustedBand(float(f[0]), float(f[-1]), "; ".join(reasons + [
            "the rules leave no band: nothing trimmed, check the data"]), noise_quantity=noise_q)
    return TrustedBand(float(f[i]), float(f[j]), "; ".join(reasons), noise_quantity=noise_q)


def edge_hits(chatter_hz, band: tuple[float, float], freq_hz) -> np.ndarray:
    """Which chatter frequencies lie at (or beyond) an edge of a trimmed band: within two frequency steps.

    A stability limit whose chatter frequency sits on the edge of the band
    the FRF was cut to may belong to a resonance outside the band: it cannot be
    trusted. Only an edge that cuts data off counts (``band`` inside ``freq_hz``).

    Parameters
    ----------
    chatter_hz : array_like
        Chatter frequencies, Hz (nan where no limit: False).
    band : (float, float)
        The band used, Hz.
    freq_hz : array_like
        The full grid of the measured data, Hz.

    Returns
    -------
    numpy.ndarray
        Boolean, True where the chatter frequency is at a cutting edge.

    Examples
    --------
    >>> edge_hits([200.5, 950.0, np.nan], (200.0, 3000.0), np.arange(0.0, 3001.0)).tolist()
    [True, False, False]
    """
    c = np.asarray(chatter_hz, float)
    f = np.asarray(freq_hz, float)
    lo, hi = band
    out = np.zeros(c.shape, bool)
    with np.errstate(invalid="ignore"):
        if f.size and lo > f[0]:
            steps = np.diff(f[f >= lo][:3])
            out |= c <= lo + (steps.sum() if steps.size else 0.0)
        if f.size and hi < f[-1]:
            steps = np.diff(f[f <= hi][-3:])
            out |= c >= hi - (steps.sum() if steps.size else 0.0)
    return out & np.isfinite(c)
