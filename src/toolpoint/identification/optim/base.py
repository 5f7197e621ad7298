"""What the optimisers share: termination criteria, progress tracking, result.

In pymoo's spirit the *problem* (:class:`toolpoint.identification.objective.JointProblem`:
``evaluate(X)``, bounds ``xl``/``xu``, ``nfev``), the *algorithm* (GA, PSO, SA,
DE, hybrid; options in ``__init__``) and the *termination* are separate. Every
algorithm works on the unit cube internally and reports a scipy-style
``OptimizeResult``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult


@dataclass(frozen=True)
class Termination:
    """When to stop (whichever comes first).

    max_iter : iterations (generations); max_evals : model evaluations (points);
    stall_iter / ftol : stop when the best objective improved by less than
    ftol (relative) over the last ``stall_iter`` iterations (MATLAB's
    MaxStallGenerations / FunctionTolerance); f_target : stop when reached.
    """

    max_iter: int | None = None
    max_evals: int | None = None
    stall_iter: int | None = None
    ftol: float = 1e-6
    f_target: float | None = None


class Tracker:
    """Best point so far, per-iteration history, termination and callback."""

    def __init__(self, problem, termination: Termination, callback=None):
        self.problem = problem
        self.term = termination
        self.callback = callback
        self.nfev0 = problem.nfev
        self.t0 = time.perf_counter()
        self.best_x = None
        self.best_f = np.inf
        self.history: list[float] = []
        self.nit = 0
        self.message = "maximum number of iterations reached"

    @property
    def nfev(self) -> int:
        return self.problem.nfev - self.nfev0

    def offer(self, X: np.ndarray, F: np.ndarray) -> None:
        """Consider evaluated points X (N, 4) with objectives F (N,)."""
        k = int(np.argmin(F))
        if F[k] < self.best_f:
            self.best_f = float(F[k])
            self.best_x = np.array(X[k], float)

    def next_iteration(self) -> bool:
        """Record the iteration; True when a termination criterion is met."""
        self.nit += 1
        self.history.append(self.best_f)
        if self.callback is not None:
            self.callback(self.nit, self.best_f, self.nfev)
        t = self.term
        if t.f_target is not None and self.best_f <= t.f_target:
            self.message = "objective target reached"
            return True
        if t.max_evals is not None and self.nfev >= t.max_evals:
            self.message = "maximum number of evaluations reached"
            return True
        if t.max_iter is not None and self.nit >= t.max_iter:
            self.message = "maximum number of iterations reached"
            return True
        if t.stall_iter and len(self.history) > t.stall_iter:
            old = self.history[-1 - t.stall_iter]
            if old - self.best_f <= t.ftol * max(abs(old), 1e-300):
                self.message = f"best objective changed less than ftol={t.ftol:g} over {t.stall_iter} iterations"
                return True
        return False

    def result(self, method: str, success: bool = True, **extra) -> OptimizeResult:
        return OptimizeResult(
            x=self.best_x,
            fun=self.best_f,
            nfev=self.nfev,
            nit=self.nit,
            seconds=time.perf_counter() - self.t0,
            history=np.array(self.history),
            message=self.message,
            success=success,
            method=method,
            **extra,
        )


def to_unit(problem, X):
    return (np.asarray(X) - problem.xl) / (problem.xu - problem.xl)


def from_unit(problem, U):
    return problem.xl + np.asarray(U) * (problem.xu - problem.xl)
