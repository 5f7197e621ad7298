r"""Confidence intervals and identifiability of the identified joint.

Linearising the residuals r(x) (stacked real and imaginary parts, n = 2F
values) about the least-squares optimum x̂ in log10 space, with Jacobian J and
residual variance s² = ‖r‖² / (n − 4),

    cov(x̂) = s² (JᵀJ)⁻¹,    x̂_i ± t₀.₉₇₅,ₙ₋₄ · sqrt(cov_ii)

is the 95 % interval of log10 p_i (t from :func:`~toolpoint.identification.params.ci_quantile`);
back-transformed it is [p̂/q, p̂·q] with q = 10^(t·se). (JᵀJ)⁻¹ is formed from
the SVD of J, so a direction the data do not see gets an infinite variance
instead of a round-off number.

A parameter is flagged as not identifiable from this FRF when its interval
spans more than a factor :data:`~toolpoint.identification.params.IDENTIFIED_RATIO`
(2) or it sits on a search bound. The correlation ρ_ij = cov_ij / sqrt(cov_ii cov_jj) says which
parameters trade off: a flagged parameter's message names its partners with
|ρ| > :data:`~toolpoint.identification.params.CORRELATION_LIMIT` (0.95), and with ``pairs=True`` every
such pair gets its own message.
"""

from __future__ import annotations

import numpy as np

from .params import CORRELATION_LIMIT, IDENTIFIED_RATIO, PARAMS, UNITS, Bounds, ci_quantile, interval_ratio

__all__ = ["confidence_intervals", "intervals_and_correlation", "identifiability_warnings"]


def confidence_intervals(problem, x_log, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Linearised confidence intervals of the joint parameters at ``x_log``.

    Parameters
    ----------
    problem : JointProblem
        Supplies ``residuals(x)`` and ``jacobian(x)`` (log10 space; 5 evaluations are counted).
    x_log : (4,) array
        log10 [kt, ct, kr, cr] (SI), normally the least-squares optimum.
    level : float, default 0.95
        Two-sided confidence level.

    Returns
    -------
    ci : (4, 2) ndarray
        [lo, hi] per parameter, SI units (N/m, N s/m, N m/rad, N m s/rad); [0, inf] where the data do not
        see the parameter.
    se : (4,) ndarray
        Standard errors of log10 p (inf where unseen, 0 when the fit is exact).
    """
    ci, se, _ = intervals_and_correlation(problem, x_log, level)
    return ci, se


def intervals_and_correlation(problem, x_log, level: float = 0.95):
    """:func:`confidence_intervals` and the correlation matrix of the log10 parameters.

    Returns
    -------
    ci : (n, 2) ndarray
    se : (n,) ndarray
    corr : (n, n) ndarray
        ρ_ij of log10 p (from (JᵀJ)⁻¹, so defined even for an exact fit); NaN where a direction is unseen.

    Examples
    --------
    Two parameters that only enter as their sum trade off completely (ρ = −1 is reported as NaN there:
    the direction is unseen; here a tiny difference keeps it finite):

    >>> class P:
    ...     def residuals(self, x): return np.array([x[0] + x[1], x[0] + 1.001 * x[1], 0.1])
    ...     def jacobian(self, x): return np.array([[1.0, 1.0], [1.0, 1.001], [0.0, 0.0]])
    >>> round(float(intervals_and_correlation(P(), np.zeros(2))[2][0, 1]), 4)
    -1.0
    """
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
    half = ci_quantile(dof, level) * se
    with np.errstate(over="ignore"):
        ci = np.stack([10 ** (x - half), 10 ** (x + half)], -1)
    cov = np.einsum("ki,k,kj->ij", Vt, inv_sv2, Vt) if np.all(np.isfinite(inv_sv2)) else np.full((x.size,) * 2, np.nan)
    d = np.sqrt(np.diag(cov))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(d, d)
    return ci, se, corr


def identifiability_warnings(x_log, ci, bounds: Bounds, max_ratio: float = IDENTIFIED_RATIO,
                             bound_tol: float = 1e-3, *, names=PARAMS, units=None, corr=None,
                             corr_limit: float = CORRELATION_LIMIT, pairs: bool = False) -> list[str]:
    """Messages for parameters that the FRF does not determine.

    Parameters
    ----------
    x_log : (4,) array
        Identified log10 [kt, ct, kr, cr] (SI).
    ci : (4, 2) array
        95 % intervals, SI (from :func:`confidence_intervals`).
    bounds : Bounds
        Search bounds, SI.
    max_ratio : float, default IDENTIFIED_RATIO (2)
        An interval with hi/lo above this is "not identifiable".
    bound_tol : float, default 1e-3
        A value within this fraction of the log10 bound range from a bound "sits on" it.
    names : sequence of str, default PARAMS
        Parameter names, in order.
    units : dict, optional
        name → unit (default :data:`~toolpoint.identification.params.UNITS`).
    corr : (n, n) array, optional
        Correlation of the log10 parameters (:func:`intervals_and_correlation`): a not-identifiable
        parameter's message then names the parameters it trades off with (|ρ| > ``corr_limit``).
    corr_limit : float, default CORRELATION_LIMIT (0.95)
    pairs : bool, default False
        Also one message per pair with |ρ| > ``corr_limit`` (``"A and B trade off …"``).

    Returns
    -------
    list of str
        One message per finding, starting with the parameter name (e.g. ``"cr is not identifiable …"``).

    Examples
    --------
    >>> b = Bounds.from_dict()
    >>> x = np.log10([2.1e7, 15.0, 1.4e6, 3.0])
    >>> ci = np.array([[2.0e7, 2.2e7], [14.0, 16.0], [1.3e6, 1.5e6], [0.5, 18.0]])
    >>> [w.split(":")[0] for w in identifiability_warnings(x, ci, b)]
    ['cr is not identifiable from this FRF']
    """
    out = []
    x = np.asarray(x_log, float)
    ci = np.asarray(ci, float)
    units = UNITS if units is None else units
    ratios = interval_ratio(ci[:, 0], ci[:, 1])
    span = bounds.log_hi - bounds.log_lo
    rho = None if corr is None else np.asarray(corr, float)
    for i, name in enumerate(names):
        lo, hi = ci[i]
        if not ratios[i] <= max_ratio:
            partners = "" if rho is None else ", ".join(
                f"{names[j]} (ρ = {rho[i, j]:+.3f})" for j in range(len(names))
                if j != i and abs(rho[i, j]) > corr_limit)
            out.append(
                f"{name} is not identifiable from this FRF: its 95 % interval {lo:.3g}–{hi:.3g} {units[name]} "
                f"spans a factor {ratios[i]:.3g} (> {max_ratio:g})" + (f"; it trades off with {partners}"
                                                                       if partners else "")
            )
        for b, side in ((bounds.log_lo[i], "lower"), (bounds.log_hi[i], "upper")):
            if abs(x[i] - b) <= bound_tol * span[i]:
                out.append(
                    f"{name} = {10 ** x[i]:.4g} {units[name]} sits on the {side} search bound: "
                    "widen the bounds, or the FRF does not determine it"
                )
    if pairs and rho is not None:
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if abs(rho[i, j]) > corr_limit:
                    out.append(f"{names[i]} and {names[j]} trade off: correlation {rho[i, j]:+.4f} of their log10 "
                               f"estimates (|ρ| > {corr_limit:g}); the data fix a combination of them better than "
                               "either")
    return out
