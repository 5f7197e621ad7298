"""Common-pole modal fit of one or several FRFs: complex modes, residual terms, a noise model, automatic order.

All FRFs of one linear structure to one input share its poles. With n modes in
the band, the receptance of FRF e (e = 1 … m) is modelled as

    H_e(ω) = Σ_r [ A_er / (iω − λ_r) + conj(A_er) / (iω − conj λ_r) ] + U_e − L_e / ω²      (m/N)

with shared complex poles λ_r = −σ_r + iω_dr (rad/s; natural frequency
ω_r = |λ_r|, damping ratio ζ_r = σ_r / ω_r), complex modal constants A_er
(so non-proportional damping and cross FRFs are represented), and real
residual terms for modes outside the band: U_e (m/N, modes above) and L_e
(1/kg, modes below). Mobility and accelerance are iω H and −ω² H.

Noise model. The fit minimises the weighted error in the quantity the data
were *measured* in, where the noise is white: a hammer test measures
accelerance, so its receptance noise grows like 1/ω², and fitting receptance
would chase that noise at low frequency. Each FRF is weighted by
1 / max |y_e| in that quantity (noise proportional to each FRF's level), or,
when the coherence γ² of the measurement is known, point by point by
1 / σ_e(ω) with σ_e ∝ |y_e| √((1 − γ²) / γ²) (the standard deviation of the
H1 estimate).

Fit. (1) Starting poles from the least-squares complex-frequency estimator
(LSCF, a common-denominator rational fit in z = exp(iωΔt)) at the upper half of
the orders up to P; a pole is a candidate when it is stable over those orders
(frequency within 1 %, damping within 20 %); when none is (noise, no resonance),
from the most prominent peaks of the weighted magnitude, ``n_modes`` of them or
3. (2) Variable projection: for given
poles the real coefficients of all FRFs follow from one linear least-squares
solve (one QR for all FRFs when the weights are one per FRF), and a
Levenberg–Marquardt iteration on the 2n × 2n normal equations of Kaufman's
Jacobian moves only the poles (ln σ_r, ln ω_dr). This is the maximum-likelihood
estimate under the noise model, and its spread reaches the Cramér–Rao bound
(``benchmarks/bench_modal.py``). (3) Order: modes whose removal lowers the
Bayesian information criterion are removed, then a mode is added where the
weighted residual is largest while that lowers it, then broad poles beyond the
band (residual terms of the modes there) while that lowers it; an in-band pole
at a damping limit (ζ ≤ 1e-6 or ≥ 0.5), or any pole beyond 0.25 f_lo … 4 f_hi,
is removed and the rest refitted. A fit within 1e-6 relative RMS of the data
counts as exact (computed FRFs are no finite sum of viscous modes below that).
Last, an in-band mode the data do not determine (Gauss–Newton standard deviation
of ln ζ above 1, or of f_n above ζ f_n) is removed. Poles outside the band are
never reported as modes. When an FRF is declared a driving point (``driving_point``),
its modes of negative modal mass are dropped if the model without them is nearly as
likely (BIC within 10), and otherwise kept with a :class:`DrivingPointWarning`.

Examples
--------
Two receptances of a two-mode structure (300 and 800 Hz, 2 % damping):

>>> import numpy as np
>>> f = np.arange(50.0, 1200.0, 2.0)
>>> w = 2 * np.pi * f
>>> q = [1 / ((2 * np.pi * fn) ** 2 - w**2 + 2j * 0.02 * 2 * np.pi * fn * w) for fn in (300.0, 800.0)]
>>> Y = np.stack([q[0] + 0.5 * q[1], 0.3 * q[0] - q[1]], -1) / 1e3
>>> fit = fit_modal(f, Y)
>>> fit.fn_hz.round(6).tolist(), fit.zeta.round(6).tolist(), bool(fit.fit_error.max() < 1e-8)
([300.0, 800.0], [0.02, 0.02], True)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dgeqrf as _geqrf
from scipy.signal import find_peaks

from ..blas import single_thread_blas
from ..errors import InputError
from ..frf import FRF, QUANTITIES, check_freq_hz

__all__ = ["ModalFit", "fit_modal", "fit_frfs", "ZETA_LIMITS", "DrivingPointWarning"]

ZETA_LIMITS = (1e-6, 0.5)
"""A fitted pole with a damping ratio outside these limits is not a mode (it is removed)."""


_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}  # quantity = (iω)^k × receptance
_POINTS_PER_MODE = 8  # fewest band points per requested mode (fit_modal's n_modes)
_MIN_POINTS = 10
_PEAK_STARTS = 3  # starting poles from the most prominent peaks when the stabilisation diagram has none
_EXACT = 1e-6  # relative RMS misfit below which a fit counts as exact (order selection only)
_STRONG = 10.0  # BIC difference that is "very strong" evidence (Kass & Raftery): the driving-point rule's margin


class DrivingPointWarning(UserWarning):
    """A fit of a driving-point FRF keeps modes of negative modal mass, because the data demand them."""


@dataclass(frozen=True)
class ModalFit:
    """A fitted common-pole model of m FRFs (receptance form; see the module docstring).

    Attributes
    ----------
    poles : numpy.ndarray
        (n,) complex poles λ_r = −σ_r + iω_dr, rad/s, Im > 0, sorted by frequency.
    residues : numpy.ndarray
        (n, m) complex modal constants A_er of the receptances, m/(N s).
    upper_residual : numpy.ndarray
        (m,) U_e, m/N (constant compliance of modes above the band).
    lower_residual : numpy.ndarray
        (m,) L_e, 1/kg (−L_e/ω² of modes below the band).
    band_hz : tuple of float
        (f_lo, f_hi), Hz, the fitted band.
    quantity : str
        The quantity the fit was weighted in (the one the noise is white in).
    fit_error : numpy.ndarray
        (m,) relative RMS error ‖fit − y_e‖ / ‖y_e‖ per FRF over the band, in ``quantity``.
    labels : tuple of str
        Names of the m FRFs.
    residual_poles, residual_residues : numpy.ndarray
        (k,) poles outside the band (within 0.25 f_lo … 4 f_hi, any damping) and their (k, m)
        modal constants: residual terms of out-of-band modes, not reported as modes.
    velocity_residual : numpy.ndarray, optional
        (m,) V_e in a further residual term iω V_e, s·m/N (damping of out-of-band modes); None = 0.
    diagram : tuple
        The stabilisation diagram the automatic order started from: ``(order, poles)`` per LSCF model order
        (poles in rad/s, Im > 0); () when not computed.
    notes : tuple of str
        What the fit did or found that a user should read, one line each (the driving-point rule: modes of
        negative modal mass dropped, or kept with a :class:`DrivingPointWarning`).
    """

    poles: np.ndarray
    residues: np.ndarray
    upper_residual: np.ndarray
    lower_residual: np.ndarray
    band_hz: tuple
    quantity: str
    fit_error: np.ndarray
    labels: tuple = ()
    residual_poles: np.ndarray = field(default_factory=lambda: np.empty(0, complex))
    residual_residues: np.ndarray | None = None
    velocity_residual: np.ndarray | None = None
    diagram: tuple = ()
    notes: tuple = ()

    @property
    def n_modes(self) -> int:
        """Number of modes n."""
        return self.poles.size

    @property
    def omega_n(self) -> np.ndarray:
        """Natural angular frequencies ω_r = |λ_r|, rad/s, (n,)."""
        return np.abs(self.poles)

    @property
    def fn_hz(self) -> np.ndarray:
        """Natural frequencies f_r = |λ_r| / 2π, Hz, (n,)."""
        return self.omega_n / (2 * np.pi)

    @property
    def zeta(self) -> np.ndarray:
        """Damping ratios ζ_r = −Re λ_r / |λ_r|, (n,)."""
        return -self.poles.real / self.omega_n

    def values(self, freq_hz, quantity: str = "receptance", *, residuals: bool = True) -> np.ndarray:
        """The fitted FRFs (F, m) at ``freq_hz`` (Hz) in ``quantity`` (receptance m/N by default).

        Parameters
        ----------
        freq_hz : array_like
            Frequencies, Hz (> 0 Hz when ``residuals`` and a lower residual is present).
        quantity : str
            ``"receptance"``, ``"mobility"`` or ``"accelerance"``.
        residuals : bool
            Include U_e − L_e/ω².

        Returns
        -------
        numpy.ndarray
            (F, m) complex.
        """
        w = 2 * np.pi * np.asarray(freq_hz, float).reshape(-1)
        poles, residues = self.poles, self.residues
        if residuals and self.residual_poles.size:
            poles = np.r_[poles, self.residual_poles]
            residues = np.vstack([residues, self.residual_residues])
        D = _basis(w, poles, residuals)
        n = poles.size
        c = np.vstack([residues.real, residues.imag])
        m = self.upper_residual.size
        c = c.reshape(2, n, m).transpose(1, 0, 2).reshape(2 * n, m)  # m explicit: n may be 0
        if residuals:
            vel = np.zeros_like(self.upper_residual) if self.velocity_residual is None else self.velocity_residual
            c = np.vstack([c, self.upper_residual[None], vel[None], self.lower_residual[None]])
        with np.errstate(divide="ignore", invalid="ignore"):
            return (D @ c) * _factor(w, _power(quantity))[:, None]

    def __call__(self, freq_hz) -> np.ndarray:
        """The fitted receptances (F, m), m/N, at ``freq_hz`` (Hz): ``values(freq_hz)``."""
        return self.values(freq_hz)

    def frf(self, freq_hz, index: int = 0, quantity: str = "receptance") -> FRF:
        """FRF ``index`` of the fit at ``freq_hz`` (Hz) as an :class:`~toolpoint.frf.FRF` in ``quantity``."""
        label = self.labels[index] if index < len(self.labels) else f"FRF {index}"
        return FRF(freq_hz, self.values(freq_hz, quantity)[:, index], quantity, f"{label}, modal fit")

    def real_modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Second-order form of each mode: H_e = Σ_r (a_er + iω b_er) / (ω_r² − ω² + 2iζ_r ω_r ω).

        A_er/(iω − λ_r) + c.c. = (−2 Re(A_er conj λ_r) + iω 2 Re A_er) / (ω_r² − ω² + 2iζ_r ω_r ω), so
        a_er = −2 Re(A_er conj λ_r) (N⁻¹ s⁻² m… i.e. 1/kg for a driving point: 1/modal mass) and
        b_er = 2 Re A_er (m/(N s)), which is 0 for a proportionally damped (real) mode.

        Returns
        -------
        tuple of numpy.ndarray
            (a, b), each (n, m): a in 1/kg, b in s/kg.
        """
        return _real_form(self.poles, self.residues)

    def residual_real_modes(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`real_modes` of the residual poles outside the band (``residual_poles``): (a, b), each (k, m)."""
        if self.residual_poles is None or self.residual_residues is None or not np.size(self.residual_poles):
            empty = np.zeros((0, self.residues.shape[1]))
            return empty, empty.copy()
        return _real_form(self.residual_poles, self.residual_residues)

    def modal_mass(self, index: int = 0) -> np.ndarray:
        """Real-mode-equivalent modal masses 1 / a_r (kg), (n,), of the driving-point FRF ``index``.

        Exact for proportional damping (b_r = 0); otherwise the iω b_r part of each
        mode is neglected (see :meth:`real_modes`).
        """
        a, _ = self.real_modes()
        return 1.0 / a[:, index]

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A real state-space form (A, B, C) of the modes (residual terms left out).

        Per mode the states are (q_r, q̇_r) with q̈_r + 2ζ_r ω_r q̇_r + ω_r² q_r = u and
        output y_e = Σ_r a_er q_r + b_er q̇_r, so C (sI − A)⁻¹ B reproduces
        Σ_r (a_er + s b_er) / (s² + 2ζ_r ω_r s + ω_r²), i.e. the fitted modes exactly,
        non-proportional damping included (s = iω).

        Returns
        -------
        tuple of numpy.ndarray
            A (2n, 2n) in 1/s and 1/s², B (2n, 1), C (m, 2n) (m/N per unit of u).

        Examples
        --------
        >>> fit = ModalFit(np.array([-10 + 600j]), np.array([[1e-6 - 2e-5j]]), np.zeros(1), np.zeros(1),
        ...                (10.0, 200.0), "receptance", np.zeros(1))
        >>> A, B, C = fit.state_space()
        >>> s = 2j * np.pi * 95.0
        >>> h = (C @ np.linalg.solve(s * np.eye(2) - A, B))[0, 0]
        >>> bool(np.isclose(h, fit.values([95.0])[0, 0], rtol=1e-12))
        True
        """
        n, m = self.residues.shape
        a, b = self.real_modes()
        wn, ze = self.omega_n, self.zeta
        A = np.zeros((2 * n, 2 * n))
        B = np.zeros((2 * n, 1))
        C = np.zeros((m, 2 * n))
        for r in range(n):  # a handful of modes: block assembly
            A[2 * r: 2 * r + 2, 2 * r: 2 * r + 2] = [[0.0, 1.0], [-wn[r] ** 2, -2 * ze[r] * wn[r]]]
            B[2 * r + 1, 0] = 1.0
            C[:, 2 * r], C[:, 2 * r + 1] = a[r], b[r]
        return A, B, C

    def table(self) -> str:
        """Human-readable table: one line per mode (frequency Hz, damping %)."""
        lines = [f"{'mode':>4} {'fn [Hz]':>10} {'zeta [%]':>9}"]
        lines += [f"{r + 1:>4} {self.fn_hz[r]:>10.3f} {100 * self.zeta[r]:>9.4f}" for r in range(self.n_modes)]
        lines.append("fit error (relative RMS, " + self.quantity + "): "
                     + ", ".join(f"{100 * e:.3g} %" for e in self.fit_error))
        return "\n".join(lines)


# --------------------------------------------------------------------------- model pieces
def _real_form(poles, residues) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) of A/(iω − λ) + c.c. = (a + iω b)/(ω_r² − ω² + 2iζ_r ω_r ω): a = −2 Re(A conj λ), b = 2 Re A."""
    poles, residues = np.asarray(poles), np.asarray(residues)
    return -2 * (residues * np.conj(poles)[:, None]).real, 2 * residues.real


def _power(quantity: str) -> int:
    if quantity not in _POWER:
        raise InputError(f"unknown quantity {quantity!r} (one of {', '.join(QUANTITIES)})", field="quantity")
    return _POWER[quantity]


def _factor(w, k: int) -> np.ndarray:
    """(iω)^k: receptance → mobility (k = 1) or accelerance (k = 2)."""
    return (1j * w) ** k


def _basis(w, poles, residuals) -> np.ndarray:
    """Receptance columns (F, 2n + k): per mode u + v and i(u − v), u = 1/(iω − λ), v = 1/(iω − conj λ).

    ``residuals``: bool (all residual columns 1, iω and −1/ω², or none) or three
    bools (upper, velocity, lower) choosing each.
    """
    up, vel, low = (residuals,) * 3 if isinstance(residuals, bool) else residuals
    s = 1j * w[:, None]
    u, v = 1.0 / (s - poles), 1.0 / (s - np.conj(poles))
    cols = [np.stack([u + v, 1j * (u - v)], -1).reshape(w.size, -1)]
    if up:
        cols.append(np.ones((w.size, 1)))
    if vel:
        cols.append(s)
    if low:
        with np.errstate(divide="ignore"):
            cols.append((-1.0 / w**2)[:, None])
    return np.hstack(cols).astype(complex)


class _Problem:
    """The weighted data and the variable-projection residual / Jacobian for a set of poles."""

    def __init__(self, w, Yq, Wt, k, residuals):
        self.w, self.k = w, k
        self.residuals = (residuals,) * 3 if isinstance(residuals, bool) else tuple(residuals)
        self.fac = _factor(w, k)
        self.Wt = Wt  # (F, m) real weights
        self.B = np.concatenate([(Yq * Wt).real, (Yq * Wt).imag], 0).T[..., None]  # (m, 2F, 1)
        # Separable weights W_e(ω) = w0(ω) wt_e (no coherence): every FRF has the same design matrix
        # up to a factor, so one QR serves all FRFs (m times less work than one per FRF).
        wt = Wt[0] / Wt[0, 0]
        self.shared = bool(np.allclose(Wt, Wt[:, :1] * wt, rtol=1e-13, atol=0.0))
        if self.shared:
            self.wt = Wt[0].copy()  # (m,): W_e(ω) = wt_e w0(ω) with w0 = W_0(ω) / W_0(ω_1)
            self.w0 = Wt[:, :1].T / Wt[0, 0]  # (1, F)
            self.B1 = self.B / self.wt[:, None, None]  # data weighted by w0 only
        self.N = 2 * Yq.size
        # Floor of the residual: a fit within 1e-6 relative RMS of the weighted data counts as exact and
        # the criterion rewards no further pole. No measured FRF is that clean, and a computed one
        # (RCSA, FE: frequency-dependent damping, the infinitely many modes of continuous beams) differs
        # from every finite sum of viscous modes at about that level: below it, poles only chase that.
        self.floor = _EXACT**2 * float(np.sum(self.B**2))
        self.plim = (np.log(1e-7 * w.min()), np.log(10 * w.max()))  # range of ln σ and ln ω_d, rad/s
        # a pole this far outside the range where poles are kept (_RESIDUAL) is removed anyway: stop refining
        self.wstop = (0.25 * _RESIDUAL[0] * w.min(), 4.0 * _RESIDUAL[1] * w.max())
        self._set_residual_columns()
        self._cache = {}

    def _set_residual_columns(self):
        """The weighted residual-term rows (mm, k, 2F) of the transposed design matrix (independent of the poles);
        and fresh work buffers."""
        R = _basis(self.w, np.empty(0, complex), self.residuals) * self.fac[:, None]  # (F, k)
        ws = self.w0 if self.shared else self.Wt.T  # (1, F) or (m, F)
        RW = R.T[None] * ws[:, None, :]  # (mm, k, F)
        self._resrows = np.ascontiguousarray(np.concatenate([RW.real, RW.imag], 2))
        self._ws = {}  # reused work arrays: fresh (F × P) arrays cost page faults (≈ half the time of a solve)

    def _buffers(self, key, *shapes):
        if key not in self._ws:
            self._ws[key] = tuple(np.empty(sh) for sh in shapes)
        return self._ws[key]

    def design(self, poles):
        """Weighted stacked real design matrices of the fit quantity, *transposed*: (mm, P, 2F), one column per
        row, mm = m, or 1 (weighted by w0 only) when the weights are separable (``shared``); also
        u = 1/(iω − λ), v = 1/(iω − conj λ), (n, F).

        Written into a reused buffer: valid until the next call.
        """
        s = 1j * self.w[None, :]
        u, v = 1.0 / (s - poles[:, None]), 1.0 / (s - np.conj(poles)[:, None])
        F, n = self.w.size, poles.size
        fw = self.fac[None, :] * (self.w0 if self.shared else self.Wt.T)  # (mm, F) complex: (iω)^k × weight
        mm, k = self._resrows.shape[:2]
        At, W = self._buffers(("design", n), (mm, 2 * n + k, 2 * F), (2 * n + k, 2 * F))
        for e in range(mm):  # one design matrix per distinct weighting
            t = (u + v) * fw[e]
            At[e, 0:2 * n:2, :F], At[e, 0:2 * n:2, F:] = t.real, t.imag
            t = (u - v) * (1j * fw[e])
            At[e, 1:2 * n:2, :F], At[e, 1:2 * n:2, F:] = t.real, t.imag
            At[e, 2 * n:] = self._resrows[e]
        return At, W, u, v

    def solve(self, poles, uv: bool = False):
        """Coefficients (m, P), residual (m, 2F) and the projection factors (At, Rp) for the poles.

        Least squares by the corrected seminormal equations with R from a Householder QR of the
        column-scaled design matrix As = Atᵀ (LAPACK geqrf, Q never formed): c = R⁺R⁺ᵀAsᵀb plus one
        correction step with the residual, as accurate as solving with Q (Björck) at half the cost.
        R⁺ (pseudo-inverse, rcond 1e-13) keeps a rank-deficient basis (a pole without a modal
        constant) harmless. The orthogonal projector onto the columns is As R⁺ R⁺ᵀ Asᵀ (Jacobian).
        With ``uv`` also returns u, v of :meth:`design`. At lives in a reused buffer: the cached
        evaluation (:meth:`_eval`) that refers to it is dropped here.
        """
        self._cache.clear()
        At, W, u, v = self.design(poles)
        B = self.B1 if self.shared else self.B
        sc = np.sqrt(np.einsum("epf,epf->ep", At, At))[..., None]  # (mm, P, 1) column norms
        sc[sc == 0] = 1.0
        At /= sc
        P = At.shape[1]
        Rp = np.empty((At.shape[0], P, P))
        for e in range(At.shape[0]):
            if P:
                W[...] = At[e]
                qr_, _, _, _ = _geqrf(W.T, overwrite_a=1)  # W.T: Fortran-ordered, factorised in place
                Rp[e] = np.linalg.pinv(np.triu(qr_[:P, :P]), rcond=1e-13)
        As = At.transpose(0, 2, 1)
        RpT = Rp.transpose(0, 2, 1)
        c = Rp @ (RpT @ (At @ B))
        r = As @ c - B
        c -= Rp @ (RpT @ (At @ r))  # one correction step
        r = (As @ c - B)[..., 0]
        c = c / sc
        if self.shared:
            r = r * self.wt[:, None]
        out = (c[..., 0], r, (At, Rp))
        return out + (u, v) if uv else out

    def rss(self, poles) -> float:
        """Weighted residual sum of squares."""
        return float(np.sum(self.solve(poles)[1] ** 2))

    def bic(self, rss: float, n: int) -> float:
        """Bayesian information criterion of a fit with n modes."""
        m = self.B.shape[0]
        kpar = 2 * n + m * (2 * n + sum(self.residuals))
        return self.N * np.log(max(rss, self.floor) / self.N) + kpar * np.log(self.N)

    def _eval(self, p):
        """Poles, clipped parameters, coefficients, residual, projection factors, u, v at parameters p (the last one
        cached)."""
        key = p.tobytes()
        if key not in self._cache:
            n = p.size // 2
            # A residual pole may run off towards 0 or ∞ rad/s: clip (ln σ, ln ω_d) to a range where
            # exp and the basis stay finite; such a pole is then removed as invalid (_valid).
            pc = np.clip(p, *self.plim)
            lam = -np.exp(pc[:n]) + 1j * np.exp(pc[n:])
            self._cache.clear()
            self._cache[key] = (lam, pc) + self.solve(lam, uv=True)
        return self._cache[key]

    def fun(self, p):
        """Weighted residual vector at parameters p = (ln σ_r, ln ω_dr)."""
        return self._eval(p)[3].ravel()

    def jac(self, p):
        """Kaufman's variable-projection Jacobian (m 2F, 2n) at parameters p = (ln σ_r, ln ω_dr).

        A view of a reused buffer: valid until the next call.
        """
        lam, pc, c, _, (At, Rp), u, v = self._eval(p)
        n = lam.size
        F = self.w.size
        u2, v2 = u * u, v * v  # (n, F)
        # mode r of FRF e is A_er u + conj(A_er) v (A = c_2r + i c_2r+1); d/dp = A u² g + conj(A g) v²
        # with g = dλ/dp: −σ for ln σ, iω_d for ln ω_d
        A = c[:, 0:2 * n:2] + 1j * c[:, 1:2 * n:2]  # (m, n)
        m = A.shape[0]
        fw = self.fac[None, :] * self.Wt.T  # (m, F)
        (Vt,) = self._buffers(("jac", n), (2 * n, m, 2 * F))  # rows: parameters
        for e in range(m):
            for h, g in enumerate((A[e] * lam.real, A[e] * (1j * lam.imag))):
                d = (u2 * g[:, None] + v2 * np.conj(g)[:, None]) * fw[e]
                Vt[h * n:(h + 1) * n, e, :F], Vt[h * n:(h + 1) * n, e, F:] = d.real, d.imag
        # project out the columns of the design matrix: Vᵀ − (Vᵀ As) R⁺ R⁺ᵀ Asᵀ
        if At.shape[0] == 1:  # shared: one projector for all FRFs
            X = Vt.reshape(-1, 2 * F)
            X -= ((X @ At[0].T) @ Rp[0] @ Rp[0].T) @ At[0]
        else:
            for e in range(m):
                Vt[:, e] -= ((Vt[:, e] @ At[e].T) @ Rp[e] @ Rp[e].T) @ At[e]
        Vt[pc != p] = 0.0  # the clipped residual is flat in a clipped parameter
        return Vt.reshape(2 * n, -1).T

    def refine(self, poles, tol: float = 1e-10, stop=None):
        """Poles moved by Levenberg–Marquardt on the variable-projection residual.

        Marquardt's scaled damping on the 2n × 2n normal equations JᵀJ (J: Kaufman's Jacobian,
        m·2F rows): the step costs O(2n)³ instead of a QR of J, which was most of the time
        spent in MINPACK. Stops when an accepted, nearly Gauss–Newton step (damping ≤ 1e-2) lowers
        the residual sum of squares by less than the fraction ``tol`` or moves every ln σ, ln ω_d
        by less than ``tol``; or when ``stop(poles)`` is true after an accepted step (a trial already
        known to be rejected).
        """
        if poles.size == 0:
            return poles
        n = poles.size
        p = np.r_[np.log(-poles.real), np.log(poles.imag)]
        r = self.fun(p)
        cost = float(r @ r)
        J = self.jac(p)
        mu = 1e-3
        d_max = np.zeros(p.size)
        for _ in range(10 * (p.size + 1)):  # at most; a converging fit needs far fewer
            H, g = J.T @ J, J.T @ r
            # Moré's scaling (MINPACK): the largest diagonal met so far, not the current one. A residual pole
            # run to critical damping is flat in ln ω_d; scaled by that column's current ~0 norm, the step
            # along it was ~1e5 with a round-off sign, and the model chosen flipped between CPUs (a 1e-15
            # change of a blank's FRFs flipped it in 9 of 30 fits; docs/design/measurements.md)
            d_max = np.maximum(d_max, np.diag(H))
            d = d_max.copy()
            d[d <= 0] = 1.0  # a clipped parameter (zero column): no step
            try:
                step = -np.linalg.solve(H + mu * np.diag(d), g)
            except np.linalg.LinAlgError:
                mu *= 10.0
                continue
            p_new = p + step
            r_new = self.fun(p_new)
            cost_new = float(r_new @ r_new)
            if cost_new < cost:
                # converged only when a (nearly) Gauss–Newton step gains little: a heavily damped
                # step is short and gains little far from the minimum too
                done = mu <= 1e-2 and (cost - cost_new <= tol * cost or np.max(np.abs(step)) <= tol)
                p, r, cost = p_new, r_new, cost_new
                if done or cost == 0.0:
                    break
                if stop is not None:  # a trial only: the final refinement converges every pole it keeps
                    if np.any(p[:n] < self.plim[0]):
                        break  # a damping ran to 0 (ln σ below its clip): that pole is removed anyway
                    wn = np.hypot(np.exp(np.clip(p[:n], *self.plim)), np.exp(np.clip(p[n:], *self.plim)))
                    if np.any((wn < self.wstop[0]) | (wn > self.wstop[1])):
                        break  # a pole ran far out of the range where poles are kept: it is removed anyway
                    x = np.clip(p, *self.plim)
                    if stop(-np.exp(x[:n]) + 1j * np.exp(x[n:])):
                        break
                J = self.jac(p)
                mu = max(mu / 3.0, 1e-12)
            else:
                mu *= 10.0
                if mu > 1e12:  # no descent left: at a minimum to round-off
                    break
        x = np.clip(p, *self.plim)
        return -np.exp(x[:n]) + 1j * np.exp(x[n:])


# --------------------------------------------------------------------------- starting poles
def _lscf(w, Yq, Wt, order: int, dt: float, first: int = 1) -> list[np.ndarray]:
    """Poles (Im > 0, Re < 0) of the LSCF common-denominator fit at orders ``first`` … ``order``.

    Per FRF e the equation error W_e (N_e(z) − y_e d(z)) with z = exp(iωΔt) and real
    polynomial coefficients is minimised; eliminating each numerator leaves the
    reduced normal matrix M = Σ_e (T_e − S_eᵀ R_e⁻¹ S_e) for the denominator (its
    leading coefficient fixed to 1). All orders use leading blocks of one set of
    products.
    """
    # Each product Re(X_eᴴ X_e) etc. is Toeplitz: (Ωᴴ diag(d) Ω)_kl = Σ_f d_f z_f^(l−k), so only the
    # 2P + 1 moments Σ_f d_f z_f^j are needed (O(F P) instead of O(F P²)).
    j = np.arange(-order, order + 1)
    E = np.exp(1j * np.outer(w * dt, j))  # (F, 2P+1)
    W2 = Wt**2
    mom = np.concatenate([W2, -W2 * Yq, W2 * np.abs(Yq) ** 2], 1).T @ E  # (3m, 2P+1)
    idx = np.arange(order + 1)
    lag = idx[None, :] - idx[:, None] + order  # l − k, shifted
    G = mom.real[:, lag]  # (3m, P+1, P+1)
    m = Yq.shape[1]
    Rm, Sm, Tm = G[:m], G[m:2 * m], G[2 * m:]
    out = []
    for p in range(first, order + 1):
        b = slice(0, p + 1)
        R, S, T = Rm[:, b, b], Sm[:, b, b], Tm[:, b, b]
        M = np.sum(T - S.transpose(0, 2, 1) @ np.linalg.solve(R, S), 0)
        try:
            alpha = np.r_[-np.linalg.solve(M[:p, :p], M[:p, p]), 1.0]
        except np.linalg.LinAlgError:
            out.append(np.empty(0, complex))
            continue
        z = np.roots(alpha[::-1])
        z = z[np.abs(z) > 0]
        lam = np.log(z.astype(complex)) / dt
        out.append(lam[(lam.imag > 0) & (lam.real < 0)])
    return out


def _stable_poles(diagram, f_lo, f_hi) -> np.ndarray:
    """Poles of the top order of ``diagram`` that recur (f within 1 %, ζ within 20 %) in ≥ 60 % of its other orders."""
    def ok(lam):
        wn = np.abs(lam)
        ze = -lam.real / wn
        keep = (wn >= 2 * np.pi * _OUT[0] * f_lo) & (wn <= 2 * np.pi * _OUT[1] * f_hi) & (ze > ZETA_LIMITS[0]) \
            & (ze < 0.3)
        return lam[keep]

    top = ok(diagram[-1])
    lower = [ok(d) for d in diagram[:-1]]
    if not lower:
        return top
    keep = []
    for lam in top:
        wn, ze = abs(lam), -lam.real / abs(lam)
        hits = 0
        for d in lower:
            if d.size:
                wd, zd = np.abs(d), -d.real / np.abs(d)
                hits += bool(np.any((abs(wd - wn) < 0.01 * wn) & (abs(zd - ze) < 0.2 * ze)))
        if hits >= 0.6 * len(lower):
            keep.append(lam)
    return np.array(keep, complex)


# --------------------------------------------------------------------------- order selection
_OUT = (0.5, 1.5)  # starting poles from 0.5 f_lo to 1.5 f_hi; those outside the band only as residual terms
_RESIDUAL = (0.25, 4.0)  # residual poles are kept from 0.25 f_lo to 4 f_hi


def _valid(poles, f_lo, f_hi) -> np.ndarray:
    """Mask of poles the fit keeps.

    In the band: damping inside ZETA_LIMITS (a mode). Outside it, from 0.25 f_lo to 4 f_hi:
    any damping (a residual term of out-of-band modes, which may be as broad as critical).
    """
    wn = np.abs(poles)
    ze = -poles.real / wn
    inband = (wn >= 2 * np.pi * f_lo) & (wn <= 2 * np.pi * f_hi)
    zmax = np.where(inband, ZETA_LIMITS[1], np.inf)
    return ((wn >= 2 * np.pi * _RESIDUAL[0] * f_lo) & (wn <= 2 * np.pi * _RESIDUAL[1] * f_hi)
            & (ze > ZETA_LIMITS[0]) & (ze < zmax) & np.isfinite(wn))


_TRIAL_TOL = 1e-8  # LM tolerances while choosing the order (1e-6 stopped broad residual poles too early)
_FINAL_TOL = 1e-10  # the final refinement of the chosen model


def _refine_clean(prob, poles, f_lo, f_hi, tol=_TRIAL_TOL, stop=None):
    """Refine; remove poles that left the band or reached a damping limit; repeat until all are modes."""
    while True:
        poles = prob.refine(poles, tol, stop)
        ok = _valid(poles, f_lo, f_hi)
        if ok.all():
            return poles
        poles = poles[ok]


def _drop_one(prob, poles):
    """The poles without the mode whose removal (others fixed) raises the residual least; and that rss."""
    trials = [prob.rss(np.delete(poles, r)) for r in range(poles.size)]
    r = int(np.argmin(trials))
    return np.delete(poles, r), trials[r]


def _new_pole(prob, poles, f, tried=None):
    """A trial pole (ζ = 1 %) where the smoothed weighted residual is largest (outside ``tried``); its index."""
    _, r, _ = prob.solve(poles)
    F = f.size
    mag = np.convolve(np.sqrt(np.sum(r[:, :F] ** 2 + r[:, F:] ** 2, 0)), np.ones(5) / 5, "same")
    if tried is not None:
        mag = np.where(tried, -1.0, mag)
    j = int(np.argmax(mag))
    wn = 2 * np.pi * f[j]
    return np.r_[poles, wn * (-0.01 + 1j * np.sqrt(1 - 1e-4))], j


def _select(prob, poles, f, f_lo, f_hi, n_modes, max_modes):
    poles = _refine_clean(prob, poles, f_lo, f_hi)
    rss = prob.rss(poles)
    if n_modes is not None:
        while poles.size > n_modes:
            poles, _ = _drop_one(prob, poles)
            poles = _refine_clean(prob, poles, f_lo, f_hi)
        for _ in range(3 * n_modes):
            if poles.size >= n_modes:
                break
            poles = _refine_clean(prob, _new_pole(prob, poles, f)[0], f_lo, f_hi)
        return poles
    # backward: remove modes the criterion does not want
    while poles.size:
        trial, rss_t = _drop_one(prob, poles)
        if prob.bic(rss_t, trial.size) >= prob.bic(rss, poles.size):
            # with the other poles fixed the removal does not pay; refined, it may (a noise pole
            # beside a mode shares that mode's peak)
            trial = _refine_clean(prob, trial, f_lo, f_hi)
            rss_t = prob.rss(trial)
            if prob.bic(rss_t, trial.size) >= prob.bic(rss, poles.size):
                break
            poles, rss = trial, rss_t
            continue
        poles = _refine_clean(prob, trial, f_lo, f_hi)
        rss = prob.rss(poles)
    # forward: add a mode where the residual is largest while the criterion improves
    tried = np.zeros(f.size, bool)
    misses = 0
    while poles.size < max_modes and misses < 2:
        trial, j = _new_pole(prob, poles, f, tried)
        trial = _refine_clean(prob, trial, f_lo, f_hi)
        rss_t = prob.rss(trial)
        # judged by the criterion alone: a trial that lost a pole on the way (left the band, hit a
        # damping limit) may still be the better model
        better = prob.bic(rss_t, trial.size) < prob.bic(rss, poles.size)
        if better and trial.size > poles.size:
            poles, rss, misses, tried = trial, rss_t, 0, np.zeros(f.size, bool)
            continue
        if better:  # no pole added, but the others moved to a better fit: keep them; still a miss here
            poles, rss = trial, rss_t
        misses += 1  # try the next-largest residual elsewhere once more
        tried |= np.abs(f - f[j]) <= 0.02 * f[j]
    return _add_residual_poles(prob, poles, f_lo, f_hi)


def _add_residual_poles(prob, poles, f_lo, f_hi, most: int = 4):
    """Add broad poles beyond the band (start 1.5 f_hi or 0.5 f_lo, ζ = 0.3) while the criterion improves.

    Why: the constant, iω and 1/ω² residual terms describe modes far outside the band; modes just
    above it (a stiff blank's bending modes above 3 kHz) need a pole of their own, which the forward
    step, seeding only at in-band residual peaks, would not try.
    """
    def n_in(p):
        return int(np.sum((np.abs(p) >= 2 * np.pi * f_lo) & (np.abs(p) <= 2 * np.pi * f_hi)))

    rss = prob.rss(poles)
    for _ in range(most):
        best = None
        for fs in (1.5 * f_hi, 0.5 * f_lo):
            trial = np.r_[poles, 2 * np.pi * fs * (-0.3 + 1j * np.sqrt(0.91))]  # |λ| = ω_s, ζ = 0.3
            trial = _refine_clean(prob, trial, f_lo, f_hi)
            if n_in(trial) > n_in(poles):  # it ran into the band: a mode, which only the forward step adds
                continue
            b = prob.bic(prob.rss(trial), trial.size)
            if best is None or b < best[0]:
                best = (b, trial)
        if best is None or best[0] >= prob.bic(rss, poles.size):
            return poles
        if best[1].size <= poles.size:  # the new pole left: the others only moved to a better fit
            return best[1]
        poles = best[1]
        rss = prob.rss(poles)
    return poles


# --------------------------------------------------------------------------- entry points
def fit_modal(freq_hz, Y, *, quantity: str = "receptance", noise: str | None = None, band=None,
              n_modes: int | None = None, coherence=None, weights=None, residuals: bool = True,
              max_order: int | None = None, max_modes: int = 30, labels=(),
              driving_point: int | None = None) -> ModalFit:
    """Fit common complex poles, modal constants and residual terms to the columns of ``Y``.

    Parameters
    ----------
    freq_hz : array_like
        (F,) frequencies, Hz, strictly increasing.
    Y : array_like
        (F, m) or (F,) complex FRFs of one structure to one input, in ``quantity``.
    quantity : str
        What ``Y`` holds: ``"receptance"`` (m/N), ``"mobility"`` or ``"accelerance"``.
    noise : str, optional
        The quantity the measurement noise is white in, i.e. the one that was
        measured (default ``quantity``); the fit is weighted in it.
    band : (float, float), optional
        (f_lo, f_hi) Hz to fit; default all points above 0 Hz.
    n_modes : int, optional
        Number of modes; default (None) chosen by the information criterion. At most
        ``max_modes`` and one per 8 frequencies in the band.
    coherence : array_like, optional
        (F,) or (F, m) coherence γ² in [0, 1] of the measurement: point weights 1/σ_e(ω).
    weights : array_like, optional
        (m,) weight per FRF instead of 1 / max |y_e| (in the ``noise`` quantity).
    residuals : bool
        Fit the residual terms U_e, L_e of out-of-band modes.
    max_order : int, optional
        Highest LSCF order of the stabilisation diagram (default from the number of peaks).
    max_modes : int
        Most modes the automatic order may reach.
    labels : sequence of str
        Names of the FRFs.
    driving_point : int, optional
        Index of the column of ``Y`` that is a driving point (response at the input, e.g. a tool-point
        receptance): its modes must have positive modal mass (real-mode-equivalent a_r > 0, see
        :meth:`ModalFit.real_modes`). The automatic order then drops modes of negative mass when a
        model without them is nearly as likely (BIC within 10); when the data demand them, the fit is
        kept and a :class:`DrivingPointWarning` (and ``ModalFit.notes``) names them. With ``n_modes``
        given, such modes are only named. None (default): no such check.

    Returns
    -------
    ModalFit
        Poles sorted by frequency, every one inside the band with damping inside :data:`ZETA_LIMITS`.

    Raises
    ------
    InputError
        One line: bad grid, band outside the data, fewer than 10 points in the band,
        non-finite or all-zero FRF, bad coherence, weights or ``n_modes``.
    """
    f = check_freq_hz(freq_hz, field="freq_hz")
    Y = np.asarray(Y, dtype=complex)
    if Y.ndim == 1:
        Y = Y[:, None]
    if Y.ndim != 2 or Y.shape[0] != f.size:
        raise InputError(f"shape {Y.shape} does not match {f.size} frequencies: need ({f.size},) or ({f.size}, m)",
                         field="values")
    k_in, k = _power(quantity), _power(noise or quantity)
    if n_modes is not None and (int(n_modes) != n_modes or n_modes < 1):
        raise InputError(f"must be a positive integer, got {n_modes!r}", field="n_modes")
    lo, hi = (0.0, np.inf) if band is None else (float(band[0]), float(band[1]))
    if not (np.isfinite(lo) and lo < hi):
        raise InputError(f"band must be LO < HI, got {lo:g}:{hi:g}", field="band")
    sel = (f >= lo) & (f <= hi) & (f > 0)
    if sel.sum() < _MIN_POINTS:
        raise InputError(f"needs at least {_MIN_POINTS} frequencies > 0 Hz in the band {lo:g}–{hi:g} Hz, got "
                         f"{int(sel.sum())} (data cover {f[0]:g}–{f[-1]:g} Hz)" if f.size else "no frequencies",
                         field="band")
    f, Y = f[sel], Y[sel]
    if n_modes is not None and (n_modes > max_modes or _POINTS_PER_MODE * n_modes > f.size):
        # every mode brings a pole and a residue per FRF: fewer points than that only fit noise (and
        # the order search's cost grows with n_modes)
        raise InputError(f"{n_modes} modes need at least {_POINTS_PER_MODE * n_modes} frequencies in the band and at "
                         f"most max_modes = {max_modes} modes; the band has {f.size} points", field="n_modes")
    bad = ~np.isfinite(Y)
    if bad.any():
        j = int(np.flatnonzero(bad.any(1))[0])
        raise InputError(f"values must be finite (first non-finite value at {f[j]:g} Hz)", field="values")
    zero = np.flatnonzero(np.abs(Y).max(0) == 0)
    if zero.size:
        raise InputError(f"FRF {int(zero[0])} is zero everywhere in the band: nothing to fit (need an FRF that is "
                         "not all zero)", field="values")
    if driving_point is not None and (int(driving_point) != driving_point or not 0 <= driving_point < Y.shape[1]):
        raise InputError(f"must be the index of one of the {Y.shape[1]} FRFs, got {driving_point!r}",
                         field="driving_point")
    w = 2 * np.pi * f
    Yq = Y * _factor(w, k - k_in)[:, None]  # into the measured quantity
    Wt = _weights(Yq, coherence, weights, sel)
    with single_thread_blas():  # tall-skinny QRs: threads only add overhead
        fit = _fit(f, w, Yq, Wt, k, residuals, n_modes, max_order, max_modes, tuple(labels),
                   noise or quantity, None if driving_point is None else int(driving_point))
    for note in fit.notes:
        if note.startswith("warning: "):
            warnings.warn(note[len("warning: "):], DrivingPointWarning, stacklevel=2)
    return fit


def _weights(Yq, coherence, weights, sel) -> np.ndarray:
    F, m = Yq.shape
    if weights is not None:
        wt = np.asarray(weights, float).reshape(-1)
        if wt.size != m or not np.all(np.isfinite(wt) & (wt > 0)):
            raise InputError(f"need {m} finite weights > 0, got {wt.size}", field="weights")
    else:
        wt = 1.0 / np.abs(Yq).max(0)
    W = np.broadcast_to(wt, (F, m)).copy()
    if coherence is not None:
        g = np.asarray(coherence, float)
        g = g.reshape(sel.size, -1) if g.size in (sel.size, sel.size * m) else None
        if g is None or not np.all(np.isfinite(g) & (g >= 0) & (g <= 1)):
            raise InputError("coherence must be (F,) or (F, m) values in [0, 1] on the FRF's grid", field="coherence")
        g = np.clip(np.broadcast_to(g[sel], (F, m)), 1e-3, 1 - 1e-6)
        # σ_e(ω) ∝ |y_e| √((1 − γ²)/γ²): relative, so the weight is the level-free 1/σ,
        # with |y| floored at 1 % of the peak so antiresonances are not over-weighted.
        lev = np.maximum(np.abs(Yq), 0.01 * np.abs(Yq).max(0))
        W = 1.0 / (lev * np.sqrt((1 - g) / g))
        W = W / np.median(W, 0) * wt
    return W


def _fit(f, w, Yq, Wt, k, residuals, n_modes, max_order, max_modes, labels, quantity, driving) -> ModalFit:
    f_lo, f_hi = float(f[0]), float(f[-1])
    prob = _Problem(w, Yq, Wt, k, residuals)
    mag = np.sqrt(np.sum(np.abs(Yq * Wt) ** 2, 1))
    pk, props = find_peaks(mag, prominence=0.02 * mag.max())
    if max_order is None:
        want = max(pk.size, n_modes or 0)
        max_order = int(np.clip(4 * want + 16, 24, 80))
    dt = 1.0 / (2.0 * f_hi)
    max_order = int(max_order)  # the upper half of the orders makes the stabilisation diagram
    first = max_order // 2 + 1
    diagram = _lscf(w, Yq, Wt, max_order, dt, first=first)
    poles = _stable_poles(diagram, f_lo, f_hi)
    if poles.size == 0:
        # Nothing stable: start from the most prominent peaks, as many as the modes asked for (automatic
        # order: _PEAK_STARTS; the forward step adds more where the criterion wants them). Not from every
        # peak: white noise has a peak every ~3 points, and refining ~1000 poles took minutes.
        top = pk[np.argsort(props["prominences"])[::-1][:max(n_modes or 0, _PEAK_STARTS)]]
        wn = w[np.sort(top)] if pk.size else w[[int(np.argmax(mag))]]
        poles = wn * (-0.02 + 1j * np.sqrt(1 - 4e-4))
    poles = _select(prob, poles, f, f_lo, f_hi, n_modes, max_modes)
    if residuals:
        # Each residual term only where the criterion wants it: a lower residual fitted to
        # accelerance noise at low frequency would become a large −L/ω² receptance error.
        best = min(((u, v, lw) for u in (True, False) for v in (True, False) for lw in (True, False)),
                   key=lambda ul: _with(prob, ul).bic(_with(prob, ul).rss(poles), poles.size))
        if best != prob.residuals:
            prob = _with(prob, best)
    final = _refine_clean(prob, poles, f_lo, f_hi, _FINAL_TOL)
    # A residual pole below or above the band may drift out of its range on the way to the tight
    # optimum and be dropped: keep the model of the order selection when it is the better one.
    if final.size == poles.size or prob.bic(prob.rss(final), final.size) < prob.bic(prob.rss(poles), poles.size):
        poles = final
    if n_modes is None:  # the automatic order reports only modes the data determine
        while True:
            bad = _undetermined(prob, poles, f_lo, f_hi)
            if bad is None:
                break
            poles = _refine_clean(prob, np.delete(poles, bad), f_lo, f_hi, _FINAL_TOL)
    notes = ()
    if driving is not None:
        poles, notes = _positive_masses(prob, poles, f_lo, f_hi, driving, enforce=n_modes is None)
    poles = poles[np.argsort(np.abs(poles))]
    c, _, _ = prob.solve(poles)
    n = poles.size
    res = c[:, 0:2 * n:2] + 1j * c[:, 1:2 * n:2]  # (m, n)
    UVL = np.zeros((3, c.shape[0]))
    j = 2 * n
    for t in range(3):
        if prob.residuals[t]:
            UVL[t], j = c[:, j], j + 1
    U, V, L = UVL
    res = res.T.copy()
    fn = np.abs(poles) / (2 * np.pi)
    mode = (fn >= f_lo) & (fn <= f_hi)
    kw = dict(residual_poles=poles[~mode], residual_residues=res[~mode],
              diagram=tuple((first + i, np.asarray(d)) for i, d in enumerate(diagram)), notes=notes)
    fit = ModalFit(poles[mode], res[mode], U, L, (f_lo, f_hi), quantity, np.zeros(c.shape[0]), labels,
                   velocity_residual=V, **kw)
    err = np.linalg.norm(fit.values(f, quantity) - Yq, axis=0) / np.linalg.norm(Yq, axis=0)
    return ModalFit(fit.poles, fit.residues, U, L, fit.band_hz, quantity, err, labels, velocity_residual=V, **kw)


def _negative_masses(prob, poles, f_lo, f_hi, driving) -> np.ndarray:
    """Indices of the in-band poles whose modal constant on FRF ``driving`` is a negative (or infinite) modal
    mass: real-mode-equivalent a_r = −2 Re(A_r conj λ_r) ≤ 0 (:meth:`ModalFit.real_modes`)."""
    c, _, _ = prob.solve(poles)
    n = poles.size
    A = c[driving, 0:2 * n:2] + 1j * c[driving, 1:2 * n:2]
    a = -2 * (A * np.conj(poles)).real
    inband = (np.abs(poles) >= 2 * np.pi * f_lo) & (np.abs(poles) <= 2 * np.pi * f_hi)
    return np.flatnonzero(inband & ~(a > 0))


def _positive_masses(prob, poles, f_lo, f_hi, driving, enforce=True):
    """The driving-point rule: poles whose in-band modes all have positive modal mass on FRF ``driving``, if
    the data allow; and the notes (one line each) saying what was done.

    A driving point's modes all have positive modal mass; a mode of negative mass is a fit artefact (a noise
    pole, one real mode split in two) — or the FRF is no driving point (a transfer FRF's modal constants
    alternate in sign). The data decide which: the modes of negative mass are removed one at a time (the
    removal that raises the criterion least first, the others refitted) until none is left, and that
    model replaces the fit when its BIC exceeds the fit's by at most 10 ("very strong" evidence, Kass &
    Raftery). Otherwise the data demand those modes: the fit is kept whole, and a warning names them. A
    real mode is thus never removed for its sign alone.
    """
    neg = _negative_masses(prob, poles, f_lo, f_hi, driving)
    if neg.size == 0:
        return poles, ()
    fn = np.abs(poles) / (2 * np.pi)

    def names(idx):
        return ", ".join(f"{x:.1f}" for x in np.sort(fn[idx])) + " Hz"

    why = "the number of modes was given"
    if enforce:
        bic0 = prob.bic(prob.rss(poles), poles.size)
        cur, cur_neg = poles, neg
        while cur_neg.size:
            best = None
            for r in cur_neg:
                trial = _refine_clean(prob, np.delete(cur, r), f_lo, f_hi, _FINAL_TOL)
                b = prob.bic(prob.rss(trial), trial.size)
                if best is None or b < best[0]:
                    best = (b, trial)
            if best[0] - bic0 > _STRONG:
                why = f"without them the BIC rises by {best[0] - bic0:.3g}"
                break
            cur = best[1]
            cur_neg = _negative_masses(prob, cur, f_lo, f_hi, driving)
        else:
            return cur, (f"note: driving point: modes of negative modal mass dropped at {names(neg)} (BIC "
                         f"{best[0] - bic0:+.3g} without them: as likely)",)
    return poles, (f"warning: driving point: modes of negative modal mass kept at {names(neg)} ({why}): check "
                   "that the FRF is a driving point (a transfer FRF's modal constants alternate in sign)",)


def _undetermined(prob, poles, f_lo, f_hi):
    """Index of the in-band pole worst determined by the data, if any is undetermined; else None.

    From the Gauss–Newton covariance s² (JᵀJ)⁻¹ of (ln σ_r, ln ω_dr) at the fit (J: the
    variable-projection Jacobian, s² = rss / (N − parameters), rss floored as in the criterion):
    a mode is undetermined when the standard deviation of ln ζ exceeds 1 (damping not known within
    a factor e) or that of its natural frequency exceeds ζ f_n (half the half-power bandwidth:
    the data do not place the peak). A seed the refinement could not move (no modal constant) has
    an infinite variance.
    """
    inband = (np.abs(poles) >= 2 * np.pi * f_lo) & (np.abs(poles) <= 2 * np.pi * f_hi)
    if not inband.any():
        return None
    n = poles.size
    p = np.r_[np.log(-poles.real), np.log(poles.imag)]
    r, J = prob.fun(p), prob.jac(p)
    m = prob.B.shape[0]
    kpar = 2 * n + m * (2 * n + sum(prob.residuals))
    s2 = max(float(r @ r), prob.floor) / max(r.size - kpar, 1)
    G = J.T @ J
    d = np.sqrt(np.diag(G))
    flat = ~(d > 0)  # a parameter the residual does not depend on (clipped, or no modal constant)
    d[flat] = 1.0
    e, v = np.linalg.eigh(G / np.outer(d, d))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        cov = s2 * (v / np.maximum(e, 1e-300)) @ v.T / np.outer(d, d)
    cov[~np.isfinite(cov)] = np.inf
    cov[flat, :] = cov[:, flat] = np.inf
    s2r, d2r = poles.real**2, poles.imag**2
    a = s2r / (s2r + d2r)  # ln ω_n = a ln σ + (1 − a) ln ω_d; ln ζ = (1 − a)(ln σ − ln ω_d)
    i, j = np.arange(n), np.arange(n) + n
    with np.errstate(invalid="ignore"):
        var_wn = a**2 * cov[i, i] + (1 - a) ** 2 * cov[j, j] + 2 * a * (1 - a) * cov[i, j]
        var_ze = (1 - a) ** 2 * (cov[i, i] + cov[j, j] - 2 * cov[i, j])
    ze = -poles.real / np.abs(poles)
    score = np.maximum(np.sqrt(np.abs(var_ze)), np.sqrt(np.abs(var_wn)) / ze)
    score = np.where(np.isfinite(score), score, np.inf)
    score[~inband] = 0.0
    worst = int(np.argmax(score))
    return worst if score[worst] > 1.0 else None


def _with(prob, residuals):
    """The same problem with other residual columns (a shallow copy)."""
    out = object.__new__(_Problem)
    out.__dict__.update(prob.__dict__)
    out.residuals, out._cache = tuple(residuals), {}
    out._set_residual_columns()
    return out


def fit_frfs(frfs, *, noise: str | None = None, band=None, n_modes: int | None = None, **kw) -> ModalFit:
    """:func:`fit_modal` of FRF objects (one structure, one input, one grid).

    The noise quantity is, in order: ``noise``; the quantity the file held
    (``frf.meta["file_quantity"]``, set by the readers, which convert to receptance);
    the FRF's own ``quantity``. ``frf.meta["coherence"]`` ((F,) γ²), when every FRF
    has it, gives the point weights. The first FRF with a true ``frf.meta["driving_point"]``
    is the ``driving_point`` of :func:`fit_modal` unless that is given.

    Parameters
    ----------
    frfs : FRF or sequence of FRF
        SISO FRFs on one frequency grid.
    noise, band, n_modes, **kw
        As in :func:`fit_modal`.

    Returns
    -------
    ModalFit
    """
    frfs = [frfs] if isinstance(frfs, FRF) else list(frfs)
    if not frfs:
        raise InputError("no FRF given", field="frf")
    for g in frfs:
        if not isinstance(g, FRF) or not g.is_siso:
            raise InputError("expected SISO FRFs", field="frf")
        if not np.array_equal(g.freq_hz, frfs[0].freq_hz):
            raise InputError(f"FRF {g.label!r} is on another frequency grid than {frfs[0].label!r}", field="frf")
    q = noise or frfs[0].meta.get("file_quantity", frfs[0].quantity)
    Y = np.stack([g.values for g in frfs], -1)
    quantity = frfs[0].quantity
    if any(g.quantity != quantity for g in frfs):
        Y = np.stack([g.to_receptance().values for g in frfs], -1)
        quantity = "receptance"
    if "driving_point" not in kw:
        flagged = [k for k, g in enumerate(frfs) if g.meta.get("driving_point")]
        kw["driving_point"] = flagged[0] if flagged else None
    if "coherence" not in kw and all("coherence" in g.meta for g in frfs):
        kw["coherence"] = np.stack([np.asarray(g.meta["coherence"], float).reshape(-1) for g in frfs], -1)
    return fit_modal(frfs[0].freq_hz, Y, quantity=quantity, noise=q, band=band, n_modes=n_modes,
                     labels=[g.label for g in frfs], **kw)
