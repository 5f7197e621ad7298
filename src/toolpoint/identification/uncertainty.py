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

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, least_squares

from .params import CORRELATION_LIMIT, IDENTIFIED_RATIO, PARAMS, UNITS, Bounds, ci_quantile, interval_ratio

__all__ = ["confidence_intervals", "intervals_and_correlation", "identifiability_warnings", "profile_intervals",
           "ProfileResult", "open_end_warnings"]


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


@dataclass(frozen=True)
class ProfileResult:
    """Profile-likelihood intervals (:func:`profile_intervals`).

    Attributes
    ----------
    ci : (n, 2) ndarray
        [lo, hi] per parameter, SI.
    open_end : (n, 2) bool ndarray
        True where the interval runs into the search bound on that side (the data do not bound the
        parameter there; the end reported is the bound).
    x_better : (n,) ndarray or None
        A point (log10) met while profiling whose sum of squares is lower than at ``x_log`` by more than
        0.1 % of the interval's threshold rise (the search had not found the least-squares minimum), else None.
    nfev : int
        Model evaluations spent (a Jacobian counted as ``n_var``).
    """

    ci: np.ndarray
    open_end: np.ndarray
    x_better: np.ndarray | None
    nfev: int


def profile_intervals(problem, x_log, se=None, level: float = 0.95, xtol: float = 1e-4) -> ProfileResult:
    r"""Profile-likelihood 95 % intervals of every parameter (log10 space, search bounds respected).

    With S(x) = ‖r(x)‖² (the problem's scaled residuals), Ŝ = S(x̂), s² = Ŝ/(n − p) and the profile
    S_i(θ) = min over the other parameters of S with x_i = θ (least squares, exact Jacobian, within the
    bounds), the interval of x_i is

        {θ : S_i(θ) − Ŝ ≤ t²_{0.975, n−p} s²},

    the likelihood-ratio interval of a Gaussian least-squares fit (it equals the linearised interval
    when the model is linear; unlike that one it follows the curved valleys along which parameters trade
    off and stops at the search bounds). Each end is bracketed by steps of growing length from x̂ (the
    first the linearised half-width) and found by Brent's method to ``xtol`` (log10), or to 0.1 % of the
    linearised half-width when that is smaller. An exact fit (Ŝ = 0) gives the point x̂.

    Parameters
    ----------
    problem
        ``residuals(x)``, ``jacobian(x)``, bounds ``xl``/``xu``, ``nfev``.
    x_log : (n,) array
        The least-squares optimum, log10 SI.
    se : (n,) array, optional
        Linearised standard errors of log10 p (first step); default 0.05 of the bound range.
    level : float, default 0.95
    xtol : float, default 1e-4
        Tolerance of each end, log10 (0.023 %), at most.

    Returns
    -------
    ProfileResult

    Examples
    --------
    A one-parameter linear fit: the profile interval is the linearised one.

    >>> class P:
    ...     xl, xu, nfev = np.array([-5.0]), np.array([5.0]), 0
    ...     t = np.linspace(0, 1, 20)
    ...     y = 2.0 * t + 0.1 * np.sin(37 * t)
    ...     def residuals(self, x): return x[0] * self.t - self.y
    ...     def jacobian(self, x): return self.t[:, None]
    >>> r = profile_intervals(P(), np.array([P.y @ P.t / (P.t @ P.t)]))
    >>> lin, _, _ = intervals_and_correlation(P(), np.array([P.y @ P.t / (P.t @ P.t)]))
    >>> bool(np.allclose(np.log10(r.ci), np.log10(lin), atol=1e-4)), r.open_end.tolist()
    (True, [[False, False]])
    """
    x_hat = np.asarray(x_log, float)
    n_var = x_hat.size
    nfev0 = problem.nfev
    r0 = problem.residuals(x_hat)
    S0 = float(r0 @ r0)
    dof = max(r0.size - n_var, 1)
    thr = ci_quantile(dof, level) ** 2 * S0 / dof  # allowed rise of S
    xl, xu = np.asarray(problem.xl, float), np.asarray(problem.xu, float)
    best = [S0, None]
    ci = np.empty((n_var, 2))
    open_end = np.zeros((n_var, 2), bool)
    for i in range(n_var):
        others = np.arange(n_var) != i
        warm = {x_hat[i]: x_hat[others]}

        def rise(theta, i=i, others=others, warm=warm):
            """S_i(θ) − Ŝ − thr (negative inside the interval)."""
            x = x_hat.copy()
            x[i] = theta
            if others.any():
                near = min(warm, key=lambda t: abs(t - theta))
                z0 = np.clip(warm[near], xl[others], xu[others])

                def res(z):
                    x[others] = z
                    return problem.residuals(x)

                def jac(z):
                    x[others] = z
                    return problem.jacobian(x)[:, others]

                sol = least_squares(res, z0, jac=jac, bounds=(xl[others], xu[others]), method="trf",
                                    x_scale="jac", ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=100)
                x[others] = sol.x
                warm[theta] = sol.x
                S = 2 * float(sol.cost)
            else:
                r = problem.residuals(x)
                S = float(r @ r)
            # lower by more than 0.1 % of the interval's threshold: a real minimum elsewhere, not round-off of
            # the search (scipy versions end a converged search ~1e-7 S0 apart)
            if S < best[0] and S < S0 - 1e-3 * thr:
                best[0], best[1] = S, x.copy()
            return S - S0 - thr

        if thr == 0:  # an exact fit: the interval is the point
            ci[i] = x_hat[i]
            continue
        sd = se[i] if se is not None and np.isfinite(se[i]) and se[i] > 0 else 0.05 * (xu[i] - xl[i])
        if ci_quantile(dof, level) * sd < LINEAR_SCALE:
            # an interval this narrow (in decades) is where every smooth model is linear: the profile would only
            # follow round-off of the re-solves (noise-free data), so it is the linearised interval
            ci[i] = x_hat[i] + np.array([-1.0, 1.0]) * ci_quantile(dof, level) * sd
            continue
        tol = min(xtol, 1e-3 * ci_quantile(dof, level) * sd)  # narrow intervals: 0.1 % of their half-width
        for side, (lim, col) in enumerate(((xl[i], 0), (xu[i], 1))):
            sign = -1.0 if side == 0 else 1.0
            a, step = x_hat[i], ci_quantile(dof, level) * sd
            end = None
            while end is None:
                if sign * (lim - a) <= 0:  # x̂ on this bound
                    end, open_end[i, col] = lim, True
                    break
                b = a + sign * step
                if sign * (b - lim) >= 0:
                    b = lim
                if rise(b) > 0:
                    lo_, hi_ = sorted((a, b))
                    if hi_ - lo_ <= tol:
                        end = b
                    elif a == x_hat[i] and rise(a) >= 0:
                        # a fit at round-off (noise-free data): re-solving at x̂ itself lands above Ŝ + thr, so
                        # the interval is narrower than the search can resolve; it ends at x̂
                        end = a
                    else:
                        end = brentq(rise, lo_, hi_, xtol=tol)
                elif b == lim:
                    end, open_end[i, col] = lim, True
                else:
                    a, step = b, 4 * step
            ci[i, col] = end
    ci = 10.0**ci
    return ProfileResult(ci, open_end, best[1], problem.nfev - nfev0)


#: Half-width (decades of the parameter) below which a profile interval is the linearised one: 1e-6 decade is a
#: relative change of 2.3e-6, where a smooth model's curvature is below the re-solves' round-off.
LINEAR_SCALE = 1e-6


def open_end_warnings(prof: ProfileResult, names, units) -> list[str]:
    """Messages for the interval ends of ``prof`` that reached a search bound, and for a better point met.

    Examples
    --------
    >>> p = ProfileResult(np.array([[1.0, 4.0]]), np.array([[False, True]]), None, 0)
    >>> open_end_warnings(p, ["kt"], {"kt": "N/m"})[0].split(":")[0]
    'kt has a 95 % interval that runs into the upper search bound (4 N/m)'
    """
    out = []
    for i, name in enumerate(names):
        for side, col in (("lower", 0), ("upper", 1)):
            if prof.open_end[i, col]:
                out.append(f"{name} has a 95 % interval that runs into the {side} search bound "
                           f"({prof.ci[i, col]:.4g} {units[name]}): the data do not bound it on that side")
    if prof.x_better is not None:
        out.append("the search did not end at the least-squares minimum: profiling met a lower objective at "
                   + ", ".join(f"{n} = {10**v:.4g}" for n, v in zip(names, prof.x_better))
                   + " (search again, e.g. with more starts)")
    return out
