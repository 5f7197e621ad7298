r"""How fast a chattering cut's chatter grew: its rate σ (1/s), read from the record.

Just past the stability limit, a regenerative chatter grows as e^{σ t} from whatever kicked it (the entry, the
cutting noise) until the tool leaves the cut and the amplitude saturates; to first order σ = κ ln(a / a_lim), κ the
growth rate of the limiting lobe (:func:`toolpoint.shop.model.growth_rate`, ≈ ζ ω_n of the chattering mode). So a
chattering cut whose record shows σ says how far past the limit it was, σ / κ: the limit from both sides, where the
label alone bounds it from one (:func:`toolpoint.shop.update`'s growth term; ``docs/design/shop.md``, *A chattering
cut's growth rate*).

The reading (:func:`chatter_growth`):

1. the **revolution difference** d(t) = y(t) − y(t − 60/n) removes everything that repeats every revolution — the
   tooth passing and the runout's spindle lines, which a chatter rise would otherwise sit on — and keeps the
   chatter with its growth (|1 − e^{−(σ + iω) P}| is constant in time);
2. band-passed ±B about the chatter frequency (B = 0.4 f_t, within 40–300 Hz and half the chatter frequency: the
   envelope of a rise, not the aliases f_c ± f_t), its **power in windows** of max(2 tooth periods, 1/B);
3. the **rise**: the level L the chatter settles at (the median of the cut's last 30 %, at most its top); the rise
   ends at the first window within e⁻¹ (amplitude) of L after the last one more than e⁻² below it, and starts at
   the quietest window before that, after any transient louder than the rise's foot (a real cut's entry rings and
   decays first);
4. fitted by ln(F + A e^{2 σ t}) (least squares in ln power; F the floor — noise, what the band holds besides
   chatter —, A the chatter at the rise's start); when the rise spans more than 30 windows they are lengthened to
   a thirtieth of it (less scatter per window) and the rise is found again.

Refused (``rate_per_s`` None, with the reason): a rise already done at the cut's start (nothing quiet before it),
a rise in fewer than 5 windows (too fast to read: seen on simulated cuts 60 % past the limit), one that gains less
than 3× in amplitude, a **step** (two levels with one break fit the windows as well as the exponential: the chatter
came at once, a kick or a change of engagement), and one that **accelerates** — a fit with a growing rate,
e^{2 σ t + 2 q t²}, better by far and whose rate at least triples over the rise: a cut whose depth or engagement
grows (a ramp) has no one σ.
What it does not check: a change of engagement just before a rise that is otherwise exponential.

Measured (``benchmarks/bench_growth.py --only estimator``: simulated Cornelius-case cuts a = a_SDM e^x, x 0.03–0.6,
against the SDM's ln ρ / T): see ``docs/design/shop.md``. Fast rises (x ≳ 0.3) read low: saturation bends them
before the windows resolve them, so :func:`toolpoint.shop.update` gives a reading below its prediction a wider
error than one above. Through a phone's automatic gain control (``bench_growth.py --agc``: attack 0.05 s, release
2 s; and 0.5 s, 0.5 s) fewer rises are read — the gain levels the rise's foot, and the reading is refused as "already
there at the cut's start" (25 and 8 of 60 read, against 44 without); those read were 0.94× and 0.98× the SDM's at
the median (ln sd 0.18 and 0.27, against 0.91× and 0.30), the slow control's 95 % point 1.75× (reading further past
the limit: the safe side). So `cut`'s gain-control warning does not stop the reading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ChatterGrowth", "RingDecay", "chatter_growth", "ring_decay"]

_MIN_WINDOWS = 5  # windows in a rise, at least
_MIN_RISE = 2 * math.log(3.0)  # ln power: 3× in amplitude
_MAX_WINDOWS = 30  # a longer rise is read in longer windows
_ACCELERATION = 3.0  # rate at the rise's top over its rate at the start, refused at or above …
_ACCEL_F = 10.0  # … when the accelerating fit's residual improves by this F statistic


@dataclass(frozen=True)
class ChatterGrowth:
    """The growth of a chattering cut's chatter.

    Attributes
    ----------
    rate_per_s : float or None
        σ, 1/s: the amplitude grew as e^{σ t}. None when not read (``reason``).
    start_s, end_s : float or None
        The rise fitted, s (the record's time).
    rise_ln : float or None
        ln of the amplitude's gain over the rise (from the fitted floor's level to its top).
    reason : str or None
        Why the rate was not read.
    """

    rate_per_s: float | None
    start_s: float | None = None
    end_s: float | None = None
    rise_ln: float | None = None
    reason: str | None = None

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        def r(v, n=4):
            return None if v is None else float(round(v, n))
        return {"rate_per_s": r(self.rate_per_s, 3), "start_s": r(self.start_s), "end_s": r(self.end_s),
                "rise_ln": r(self.rise_ln, 2), "reason": self.reason}


def _levels(seg, w, s0, rate):
    m = seg.size // w
    lp = np.log(np.mean(seg[:m * w].reshape(m, w) ** 2, axis=1) + 1e-300)
    return lp, s0 + (np.arange(m) + 0.5) * w / rate


def _rise(lp):
    """(k0, k1) of the rise in the ln powers lp, or (None, reason)."""
    k = 5  # smoothed over 5 windows to find it; fitted on the windows themselves
    sm = np.convolve(np.r_[np.full(k // 2, lp[0]), lp, np.full(k // 2, lp[-1])], np.ones(k) / k, mode="valid")
    top = min(float(np.median(sm[int(0.7 * sm.size):])), float(sm.max()))
    # the last window near the top bounds the search: a dip after it (the exit, the tool leaving the cut) is no foot
    last_up = int(np.flatnonzero(sm >= top - 2.0)[-1])
    below = np.flatnonzero(sm[:last_up] < top - 4.0)
    if below.size == 0:
        return None, "the chatter is already there at the cut's start: its rise is not in the record"
    kb = int(below[-1])
    k1 = kb + int(np.argmax(sm[kb:] >= top - 2.0))
    loud = np.flatnonzero(sm[:kb + 1] > sm[kb] + 2.0)  # a transient (the entry) before the rise's foot
    kp = int(loud[-1]) if loud.size else 0
    k0 = kp + int(np.argmin(sm[kp:kb + 1]))
    if k1 - k0 < _MIN_WINDOWS:
        return None, f"the chatter rose within {k1 - k0} windows: too fast to read"
    return (k0, k1), None


def chatter_growth(samples, rate_hz: float, *, rpm: float, teeth: int, chatter_hz: float, start_s: float,
                   end_s: float) -> ChatterGrowth:
    """σ (1/s) of a chattering cut's rise (module docstring).

    Parameters
    ----------
    samples : array_like, shape (T,)
        The record (any unit).
    rate_hz : float
        Its sampling rate, Hz.
    rpm : float
        Spindle speed, rpm — the measured one (:attr:`CutAnalysis.rpm`): the revolution difference needs it to
        ~0.1 %.
    teeth : int
        Number of teeth.
    chatter_hz : float
        The chatter frequency, Hz.
    start_s, end_s : float
        The cut (entry to exit), s from the record's start.

    Returns
    -------
    ChatterGrowth

    Examples
    --------
    A tone at 1030 Hz growing at 20 /s from under white noise, then saturating, over spindle lines at 6000 rpm:

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> rate = 20000.0
    >>> t = np.arange(int(3 * rate)) / rate
    >>> amp = np.minimum(1e-3 * np.exp(20 * t), 1.0)
    >>> y = amp * np.sin(2 * np.pi * 1030 * t) + np.sin(2 * np.pi * 200 * t) + 0.01 * rng.standard_normal(t.size)
    >>> g = chatter_growth(y, rate, rpm=6000, teeth=2, chatter_hz=1030.0, start_s=0.0, end_s=3.0)
    >>> round(g.rate_per_s, 1)  # within 5 % of 20 /s: the sharp saturation bends the last windows
    20.6
    """
    from scipy.optimize import least_squares
    from scipy.signal import butter, sosfiltfilt

    y = np.asarray(samples, float)
    rate = float(rate_hz)
    P = 60.0 / float(rpm)
    T = P / int(teeth)
    B = min(max(0.4 / T, 40.0), 300.0, 0.5 * float(chatter_hz))
    lo, hi = float(chatter_hz) - B, float(chatter_hz) + B
    if hi >= 0.5 * rate:
        return ChatterGrowth(None, reason="the chatter frequency lies at the record's Nyquist frequency")
    i_a, i_b = max(int(start_s * rate), 0), min(int(math.ceil(end_s * rate)), y.size)
    x = y[i_a:i_b]
    lag = P * rate  # the revolution difference, by linear interpolation of the lagged record
    t = np.arange(x.size, dtype=float)
    d = x - np.interp(t - lag, t, x, left=np.nan)
    s0 = start_s + P + 1.0 / B  # a revolution in (the difference needs one) and the filter's settling
    i0 = int((s0 - start_s) * rate)
    i1 = int((end_s - start_s - 1.0 / B) * rate)
    if i1 - i0 < 8 * 32:
        return ChatterGrowth(None, reason="the cut is too short to read a rise")
    b = sosfiltfilt(butter(4, [lo, hi], btype="band", fs=rate, output="sos"), np.nan_to_num(d[int(lag) + 1:]))
    seg = b[i0 - int(lag) - 1:i1 - int(lag) - 1]
    w = max(int(round(max(2 * T, 1.0 / B) * rate)), 32)
    if seg.size // w < 2 * _MIN_WINDOWS:
        return ChatterGrowth(None, reason="the cut is too short to read a rise")
    lp, tt = _levels(seg, w, s0, rate)
    r, why = _rise(lp)
    if r is not None and (tt[r[1]] - tt[r[0]]) * rate / _MAX_WINDOWS > w:
        w = int((tt[r[1]] - tt[r[0]]) * rate / _MAX_WINDOWS)
        lp, tt = _levels(seg, w, s0, rate)
        r, why = _rise(lp)
    if r is None:
        return ChatterGrowth(None, reason=why)
    k0, k1 = r
    xs, z = tt[k0:k1 + 1] - tt[k0], lp[k0:k1 + 1]
    if z.max() - z.min() < _MIN_RISE:
        return ChatterGrowth(None, reason="the chatter gained less than 3× in amplitude over its rise")
    g0 = max((z[-1] - z[0]) / (2 * xs[-1]), 1.0)
    fit = least_squares(lambda q: np.logaddexp(q[0], q[1] + 2 * q[2] * xs) - z, (z[0], z[0] - 2.0, g0),
                        bounds=([-np.inf, -np.inf, 0.0], [np.inf, np.inf, 1e4]))
    F, A, sigma = (float(v) for v in fit.x)
    n = z.size
    # a step (two levels, one break) that fits as well: the chatter came at once — a kick, a change of engagement —
    # and the exponential's rate is the windows', not the chatter's
    c1, c2 = np.cumsum(z), np.cumsum(z * z)
    j = np.arange(1, n)
    left = c2[j - 1] - c1[j - 1] ** 2 / j
    right = (c2[-1] - c2[j - 1]) - (c1[-1] - c1[j - 1]) ** 2 / (n - j)
    if float(np.min(left + right)) <= float(np.sum(fit.fun ** 2)):
        return ChatterGrowth(None, float(tt[k0]), float(tt[k1]), None,
                             reason="the chatter came at once, a step in its level (a kick, or a change of "
                                    "engagement), not as a growth")
    if n > 6:  # does the rise accelerate (a growing depth or engagement)?
        D = xs[-1]
        acc = least_squares(lambda q: np.logaddexp(q[0], q[1] + 2 * q[2] * xs + 2 * q[3] * xs ** 2) - z,
                            (F, A, sigma, 0.0),
                            bounds=([-np.inf, -np.inf, 0.0, 0.0], [np.inf, np.inf, 1e4, 1e6]))
        s3, s4 = float(np.sum(fit.fun ** 2)), float(np.sum(acc.fun ** 2))
        fstat = (s3 - s4) / max(s4 / (n - 4), 1e-12)
        s_a, q_a = float(acc.x[2]), float(acc.x[3])
        if fstat > _ACCEL_F and s_a + 2 * q_a * D >= _ACCELERATION * max(s_a, 1e-9):
            return ChatterGrowth(None, float(tt[k0]), float(tt[k1]), None,
                                 reason=f"the rise accelerates, its rate from {s_a:.3g} to {s_a + 2 * q_a * D:.3g} /s: "
                                        "a cut whose depth or engagement changes")
    rise = 0.5 * float(np.logaddexp(F, A + 2 * sigma * xs[-1]) - np.logaddexp(F, A))  # ln amplitude over the rise
    return ChatterGrowth(sigma, float(tt[k0]), float(tt[k1]), rise)


@dataclass(frozen=True)
class RingDecay:
    """How fast the line a cut rings at decays: the closed loop's least damped mode, driven by the cutting noise.

    Attributes
    ----------
    rate_per_s : float or None
        σ ≤ 0, 1/s: the line's autocorrelation decays as e^{σ|τ|} (its spectrum a Lorentzian of half-width |σ|/2π Hz).
        None when not read (``reason``).
    ln_sd : float or None
        Standard deviation of ln|σ| from the fit's curvature (Whittle's Fisher information); the reading's scatter
        against the semi-discretisation was larger (``docs/design/shop.md``, *A stable cut's ring*).
    freq_hz : float or None
        The line's centre, Hz.
    resolved : bool
        |σ| ≥ 1/T (T the part read): the line is wider than the record's resolution. An unresolved line is as narrow as
        a steady tone — a chatter's limit cycle, or a ring that decays slower than the record can tell.
    reason : str or None
        Why the rate was not read.
    late_power_ratio : float or None
        The line's power (its bins, the floor subtracted) in the part's second half over that in its first half:
        about 1 for a ring the cutting noise sustains, e^{σT} for a kick (the entry's) that decays over the part.
        None where the rate was not read, or the line stands above the floor in neither half.
    sustained : bool or None
        ``late_power_ratio`` ≥ :data:`SUSTAINED_MIN`: the line rings through the part, as the cutting noise makes it
        ring — not a kick dying away, which any cut's entry gives. None where the ratio was not read.
    peak_to_floor : float or None
        The fitted line's peak over the fitted floor (power ratio): where it is under :data:`RING_MIN_PEAK_DB` the
        "line" is a bump of the record's noise, not a mode ringing (``docs/design/shop.md``, *An entry's kick, or a
        bump of the noise, is no ring*).
    """

    rate_per_s: float | None
    ln_sd: float | None = None
    freq_hz: float | None = None
    resolved: bool = False
    reason: str | None = None
    late_power_ratio: float | None = None
    sustained: bool | None = None
    peak_to_floor: float | None = None

    def to_dict(self) -> dict:
        """JSON-ready dict."""
        def r(v, n=3):
            return None if v is None else float(round(v, n))
        return {"rate_per_s": r(self.rate_per_s, 2), "ln_sd": r(self.ln_sd), "freq_hz": r(self.freq_hz, 2),
                "resolved": bool(self.resolved), "reason": self.reason,
                "late_power_ratio": r(self.late_power_ratio), "sustained": self.sustained,
                "peak_to_floor_db": None if not self.peak_to_floor else r(10 * math.log10(self.peak_to_floor), 1)}


_RING_MIN_S = 0.2  # s of cut, at least, to read a ring
_RING_MAX_S = 8.0  # s: the middle of a longer part is read
_RING_MIN_RATE = 0.3  # 1/s: the fit's lower bound on |σ| (a steady tone reads there)
RING_MIN_PEAK_DB = 10.0
"""The least height of a ring's fitted line over its fitted floor, dB, for the line to be a mode ringing rather than a
bump of the record's noise. Measured (2026-12-01): noise-driven modes (``tests/shop/test_ring.py``'s ``_sdof``, 36
records) 26.6 dB and up; the rings of the benchmark shop's stable cuts with 5 % force noise (two-mode case, 45) 16 dB
and up; "lines" the fit found in pink noise alone (6 of 20 records) 5.2–7.5 dB, and the one EM16-50 whole-loop ring
that turned the precursor on in a shop without force noise 5.4 dB."""
SUSTAINED_MIN = 0.1
"""The least ratio of a ring's power in the second half of the part to that in the first (:class:`RingDecay`'s
``late_power_ratio``) that counts as sustained. A ring the noise drives has ratio 1 in expectation, scattered as an F
ratio with ~2|σ|T/π degrees of freedom a half; a kick decaying at σ over the part has e^{σT}, and a kick the fit
calls resolved (|σ|T ≥ 1 as read) decays far faster than it reads — the Whittle fit assumes a stationary line, and a
tapered transient looks narrower than it is (a kick of −20 /s read −3 to −8 /s). Measured (2026-12-01, the
``_sdof`` records of ``tests/shop/test_ring.py``, 60 seeds each): noise-driven modes over σT = −6 to −83 gave ratios
of 0.088 at the least, 1 of 360 below 0.1 (σT = −5.9); kicks of −20 /s over 1 s 0.000–0.006 in 12 of 12."""


def fast_len_at_most(n: int) -> int:
    """The longest length ≤ ``n`` whose complex FFT is fast (``scipy.fft.next_fast_len``: a product of 2, 3, 5, 7, 11);
    at most 4.3 % shorter for n in 200–20000 (``benchmarks/bench_fft_sizes.py``)."""
    from scipy import fft as sfft

    m = int(n)
    while m > 1 and sfft.next_fast_len(m) != m:
        m -= 1
    return m


def ring_decay(samples, rate_hz: float, *, rpm: float, teeth: int, line_hz: float, start_s: float,
               end_s: float) -> RingDecay:
    r"""σ (1/s, ≤ 0) of the line at ``line_hz`` in a cut: how fast the closed loop's least damped mode forgets a kick.

    Below the stability limit the cutting force's noise keeps the closed loop's modes ringing; the least damped one
    rings with an autocorrelation A e^{σ|τ|} cos 2πf₀τ, σ = ln ρ / T the semi-discretisation's rate (ρ the spectral
    radius per tooth period T) — just under the limit σ ≈ κ ln(a / a_lim), as the growth just past it. A chatter's
    limit cycle is a steady tone: σ ≈ 0 within the record's resolution.

    The reading:

    1. over the part's middle 8 s at most, a whole number of revolutions, the spindle harmonics within 1.5 B of the
       line are removed, each by its projection (sinusoids at k n/60, orthogonal over whole revolutions; B = 0.4 f_t
       within 60–200 Hz and half the line's frequency);
    2. the rest is shifted to baseband about ``line_hz``, low-passed at 2 B and decimated to ~6 B;
    3. its Hann-tapered periodogram is fitted by the **debiased Whittle likelihood** (Sykulski et al. 2019,
       Biometrika 106(2), doi:10.1093/biomet/asy071): the expected periodogram of a Lorentzian line plus a white
       floor, E I(f) = Σ_τ R(τ) c_w(τ) e^{−i2πfτ} (c_w the taper's autocorrelation), exact for the taper's leakage
       however narrow the line; over |f| < B, the bins within 2/T of a removed harmonic left out. L-BFGS-B on the
       likelihood's exact gradient from three starting widths; ``ln_sd`` from the likelihood's curvature.

    Checked against the closed form −ζω_n of a mode driven by white noise (``tests/shop/test_ring.py``: median
    0.84–0.98 of it over 12 seeds, ±1.96 ``ln_sd`` holding it in 10–11 of 12). A line centred on a spindle harmonic
    reads low, its centre's bins left out (a mode at 800 Hz, the 8th harmonic at 6000 rpm: 0.69–0.86 of −25 /s).

    Refused (``rate_per_s`` None): a part shorter than 0.2 s or 20 revolutions, a line at the Nyquist frequency, and a
    fit whose line is wider than a quarter of the band or sits more than a quarter of it from ``line_hz`` (no line
    narrower than the band there).

    Parameters
    ----------
    samples, rate_hz, rpm, teeth
        The record (any unit), its sampling rate (Hz), the measured spindle speed (rpm) and the teeth, as for
        :func:`chatter_growth`.
    line_hz : float
        The line to read, Hz (:attr:`CutSegment.peak_hz`).
    start_s, end_s : float
        The part of the record to read (the cut, without entry and exit), s.

    Returns
    -------
    RingDecay

    Examples
    --------
    A mode at 830 Hz with ζ = 0.5 % (σ = −ζω_n = −26.1 /s) driven by white noise, over spindle lines at 6000 rpm:

    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(1)
    >>> rate, w, z = 20000.0, 2 * np.pi * 830.0, 0.005
    >>> r, th = np.exp(-z * w / rate), w * np.sqrt(1 - z * z) / rate
    >>> y = lfilter([1.0], [1.0, -2 * r * np.cos(th), r * r], rng.standard_normal(int(4 * rate)))
    >>> t = np.arange(y.size) / rate
    >>> y = y / y.std() + 20 * np.sin(2 * np.pi * 100 * t) + 10 * np.sin(2 * np.pi * 800 * t)
    >>> d = ring_decay(y, rate, rpm=6000, teeth=2, line_hz=835.0, start_s=0.0, end_s=4.0)
    >>> round(d.rate_per_s, 1), round(d.ln_sd, 2), d.resolved  # −26.1 /s within its ±1.96 ln sd
    (-22.7, 0.11, True)
    """
    from scipy import fft as sfft  # every nll below is one FFT: NumPy 1.26's (CI's floor) ~3× slower at odd lengths
    from scipy.optimize import minimize
    from scipy.signal import butter, sosfiltfilt

    from ..errors import InputError

    rate = float(rate_hz)
    for v, name in ((rate, "rate_hz"), (float(rpm), "rpm")):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"must be a positive number, got {v:g}", field=name)
    if int(teeth) != teeth or teeth < 1:
        raise InputError(f"must be a whole number ≥ 1, got {teeth}", field="teeth")
    f_s = float(rpm) / 60.0
    f_t = int(teeth) * f_s
    f_p = float(line_hz)
    i_a, i_b = max(int(start_s * rate), 0), min(int(math.ceil(end_s * rate)), len(samples))
    x = np.asarray(samples[i_a:i_b], float)
    T = x.size / rate
    if T < max(_RING_MIN_S, 20.0 / f_s):
        return RingDecay(None, reason=f"the part is {T:.2f} s long: a ring is read over 0.2 s and 20 revolutions")
    B = min(max(0.4 * f_t, 60.0), 200.0, 0.5 * f_p)
    if not B >= 10.0:
        return RingDecay(None, reason=f"the line at {f_p:.3g} Hz is too low to read a ring at")
    if f_p + 2.0 * B >= 0.5 * rate:
        return RingDecay(None, reason="the line lies at the record's Nyquist frequency")
    # the middle 8 s of the part at most, a whole number of revolutions: over it the harmonics' sinusoids are
    # orthogonal, and each is removed by its own projection (an n × 2K least-squares matrix of a long record would
    # not fit in memory)
    n = int(round(math.floor(min(T, _RING_MAX_S) * f_s) / f_s * rate))
    i0 = (x.size - n) // 2
    x = x[i0:i0 + n] - x[i0:i0 + n].mean()
    t = np.arange(n) / rate
    # 1. the periodic part near the line: the spindle harmonics within 1.5 B of it
    k = np.arange(max(1, math.floor((f_p - 1.5 * B) / f_s)), math.ceil((f_p + 1.5 * B) / f_s) + 1)
    fh = k * f_s
    fh = fh[fh < 0.5 * rate]
    for h in fh:
        e = np.exp(2j * np.pi * h * t)
        x = x - np.real((2.0 / n) * np.vdot(e, x) * e)
    # 2. baseband about the line, low-passed and decimated
    z = x * np.exp(-2j * np.pi * f_p * t)
    # at 2 B: flat to 2e-4 over the band fitted (an edge at 1.25 B thinned the line's tails there: σ read 5 % lower on
    # a simulated mode)
    sos = butter(6, 2.0 * B, fs=rate, output="sos")
    z = sosfiltfilt(sos, z.real) + 1j * sosfiltfilt(sos, z.imag)
    q = max(int(rate / (6 * B)), 1)
    rd = rate / q
    edge = int(rd * 2.0 / B)  # the filter's settling at either end
    z = z[::q][edge:-edge]
    # the middle of it at a length whose FFT is fast (a product of 2, 3, 5, 7, 11: at most 4.3 % shorter): every
    # likelihood below is one FFT of it, 4–8× faster than at an awkward length of about the same size (Bluestein's;
    # scipy.fft, 2026-12-01: 192 µs at 4799 samples against 50 µs at 4800, 708 µs at 9601 against 85 µs at 9600;
    # benchmarks/bench_fft_sizes.py)
    m = fast_len_at_most(z.size)
    z = z[(z.size - m) // 2:(z.size - m) // 2 + m]
    Tm = m / rd
    w = np.hanning(m)
    w /= math.sqrt(float(np.sum(w * w)))
    pgram = np.abs(sfft.fft(w * z)) ** 2
    f = np.fft.fftfreq(m, 1.0 / rd)
    cw = np.correlate(w, w, "full")[m - 1:]  # c_w(τ), τ = 0 … m − 1
    tau = np.arange(m) / rd
    use = np.abs(f) < B
    for h in fh:
        use &= np.abs(f + f_p - h) > 2.0 / Tm
    if int(use.sum()) < 8:
        return RingDecay(None, reason=f"too few bins about {f_p:.1f} Hz between the spindle harmonics to fit a line")
    Iu = pgram[use]
    lo_n = math.log(1e-10 * float(Iu.max()))  # a floor held higher would take the line's tails and narrow it
    lo_s, hi_s = math.log(_RING_MIN_RATE), math.log(3.0 * B)

    def clip(p):
        return np.array([p[0], p[1], min(max(p[2], lo_s), hi_s), max(p[3], lo_n)])

    def nll(p):
        lnA, dlt, lns, lnN = clip(p)
        r = math.exp(lnA) * np.exp((-math.exp(lns) + 2j * np.pi * dlt) * tau) * cw
        E = np.maximum(2 * np.real(sfft.fft(r)) - r[0].real, 0.0)[use] + math.exp(lnN)
        return float(np.sum(np.log(E) + Iu / E))

    def nll_grad(p):
        # the likelihood and its gradient: ∂r/∂ln A = r, ∂r/∂δ = i2πτ r, ∂r/∂ln σ = −στ r, the three in one batched FFT
        # (L-BFGS-B: 20–45 of them a start against Nelder–Mead's 270–700, σ the same to 1.3e-4 over 90 noise-driven
        # modes and tones, 5× less CPU; 2026-12-04); the floor is v = N / n0, linear: in ln N the gradient vanishes
        # with the floor, and a wide line's fit stopped on a floor of nothing
        lnA, dlt, lns, v = p
        s = math.exp(lns)
        r = math.exp(lnA) * np.exp((-s + 2j * np.pi * dlt) * tau) * cw
        F = sfft.fft(np.stack((r, (2j * np.pi) * tau * r, -s * tau * r)), axis=-1)[:, use]
        S = 2 * F[0].real - r[0].real
        on = S > 0.0
        E = np.where(on, S, 0.0) + v * n0
        dE = 1.0 / E - Iu / (E * E)  # ∂/∂E of the likelihood's terms
        dS = 2 * F.real
        dS[0] -= r[0].real
        g = np.empty(4)
        g[:3] = dS @ np.where(on, dE, 0.0)
        g[3] = n0 * float(np.sum(dE))
        return float(np.sum(np.log(E) + Iu / E)), g

    n0 = max(float(np.median(Iu)), math.exp(lo_n))  # the floor's scale (v = 1 at the start)
    ipk = int(np.argmax(np.where(use, pgram, 0.0)))
    best = None
    # bounded, so that no step of the quasi-Newton leaves the floats: the line's R(0) within e^±30 of the one that
    # makes the periodogram's peak at the widest line (an unbounded first step overflowed ln A on a shop record)
    ln_a = math.log(float(Iu.max()) * 3.0 * B / rd)
    bounds = [(ln_a - 30.0, ln_a + 30.0), (-B, B), (lo_s, hi_s), (math.exp(lo_n) / n0, 1e6)]
    for s0 in (3.0, 30.0, 300.0):  # a tone, a light ring, a well-damped one
        p0 = [math.log(max(pgram[ipk] - n0, n0) * s0 / (2 * rd)), float(f[ipk]), min(max(math.log(s0), lo_s), hi_s),
              1.0]
        res = minimize(nll_grad, p0, jac=True, method="L-BFGS-B", bounds=bounds)
        if best is None or res.fun < best.fun:
            best = res
    best.x[3] = math.log(best.x[3] * n0)
    p = clip(best.x)
    sig, f0 = math.exp(p[2]), f_p + float(p[1])
    if sig / (2 * np.pi) > B / 4 or abs(f0 - f_p) > B / 4:
        return RingDecay(None, freq_hz=f0, reason=f"no line narrower than the band at {f_p:.1f} Hz (fit: "
                                                  f"{f0:.1f} Hz, {sig:.3g} /s)")
    h = 1e-3  # the curvature in ln σ, the others profiled out (the full Hessian's inverse)
    H = np.zeros((4, 4))
    e = np.eye(4) * h
    for i in range(4):
        for j in range(i, 4):
            H[i, j] = H[j, i] = (nll(p + e[i] + e[j]) - nll(p + e[i] - e[j]) - nll(p - e[i] + e[j])
                                 + nll(p - e[i] - e[j])) / (4 * h * h)
    try:
        v = float(np.linalg.inv(H)[2, 2])
        sd = math.sqrt(v) if v > 0 else None
    except np.linalg.LinAlgError:
        sd = None
    late = _late_power_ratio(z, rd, B, float(p[1]), sig, fh - f_p)
    # the fitted line's peak over the fitted floor (the expected periodogram's, without the floor, at its maximum)
    r_fit = math.exp(p[0]) * np.exp((-sig + 2j * np.pi * float(p[1])) * tau) * cw
    peak = float(np.max(2 * np.real(sfft.fft(r_fit)) - r_fit[0].real))
    return RingDecay(-sig, sd, f0, bool(sig * Tm >= 1.0), late_power_ratio=late,
                     sustained=None if late is None else bool(late >= SUSTAINED_MIN),
                     peak_to_floor=peak / math.exp(p[3]))


def _late_power_ratio(z, rd: float, B: float, d_hz: float, sig: float, harm_hz) -> float | None:
    """The line's power in the second half of the baseband series ``z`` (sampled at ``rd`` Hz, the line at ``d_hz``,
    its half-width σ/2π) over that in the first: each half's Hann periodogram summed over the line's bins (within 3
    half-widths of it, or 3 bins where that is wider), less the floor there (the mean of the bins twice as far or
    more from the line within ±B, away from the spindle harmonics ``harm_hz``). None where neither half holds the
    line above its floor; 0 where the second half does not (a kick that died away); inf where only it does."""
    h = z.size // 2
    if h < 16:
        return None
    f = np.fft.fftfreq(h, 1.0 / rd)
    df = rd / h
    hw = max(3.0 * sig / (2 * np.pi), 3.0 * df)
    away = np.ones(h, bool)
    for fh in np.atleast_1d(harm_hz):
        away &= np.abs(f - fh) > 2.0 * df
    line = (np.abs(f - d_hz) <= hw) & away
    floor = (np.abs(f) < B) & (np.abs(f - d_hz) >= 2.0 * hw) & away
    if int(line.sum()) < 1 or int(floor.sum()) < 8:
        return None
    w = np.hanning(h)
    w /= math.sqrt(float(np.sum(w * w)))
    pw = []
    for zz in (z[:h], z[h:2 * h]):
        ii = np.abs(np.fft.fft(w * zz)) ** 2
        pw.append(float(np.sum(ii[line]) - line.sum() * np.mean(ii[floor])))
    p1, p2 = (max(v, 0.0) for v in pw)
    if p1 <= 0 and p2 <= 0:
        return None
    return math.inf if p1 <= 0 else p2 / p1
