r"""The uncertain forward model of test cuts: modal parameters and K_t → stability limit and chatter frequency.

A symmetric tool (Φ_xx = Φ_yy = Φ, no cross terms) with M real modes,

    Φ(f) = Σ_m 1 / (k_m (1 − r_m² + 2 i ζ_m r_m)),  r_m = f / f_m   (m/N),

cut as :class:`~toolpoint.stability.CuttingConditions` says. Every uncertain parameter is log-normal:
ln θ = ln θ̃ + σ z, z ~ N(0, 1) (θ̃ the median, σ the log standard deviation, about the coefficient of
variation for σ ≲ 0.3). The parameters: f_m (Hz), k_m (N/m), ζ_m per mode, K_t (N/m²) and K_r.

The zero-order limit (Altintas & Budak 1995) at *one* speed n comes from the lobe crossings: with
μ_b(f) = λ_b Φ(f) (λ_b the eigenvalues of the average directional matrix, which holds K_t and K_r),
a lobe k passes n where g(f) = 60 f / (N n) − ε(f)/2π equals the integer k, ε = π + 2 arg(−μ), and there
the limit is a = 1 / (−2 Re μ). The limit at n is the smallest over all crossings (f, b, k), and the
chatter frequency is that crossing's f. :func:`limit_at_speeds` evaluates this for many samples at a
few speeds (the test cuts) — the same formulas as :mod:`toolpoint.stability.zoa_batch` (which gives the
limit on a whole speed grid); the tests compare the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from ..stability.cutting import CuttingConditions
from ..stability.milling import average_directional_matrix

__all__ = ["ModalPrior", "Samples", "limit_at_speeds", "floor_limit", "growth_rate", "sdm_limits", "receptance",
           "cornelius_2024", "example_tool"]


@dataclass(frozen=True)
class ModalPrior:
    """Log-normal prior of a symmetric M-mode tool and its cutting coefficients.

    Attributes
    ----------
    freq_hz, stiffness_n_m, damping : tuple of float
        Medians per mode: natural frequency (Hz), modal stiffness (N/m), damping ratio.
    sigma_freq, sigma_stiffness, sigma_damping : tuple of float
        Log standard deviations per mode (≈ coefficients of variation).
    cutting : CuttingConditions
        The cut; its K_t and K_r are the medians.
    sigma_kt, sigma_kr : float
        Log standard deviations of K_t and K_r.
    name : str
        For reports.
    rpm_range : (float, float) or None
        The machine's speed range, rpm (default: lobes k = 0…5 of the modes).
    """

    freq_hz: tuple
    stiffness_n_m: tuple
    damping: tuple
    sigma_freq: tuple
    sigma_stiffness: tuple
    sigma_damping: tuple
    cutting: CuttingConditions
    sigma_kt: float = 0.1
    sigma_kr: float = 0.05
    name: str = "tool"
    rpm_range: tuple | None = None

    def __post_init__(self):
        m = len(self.freq_hz)
        for nm in ("stiffness_n_m", "damping", "sigma_freq", "sigma_stiffness", "sigma_damping"):
            if len(getattr(self, nm)) != m:
                raise InputError(f"needs {m} values (one per mode), got {len(getattr(self, nm))}", field=nm)
        for nm in ("freq_hz", "stiffness_n_m", "damping"):
            v = np.asarray(getattr(self, nm), float)
            if not np.all(np.isfinite(v) & (v > 0)):
                raise InputError(f"must be finite and > 0, got {list(v)}", field=nm)
        if not np.all(np.asarray(self.damping) < 1):
            raise InputError(f"damping ratios must be < 1, got {list(self.damping)}", field="damping")
        sig = np.r_[self.sigma_freq, self.sigma_stiffness, self.sigma_damping, self.sigma_kt, self.sigma_kr]
        if not np.all(np.isfinite(sig) & (sig >= 0) & (sig <= 2)):
            raise InputError("log standard deviations must be in [0, 2]", field="sigma")
        if self.rpm_range is not None:
            lo, hi = self.rpm_range
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi <= 200_000):
                raise InputError(f"must be 0 < min < max ≤ 200000 rpm, got {self.rpm_range}", field="rpm_range")

    @property
    def modes(self) -> int:
        """Number of modes M."""
        return len(self.freq_hz)

    @property
    def names(self) -> list:
        """Parameter names in the order of :attr:`Samples.theta`'s columns."""
        m = range(1, self.modes + 1)
        return ([f"f{i}_hz" for i in m] + [f"k{i}_n_m" for i in m] + [f"zeta{i}" for i in m]
                + ["kt_n_m2", "kr"])

    @property
    def log_median(self) -> np.ndarray:
        """ln of the medians, shape (3M + 2,)."""
        c = self.cutting
        return np.log(np.r_[self.freq_hz, self.stiffness_n_m, self.damping, c.tangential_coeff, c.radial_ratio])

    @property
    def sigma(self) -> np.ndarray:
        """Log standard deviations, shape (3M + 2,)."""
        return np.r_[self.sigma_freq, self.sigma_stiffness, self.sigma_damping, self.sigma_kt, self.sigma_kr]

    def theta(self, z) -> np.ndarray:
        """Parameters (S, 3M + 2) from standard normal z (S, 3M + 2); a zero σ holds its median."""
        return np.exp(self.log_median + np.asarray(z) * self.sigma)

    def sample(self, n: int, rng: np.random.Generator) -> "Samples":
        """``n`` prior samples."""
        z = rng.standard_normal((n, self.sigma.size))
        return Samples(self, z)

    def with_median(self, theta) -> "ModalPrior":
        """The same prior centred on ``theta`` (e.g. a truth drawn from it, for a virtual campaign)."""
        m = self.modes
        t = np.asarray(theta, float)
        cut = replace(self.cutting, tangential_coeff=float(t[3 * m]), radial_ratio=float(t[3 * m + 1]))
        return replace(self, freq_hz=tuple(t[:m]), stiffness_n_m=tuple(t[m:2 * m]), damping=tuple(t[2 * m:3 * m]),
                       cutting=cut)

    def tool(self, theta):
        """(ModalModel, CuttingConditions) of one parameter vector θ: the same M modes in x and y (modal mass
        k/(2π f)²) and the cut with θ's K_t and K_r — the input of the SDM and the time-domain simulation."""
        from ..stability import ModalModel

        m = self.modes
        t = np.asarray(theta, float)
        cut = replace(self.cutting, tangential_coeff=float(t[3 * m]), radial_ratio=float(t[3 * m + 1]))
        return ModalModel(t[:m], t[2 * m:3 * m], t[m:2 * m] / (2 * np.pi * t[:m]) ** 2), cut

    def freq_grid(self) -> np.ndarray:
        """Frequencies (Hz): 400 points over the modes' ±4σ range (×0.5 … ×1.6), and around each mode ≥ 16
        points per half-power band over its own ±4σ range (lightly damped modes need them, the rest does not)."""
        f = np.asarray(self.freq_hz)
        s = np.asarray(self.sigma_freq)
        z = np.asarray(self.damping) * np.exp(-4 * np.asarray(self.sigma_damping))
        lo, hi = float(np.min(f * np.exp(-4 * s))) * 0.5, float(np.max(f * np.exp(4 * s))) * 1.6
        parts = [np.linspace(lo, hi, 400)]
        for fm, sm, zm in zip(f, s, z):
            a, b = fm * np.exp(-4 * sm) * (1 - 4 * zm), fm * np.exp(4 * sm) * (1 + 4 * zm)
            step = max(0.05, 2 * zm * a / 16)
            parts.append(np.arange(a, b, step))
        return np.unique(np.round(np.concatenate(parts), 6))


@dataclass(frozen=True)
class Samples:
    """Samples of a :class:`ModalPrior` in its standard-normal coordinates z (S, 3M + 2)."""

    prior: ModalPrior
    z: np.ndarray

    @property
    def theta(self) -> np.ndarray:
        """The parameters, (S, 3M + 2), SI."""
        return self.prior.theta(self.z)


def receptance(prior: ModalPrior, theta, freq_hz) -> np.ndarray:
    """Φ(f) of each parameter row: (S, F) complex, m/N."""
    m = prior.modes
    t = np.atleast_2d(theta)
    f = np.asarray(freq_hz, float)
    # 1 / (k (d + i e)) = (d − i e) / (k (d² + e²)), d = 1 − r², e = 2ζr: in real arithmetic, the same to
    # rounding and 1.8× faster than NumPy's complex division (0.128 → 0.070 s CPU, 500 samples × 3 modes × 1919
    # frequencies, 2026-11-26). Mode by mode, added in the order NumPy's sum over the modes' axis adds them: the
    # same bits, without (S, M, F) temporaries (CPU, 100 example-tool samples × 3 modes × 1919 frequencies: 6.1–7.3 →
    # 3.3–3.8 ms; limit_at_speeds of 500 of them at 4 speeds 167–178 → 154–155 ms; 2026-12-07)
    re = im = 0.0  # no modes: no response (as the sum over an empty axis; broadcast below)
    for j in range(m):
        r = f[None, :] / t[:, j, None]
        d = 1.0 - r * r
        e = 2.0 * t[:, 2 * m + j, None] * r
        g = 1.0 / (t[:, m + j, None] * (d * d + e * e))
        if j == 0:
            re, im = d * g, e * g
        else:
            re += d * g
            im += e * g
    out = np.empty((t.shape[0], f.size), complex)
    out.real = re
    out.imag = -im
    return out


def _eigs(prior: ModalPrior, theta) -> np.ndarray:
    """λ_b per sample (S, 2): eigenvalues of the average directional matrix with that sample's K_t, K_r."""
    c = prior.cutting
    phi_st, phi_ex = c.immersion_angles
    m = prior.modes
    t = np.atleast_2d(theta)
    kt, kr = t[:, 3 * m], t[:, 3 * m + 1]
    # H0 is linear in K_t and affine in K_r: H0 = K_t (A + K_r B)
    a0 = average_directional_matrix(c.teeth, 1.0, 0.0, phi_st, phi_ex)
    b0 = average_directional_matrix(c.teeth, 1.0, 1.0, phi_st, phi_ex) - a0
    h = kt[:, None, None] * (a0[None] + kr[:, None, None] * b0[None])
    tr = h[:, 0, 0] + h[:, 1, 1]
    det = h[:, 0, 0] * h[:, 1, 1] - h[:, 0, 1] * h[:, 1, 0]
    root = np.sqrt((tr * tr / 4 - det).astype(complex))
    return np.stack([tr / 2 + root, tr / 2 - root], axis=1)


def limit_at_speeds(prior: ModalPrior, theta, rpm, freq_hz=None, *, floor: bool = False) -> tuple:
    """Zero-order limit (m) and chatter frequency (Hz) of each sample at each speed.

    Parameters
    ----------
    prior : ModalPrior
    theta : array_like, shape (S, 3M + 2)
    rpm : array_like, shape (R,)
    freq_hz : array_like, optional
        Frequency grid (default :meth:`ModalPrior.freq_grid`).
    floor : bool, default False
        Also return each sample's lobes' floor (:func:`floor_limit`), from the same pass over the grid.

    Returns
    -------
    limit_m, chatter_hz : ndarray, shape (S, R)
        inf / nan where no lobe reaches the speed within the grid.
    floor_m : ndarray, shape (S,)
        With ``floor``: :func:`floor_limit`'s.

    Examples
    --------
    One mode at the prior's median, compared with :func:`~toolpoint.stability.zoa_batch.zoa_limits` (a second
    method: lobe pieces interpolated over the tooth period) at the same speeds:

    >>> import numpy as np
    >>> from toolpoint.stability import CuttingConditions
    >>> from toolpoint.stability.zoa_batch import zoa_limits
    >>> cut = CuttingConditions(teeth=3, tangential_coeff=7e8, radial_ratio=0.3, radial_immersion=0.5)
    >>> pr = ModalPrior((900.0,), (5e6,), (0.03,), (0.0,), (0.0,), (0.0,), cut, 0.0, 0.0)
    >>> f = pr.freq_grid()
    >>> rpm = np.array([9000.0, 12000.0, 15000.0])
    >>> a, fc = limit_at_speeds(pr, pr.theta(np.zeros((1, 5))), rpm, f)
    >>> ref = zoa_limits(f, receptance(pr, pr.theta(np.zeros((1, 5))), f)[0], cut, rpm, subdivide=16)
    >>> bool(np.all(np.abs(a[0] / ref - 1) < 2e-3))
    True
    """
    t = np.atleast_2d(np.asarray(theta, float))
    f = prior.freq_grid() if freq_hz is None else np.asarray(freq_hz, float)
    n = np.atleast_1d(np.asarray(rpm, float))
    # In blocks of samples whose (S, 2, F) temporaries stay in cache (~1–2 MB each), not one pass over all: the
    # same bits, 0.174 → 0.106 s CPU per call (best of 15) on 1000 EM16-50 samples at four speeds (blocks of 100;
    # 2026-12-02).
    parts = [_limit_block(prior, t[i: i + _BLOCK], n, f) for i in range(0, t.shape[0], _BLOCK)]
    return tuple(np.concatenate([p[k] for p in parts]) for k in range(3 if floor else 2))


_BLOCK = 100  # samples per block of limit_at_speeds


def _mu(prior: ModalPrior, t, f) -> np.ndarray:
    """μ_b(f) = λ_b Φ(f) of each sample, (S, 2, F)."""
    return _eigs(prior, t)[:, :, None] * receptance(prior, t, f)[:, None, :]


def _floor(q) -> np.ndarray:
    """The least limit 1 / max q of each sample (S,) from q = −2 Re μ (S, 2, F); inf where q ≤ 0 everywhere."""
    qmax = q.max(axis=(1, 2))
    with np.errstate(divide="ignore"):
        return np.where(qmax > 0, 1.0 / np.where(qmax > 0, qmax, 1.0), np.inf)


def _limit_block(prior: ModalPrior, t, n, f) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`limit_at_speeds` of one block of samples t (S, 3M + 2) at speeds n (R,), grid f (F,), and the floor."""
    mu = _mu(prior, t, f)  # (S, 2, F)
    q = -2.0 * mu.real  # 1/a, valid where > 0
    N = prior.cutting.teeth
    S, R = t.shape[0], n.size
    best_q = np.zeros((S, R))
    best_f = np.full((S, R), np.nan)
    # Only segments with Re μ < 0 at both ends can hold a lobe (frac wraps only where Re μ > 0): 43–61 % of the
    # (sample, branch, frequency) points on the benchmark priors. Their ends are gathered once, so each speed
    # costs a few passes over those segments, and only the crossings (a few per lobe) are interpolated
    # (`bench_shop.py --only forward`: 0.18 → 0.12 s and 0.48 → 0.26 s per call, 2026-11-26).
    F = f.size
    seg = np.flatnonzero((q[..., :-1] > 0) & (q[..., 1:] > 0))  # (S, 2, F − 1) order: by sample
    s_i, f_i = seg // (2 * (F - 1)), seg % (F - 1)
    p0 = seg + seg // (F - 1)  # the segment's first point in the (S, 2, F) order
    q0, q1 = q.ravel()[p0], q.ravel()[p0 + 1]
    # The phase fraction only at the points with q > 0, which hold every segment's ends (the arctangent was a third
    # of a block's CPU over all points; elementwise, so the same bits: EM12-60 update after 6 cuts, 2026-12-02)
    pos = (q > 0).ravel()
    at = np.cumsum(pos) - 1  # the position of each point with q > 0 among them
    mp = mu.ravel()[pos]
    frac = (np.pi + 2 * np.arctan2(-mp.imag, -mp.real)) / (2 * np.pi)
    h0, h1 = frac[at[p0]], frac[at[p0 + 1]]
    f0, f1 = f[f_i], f[f_i + 1]
    e0, e1 = 60.0 * f0, 60.0 * f1  # hoisted out of the speeds' loop: the same expression, the same bits
    for r in range(R):  # a few test speeds; vectorised over samples, branches, frequencies
        g0, g1 = e0 / (N * n[r]) - h0, e1 / (N * n[r]) - h1  # the full grid's expression: same bits
        k0, k1 = np.floor(g0), np.floor(g1)
        x = np.flatnonzero(k0 != k1)
        if x.size == 0:
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.clip((np.maximum(k0[x], k1[x]) - g0[x]) / (g1[x] - g0[x]), 0, 1)
        qc = q0[x] + w * (q1[x] - q0[x])
        fc = f0[x] + w * (f1[x] - f0[x])
        sx = s_i[x]
        o = np.lexsort((qc, sx))  # by sample, then q: the last of each sample's run is its largest crossing
        last = o[np.r_[sx[o][1:] != sx[o][:-1], True]]
        best_q[sx[last], r] = qc[last]
        best_f[sx[last], r] = np.where(qc[last] > 0, fc[last], np.nan)
    with np.errstate(divide="ignore"):
        limit = np.where(best_q > 0, 1.0 / np.where(best_q > 0, best_q, 1.0), np.inf)
    return limit, best_f, _floor(q)


def floor_limit(prior: ModalPrior, theta, freq_hz=None) -> np.ndarray:
    """The zero-order lobes' floor of each sample, m (S,): the least limit over all speeds,
    a_min = 1 / max_{b, f} (−2 Re λ_b Φ(f)) (Altintas & Budak 1995: every lobe's minimum touches it); inf where Re
    λ_b Φ ≥ 0 everywhere on the grid (no lobe).

    Examples
    --------
    One mode: the floor is the least of the limits on a fine speed grid, as :func:`limit_at_speeds` finds them
    (within the grid's reach of the lobes' minima):

    >>> import numpy as np
    >>> from toolpoint.stability import CuttingConditions
    >>> cut = CuttingConditions(teeth=3, tangential_coeff=7e8, radial_ratio=0.3, radial_immersion=0.5)
    >>> pr = ModalPrior((900.0,), (5e6,), (0.03,), (0.0,), (0.0,), (0.0,), cut, 0.0, 0.0)
    >>> th = pr.theta(np.zeros((1, 5)))
    >>> a, _ = limit_at_speeds(pr, th, np.linspace(6000.0, 20000.0, 4000))
    >>> bool(abs(a.min() / floor_limit(pr, th)[0] - 1) < 2e-3)
    True
    """
    t = np.atleast_2d(np.asarray(theta, float))
    f = prior.freq_grid() if freq_hz is None else np.asarray(freq_hz, float)
    # blocks, as limit_at_speeds: the (S, 2, F) temporaries stay small
    return np.concatenate([_floor(-2.0 * _mu(prior, t[i: i + _BLOCK], f).real) for i in range(0, t.shape[0], _BLOCK)])


def growth_rate(prior: ModalPrior, theta, rpm, chatter_hz) -> np.ndarray:
    r"""How fast chatter grows just past the zero-order limit: κ = Re ∂s/∂ln a at the limit (1/s).

    The zero-order characteristic equation of a symmetric tool, per eigenvalue λ_b of the average directional
    matrix, is 1 + a c λ_b G(s) = 0 with G(s) = (1 − e^{−sT}) Φ(s) (T the tooth period, Φ(s) = Σ_m ω_m² /
    (k_m (s² + 2ζ_m ω_m s + ω_m²))). At the limit a root sits at s = iω_c; implicit differentiation gives

        ∂s/∂ln a = −G(s) / G'(s) = −1 / (T e^{−sT} / (1 − e^{−sT}) + Φ'(s) / Φ(s)),

    so a cut at a = a_lim e^x grows chatter as e^{κ x t} over t seconds (x small). For one mode away from the
    tooth-passing harmonics κ ≈ ζ ω_n: a lightly damped mode chatters slowly just past its limit (a campaign
    tool's 750 Hz mode with ζ = 0.4 %: κ ≈ 30 /s, so 10 % past the limit chatter grows by e^3 in 1 s; the
    Cornelius case: κ ≈ 350–650 /s). Checked against the semi-discretisation's spectral radius ρ per tooth
    period (ln ρ / (T x) at x = ln 1.05) in ``tests/shop/test_shop_update.py``.

    Parameters
    ----------
    prior : ModalPrior
    theta : array_like, shape (S, 3M + 2)
    rpm : array_like, shape (R,)
    chatter_hz : array_like, shape (S, R)
        The limiting lobe's chatter frequency (:func:`limit_at_speeds`); nan where no lobe reaches the speed.

    Returns
    -------
    ndarray, shape (S, R)
        κ, 1/s; nan where ``chatter_hz`` is nan.
    """
    t = np.atleast_2d(np.asarray(theta, float))
    m = prior.modes
    n = np.atleast_1d(np.asarray(rpm, float))
    fc = np.asarray(chatter_hz, float)
    s = 2j * np.pi * fc  # (S, R)
    T = 60.0 / (n * prior.cutting.teeth)  # (R,)
    wn = 2 * np.pi * t[:, None, :m]  # (S, 1, M)
    k, z = t[:, None, m:2 * m], t[:, None, 2 * m:3 * m]
    sm = s[..., None]
    den = sm * sm + 2 * z * wn * sm + wn * wn
    phi = np.sum(wn * wn / (k * den), axis=-1)
    dphi = -np.sum(wn * wn * (2 * sm + 2 * z * wn) / (k * den * den), axis=-1)
    e = np.exp(-s * T[None, :])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.real(-1.0 / (T[None, :] * e / (1 - e) + dphi / phi))


def sdm_limits(prior: ModalPrior, theta, rpm, *, chatter: bool = True):
    """Semi-discretisation limit (m) and chatter frequency (Hz) of one θ at increasing speeds.

    :func:`~toolpoint.stability.sdm_lobes` with its default depth range, which is widened where the pockets go
    deeper than 100 × the zero-order minimum (a campaign tool, EM28-80: one 654 Hz mode, 25 % immersion, up
    milling — 35–52 mm at 9540–9890 rpm against a minimum of 0.34 mm, where the simulated cut chatters at
    47 mm). ``inf`` only for speeds stable at 10⁴ × the minimum.

    Parameters
    ----------
    prior : ModalPrior
    theta : array_like, shape (3M + 2,)
    rpm : array_like, shape (R,)
        Increasing speeds, rpm.
    chatter : bool, default True
        ``False``: the limits only (chatter frequencies ``nan``), a sixth to a third faster.

    Returns
    -------
    limit_m, chatter_hz : ndarray, shape (R,)
    """
    from ..stability import sdm_lobes

    mm, cut = prior.tool(np.asarray(theta, float))
    res = sdm_lobes(mm, mm, cut, rpm=np.asarray(rpm, float), chatter=chatter)
    return res.depth_m, res.chatter_hz


def example_tool(sigma: float = 0.15) -> ModalPrior:
    """A toolpoint tool: the three strongest modes of the tool-point FRF of ``examples/numerical_case.toml``
    (2213 Hz, 9.02e6 N/m, ζ 0.99 %; 776 Hz, 2.84e7 N/m, ζ 0.55 %; 1908 Hz, 1.96e7 N/m, ζ 2.68 %, peak-picked by
    :func:`toolpoint.shop.prior.modes_from_frf`), 3 teeth, K_t 700 N/mm², K_r 0.3, 50 % immersion, climb, speeds
    5000–30000 rpm; log standard deviations: ``sigma`` on stiffness, damping and K_t, 0.03 on frequency."""
    cut = CuttingConditions(teeth=3, tangential_coeff=700e6, radial_ratio=0.3, radial_immersion=0.5, milling="down")
    return ModalPrior((2213.0, 776.0, 1908.0), (9.02e6, 2.84e7, 1.96e7), (0.0099, 0.0055, 0.0268), (0.03,) * 3,
                      (sigma,) * 3, (sigma,) * 3, cut, sigma_kt=sigma, sigma_kr=0.05,
                      name="toolpoint example tool (numerical_case.toml)", rpm_range=(5000.0, 30000.0))


def cornelius_2024(sigma: float = 0.1) -> ModalPrior:
    """The two-mode numerical case like Cornelius, Karandikar, Tyler & Schmitz 2024 (modes 1243 Hz, 2.92e6 N/m,
    ζ 6.19 % and 1747 Hz, 1.2e7 N/m, ζ 2.88 %; K_t 2003 N/mm², K_r/K_t 0.404; 4 teeth, 50 % immersion, climb),
    with log standard deviations ``sigma`` on stiffness and damping, sigma/4 on frequency, sigma on K_t; speeds
    5000–25000 rpm."""
    cut = CuttingConditions(teeth=4, tangential_coeff=2003e6, radial_ratio=0.404, radial_immersion=0.5,
                            milling="down")
    return ModalPrior((1243.0, 1747.0), (2.92e6, 1.2e7), (0.0619, 0.0288), (sigma / 4,) * 2, (sigma,) * 2,
                      (sigma,) * 2, cut, sigma_kt=sigma, sigma_kr=sigma / 4, name="Cornelius 2024 two-mode case",
                      rpm_range=(5000.0, 25000.0))
