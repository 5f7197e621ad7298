"""Identification problem: the holder–tool joint from a measured tool-point FRF.

Unknowns p = [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad] (Eq. 7), searched as
x = log10 p because they span decades. The objective is the paper's Eq. (8):
the Euclidean norm of the complex difference between model and measurement,
real and imaginary parts together,

    f(x) = ‖h(10^x) − h̄‖₂ = sqrt(Σ_j |h(ω_j) − h̄(ω_j)|²)   (m/N).

A whole population X (N, 4) is evaluated in one call, vectorised over
frequencies and members (see :class:`~toolpoint.dynamics.coupling.ToolPointCoupler`:
with e = (T_ii,00 − h̄)·den − num, linear in the joint coefficients c(p),
f² = Σ|e|²/|den|² is two real matrix products per block of members).
"""

from __future__ import annotations

import numpy as np

from ..dynamics.coupling import CHUNK, ToolPointCoupler, joint_coefficients
from ..frf import FRF
from .params import Bounds

__all__ = ["JointProblem"]


class JointProblem:
    """Minimise f(x) over x = log10 [kt, ct, kr, cr] within ``bounds``.

    Parameters
    ----------
    coupler : ToolPointCoupler
        Coupling on the measured frequencies (see :class:`toolpoint.dynamics.model.ToolPointModel`).
    measured : (F,) complex array or FRF
        Measured tool-point receptance, m/N.
    bounds : Bounds, optional
        Search bounds, SI (default the paper's).

    Attributes
    ----------
    xl, xu : (4,) ndarray
        log10 of the bounds.
    residual_scale : float
        RMS of |measured|, m/N: least-squares residuals are divided by it.
    nfev : int
        Model evaluations so far, counted as points (members), not calls.
    """

    n_var = 4

    def __init__(self, coupler: ToolPointCoupler, measured, bounds: Bounds | None = None):
        self.coupler = coupler
        self.measured = np.asarray(measured.values if isinstance(measured, FRF) else measured, complex)
        if self.measured.shape != coupler.t00.shape:
            raise ValueError("measured FRF and model frequencies differ")
        self.bounds = bounds or Bounds.from_dict()
        self.xl, self.xu = self.bounds.log_lo, self.bounds.log_hi
        d = coupler.t00 - self.measured
        self._E = (d * coupler.B_den - coupler.B_num).view(float)  # (8, 2F) real view
        self._D = coupler.B_den.view(float)
        # residuals for least squares are divided by the RMS of the measurement:
        # O(1) numbers keep scipy's absolute gradient tolerance meaningful
        self.residual_scale = float(np.sqrt(np.mean(np.abs(self.measured) ** 2))) or 1.0
        self.nfev = 0

    def evaluate(self, X) -> np.ndarray:
        """Objective f (N,) for X (N, 4) or (4,) in log10 space; m/N."""
        X = np.asarray(X, float)
        single = X.ndim == 1
        c = joint_coefficients(10.0 ** np.atleast_2d(X))
        out = np.empty(c.shape[0])
        for s in range(0, c.shape[0], CHUNK):  # cache-sized blocks (see coupling.CHUNK)
            x = c[s : s + CHUNK]
            e = x @ self._E
            d = x @ self._D
            e *= e
            d *= d
            num = e[:, ::2] + e[:, 1::2]  # |e|²
            den = d[:, ::2] + d[:, 1::2]  # |den|²
            out[s : s + CHUNK] = np.sqrt(np.einsum("ij,ij->i", num, 1.0 / den))
        self.nfev += c.shape[0]
        return out[0] if single else out

    __call__ = evaluate

    def residuals(self, x) -> np.ndarray:
        """Stacked real and imaginary residuals (2F,) at one x (log10), in units of
        ``residual_scale`` (so f = residual_scale · ‖residuals‖)."""
        r = (self.coupler(10.0 ** np.asarray(x, float)) - self.measured) / self.residual_scale
        self.nfev += 1
        return np.concatenate([r.real, r.imag])

    def jacobian(self, x) -> np.ndarray:
        """∂residuals/∂x (2F, 4) in log10 space (exact; counted as 4 evaluations)."""
        p = 10.0 ** np.asarray(x, float)
        J = self.coupler.jacobian(p[None])[0] * (np.log(10.0) * p / self.residual_scale)[:, None]  # (4, F)
        self.nfev += self.n_var
        return np.concatenate([J.real, J.imag], axis=1).T

    def model(self, x) -> np.ndarray:
        """Model tool-point receptance (F,) at one x (log10); not counted."""
        return self.coupler(10.0 ** np.asarray(x, float))
