"""Particle swarm optimisation, global-best topology (see :class:`PSO`)."""

from __future__ import annotations

import numpy as np

from .base import Optimizer, Tracker, from_unit, horizon, start_unit

__all__ = ["PSO"]


class PSO(Optimizer):
    r"""Particle swarm on the unit cube of x = log10 [kt, ct, kr, cr].

    .. math::

        v \leftarrow w_k v + c_1 r_1 \odot (p_{best} - x) + c_2 r_2 \odot (g_{best} - x), \qquad
        x \leftarrow x + v

    with r1, r2 ~ U(0, 1) per particle and dimension, cognitive c1 and social c2 (the paper's 0.5 and 1.35).
    The inertia weight decreases linearly (Shi & Eberhart 1998),
    w_k = w0 + (w1 − w0)·min(k / (H − 1), 1) at velocity update k = 0, 1, …, where H is the number of
    iterations the run can last: ``maxiter``, or fewer when the budget ``maxfev`` affords fewer (see
    :func:`~toolpoint.identification.optim.base.horizon`), so the swarm explores first and converges by the
    end of the run it actually has. Velocities are limited to ``max_velocity`` of the bound range per
    iteration; a particle that leaves the box is put back on the bound and its velocity component zeroed.
    The swarm is evaluated in one vectorised call per iteration; with ``maxfev`` the last iteration moves
    only the particles that fit, so the budget is never exceeded.

    Parameters
    ----------
    popsize : int, default 120
        Particles in the swarm (the paper's value).
    maxiter : int or None, default 280
        Iteration limit (the paper's); the initial swarm is iteration 1. Also the inertia schedule's length.
    maxfev : int or None, default None
        Evaluation budget (model evaluations); never exceeded.
    stall_iter : int or None, default None
        Stall window, iterations; None (default) disables the stall test, so the run lasts ``maxiter``
        iterations and reports ``success=False`` (status 1) unless ``f_target`` is reached.
    tol : float, default 1e-6
        Converged when the best objective improved by at most ``tol`` (relative) over the last
        ``stall_iter`` iterations.
    f_target : float or None, default None
        Converged when the best objective is ≤ this value, m/N.
    cognitive : float, default 0.5
        c1.
    social : float, default 1.35
        c2.
    inertia : (float, float), default (0.9, 0.4)
        (w0, w1), start and end of the inertia schedule.
    max_velocity : float, default 0.2
        Velocity limit per iteration, fraction of the bound range.

    Notes
    -----
    Deprecated option names (one release): ``swarm_size`` → ``popsize``, ``iterations`` → ``maxiter``,
    ``stall_iterations`` → ``stall_iter``, ``function_tolerance`` → ``tol`` (same meaning here).

    The result carries ``popsize`` and ``inertia``, the last inertia weight used.

    Examples
    --------
    >>> pso = PSO(maxiter=100, maxfev=1200)
    >>> pso.inertia_weight(0, 10), pso.inertia_weight(9, 10)
    (0.9, 0.4)
    """

    name = "pso"
    _OPTIONS = ("popsize", "maxiter", "maxfev", "stall_iter", "tol", "f_target", "cognitive", "social", "inertia",
                "max_velocity")

    def __init__(
        self,
        *,
        popsize: int = 120,
        maxiter: int | None = 280,
        maxfev: int | None = None,
        stall_iter: int | None = None,
        tol: float = 1e-6,
        f_target: float | None = None,
        cognitive: float = 0.5,
        social: float = 1.35,
        inertia: tuple[float, float] = (0.9, 0.4),
        max_velocity: float = 0.2,
    ):
        self.popsize = popsize
        self.maxiter = maxiter
        self.maxfev = maxfev
        self.stall_iter = stall_iter
        self.tol = tol
        self.f_target = f_target
        self.cognitive = cognitive
        self.social = social
        self.inertia = inertia
        self.max_velocity = max_velocity

    def inertia_weight(self, k: int, H: int | None) -> float:
        """w_k = w0 + (w1 − w0)·min(k / (H − 1), 1) at velocity update k of an H-iteration run (w0 if H is None)."""
        if H is None:
            return self.inertia[0]
        return self.inertia[0] + (self.inertia[1] - self.inertia[0]) * min(k / max(H - 1, 1), 1.0)

    def _minimize(self, problem, rng: np.random.Generator, callback=None):
        term = self.termination()
        tr = Tracker(problem, term, callback)
        n, d = self.popsize, problem.n_var
        if term.maxfev is not None:
            n = max(1, min(n, term.maxfev))
        H = horizon(term, n, n)  # the inertia schedule follows the run's real length
        X = rng.random((n, d))
        if (s0 := start_unit(problem)) is not None:
            X[0] = s0  # one particle at the problem's start
        V = rng.uniform(-self.max_velocity, self.max_velocity, (n, d))
        F = problem.evaluate(from_unit(problem, X))
        P, PF = X.copy(), F.copy()
        tr.offer(from_unit(problem, X), F)
        k = 0
        w = None
        while not tr.next_iteration():
            w = self.inertia_weight(k, H)
            g = P[np.argmin(PF)]
            r1, r2 = rng.random((n, d)), rng.random((n, d))
            V = w * V + self.cognitive * r1 * (P - X) + self.social * r2 * (g - X)
            V = np.clip(V, -self.max_velocity, self.max_velocity)
            X = X + V
            out = (X < 0) | (X > 1)
            X = np.clip(X, 0, 1)
            V[out] = 0.0
            m = int(min(n, tr.budget))  # particles evaluated (all but at the end of a budget)
            F = problem.evaluate(from_unit(problem, X[:m]))
            better = F < PF[:m]
            P[:m][better], PF[:m][better] = X[:m][better], F[better]
            tr.offer(from_unit(problem, X[:m]), F)
            k += 1
        return tr.result(self.name, popsize=n, inertia=w)
