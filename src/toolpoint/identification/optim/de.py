"""scipy's differential evolution on the same problem (vectorised population calls)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import differential_evolution

from .base import Termination, Tracker


class DE:
    """``scipy.optimize.differential_evolution`` (best1bin, deferred updating, no polishing)."""

    name = "de"

    def __init__(self, popsize: int = 15, maxiter: int = 1000, tol: float = 1e-8, mutation=(0.5, 1.0),
                 recombination: float = 0.7, init: str = "latinhypercube"):
        self.popsize = popsize
        self.maxiter = maxiter
        self.tol = tol
        self.mutation = mutation
        self.recombination = recombination
        self.init = init

    def termination(self) -> Termination:
        return Termination(max_iter=self.maxiter)

    def minimize(self, problem, rng: np.random.Generator, termination: Termination | None = None, callback=None):
        term = termination or self.termination()
        tr = Tracker(problem, term, callback)

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
            maxiter=term.max_iter or self.maxiter,
            tol=self.tol,
            mutation=self.mutation,
            recombination=self.recombination,
            init=self.init,
            rng=rng,
            polish=False,
            updating="deferred",
            vectorized=True,
            callback=cb,
        )
        if tr.message == "maximum number of iterations reached" and not res.message.startswith("Maximum"):
            tr.message = f"scipy: {res.message}"
        return tr.result(self.name)
