"""Common-pole modal fit of several FRFs of one structure: a denoiser that keeps peaks.

All FRFs of one linear structure share its poles. With n modes in and near the
band, each FRF y_e (e = 1 … m) is modelled as

    y_e(ω) = Σ_r (a_er + iω b_er / ω_r) / (ω_r² − ω² + 2iζ_r ω_r ω)
             + c_e + iω d_e / ω_max − g_e (ω_min / ω)²

with shared natural frequencies f_r = ω_r / 2π (Hz) and damping ratios ζ_r,
and real coefficients per FRF. A complex-conjugate pole pair with a *complex*
residue gives exactly the numerator a + iω b, so non-proportional damping
(bearing dampers) and cross FRFs are represented; c, d and g are the residuals
of modes above and below the band (stiffness, damping, mass lines).

Fit: separable (variable-projection) least squares, as in
:mod:`toolpoint.stability.modalfit`. For given poles the coefficients of all
FRFs follow from one linear least-squares solve with m right-hand sides;
:func:`scipy.optimize.least_squares` moves the poles (f_r, ln ζ_r). Modes
start at the peaks of the summed |y_e|; a mode is then added where the
residual is largest until the Bayesian information criterion stops improving
twice in a row (or the fit reaches ``tol``, noise-free data). Each FRF is
scaled by ``weights`` (default: 1 / its peak magnitude, i.e. noise assumed
proportional to each FRF's level), so the criterion sees comparable noise.

Why: inverse RCSA amplifies measurement noise 100–500× into the spindle–holder
receptance (:mod:`toolpoint.dynamics.inverse_rcsa`). Savitzky–Golay smoothing trades
that noise for rounded peaks (a 100 Hz window cut the sharpest peak of the
synthetic campaign's h to a quarter); fitting the three measured blank FRFs
with common poles first removes the noise without touching the peaks
(``benchmarks/bench_inverse_rcsa.py`` prints the comparison).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import find_peaks
from threadpoolctl import threadpool_limits

__all__ = ["PoleFit", "fit_common_poles"]

_ZETA_MIN, _ZETA_MAX = 1e-5, 0.5


@dataclass(frozen=True)
class PoleFit:
    """A fitted common-pole model; call it with frequencies (Hz) for the (F, m) FRFs.

    fn_hz, zeta : (n,) natural frequencies (Hz) and damping ratios of the shared poles.
    coef : (2n + 3, m) real coefficients per FRF (unscaled, in the FRFs' units).
    w_min, w_max : rad/s, the band edges used to normalise the residual terms.
    fit_error : (m,) relative RMS error ‖fit − y_e‖ / ‖y_e‖ per FRF over the band.
    """

    fn_hz: np.ndarray
    zeta: np.ndarray
    coef: np.ndarray
    w_min: float
    w_max: float
    fit_error: np.ndarray

    @property
    def n_modes(self) -> int:
        return self.fn_hz.size

    def __call__(self, freq_hz) -> np.ndarray:
        w = 2 * np.pi * np.asarray(freq_hz, float).reshape(-1)
        return _basis(w, self.fn_hz, self.zeta, self.w_min, self.w_max) @ self.coef


def _basis(w, fn, zeta, w_min, w_max) -> np.ndarray:
    """Columns of the model, (F, 2n + 3) complex."""
    wn = 2 * np.pi * np.asarray(fn, float)
    wc = w[:, None]
    q = 1.0 / (wn**2 - wc**2 + 2j * zeta * wn * wc)
    one = np.ones((w.size, 1))
    return np.hstack([q, 1j * wc / wn * q, one, 1j * wc / w_max, -((w_min / wc) ** 2)]).astype(complex)


def _solve(D, Y):
    """Real coefficients C minimising ‖D C − Y‖ column by column (complex D, Y)."""
    A = np.vstack([D.real, D.imag])
    s = np.linalg.norm(A, axis=0)
    s[s == 0] = 1.0
    C, *_ = np.linalg.lstsq(A / s, np.vstack([Y.real, Y.imag]), rcond=None)
    return C / s[:, None]


def _fit(w, Y, fn0, z0, fb, w_min, w_max):
    """Poles by least_squares with the Kaufman variable-projection Jacobian.

    For residual r = P⊥ y (P⊥ the projector off the basis columns A), Kaufman's
    approximation of ∂r/∂p_k is −P⊥ (∂A/∂p_k) c; only the two columns of mode r
    depend on its (f_r, ln ζ_r), so the Jacobian costs one QR and O(F n m).
    """
    n, F, m = fn0.size, w.size, Y.shape[1]
    B = np.vstack([Y.real, Y.imag])
    wc = w[:, None]
    cache = {}

    def both(p):
        key = p.tobytes()
        if key in cache:
            return cache[key]
        wn, ze = 2 * np.pi * p[:n], np.exp(p[n:])
        D = _basis(w, p[:n], ze, w_min, w_max)
        A = np.vstack([D.real, D.imag])
        s = np.linalg.norm(A, axis=0)
        s[s == 0] = 1.0
        Q, Rt = np.linalg.qr(A / s)
        C = np.linalg.lstsq(Rt, Q.T @ B, rcond=None)[0] / s[:, None]
        res = A @ C - B
        q = D[:, :n]
        dQ_dwn = 2 * wn + 2j * ze * wc
        dQ_du = 2j * ze * wn * wc
        dq_dwn, dq_du = -(q**2) * dQ_dwn, -(q**2) * dQ_du
        iw = 1j * wc / wn
        d2_dwn = iw * (dq_dwn - q / wn)
        d2_du = iw * dq_du
        c1, c2 = C[:n][None], C[n:2 * n][None]  # (1, n, m)
        Vf = 2 * np.pi * (dq_dwn[:, :, None] * c1 + d2_dwn[:, :, None] * c2)  # per Hz
        Vu = dq_du[:, :, None] * c1 + d2_du[:, :, None] * c2
        V = np.concatenate([Vf, Vu], 1)  # (F, 2n, m)
        V = np.concatenate([V.real, V.imag], 0).reshape(2 * F, 2 * n * m)
        V = (V - Q @ (Q.T @ V)).reshape(2 * F, 2 * n, m)
        J = V.transpose(0, 2, 1).reshape(2 * F * m, 2 * n)
        cache.clear()
        cache[key] = (res.ravel(), J)
        return cache[key]

    lo = np.r_[np.full(n, fb[0]), np.full(n, np.log(_ZETA_MIN))]
    hi = np.r_[np.full(n, fb[1]), np.full(n, np.log(_ZETA_MAX))]
    x0 = np.clip(np.r_[fn0, np.log(z0)], lo + 1e-9 * abs(lo), hi - 1e-9 * abs(hi))
    sol = least_squares(lambda p: both(p)[0], x0, jac=lambda p: both(p)[1], bounds=(lo, hi),
                        x_scale=np.r_[np.maximum(fn0 * z0, 1e-2), np.ones(n)],
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=50 * (n + 1))
    return sol.x[:n], np.exp(sol.x[n:])


def fit_common_poles(freq_hz, Y, *, weights=None, max_modes: int = 16, tol: float = 1e-9,
                     patience: int = 2) -> PoleFit:
    """Fit the common-pole model to the columns of ``Y`` (F, m), FRFs on ``freq_hz`` (Hz).

    ``weights`` (m,): each FRF is multiplied by its weight before fitting
    (default 1 / max |y_e|). Stops at ``max_modes``, at a relative RMS error
    below ``tol``, or when the BIC has not improved for ``patience`` added modes;
    returns the fit with the lowest BIC.
    """
    # Tall-skinny products and SVDs: BLAS threads only add overhead (6× slower measured on 2 cores).
    with threadpool_limits(1, user_api="blas"):
        return _fit_common_poles(freq_hz, Y, weights, max_modes, tol, patience)


def _fit_common_poles(freq_hz, Y, weights, max_modes, tol, patience) -> PoleFit:
    f = np.asarray(freq_hz, float).reshape(-1)
    Y = np.asarray(Y, complex)
    Y = Y.reshape(f.size, -1)
    if f.size < 10 or np.any(np.diff(f) <= 0) or f[0] <= 0:
        raise ValueError("need ≥ 10 increasing frequencies > 0 Hz")
    if not np.all(np.isfinite(Y)) or np.any(np.abs(Y).max(0) == 0):
        raise ValueError("every FRF must be finite and not all zero")
    wt = 1.0 / np.abs(Y).max(0) if weights is None else np.asarray(weights, float).reshape(-1)
    Yw = Y * wt
    w = 2 * np.pi * f
    w_min, w_max = float(w[0]), float(w[-1])
    fb = (0.5 * f[0], 1.5 * f[-1])
    N = 2 * Yw.size
    norm = float(np.sum(np.abs(Yw) ** 2))

    mag = np.sqrt((np.abs(Yw) ** 2).sum(1))
    pk, _ = find_peaks(mag, prominence=0.05 * mag.max())
    fn, ze = f[pk][:max_modes].astype(float), np.full(min(pk.size, max_modes), 0.02)
    best, since = None, 0
    while True:
        if fn.size:
            fn, ze = _fit(w, Yw, fn, ze, fb, w_min, w_max)
        D = _basis(w, fn, ze, w_min, w_max)
        C = _solve(D, Yw)
        r = D @ C - Yw
        rss = float(np.sum(np.abs(r) ** 2))
        bic = N * np.log(max(rss, 1e-300) / N) + (2 * fn.size + C.size) * np.log(N)
        if best is None or bic < best[0]:
            best, since = (bic, fn, ze, C), 0
        else:
            since += 1
        if fn.size >= max_modes or rss <= tol**2 * norm or since >= patience:
            break
        # the next mode where the (lightly smoothed) residual is largest
        j = int(np.argmax(np.convolve(np.sqrt((np.abs(r) ** 2).sum(1)), np.ones(5) / 5, "same")))
        fn, ze = np.r_[fn, f[j]], np.r_[ze, 0.02]
    _, fn, ze, C = best
    coef = C / wt
    fit = _basis(w, fn, ze, w_min, w_max) @ coef
    err = np.linalg.norm(fit - Y, axis=0) / np.linalg.norm(Y, axis=0)
    order = np.argsort(fn)
    n = fn.size
    idx = np.r_[order, n + order, 2 * n + np.arange(3)]
    return PoleFit(fn[order], ze[order], coef[idx], w_min, w_max, err)
