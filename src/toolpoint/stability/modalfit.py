"""Modal fit of a receptance FRF, so measured or predicted FRFs can feed the
semi-discretisation.

Model (real modes, the usual case for a tool-point driving-point FRF):

    Φ(ω) = Σ_r 1 / ( m_r (ω_r² − ω² + 2iζ_r ω_r ω) )  +  R_u  −  R_l / ω²    (m/N)

with, per mode, natural frequency f_r = ω_r/2π (Hz), damping ratio ζ_r and
modal mass m_r (kg; stiffness k_r = m_r ω_r²). The optional residuals stand
for modes outside the fitted band: R_u (m/N) a constant compliance for modes
above it, R_l (1/kg) an inertia term for modes below it.

Fit: separable (variable-projection) nonlinear least squares. For given poles
(f_r, ζ_r) the model is linear in the real coefficients 1/m_r, R_u, R_l, which
are solved exactly by linear least squares on the stacked real and imaginary
parts; :func:`scipy.optimize.least_squares` then adjusts only the poles
(f_r, ln ζ_r) on the complex residual. Poles start from the peaks of |Φ| with
half-power damping estimates; when a mode count is asked for (or the error is
still large) a mode is added where the residual is largest and the fit
repeated — so close modes hidden in one peak are found, unlike by peak picking.

The fit error reported is the relative RMS ‖Φ_fit − Φ‖ / ‖Φ‖ over the band.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares, nnls
from scipy.signal import find_peaks

from ..errors import InputError
from ..frf import FRF
from ..blas import single_thread_blas

__all__ = ["ModalModel", "fit_modes"]


@dataclass(frozen=True)
class ModalModel:
    """Modes of one direction (x or y) of the tool point.

    Attributes
    ----------
    fn_hz, zeta, mass_kg : (n,) natural frequencies (Hz), damping ratios, modal masses (kg).
    upper_residual : constant compliance R_u for modes above the band, m/N.
    lower_residual : R_l in −R_l/ω² for modes below the band, 1/kg.
    fit_error : relative RMS error of the fit (nan if not fitted).
    """

    fn_hz: np.ndarray
    zeta: np.ndarray
    mass_kg: np.ndarray
    upper_residual: float = 0.0
    lower_residual: float = 0.0
    fit_error: float = float("nan")
    label: str = ""

    def __post_init__(self):
        f, z, m = (np.atleast_1d(np.asarray(v, dtype=float)).reshape(-1) for v in (self.fn_hz, self.zeta, self.mass_kg))
        if not (f.size == z.size == m.size):
            raise InputError(f"{f.size} frequencies, {z.size} damping ratios, {m.size} masses", field="modes")
        if np.any(~np.isfinite(f) | (f <= 0)):
            raise InputError("natural frequencies must be finite and > 0 Hz", field="fn_hz")
        if np.any(~np.isfinite(z) | (z < 0)):
            raise InputError("damping ratios must be finite and ≥ 0", field="zeta")
        if np.any(~np.isfinite(m) | (m == 0)):
            raise InputError("modal masses must be finite and non-zero", field="mass_kg")
        for name, v in (("fn_hz", f), ("zeta", z), ("mass_kg", m)):
            object.__setattr__(self, name, v)

    @property
    def n_modes(self) -> int:
        """Number of modes."""
        return self.fn_hz.size

    @property
    def omega_n(self) -> np.ndarray:
        """Natural angular frequencies ω_r = 2π f_r, rad/s."""
        return 2 * np.pi * self.fn_hz

    @property
    def stiffness(self) -> np.ndarray:
        """Modal stiffness k_r = m_r ω_r², N/m."""
        return self.mass_kg * self.omega_n**2

    @property
    def damping(self) -> np.ndarray:
        """Modal viscous damping c_r = 2 ζ_r m_r ω_r, N·s/m."""
        return 2 * self.zeta * self.mass_kg * self.omega_n

    def frf(self, freq_hz, *, residuals: bool = True) -> FRF:
        """Re-synthesised receptance at ``freq_hz``.

        Parameters
        ----------
        freq_hz : array_like
            Increasing frequencies, Hz.
        residuals : bool
            Include the residual terms R_u − R_l/ω².

        Returns
        -------
        FRF
            Receptance, m/N.

        Examples
        --------
        >>> m = ModalModel([100.0], [0.05], [2.0])
        >>> k = m.stiffness[0]                         # N/m
        >>> bool(np.isclose(m.frf([0.0]).values[0], 1 / k))   # static compliance 1/k, m/N
        True
        """
        f = np.asarray(freq_hz, dtype=float).reshape(-1)
        w = 2 * np.pi * f
        basis = _mode_basis(w, self.omega_n, self.zeta)
        v = basis @ (1.0 / self.mass_kg)
        if residuals:
            v = v + self.upper_residual
            if self.lower_residual:
                with np.errstate(divide="ignore"):
                    v = v - self.lower_residual / w**2
        return FRF(f, v, "receptance", self.label or "modal fit")

    def table(self) -> str:
        """Human-readable table of the modes (one line per mode)."""
        lines = [f"{'mode':>4} {'fn [Hz]':>10} {'zeta [%]':>9} {'mass [kg]':>11} {'k [N/m]':>11}"]
        for r in range(self.n_modes):
            lines.append(
                f"{r + 1:>4} {self.fn_hz[r]:>10.2f} {100 * self.zeta[r]:>9.3f} "
                f"{self.mass_kg[r]:>11.4g} {self.stiffness[r]:>11.4g}"
            )
        if np.isfinite(self.fit_error):
            lines.append(f"fit error (relative RMS): {100 * self.fit_error:.2f} %")
        return "\n".join(lines)


def _mode_basis(w, wn, zeta):
    """Columns 1/(ω_r² − ω² + 2iζ_r ω_r ω), shape (n_freq, n_modes), s²."""
    w = w[:, None]
    return 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)


def _design(w, wn, zeta, residuals):
    cols = [_mode_basis(w, wn, zeta)]
    if residuals:
        cols.append(np.ones((w.size, 1), complex))
        cols.append((-1.0 / w**2)[:, None].astype(complex))
    return np.hstack(cols)


def _solve_linear(D, h, nonneg):
    """Real coefficients c minimising ‖D c − h‖ (complex D, h); columns scaled for conditioning.

    ``nonneg``: c ≥ 0 (non-negative least squares) — positive modal masses and
    residuals, as a driving-point FRF has; it also stops two modes at one pole
    from cancelling each other with opposite residues.
    """
    A = np.vstack([D.real, D.imag])
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    b = np.r_[h.real, h.imag]
    if nonneg:
        c, _ = nnls(A / scale, b)
    else:
        c, *_ = np.linalg.lstsq(A / scale, b, rcond=None)
    return c / scale


def _half_power_zeta(f, mag, k):
    """Damping ratio from the half-power (−3 dB) bandwidth around peak index k (fallback 2 %)."""
    target = mag[k] / np.sqrt(2)
    left = np.flatnonzero(mag[:k] < target)
    right = np.flatnonzero(mag[k:] < target)
    if left.size == 0 or right.size == 0:
        return 0.02
    i, j = left[-1], k + right[0]
    # Interpolate the crossings for a bandwidth finer than the grid.
    fl = np.interp(target, [mag[i], mag[i + 1]], [f[i], f[i + 1]])
    fr = np.interp(target, [mag[j], mag[j - 1]], [f[j], f[j - 1]])
    return float(np.clip((fr - fl) / (2 * f[k]), 1e-4, 0.3))


def _fit(w, h, f0, z0, residuals, fbounds, nonneg):
    """Variable-projection fit from initial poles (f0 Hz, z0); returns (fn, zeta, coeffs, rel_err)."""
    n = f0.size
    f0 = np.clip(f0, fbounds[0] * (1 + 1e-9), fbounds[1] * (1 - 1e-9))
    z0 = np.clip(z0, 1.1e-5, 0.49)

    def resid(p):
        fn, ze = p[:n], np.exp(p[n:])
        D = _design(w, 2 * np.pi * fn, ze, residuals)
        r = D @ _solve_linear(D, h, nonneg) - h
        return np.r_[r.real, r.imag]

    x0 = np.r_[f0, np.log(z0)]
    lo = np.r_[np.full(n, fbounds[0]), np.full(n, np.log(1e-5))]
    hi = np.r_[np.full(n, fbounds[1]), np.full(n, np.log(0.5))]
    sol = least_squares(resid, x0, bounds=(lo, hi), x_scale=np.r_[np.maximum(f0 * z0, 1e-3), np.ones(n)],
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200 * (n + 1))
    fn, ze = sol.x[:n], np.exp(sol.x[n:])
    D = _design(w, 2 * np.pi * fn, ze, residuals)
    c = _solve_linear(D, h, nonneg)
    err = np.linalg.norm(D @ c - h) / np.linalg.norm(h)
    return fn, ze, c, float(err)


def fit_modes(
    frf: FRF,
    n_modes: int | None = None,
    band: tuple[float, float] | None = None,
    *,
    residuals: bool = True,
    driving_point: bool = True,
    max_modes: int = 8,
    tol: float = 0.02,
) -> ModalModel:
    """Fit modes (f_r, ζ_r, m_r) to a receptance by separable nonlinear least squares.

    Parameters
    ----------
    frf : the FRF (receptance, or mobility/accelerance, converted).
    n_modes : number of modes; ``None`` picks them: every clear peak, then
        more while the relative RMS error exceeds ``tol`` and a new mode cuts
        it by at least 20 % (at most ``max_modes``).
    band : (f_min, f_max) Hz to fit in; default the whole FRF (0 Hz dropped).
    residuals : fit the upper/lower residual terms for out-of-band modes.
    driving_point : constrain 1/m_r and the residuals to be ≥ 0, as for a
        driving-point FRF such as the tool point's (False: any sign, e.g. a
        cross FRF).

    Returns
    -------
    ModalModel with modes sorted by frequency and ``fit_error`` set; a mode
    left with zero residue is dropped (so fewer than ``n_modes`` can come
    back). With ``driving_point=False`` a modal mass may be negative; the
    semi-discretisation rejects such a model.
    """
    if not isinstance(frf, FRF):
        raise InputError(f"expected an FRF, got {type(frf).__name__}", field="frf")
    try:
        h = frf.to_receptance()
    except ValueError as err:
        raise InputError(str(err), field="frf") from None
    h = h.band(*(band if band is not None else (None, None)))
    h = h.band(1e-12, None)  # ω = 0 carries no modal information and breaks R_l/ω²
    if len(h) < 8:
        raise InputError(f"need at least 8 frequency points in the band, got {len(h)}", field="band")
    if n_modes is not None and (int(n_modes) != n_modes or n_modes < 1):
        raise InputError(f"must be a positive integer, got {n_modes!r}", field="n_modes")
    f, v = h.freq_hz, h.values
    if not np.all(np.isfinite(v)) or not np.any(v):
        raise InputError("FRF values must be finite and not all zero", field="frf")
    # Fit in units of the peak magnitude: receptances are ~1e-6 m/N, and the
    # optimiser's tolerances (gtol) are absolute.
    unit = np.abs(v).max()
    v = v / unit
    w = 2 * np.pi * f
    mag = np.abs(v)
    fbounds = (f[0], f[-1])

    pk, prop = find_peaks(mag, prominence=0.03 * mag.max())
    pk = pk[np.argsort(prop["prominences"])[::-1]]  # most prominent first
    if pk.size == 0:
        pk = np.array([int(np.argmax(mag))])
    want = max_modes if n_modes is None else int(n_modes)
    pk = pk[:want]
    f0 = f[pk]
    z0 = np.array([_half_power_zeta(f, mag, k) for k in pk])  # a handful of peaks, not a frequency loop
    with single_thread_blas():
        fit = _grow(w, v, f, f0, z0, residuals, fbounds, driving_point, n_modes, want, max_modes, tol)
    fn, ze, c, err = fit
    c = c * unit
    n = fn.size
    upper, lower = (float(c[n]), float(c[n + 1])) if residuals else (0.0, 0.0)
    # A mode the (non-negative) fit gave no residue is superfluous: drop it.
    keep = np.flatnonzero(c[:n] != 0)
    if keep.size == 0:
        raise InputError("modal fit failed: no mode with a non-zero residue (try another band)", field="frf")
    keep = keep[np.argsort(fn[keep])]
    return ModalModel(fn[keep], ze[keep], 1.0 / c[keep], upper, lower, err, frf.label)


def _grow(w, v, f, f0, z0, residuals, fbounds, nonneg, n_modes, want, max_modes, tol):
    """Fit from the peaks, then add modes where the residual is largest (see :func:`fit_modes`)."""
    fit = _fit(w, v, f0, z0, residuals, fbounds, nonneg)

    def add_mode(fit):
        fn, ze, c, _ = fit
        D = _design(w, 2 * np.pi * fn, ze, residuals)
        k = int(np.argmax(np.abs(D @ c - v)))
        return _fit(w, v, np.r_[fn, f[k]], np.r_[ze, 0.02], residuals, fbounds, nonneg)

    if n_modes is not None:
        while fit[0].size < want:
            fit = add_mode(fit)
    else:
        while fit[3] > tol and fit[0].size < max_modes:
            trial = add_mode(fit)
            if trial[3] > 0.8 * fit[3]:
                break
            fit = trial
    return fit
