"""Hybrid: a short global search, then local least squares on the same objective.

1. **Global stage** — any of the population methods (default scipy's
   differential evolution, 40 members) with a small budget, to land in the
   basin of the global minimum;
2. **Local stage** — ``scipy.optimize.least_squares`` (trust-region
   reflective, bounds in log10 space) on the stacked real/imaginary residuals,
   whose sum of squares is the square of the paper's objective, with the exact
   Jacobian of the coupled receptance (each Jacobian counted as 4 evaluations).
   It starts from the ``starts`` best distinct points of the global stage and
   keeps the best end point.

Least squares converges quadratically near the minimum, which is why the
hybrid needs orders of magnitude fewer model evaluations than GA/SA/PSO.
See :class:`Hybrid`.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from .base import CONVERGED, MAXFEV, OTHER, Optimizer, Termination, Tracker, from_unit, start_unit
from .de import DE

__all__ = ["Hybrid"]


class _Recorder:
    """Wraps a problem to remember every point the global stage evaluates (start points for least squares)."""

    def __init__(self, problem, x_start=None):
        self.p = problem
        self.n_var, self.xl, self.xu = problem.n_var, problem.xl, problem.xu
        self.x_start = x_start  # seen by the global stage (one member there)
        self.X: list[np.ndarray] = []
        self.F: list[np.ndarray] = []

    @property
    def nfev(self):
        return self.p.nfev

    def evaluate(self, X):
        X = np.atleast_2d(X)
        F = self.p.evaluate(X)
        self.X.append(X)
        self.F.append(F)
        return F

    def best_distinct(self, k: int, min_dist: float = 0.1, first=None) -> np.ndarray:
        """The k best points at least ``min_dist`` apart (unit-cube distance); ``first`` (log10), when
        given, is the first of them and the others keep their distance from it too."""
        X, F = np.vstack(self.X), np.concatenate(self.F)
        U = (X - self.xl) / (self.xu - self.xl)
        chosen = [] if first is None else [np.asarray(first, float)]
        for i in np.argsort(F):
            if len(chosen) >= k:
                break
            if all(np.linalg.norm(U[i] - (c - self.xl) / (self.xu - self.xl)) >= min_dist for c in chosen):
                chosen.append(X[i])
        return np.array(chosen)


class Hybrid(Optimizer):
    """A short global search, then ``scipy.optimize.least_squares`` from its best distinct points.

    Parameters
    ----------
    global_stage : optimiser, default ``DE(popsize=10, maxiter=40, tol=1e-3)``
        Any of GA, SA, PSO, DE (an instance), run first with its own options.
    starts : int, default 3
        Least-squares runs, from the best global-stage points at least 0.1 apart (unit cube).
    tol : float, default 1e-14
        ``ftol``, ``xtol`` and ``gtol`` of ``least_squares`` (trust-region reflective).
    local_maxfev : int, default 200
        ``max_nfev`` of each ``least_squares`` run (residual evaluations).
    maxiter, maxfev : int or None, default None
        When given, replace the global stage's ``maxiter`` / ``maxfev``.
    use_start : {"seed", "local", "ignore"}, default "seed"
        What to do with the problem's starting point (``x_start``, e.g. ``[identify] start`` or the assembly's
        values, :class:`~toolpoint.identification.problem.FRFProblem`), when it has one: ``"seed"`` — one
        member of the global stage's population and the first least-squares start (the others are the best
        distinct global-stage points); ``"local"`` — least squares from the start only, no global stage (far
        fewer evaluations; the answer is the minimum of the start's basin, so use it for a start known to be
        close); ``"ignore"`` — as if there were none.

    Notes
    -----
    Deprecated option name (one release): ``max_local_iterations`` → ``local_maxfev``.

    Result: ``x``, ``fun`` of the best least-squares end point (with ``use_start="local"``: ``nit`` 0,
    ``global_stage`` None); ``success`` = that run converged
    (``least_squares`` status > 0), ``status`` 0 then, 2 if it hit ``local_maxfev``, 3 otherwise (scipy's
    own code is in ``status_local``); ``nit`` = global-stage iterations, ``nit_local`` = least-squares
    residual evaluations summed over the starts, ``nfev`` = all model evaluations (a Jacobian counts 4),
    ``global_nfev`` and ``global_stage`` (the global stage's result).

    Examples
    --------
    >>> Hybrid().global_stage.maxiter, Hybrid(maxiter=10).global_stage.maxiter
    (40, 10)
    """

    name = "hybrid"
    _OPTIONS = ("global_stage", "starts", "tol", "local_maxfev", "maxiter", "maxfev", "use_start")

    def __init__(self, *, global_stage=None, starts: int = 3, tol: float = 1e-14, local_maxfev: int = 200,
                 maxiter: int | None = None, maxfev: int | None = None, use_start: str = "seed"):
        if use_start not in ("seed", "local", "ignore"):
            raise ValueError(f"Hybrid: use_start must be 'seed', 'local' or 'ignore', got {use_start!r}")
        self.use_start = use_start
        stage = global_stage or DE(popsize=10, maxiter=40, tol=1e-3)
        changes = {k: v for k, v in (("maxiter", maxiter), ("maxfev", maxfev)) if v is not None}
        self.global_stage = stage.with_options(**changes) if changes else stage
        self.starts = starts
        self.tol = tol
        self.local_maxfev = local_maxfev
        self.maxiter = maxiter
        self.maxfev = maxfev

    def termination(self) -> Termination:
        """The global stage's stopping rules (the local stage stops on ``tol`` / ``local_maxfev``)."""
        return self.global_stage.termination()

    def _with_termination(self, term: Termination) -> "Hybrid":
        return self.with_options(global_stage=self.global_stage._with_termination(term), maxiter=None,
                                 maxfev=None)

    def _minimize(self, problem, rng: np.random.Generator, callback=None):
        tr = Tracker(problem, Termination(), callback)
        s0 = None if self.use_start == "ignore" else start_unit(problem)
        x_start = None if s0 is None else from_unit(problem, s0)
        if self.use_start == "local" and x_start is None:
            from ...errors import InputError

            raise InputError("the hybrid's use_start='local' needs a starting point (give [identify] start or "
                             "the values in the assembly)", field="start")
        if self.use_start == "local":
            g, x0s = None, [x_start]
        else:
            rec = _Recorder(problem, x_start)
            g = self.global_stage.minimize(rec, rng, callback=callback)
            x0s = rec.best_distinct(self.starts, first=x_start)
        best, best_f, nit_local, njev_local = None, np.inf, 0, 0
        for x0 in x0s:
            r = least_squares(
                problem.residuals,
                x0,
                jac=problem.jacobian,
                bounds=(problem.xl, problem.xu),
                method="trf",
                x_scale="jac",
                ftol=self.tol,
                xtol=self.tol,
                gtol=self.tol,
                max_nfev=self.local_maxfev,
            )
            f = float(np.sqrt(2 * r.cost)) * problem.residual_scale
            nit_local += r.nfev
            njev_local += r.njev
            if best is None or f < best_f:
                best, best_f = r, f
        # least squares never ends above its start, so its best end point is the best point found
        tr.best_x, tr.best_f = best.x, best_f
        tr.nit = 0 if g is None else g.nit
        tr.history = [*([] if g is None else g.history), best_f]
        status = CONVERGED if best.status > 0 else (MAXFEV if best.status == 0 else OTHER)
        how = ("no global stage" if g is None else f"global stage ({self.global_stage.name}): {g.message}")
        first = ", the first the given start" if x_start is not None else ""
        tr.stop(status, f"least squares (best of {len(x0s)} starts{first}): {best.message}; {how}")
        return tr.result(self.name, nit_local=nit_local, njev_local=njev_local, status_local=int(best.status),
                         global_nfev=0 if g is None else g.nfev, global_stage=g)
