"""scipy's differential evolution on the same problem (see :class:`DE`)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import differential_evolution

from .base import CONVERGED, MAXITER, OTHER, Optimizer, Termination, Tracker, from_unit, start_unit

__all__ = ["DE"]


class DE(Optimizer):
    """``scipy.optimize.differential_evolution`` (best1bin, deferred updating, no polishing), vectorised.

    The whole population is evaluated in one call per generation. scipy's own stopping rules apply
    (``maxiter``, and ``tol`` in scipy's meaning); ``success`` and ``message`` are scipy's, except when
    this wrapper's ``maxfev`` or ``f_target`` stopped the run.

    Parameters
    ----------
    popsize : int, default 15
        scipy's meaning: a *multiplier*, the population has popsize × 4 members (GA and PSO take a number
        of members).
    maxiter : int, default 1000
        Generations after the initial population (scipy's ``maxiter``).
    tol : float, default 1e-8
        scipy's relative convergence tolerance: converged when the standard deviation of the population's
        objectives is ≤ atol + tol·|mean| (not the stall test of GA/SA/PSO).
    maxfev : int or None, default None
        Evaluation budget, checked after each generation (may exceed by less than one generation).
    f_target : float or None, default None
        Converged when the best objective is ≤ this value, m/N.
    mutation : float or (float, float), default (0.5, 1.0)
        scipy's differential weight (dithered between the two values).
    recombination : float, default 0.7
        scipy's crossover probability.
    init : str, default "latinhypercube"
        scipy's initialisation.
    """

    name = "de"
    _OPTIONS = ("popsize", "maxiter", "tol", "maxfev", "f_target", "mutation", "recombination", "init")

    def __init__(self, *, popsize: int = 15, maxiter: int = 1000, tol: float = 1e-8, maxfev: int | None = None,
                 f_target: float | None = None, mutation=(0.5, 1.0), recombination: float = 0.7,
                 init: str = "latinhypercube"):
        self.popsize = popsize
        self.maxiter = maxiter
        self.tol = tol
        self.maxfev = maxfev
        self.f_target = f_target
        self.mutation = mutation
        self.recombination = recombination
        self.init = init

    def termination(self) -> Termination:
        """The stopping rules (``tol`` is scipy's own test, applied by scipy: not a stall test here)."""
        return Termination(maxiter=self.maxiter, maxfev=self.maxfev, f_target=self.f_target)

    def _with_termination(self, term: Termination) -> "DE":
        # the old API: a Termination's maxiter replaced scipy's when given; its tol never applied to DE
        return self.with_options(maxiter=term.maxiter or self.maxiter, maxfev=term.maxfev, f_target=term.f_target)

    def _minimize(self, problem, rng: np.random.Generator, callback=None):
        # scipy applies maxiter and tol; the tracker only maxfev and f_target
        tr = Tracker(problem, Termination(maxfev=self.maxfev, f_target=self.f_target), callback)

        def f(X):  # scipy passes (n_var, S) when vectorized
            F = problem.evaluate(X.T)
            tr.offer(X.T, F)
            return F

        def cb(intermediate_result):
            return tr.next_iteration()  # True stops scipy

        res = differential_evolution(
            f,
            list(zip(problem.xl, problem.xu)),
            popsize=self.popsize,
            maxiter=self.maxiter,
            tol=self.tol,
            mutation=self.mutation,
            recombination=self.recombination,
            init=self.init,
            rng=rng,
            polish=False,
            updating="deferred",
            vectorized=True,
            callback=cb,
            x0=None if (s0 := start_unit(problem)) is None else from_unit(problem, s0),  # one member at the start
        )
        if tr.status is None:  # scipy stopped by itself: pass its verdict through
            if res.success:
                tr.stop(CONVERGED, f"scipy: {res.message}")
            elif str(res.message).startswith("Maximum number of iterations"):
                tr.stop(MAXITER, f"scipy: {res.message}")
            else:
                tr.stop(OTHER, f"scipy: {res.message}")
        return tr.result(self.name)
