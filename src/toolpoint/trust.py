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
* **A receptance that rises towards 0 Hz** (physical plausibility). A tool
  clamped in a spindle is grounded: its receptance tends to a finite static
  compliance at 0 Hz and cannot rise towards 0 Hz like a free mass. An offset
  or slow drift in the acceleration channel, divided by −ω², makes exactly such
  a rise — smooth, not noisy, so the noise rule above does not see it (a lab's
  end mill: |H| 1.2e-2 m/N at 1 Hz falling as f⁻²…f⁻³ to the static compliance
  ≈ 1e-7 m/N near 60 Hz). The rule: |H| smoothed over :data:`WINDOW` points
  is followed up from the lowest frequency while it falls; its *valley* is the
  lowest value before it climbs again to :data:`RISE_CLIMB` × that value (the
  static compliance, or the flank of the first mode). When the log–log slope
  of |H| from the first point (> 0 Hz) to the valley is ≤ :data:`RISE_SLOPE`,
  the band starts at :data:`RISE_MARGIN` × the valley frequency: at the valley
  the artefact is as large as the structure's response, and one octave up an
  f⁻² rise has fallen to a quarter, f⁻³ to an eighth. When the rise never
  levels off, the data cannot tell the structure from the artefact: an
  :class:`~toolpoint.errors.InputError` says so and asks for ``--band``.
  Only a smooth rise counts (neighbouring residuals correlated above
  :data:`RISE_SMOOTH`: a rise made of noise ×1/ω² is the noise rule's), only data that start near
  0 Hz (:data:`RISE_NEAR_ZERO`) and only receptances (mobility and
  accelerance of a grounded structure vanish at 0 Hz).
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

__all__ = ["COHERENCE_MIN", "SNR_MIN", "WINDOW", "MIN_SLOPE_POINTS", "RISE_SLOPE", "RISE_CLIMB", "RISE_MARGIN",
           "RISE_SMOOTH", "RISE_NEAR_ZERO", "RECEPTANCE_RANGE", "SPIKE_RATIO", "TrustedBand", "Band", "check_band",
           "trusted_band", "common_band", "unit_note", "check_spikes", "edge_hits"]

COHERENCE_MIN = 0.8
"""Lowest ordinary coherence γ² trusted at the band ends (γ² = 0.8: noise-to-signal power ratio 0.25)."""

SNR_MIN = 2.0
"""Signal-to-noise ratio Ŝ/σ̂ (median |H| over the windowed noise estimate) from which the low end is trusted."""

WINDOW = 15
"""Points of the sliding window of the noise estimate, and of a run that starts (or ends) the trusted band."""

MIN_SLOPE_POINTS = 5
"""Fewest points (> 0 Hz) below the edge to judge whether the noise grows towards 0 Hz."""


RECEPTANCE_RANGE = (1e-10, 1e-4)
"""Plausible largest |H| of a machine-tool tool-point receptance, m/N. Measured tool points peak at ≈ 1e-8–1e-5 m/N
(Schmitz & Smith, *Machining Dynamics*, 2019; this project's examples 5.6e-6, a lab's end mill 6.8e-7); a file whose
peak lies outside this range by orders of magnitude was most likely written in another unit (mm/N reads 1000×)."""


def unit_note(frf: FRF, name: str = "") -> str:
    """A one-line hint when a receptance's size is orders of magnitude from a machine tool's (``""`` otherwise).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.arange(1.0, 3001.0)
    >>> h = 1 / (1e7 * (1 - (f / 900) ** 2 + 0.04j * f / 900))   # m/N: peak 2.5e-6
    >>> unit_note(FRF(f, h)), unit_note(FRF(f, 1e3 * h), "x.csv")[:60]
    ('', 'warning: x.csv: the largest |H| is 0.0025 m/N, orders of mag')
    """
    if frf.quantity != "receptance" or not len(frf):
        return ""
    peak = float(np.max(np.abs(frf.values)))
    lo, hi = RECEPTANCE_RANGE
    if lo <= peak <= hi or peak == 0:
        return ""
    where = f"{name}: " if name else ""
    guess = "mm/N (×1000)" if peak > hi else "another unit or scale"
    return (f"warning: {where}the largest |H| is {peak:.2g} m/N, orders of magnitude from a machine-tool tool "
            f"point's ({lo:g}–{hi:g} m/N): was the file written in {guess}? Files are read in m/N")


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


RISE_SLOPE = -1.0
"""Log–log slope of |H| towards 0 Hz at or below which a receptance is taken to rise like a free mass (f⁻²)."""

RISE_CLIMB = 1.5
"""Factor by which the smoothed |H| must climb again above its running minimum to end the falling low end."""

RISE_MARGIN = 2.0
"""The band starts this factor (one octave) above the valley of a rising low end."""

RISE_SMOOTH = 0.0
"""Lag-1 correlation of the point-to-point residuals above which a rise is smooth (an artefact of the signal
chain: curvature, correlation ≈ +1), not noise ×1/ω² (white noise: −2/3)."""

RISE_NEAR_ZERO = 0.05
"""The rise rule judges only data that start below this share of their last frequency: near 0 Hz, where a grounded
structure shows its static compliance (data that start above a mode fall as f⁻² legitimately)."""


def _rise_edge(frf: FRF, file) -> tuple[int, str]:
    """Index of the first trusted point by the rise rule, and the reason ("" when nothing is cut)."""
    f, h = frf.freq_hz, frf.values
    if frf.quantity != "receptance" or f.size < 3 * WINDOW:
        return 0, ""
    k0 = int(np.searchsorted(f, 0.0, side="right"))  # first point above 0 Hz
    if f[k0] > RISE_NEAR_ZERO * f[-1]:
        return 0, ""  # data far from 0 Hz (above a mode, say) say nothing about the static compliance
    mag = _running_median(np.abs(h[k0:]), WINDOW)
    fk = f[k0:]
    if not np.all(mag > 0):
        return 0, ""
    run_min = np.minimum.accumulate(mag)
    climbed = np.flatnonzero(mag > RISE_CLIMB * run_min)
    end = int(climbed[0]) if climbed.size else mag.size - 1
    v = int(np.argmin(mag[: end + 1]))  # the valley: lowest point before the first climb
    if v < 2:
        return 0, ""
    slope = np.log(mag[v] / mag[0]) / np.log(fk[v] / fk[0])
    if slope > RISE_SLOPE:
        return 0, ""
    n = min(v + 1, 2 * WINDOW)  # where the rise starts: steepest, the artefact (if any) far above the noise
    if _lag1_correlation(fk[:n], h[k0:][:n]) < RISE_SMOOTH and not _sinks_into_noise(fk, h[k0:], end):
        return 0, ""  # a rise made of noise ×1/ω²: the noise rule's to judge
    if not climbed.size:
        raise InputError(f"the receptance rises towards 0 Hz over the whole band (log–log slope {slope:.1f} from "
                         f"{fk[0]:g} to {fk[v]:g} Hz), as an accelerometer offset or drift divided by −ω² does, and "
                         "never levels off: the data cannot tell the structure from the artefact; give the band "
                         "to trust with --band LO:HI", file=file, field="values")
    lo = RISE_MARGIN * fk[v]
    i = int(np.searchsorted(f, lo))
    if i >= f.size - 1:
        raise InputError(f"the receptance rises towards 0 Hz up to {fk[v]:g} Hz (log–log slope {slope:.1f}), too "
                         "close to the end of the data to leave a band; give the band to trust with --band LO:HI",
                         file=file, field="values")
    return i, (f"below {f[i]:g} Hz the receptance rises towards 0 Hz as f^{slope:.1f} (a grounded structure tends "
               "to its static compliance: an offset or drift in the acceleration signal ÷ −ω²)")


def _sinks_into_noise(f: np.ndarray, h: np.ndarray, end: int) -> bool:
    """Whether the falling low end ``[0, end]`` of a rise starts above its noise and then sinks below it: a run of
    :data:`WINDOW` points with Ŝ ≥ :data:`SNR_MIN` · σ̂ (the noise rule's test) followed, before ``end``, by a run of
    :data:`WINDOW` points without.

    Below its first mode a grounded structure's |H| stays near its static compliance while noise white in accelerance
    (×1/ω² in receptance) only falls with f: the signal-to-noise ratio of structure plus such noise grows with f. One
    that is high at the lowest frequencies, drops under the noise and recovers has a third part there, rising towards
    0 Hz faster than the noise: an artefact (offset or drift ÷ −ω²) whose residuals are the noise's at high noise,
    so it does not look smooth. (A free structure's mass line f⁻² and accelerance noise keep a constant ratio.)
    """
    ok = _running_median(np.abs(h), WINDOW) >= SNR_MIN * _noise_sigma(f, h)
    first = _first_run(ok[: end + 1], WINDOW)
    if first is None:
        return False
    return _first_run(~ok[first: end + 1], WINDOW) is not None


def _noise_sigma(f: np.ndarray, h: np.ndarray) -> np.ndarray:
    """σ̂ per point: the running median (:data:`WINDOW`) of the neighbour residual over √(ln 2) (module docstring)."""
    resid = np.concatenate([[np.nan], _neighbour_residual(f, h), [np.nan]])
    resid[0], resid[-1] = resid[1], resid[-2]
    return _running_median(resid, WINDOW) / math.sqrt(math.log(2.0))


def _lag1_correlation(f: np.ndarray, h: np.ndarray) -> float:
    """Correlation of neighbouring point-to-point residuals r_k (see :func:`_neighbour_residual`): ≈ +1 where they
    are the curvature of a smooth FRF, −2/3 where they are white noise."""
    if f.size < 4:
        return 1.0
    h1, h2 = np.diff(f)[:-1], np.diff(f)[1:]
    r = h[1:-1] - (h2 * h[:-2] + h1 * h[2:]) / (h1 + h2)
    r = r / np.maximum(np.abs(h[1:-1]), 1e-300)  # relative: the steep low end does not outweigh the rest
    return float(np.real(np.sum(r[:-1] * np.conj(r[1:]))) / max(np.sum(np.abs(r[:-1]) ** 2), 1e-300))


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
    sigma = _noise_sigma(f, h)
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


def _noise_slope(frf: FRF) -> str:
    """The quantity the noise of ``frf`` looks white in over its whole grid: log–log slope of the point-to-point
    noise estimate against f near −2 → ``"accelerance"``, near −1 → ``"mobility"``, else ``""`` (judged white in
    the receptance itself, or too little noise to tell)."""
    f, h = frf.freq_hz, frf.values
    if f.size < 3 * WINDOW or frf.quantity != "receptance":
        return ""
    h1, h2 = np.diff(f)[:-1], np.diff(f)[1:]
    r = h[1:-1] - (h2 * h[:-2] + h1 * h[2:]) / (h1 + h2)
    resid = np.abs(r) / np.sqrt(1.0 + (h1**2 + h2**2) / (h1 + h2) ** 2)
    # the window, or the widest odd one the lines hold (a soft tip's band of 45–63 lines made np.convolve's "same"
    # return the kernel's length, and the slope a broadcasting error)
    n = min(4 * WINDOW + 1, r.size - 1 - (r.size % 2))
    sigma = _running_median(resid, n) / math.sqrt(math.log(2.0))
    # Noise or curvature? For white noise neighbouring residuals correlate at −2/3; for a smooth FRF's curvature
    # at ≈ +1. Only points where the local lag-1 correlation is clearly negative measure noise.
    c = np.real(r[:-1] * np.conj(r[1:]))
    kernel = np.ones(n) / n
    corr = np.convolve(c, kernel, "same") / np.maximum(np.convolve(np.abs(r[:-1]) ** 2, kernel, "same"), 1e-300)
    fk, sigma = f[1:-2], sigma[:-1]
    ok = (fk > 0) & (sigma > 0) & (corr < -0.3)
    if ok.sum() < MIN_SLOPE_POINTS or fk[ok][-1] < 2 * fk[ok][0]:
        return ""  # less than an octave: the slope says nothing
    slope = np.polyfit(np.log(fk[ok]), np.log(sigma[ok]), 1)[0]
    return "accelerance" if -2.5 <= slope <= -1.5 else ("mobility" if -1.5 < slope <= -0.5 else "")


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
    # the rise rule judges what stands above the noise: a rise made of noise ×1/ω² is the noise rule's
    i_rise, why_rise = _rise_edge(frf if i == 0 else frf.band(f[i], f[-1]), file)
    if i_rise > 0:
        i, reasons = i + i_rise, [why_rise]
    if frf.meta.get("coherence") is not None:
        ic, jc, cwhy = _coherence_edges(frf, coherence_min)
        if cwhy:
            reasons.append(cwhy)
        i, j = max(i, ic), min(j, jc)
    if j - i < 1:
        return TrustedBand(float(f[0]), float(f[-1]), "; ".join(reasons + [
            "the rules leave no band: nothing trimmed, check the data"]), noise_quantity=noise_q)
    if not noise_q and i > 0:
        # a band cut for another reason (the rise, coherence): how the noise grows inside it still tells a fit
        # how to weigh the data
        noise_q = _noise_slope(frf.band(f[i], f[j]))
    return TrustedBand(float(f[i]), float(f[j]), "; ".join(reasons), noise_quantity=noise_q)


#: A point of a measured FRF this many times larger than both its neighbours (an end point: its one neighbour) is a
#: damaged line — a number cut short ("-1.26973" for "-1.26973e-08"), a lost exponent — not a resonance: on a
#: 1 Hz grid even a mode with ζ = 0.01 % at 1 kHz stands ≈ 500× above the points 1 Hz away.
SPIKE_RATIO = 1e4


def check_spikes(frf: FRF, path=None) -> None:
    """Refuse a measured FRF with one point orders of magnitude above its neighbours, naming the frequency."""
    a = np.abs(np.asarray(frf.values).reshape(len(frf), -1)).max(axis=1)
    if a.size < 3:
        return
    left = np.r_[a[1], a[:-1]]  # the end points are compared with their one neighbour
    right = np.r_[a[1:], a[-2]]
    near = np.maximum(left, right)
    bad = np.flatnonzero((near > 0) & (a > SPIKE_RATIO * near))
    if bad.size:
        k = int(bad[0])
        raise InputError(f"the value at {frf.freq_hz[k]:g} Hz is {a[k] / near[k]:.2g}× its neighbours: a damaged or "
                         "cut-short number (e.g. a lost exponent); fix or remove that line", file=path,
                         field="values")


class Band(NamedTuple):
    """One band for several measured FRFs (:func:`common_band`).

    Attributes
    ----------
    lo_hz, hi_hz : float
        The band, Hz: given, or the intersection of the files' trusted bands.
    noise_quantity : str
        The quantity the FRFs' noise looks white in, when every FRF that tells agrees (else ``""``).
    notes : tuple of str
        One line per FRF whose band was trimmed (or the given band's line), for stderr.
    bands : tuple of TrustedBand
        Each FRF's own trusted band.
    """

    lo_hz: float
    hi_hz: float
    noise_quantity: str
    notes: tuple
    bands: tuple

    def cut(self, frf: FRF) -> FRF:
        """``frf`` cut to the smallest run of its own points covering the band (another grid: no extrapolation)."""
        f = frf.freq_hz
        i = max(int(np.searchsorted(f, self.lo_hz, side="right")) - 1, 0)
        j = min(int(np.searchsorted(f, self.hi_hz, side="left")), f.size - 1)
        if i == 0 and j == f.size - 1:
            return frf
        return frf.band(f[i], f[j])


def common_band(frfs, *, band=None, files=None, field: str = "--band", hint: str = "--band LO:HI",
                quantity_measured: str | None = None) -> Band:
    """The one band in which several measured FRFs are used: the entry point of every command.

    Parameters
    ----------
    frfs : sequence of FRF
        Measured SISO FRFs (None entries are skipped).
    band : (float, float), optional
        A band given by the user, Hz: checked against every FRF, no detection.
    files : sequence of str, optional
        Where each FRF came from, for notes and errors (default ``frf.meta["source"]``).
    field, hint : str
        The option that sets the band (named by errors) and the hint in the notes.
    quantity_measured : str, optional
        See :func:`trusted_band`.

    Returns
    -------
    Band

    Raises
    ------
    InputError
        A given band outside an FRF's data, data that cannot decide (a rise towards 0 Hz that never levels off),
        or trusted bands that do not overlap — each naming the file and ``field``.

    Examples
    --------
    >>> import numpy as np
    >>> f = np.arange(1.0, 3001.0)
    >>> h = 1 / (1e7 * (1 - (f / 900) ** 2 + 0.04j * f / 900))
    >>> b = common_band([FRF(f, h), FRF(f, h)], band=(100, 2000), files=["x.csv", "y.csv"])
    >>> b.lo_hz, b.hi_hz, b.notes
    (100.0, 2000.0, ('note: band 100–2000 Hz given by --band (no automatic trimming)',))
    >>> common_band([FRF(f, h)], band=(100, 2000), files=["x.csv"]).notes[0]
    'note: x.csv: band 100–2000 Hz given by --band (no automatic trimming)'
    """
    pairs = [(g, (files[k] if files is not None else None)) for k, g in enumerate(frfs) if g is not None]
    for g, name in pairs:
        if g.is_siso:
            check_spikes(g, name if name is not None else g.meta.get("source"))
    tbs = [trusted_band(g, band=band, file=name, field=field, quantity_measured=quantity_measured)
           for g, name in pairs]
    names = [name if name is not None else g.meta.get("source", "") for g, name in pairs]
    lo, hi = max(tb.lo_hz for tb in tbs), min(tb.hi_hz for tb in tbs)
    if band is not None:  # one line: the file's name when there is one file
        notes = (tbs[0].note(str(names[0] or "") if len(tbs) == 1 else "", hint),)
    else:
        notes = tuple(n for n in (tb.note(str(name or ""), hint) for tb, name in zip(tbs, names)) if n)
    if lo >= hi:
        each = ", ".join(f"{name} {tb.lo_hz:g}–{tb.hi_hz:g} Hz" for tb, name in zip(tbs, names))
        raise InputError(f"the trusted bands of the FRFs do not overlap ({each}): give {hint}",
                         file=names[0], field=field)
    told = {tb.noise_quantity for tb in tbs if tb.noise_quantity}
    notes += tuple(n for n in (unit_note(g.band(lo, hi), str(name or "")) for (g, _), name in zip(pairs, names))
                   if n)
    return Band(float(lo), float(hi), told.pop() if len(told) == 1 else "", notes, tuple(tbs))


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
