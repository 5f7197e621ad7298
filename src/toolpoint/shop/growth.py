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

__all__ = ["ChatterGrowth", "chatter_growth"]

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
