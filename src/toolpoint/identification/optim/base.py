"""What the optimisers share: stopping rules, status codes, progress tracking, result.

In pymoo's spirit the *problem* (:class:`toolpoint.identification.objective.JointProblem`:
``evaluate(X)``, bounds ``xl``/``xu``, ``nfev``) and the *algorithm* (GA, PSO,
SA, DE, hybrid) are separate. Every option of an algorithm, the stopping rules
included, is an argument of its ``__init__`` (scipy style, scipy's names:
``maxiter``, ``maxfev``, ``popsize``, ``tol``); :class:`Termination` is only
the read-only summary of the stopping rules that the algorithm derives from
them (:meth:`Optimizer.termination`).

Every algorithm works on the unit cube of x = log10 p internally and returns a
``scipy.optimize.OptimizeResult`` whose ``x`` and ``fun`` are in the
optimiser's own space (log10 of the parameters; objective in m/N) and whose
``success``/``status``/``message`` give the actual reason it stopped:

====== ====================================================================
status meaning
====== ====================================================================
0      converged: the stall test held (the best objective changed by at most
       ``tol``, relative, over the last ``stall_iter`` iterations), the
       objective target ``f_target`` was reached, or (DE) scipy's own
       convergence test held, or (hybrid) least squares converged
1      iteration limit ``maxiter`` reached
2      evaluation limit ``maxfev`` reached (hybrid: least squares hit its
       ``local_maxfev``)
3      stopped for another reason (the message says which)
====== ====================================================================

``success`` is ``status == 0``: a run that hits a cap is not a success even
if its answer is good, unless a convergence test held at the same iteration.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult

__all__ = ["CONVERGED", "MAXITER", "MAXFEV", "OTHER", "STATUS_MESSAGES", "Termination", "Optimizer", "Tracker",
           "horizon", "to_unit", "from_unit", "start_unit"]

CONVERGED, MAXITER, MAXFEV, OTHER = 0, 1, 2, 3
#: One-line meaning of each status code (the ``message`` adds the details).
STATUS_MESSAGES = {
    CONVERGED: "converged",
    MAXITER: "maximum number of iterations reached",
    MAXFEV: "maximum number of evaluations reached",
    OTHER: "stopped",
}

@dataclass(frozen=True, init=False)
class Termination:
    """Stopping rules of one run (whichever holds first), derived from the algorithm's options.

    Parameters
    ----------
    maxiter : int or None
        Iteration (generation) limit; the initial population counts as iteration 1.
    maxfev : int or None
        Model-evaluation limit (points evaluated, :attr:`JointProblem.nfev`).
    stall_iter : int or None
        Stall window, iterations; None disables the stall test.
    tol : float, default 1e-6
        Stall test: stop (converged) when the best objective f improved by at
        most ``tol`` relative to its value ``stall_iter`` iterations ago,
        f_old − f_best ≤ tol · f_old.
    f_target : float or None
        Stop (converged) when the best objective is ≤ this value, m/N.

    Examples
    --------
    >>> Termination(maxiter=100, stall_iter=10, tol=1e-6).maxfev is None
    True
    """

    maxiter: int | None
    maxfev: int | None
    stall_iter: int | None
    tol: float
    f_target: float | None

    def __init__(self, maxiter: int | None = None, maxfev: int | None = None, stall_iter: int | None = None,
                 tol: float = 1e-6, f_target: float | None = None):
        object.__setattr__(self, "maxiter", maxiter)
        object.__setattr__(self, "maxfev", maxfev)
        object.__setattr__(self, "stall_iter", stall_iter)
        object.__setattr__(self, "tol", float(tol))
        object.__setattr__(self, "f_target", f_target)

    def as_options(self) -> dict:
        """The same rules as algorithm options (``maxiter``, ``maxfev``, ``stall_iter``, ``tol``, ``f_target``)."""
        return {"maxiter": self.maxiter, "maxfev": self.maxfev, "stall_iter": self.stall_iter, "tol": self.tol,
                "f_target": self.f_target}


def horizon(term: Termination, first: int, per_iter: int) -> int | None:
    """Iterations a run can last under ``term``: the smaller of ``maxiter`` and what ``maxfev`` affords.

    Parameters
    ----------
    term : Termination
    first : int
        Evaluations of the first iteration (the initial population).
    per_iter : int
        Evaluations of each later iteration.

    Returns
    -------
    int or None
        H such that the run stops at iteration H at the latest (None: unbounded). With an evaluation budget
        B ≥ ``first`` the last iteration is 1 + ⌈(B − first) / per_iter⌉ (the last may evaluate only part of
        the population, to stay within B).

    Examples
    --------
    >>> horizon(Termination(maxiter=280), 120, 120), horizon(Termination(maxiter=280, maxfev=1200), 120, 120)
    (280, 10)
    """
    caps = []
    if term.maxiter is not None:
        caps.append(int(term.maxiter))
    if term.maxfev is not None:
        caps.append(1 + math.ceil(max(term.maxfev - first, 0) / max(per_iter, 1)))
    return max(min(caps), 1) if caps else None


class Optimizer:
    """Shared machinery of the optimisers: options, stopping rules and the ``minimize`` entry point.

    Subclasses set ``name``, ``_OPTIONS`` (their keyword-only ``__init__`` arguments) and implement
    ``_minimize(problem, rng, callback)``.
    """

    name = ""
    _OPTIONS: tuple[str, ...] = ()

    # These stopping options exist on every population method (DE and the hybrid override the defaults).
    maxiter: int | None = None
    maxfev: int | None = None
    stall_iter: int | None = None
    tol: float = 0.0
    f_target: float | None = None

    def options(self) -> dict:
        """The options of this instance, as keyword arguments of its class."""
        return {k: getattr(self, k) for k in self._OPTIONS}

    def with_options(self, **changes):
        """A copy with some options changed (new names only)."""
        unknown = set(changes) - set(self._OPTIONS)
        if unknown:
            raise TypeError(f"{type(self).__name__}: unknown option(s) {', '.join(sorted(unknown))}")
        return type(self)(**{**self.options(), **changes})

    def termination(self) -> Termination:
        """The stopping rules these options define."""
        return Termination(maxiter=self.maxiter, maxfev=self.maxfev, stall_iter=self.stall_iter, tol=self.tol,
                           f_target=self.f_target)

    def minimize(self, problem, rng: np.random.Generator, callback=None) -> OptimizeResult:
        """Minimise ``problem`` from the random state ``rng``.

        Parameters
        ----------
        problem : JointProblem
            ``evaluate(X)`` for X (N, 4) in log10 space, bounds ``xl``/``xu``, counter ``nfev``.
        rng : numpy.random.Generator
            The only source of randomness: the same seed gives the same run.
        callback : callable, optional
            ``callback(nit, best_f, nfev)`` after every iteration.

        Returns
        -------
        scipy.optimize.OptimizeResult
            ``x`` (log10 p), ``fun`` (m/N), ``nfev``, ``nit``, ``success``, ``status`` (see the module
            table), ``message``, ``history`` (best objective per iteration, m/N), ``seconds``, ``method``.
        """
        return self._minimize(problem, rng, callback)

    def _minimize(self, problem, rng, callback) -> OptimizeResult:  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in self.options().items())})"


class Tracker:
    """Best point so far, per-iteration history, stopping rules and callback of one run.

    Parameters
    ----------
    problem : JointProblem (or a wrapper with ``nfev``)
    termination : Termination
    callback : callable, optional
        ``callback(nit, best_f, nfev)`` after every iteration.
    """

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
        self.status: int | None = None  # set when a stopping rule held
        self.message = ""

    @property
    def nfev(self) -> int:
        """Model evaluations since the run started."""
        return self.problem.nfev - self.nfev0

    @property
    def budget(self) -> float:
        """Evaluations left before ``maxfev`` (inf without a budget)."""
        return np.inf if self.term.maxfev is None else self.term.maxfev - self.nfev

    def offer(self, X: np.ndarray, F: np.ndarray) -> None:
        """Consider evaluated points X (N, 4), log10 space, with objectives F (N,), m/N."""
        if len(F) == 0:
            return
        k = int(np.argmin(F))
        if F[k] < self.best_f:
            self.best_f = float(F[k])
            self.best_x = np.array(X[k], float)

    def stop(self, status: int, message: str) -> bool:
        """Record why the run stops; returns True."""
        self.status, self.message = status, message
        return True

    def next_iteration(self) -> bool:
        """Record the iteration just finished; True when a stopping rule holds.

        Convergence tests are checked before the caps, so a run that converges
        on its last allowed iteration is a success.
        """
        self.nit += 1
        self.history.append(self.best_f)
        if self.callback is not None:
            self.callback(self.nit, self.best_f, self.nfev)
        t = self.term
        if t.f_target is not None and self.best_f <= t.f_target:
            return self.stop(CONVERGED, f"converged: objective target {t.f_target:g} m/N reached")
        if t.stall_iter and len(self.history) > t.stall_iter:
            old = self.history[-1 - t.stall_iter]
            if old - self.best_f <= t.tol * max(abs(old), 1e-300):
                return self.stop(CONVERGED, f"converged: the best objective changed by at most tol={t.tol:g} "
                                            f"(relative) over the last {t.stall_iter} iterations")
        if t.maxfev is not None and self.nfev >= t.maxfev:
            return self.stop(MAXFEV, STATUS_MESSAGES[MAXFEV])
        if t.maxiter is not None and self.nit >= t.maxiter:
            return self.stop(MAXITER, STATUS_MESSAGES[MAXITER])
        return False

    def result(self, method: str, **extra) -> OptimizeResult:
        """The run's ``OptimizeResult`` (x in log10 space; success = status 0)."""
        status = OTHER if self.status is None else self.status
        message = self.message or STATUS_MESSAGES[status]
        return OptimizeResult(
            x=self.best_x,
            fun=self.best_f,
            nfev=self.nfev,
            nit=self.nit,
            success=status == CONVERGED,
            status=status,
            message=message,
            seconds=time.perf_counter() - self.t0,
            history=np.array(self.history),
            method=method,
            **extra,
        )


def to_unit(problem, X):
    """Map log10 points X to the unit cube of the problem's bounds."""
    return (np.asarray(X) - problem.xl) / (problem.xu - problem.xl)


def from_unit(problem, U):
    """Map unit-cube points U to log10 points within the problem's bounds."""
    return problem.xl + np.asarray(U) * (problem.xu - problem.xl)


def start_unit(problem) -> np.ndarray | None:
    """The problem's starting point (its ``x_start``, log10, if it has one) on the unit cube, else None.

    The population methods put one member there (GA, PSO: the first member; SA: the first chain; DE: scipy's
    ``x0``); the hybrid also starts least squares from it. The problem has checked that it lies inside the
    bounds (:class:`~toolpoint.identification.problem.FRFProblem` refuses a start outside them).

    Examples
    --------
    >>> class P:
    ...     xl, xu, x_start = np.zeros(2), np.full(2, 4.0), np.array([1.0, 3.0])
    >>> start_unit(P()).tolist()
    [0.25, 0.75]
    """
    x = getattr(problem, "x_start", None)
    if x is None:
        return None
    u = to_unit(problem, np.asarray(x, float))
    if not np.all((u >= -1e-9) & (u <= 1 + 1e-9)):  # round-off of log10 at a bound is allowed
        raise ValueError("the starting point lies outside the bounds")
    return np.clip(u, 0.0, 1.0)
