"""Simulated annealing with reannealing, after MATLAB's ``simulannealbnd``.

Several independent chains run side by side so that each iteration is one
vectorised evaluation. Per chain and dimension i the temperature is
T_i = T0 · 0.95^k_i (MATLAB ``temperatureexp``), k_i counting iterations.

* **Move** (``annealingfast``): step length proportional to temperature in a
  uniformly random direction, y = x + s·(T/T0) ⊙ u, ‖u‖ = 1, in the unit cube of
  the log10 parameters. A coordinate that leaves the box is placed uniformly
  between x and the bound it crossed (bounded moves, MATLAB ``sahonorbds``).
* **Acceptance** (``acceptancesa``): always if better, else with probability
  1 / (1 + exp(Δ / (f_s · max_i T_i/T0))). MATLAB compares Δ with the raw
  temperature (T0 = 300 in objective units); our objective is in m/N
  (~1e-6), so temperatures are taken relative to T0 and Δ relative to
  f_s, the mean objective of the starting points.
* **Reannealing** every ``reanneal_interval`` accepted points: the
  sensitivities s_i = |∂f/∂x_i| (forward differences, counted as evaluations)
  reset T_i = T_max · max_j s_j / s_i, capped at T0, so insensitive directions
  get larger steps again; k_i follows from T_i.

The paper's settings are the defaults: T0 = 300, reannealing interval 50.
"""

from __future__ import annotations

import numpy as np

from .base import Termination, Tracker, from_unit


class SA:
    name = "sa"

    def __init__(
        self,
        initial_temperature: float = 300.0,
        reanneal_interval: int = 50,
        chains: int = 8,
        max_iterations: int = 1500,
        step: float = 0.5,
        cooling: float = 0.95,
        stall_iterations: int | None = 500,
        function_tolerance: float = 1e-6,
    ):
        self.initial_temperature = initial_temperature
        self.reanneal_interval = reanneal_interval
        self.chains = chains
        self.max_iterations = max_iterations
        self.step = step
        self.cooling = cooling
        self.stall_iterations = stall_iterations
        self.function_tolerance = function_tolerance

    def termination(self) -> Termination:
        return Termination(max_iter=self.max_iterations, stall_iter=self.stall_iterations, ftol=self.function_tolerance)

    def _sensitivity(self, problem, X, F, h=1e-4) -> np.ndarray:
        """|∂f/∂x_i| by forward differences in the unit cube, all chains in one call."""
        n, d = X.shape
        Y = np.repeat(X[:, None, :], d, axis=1)
        step = np.where(X > 1 - h, -h, h)
        idx = np.arange(d)
        Y[:, idx, idx] += step
        FY = problem.evaluate(from_unit(problem, Y.reshape(-1, d))).reshape(n, d)
        return np.abs(FY - F[:, None]) / h + 1e-300

    def minimize(self, problem, rng: np.random.Generator, termination: Termination | None = None, callback=None):
        term = termination or self.termination()
        tr = Tracker(problem, term, callback)
        n, d = self.chains, problem.n_var
        T0 = self.initial_temperature
        X = rng.random((n, d))
        F = problem.evaluate(from_unit(problem, X))
        tr.offer(from_unit(problem, X), F)
        f_scale = float(np.mean(F))
        k = np.zeros((n, d))
        accepted = np.zeros(n, int)
        while not tr.next_iteration():
            tau = self.cooling**k  # T / T0
            u = rng.standard_normal((n, d))
            u /= np.linalg.norm(u, axis=1, keepdims=True)
            Y = X + self.step * tau * u
            lo, hi = Y < 0, Y > 1
            Y[lo] = X[lo] * rng.random(int(lo.sum()))  # uniformly between x and the bound
            Y[hi] = X[hi] + (1 - X[hi]) * rng.random(int(hi.sum()))
            FY = problem.evaluate(from_unit(problem, Y))
            tr.offer(from_unit(problem, Y), FY)
            delta = (FY - F) / f_scale
            with np.errstate(over="ignore"):
                p_accept = 1.0 / (1.0 + np.exp(delta / tau.max(axis=1)))
            acc = (delta < 0) | (rng.random(n) < p_accept)
            X[acc], F[acc] = Y[acc], FY[acc]
            accepted += acc
            k += 1
            due = accepted >= self.reanneal_interval
            if np.any(due):
                s = self._sensitivity(problem, X[due], F[due])
                tmax = tau[due].max(axis=1, keepdims=True)
                t_new = np.minimum(1.0, tmax * s.max(axis=1, keepdims=True) / s)
                k[due] = np.log(t_new) / np.log(self.cooling)
                accepted[due] = 0
        return tr.result(self.name, chains=n)
