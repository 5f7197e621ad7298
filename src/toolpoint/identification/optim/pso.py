"""Particle swarm optimisation (global-best topology).

    v ← w v + c1 r1 ⊙ (p_best − x) + c2 r2 ⊙ (g_best − x),   x ← x + v

with r1, r2 ~ U(0, 1) per particle and dimension, cognitive c1 = 0.5 and social
c2 = 1.35 (the paper's values), and the inertia weight w decreasing linearly
from ``inertia[0]`` = 0.9 to ``inertia[1]`` = 0.4 over the iterations (Shi &
Eberhart 1998), so the swarm explores first and converges later. Velocities
are limited to ``max_velocity`` of the bound range per iteration; a particle
that leaves the box is put back on the bound and its velocity component zeroed.
Unit cube of the log10 parameters; the swarm is evaluated in one vectorised call.
"""

from __future__ import annotations

import numpy as np

from .base import Termination, Tracker, from_unit


class PSO:
    name = "pso"

    def __init__(
        self,
        swarm_size: int = 120,
        iterations: int = 280,
        cognitive: float = 0.5,
        social: float = 1.35,
        inertia: tuple[float, float] = (0.9, 0.4),
        max_velocity: float = 0.2,
        stall_iterations: int | None = None,
        function_tolerance: float = 1e-6,
    ):
        self.swarm_size = swarm_size
        self.iterations = iterations
        self.cognitive = cognitive
        self.social = social
        self.inertia = inertia
        self.max_velocity = max_velocity
        self.stall_iterations = stall_iterations
        self.function_tolerance = function_tolerance

    def termination(self) -> Termination:
        return Termination(max_iter=self.iterations, stall_iter=self.stall_iterations, ftol=self.function_tolerance)

    def minimize(self, problem, rng: np.random.Generator, termination: Termination | None = None, callback=None):
        term = termination or self.termination()
        tr = Tracker(problem, term, callback)
        n, d = self.swarm_size, problem.n_var
        iters = term.max_iter or self.iterations
        X = rng.random((n, d))
        V = rng.uniform(-self.max_velocity, self.max_velocity, (n, d))
        F = problem.evaluate(from_unit(problem, X))
        P, PF = X.copy(), F.copy()
        tr.offer(from_unit(problem, X), F)
        k = 0
        while not tr.next_iteration():
            w = self.inertia[0] + (self.inertia[1] - self.inertia[0]) * min(k / max(iters - 1, 1), 1.0)
            g = P[np.argmin(PF)]
            r1, r2 = rng.random((n, d)), rng.random((n, d))
            V = w * V + self.cognitive * r1 * (P - X) + self.social * r2 * (g - X)
            V = np.clip(V, -self.max_velocity, self.max_velocity)
            X = X + V
            out = (X < 0) | (X > 1)
            X = np.clip(X, 0, 1)
            V[out] = 0.0
            F = problem.evaluate(from_unit(problem, X))
            better = F < PF
            P[better], PF[better] = X[better], F[better]
            tr.offer(from_unit(problem, X), F)
            k += 1
        return tr.result(self.name, swarm_size=n)
