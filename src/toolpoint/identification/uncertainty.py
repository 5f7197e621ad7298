"""Confidence intervals and identifiability of the identified joint.

Linearising the residuals r(x) (stacked real and imaginary parts, n = 2F
values) about the least-squares optimum x̂ in log10 space, with Jacobian J and
residual variance s² = ‖r‖² / (n − 4),

    cov(x̂) = s² (JᵀJ)⁻¹,    x̂_i ± t₀.₉₇₅,ₙ₋₄ · sqrt(cov_ii)

is the 95 % interval of log10 p_i; back-transformed it is [p̂/q, p̂·q] with
q = 10^(t·se). (JᵀJ)⁻¹ is formed from the SVD of J, so a direction the data do
not see gets an infinite variance instead of a round-off number.

A parameter is flagged as not identifiable from this FRF when its interval
spans more than a factor ``max_ratio`` (default 2) or it sits on a search bound.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import t as student_t

from .params import PARAMS, UNITS


def confidence_intervals(problem, x_log, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """(ci (4, 2) in SI units, standard errors (4,) of log10 p) at x_log."""
    x = np.asarray(x_log, float)
    r = problem.residuals(x)
    J = problem.jacobian(x)
    dof = max(r.size - x.size, 1)
    s2 = float(r @ r) / dof
    _, sv, Vt = np.linalg.svd(J, full_matrices=False)
    with np.errstate(divide="ignore"):
        inv_sv2 = np.where(sv > sv.max() * 1e-13, 1.0 / sv**2, np.inf)
    var = np.einsum("ki,k,ki->i", Vt, inv_sv2, Vt) * s2 if s2 > 0 else np.zeros(x.size)
    var = np.where(np.isnan(var), np.inf, var)  # 0·inf when the fit is exact
    se = np.sqrt(var)
    half = student_t.ppf(0.5 + level / 2, dof) * se
    with np.errstate(over="ignore"):
        ci = np.stack([10 ** (x - half), 10 ** (x + half)], -1)
    return ci, se


def identifiability_warnings(x_log, ci, bounds, max_ratio: float = 2.0, bound_tol: float = 1e-3) -> list[str]:
    """Warnings for parameters with wide intervals or at a search bound."""
    out = []
    x = np.asarray(x_log, float)
    span = bounds.log_hi - bounds.log_lo
    for i, name in enumerate(PARAMS):
        lo, hi = ci[i]
        with np.errstate(over="ignore"):
            ratio = hi / lo if lo > 0 else np.inf
        if not np.isfinite(ratio) or ratio > max_ratio:
            out.append(
                f"{name} is not identifiable from this FRF: its 95 % interval {lo:.3g}–{hi:.3g} {UNITS[name]} "
                f"spans a factor {ratio:.3g} (> {max_ratio:g})"
            )
        for b, side in ((bounds.log_lo[i], "lower"), (bounds.log_hi[i], "upper")):
            if abs(x[i] - b) <= bound_tol * span[i]:
                out.append(
                    f"{name} = {10 ** x[i]:.4g} {UNITS[name]} sits on the {side} search bound: "
                    "widen the bounds, or the FRF does not determine it"
                )
    return out
