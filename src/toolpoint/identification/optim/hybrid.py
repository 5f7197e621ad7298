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
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from .base import Termination, Tracker
from .de import DE


class _Recorder:
    """Wraps a problem to remember every point the global stage evaluates."""

    def __init__(self, problem):
        self.p = problem
        self.n_var, self.xl, self.xu = problem.n_var, problem.xl, problem.xu
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

    def best_distinct(self, k: int, min_dist: float = 0.1) -> np.ndarray:
        """The k best points at least ``min_dist`` apart (unit-cube distance)."""
        X, F = np.vstack(self.X), np.concatenate(self.F)
        U = (X - self.xl) / (self.xu - self.xl)
        chosen: list[int] = []
        for i in np.argsort(F):
            if all(np.linalg.norm(U[i] - U[j]) >= min_dist for j in chosen):
                chosen.append(int(i))
            if len(chosen) == k:
                break
        return X[chosen]


class Hybrid:
    name = "hybrid"

    def __init__(self, global_stage=None, starts: int = 3, tol: float = 1e-14, max_local_iterations: int = 200):
        self.global_stage = global_stage or DE(popsize=10, maxiter=40, tol=1e-3)
        self.starts = starts
        self.tol = tol
        self.max_local_iterations = max_local_iterations

    def termination(self) -> Termination:
        return self.global_stage.termination()

    def minimize(self, problem, rng: np.random.Generator, termination: Termination | None = None, callback=None):
        tr = Tracker(problem, termination or Termination(max_iter=1), callback)
        rec = _Recorder(problem)
        g = self.global_stage.minimize(rec, rng, termination, callback)
        tr.history = list(g.history)
        tr.nit = g.nit
        best_x, best_f = g.x, g.fun
        for x0 in rec.best_distinct(self.starts):
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
                max_nfev=self.max_local_iterations,
            )
            f = float(np.sqrt(2 * r.cost)) * problem.residual_scale
            tr.nit += r.nfev
            if f < best_f:
                best_x, best_f = r.x, f
        tr.best_x, tr.best_f = best_x, best_f
        tr.history.append(best_f)
        tr.message = f"global stage ({self.global_stage.name}): {g.message}; then least squares from {self.starts} starts"
        return tr.result(self.name, global_nfev=g.nfev)
