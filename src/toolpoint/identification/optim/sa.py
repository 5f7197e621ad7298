"""Simulated annealing with reannealing, after MATLAB's ``simulannealbnd`` (see :class:`SA`).

Why it departs from MATLAB (acceptance on ln f, reannealing along the curvature, the coolest temperature
for acceptance, no reheating) and the evidence: ``docs/design/identification.md``.
"""

from __future__ import annotations

import numpy as np

from .base import Optimizer, Tracker, from_unit, start_unit

__all__ = ["SA"]


class SA(Optimizer):
    r"""Simulated annealing with reannealing on the unit cube of x = log10 [kt, ct, kr, cr].

    ``chains`` independent chains run side by side, so that each iteration is one vectorised evaluation.
    Each chain has a point x, orthonormal move directions v_1 … v_d (the coordinate axes until the first
    reannealing) and one temperature per direction, T_k = T0 · c^a_k (MATLAB ``temperatureexp``,
    c = ``cooling``), the annealing parameter a_k counting iterations; τ_k = T_k / T0 ∈ (0, 1].

    * **Move** (``annealingfast``): y = x + s Σ_k τ_k u_k v_k, u a random unit vector, s = ``step``.
      A coordinate that leaves the box is placed uniformly between x and the bound it crossed.
    * **Acceptance**: always if better, else with probability 1 / (1 + exp(Δ / min_k τ_k)),
      Δ = ln f(y) − ln f(x).
    * **Reannealing** after every ``reanneal_interval`` accepted moves of a chain: forward differences of
      g = f² (2d + d(d−1)/2 = 14 points, counted as evaluations) give the gradient ∇g and curvature
      H = Σ_k λ_k v_k v_kᵀ at x; the eigenvectors become the move directions and
      τ_k = min(1, w_k / s), w_k = √(2 e / |λ_k|), e = Σ_k (∇g·v_k)² / (2 λ_k) (clipped to [1e-12 g, g];
      e = g if some λ_k ≤ 0), the excess of g over its quadratic model's minimum.

    With ``maxfev`` the budget is never exceeded: the last iteration moves only the chains that fit, and a
    reannealing that does not fit is skipped.

    Parameters
    ----------
    maxiter : int or None, default 4000
        Iteration limit; the initial points are iteration 1.
    maxfev : int or None, default None
        Evaluation budget (model evaluations, finite-difference points included); never exceeded.
    stall_iter : int or None, default 500
        Stall window, iterations; None disables the stall test.
    tol : float, default 5e-4
        Converged when the best objective improved by at most ``tol`` (relative) over the last
        ``stall_iter`` iterations (1e-6 per iteration × 500).
    f_target : float or None, default None
        Converged when the best objective is ≤ this value, m/N.
    initial_temperature : float, default 300.0
        T0 (the paper's); it only sets the unit of the temperatures, the search depends on T/T0.
    reanneal_interval : int, default 50
        Accepted moves of a chain between reannealings (the paper's).
    chains : int, default 16
        Chains run side by side.
    step : float, default 0.5
        s, move length at τ = 1, fraction of the bound range.
    cooling : float, default 0.95
        c of T = T0 · c^a.

    Notes
    -----
    Deprecated option names (one release): ``max_iterations`` → ``maxiter``, ``stall_iterations`` →
    ``stall_iter``, ``function_tolerance`` (average change per iteration) → ``tol`` =
    function_tolerance × stall_iter (total change over the window).

    The result carries ``chains`` (chains used) and ``reanneals`` (reannealings done, over all chains).
    """

    name = "sa"
    _OPTIONS = ("maxiter", "maxfev", "stall_iter", "tol", "f_target", "initial_temperature", "reanneal_interval",
                "chains", "step", "cooling")

    def __init__(
        self,
        *,
        maxiter: int | None = 4000,
        maxfev: int | None = None,
        stall_iter: int | None = 500,
        tol: float = 5e-4,
        f_target: float | None = None,
        initial_temperature: float = 300.0,
        reanneal_interval: int = 50,
        chains: int = 16,
        step: float = 0.5,
        cooling: float = 0.95,
    ):
        self.maxiter = maxiter
        self.maxfev = maxfev
        self.stall_iter = stall_iter
        self.tol = tol
        self.f_target = f_target
        self.initial_temperature = initial_temperature
        self.reanneal_interval = reanneal_interval
        self.chains = chains
        self.step = step
        self.cooling = cooling

    @staticmethod
    def _quadratic(lnf, X, L, h):
        """Gradient (n, d) and Hessian (n, d, d) of g = f² at each row of X by
        forward differences with steps h (n, d) away from the nearer bound;
        2d + d(d−1)/2 points per row."""
        n, d = X.shape
        h = np.clip(h, 1e-12, 0.25)
        hs = np.where(X + 2 * h <= 1.0, h, -h)
        eye = np.eye(d)
        i, j = np.triu_indices(d, 1)
        pts = np.concatenate(
            [X[:, None] + hs[:, None] * eye, X[:, None] + 2 * hs[:, None] * eye,
             X[:, None] + hs[:, None] * (eye[i] + eye[j])], axis=1)
        g = np.exp(2 * lnf(np.clip(pts.reshape(-1, d), 0.0, 1.0))).reshape(n, -1)
        g0 = np.exp(2 * L)[:, None]
        g1, g2, g3 = g[:, :d], g[:, d : 2 * d], g[:, 2 * d :]
        grad = (4 * g1 - g2 - 3 * g0) / (2 * hs)
        H = np.empty((n, d, d))
        H[:, np.arange(d), np.arange(d)] = (g2 - 2 * g1 + g0) / h**2
        H[:, i, j] = H[:, j, i] = (g3 - g1[:, i] - g1[:, j] + g0) / (hs[:, i] * hs[:, j])
        return grad, H

    def _minimize(self, problem, rng: np.random.Generator, callback=None):
        term = self.termination()
        tr = Tracker(problem, term, callback)
        d = problem.n_var
        n = self.chains if term.maxfev is None else max(1, min(self.chains, term.maxfev))
        n_curv = 2 * d + d * (d - 1) // 2
        log_c = np.log(self.cooling)

        def budget() -> float:
            return tr.budget

        def lnf(U):
            X = np.clip(from_unit(problem, U), problem.xl, problem.xu)
            F = problem.evaluate(X)
            tr.offer(X, F)
            return np.log(np.maximum(F, 1e-300))

        X = rng.random((n, d))
        if (s0 := start_unit(problem)) is not None:
            X[0] = s0  # one chain from the problem's start
        L = lnf(X)
        V = np.repeat(np.eye(d)[None], n, axis=0)  # move directions, columns
        a = np.zeros((n, d))  # annealing parameters
        accepted = np.zeros(n, int)
        reanneals = 0
        while not tr.next_iteration():
            m = int(min(n, budget()))  # chains moved this iteration
            tau = self.cooling**a[:m]
            u = rng.standard_normal((m, d))
            u /= np.linalg.norm(u, axis=1, keepdims=True)
            x = X[:m]
            Y = x + self.step * np.einsum("nij,nj->ni", V[:m], tau * u)
            lo, hi = Y < 0, Y > 1
            Y[lo] = x[lo] * rng.random(int(lo.sum()))  # uniformly between x and the bound
            Y[hi] = x[hi] + (1 - x[hi]) * rng.random(int(hi.sum()))
            LY = lnf(Y)
            delta = LY - L[:m]
            with np.errstate(over="ignore"):
                p_accept = 1.0 / (1.0 + np.exp(delta / np.maximum(tau.min(axis=1), 1e-300)))
            acc = np.zeros(n, bool)
            acc[:m] = (delta < 0) | (rng.random(m) < p_accept)
            X[acc], L[acc] = Y[acc[:m]], LY[acc[:m]]
            accepted += acc
            a += 1
            due = np.flatnonzero(accepted >= self.reanneal_interval)
            due = due[: int(min(due.size, budget() // n_curv))]
            if due.size:
                tau = self.cooling**a[due]
                h = self.step * np.sqrt(np.einsum("nij,nj->ni", V[due] ** 2, tau**2))  # move length per axis
                grad, H = self._quadratic(lnf, X[due], L[due], h)
                lam, W = np.linalg.eigh(H)
                V[due] = W
                g = np.exp(2 * L[due])
                gv = np.einsum("nij,ni->nj", W, grad)  # gradient along the directions
                e = np.where((lam > 0).all(axis=1), (gv**2 / (2 * np.abs(lam) + 1e-300)).sum(axis=1), g)
                e = np.clip(e, 1e-12 * g, g)  # excess of g over its quadratic model's minimum
                width = np.sqrt(2 * e[:, None] / (np.abs(lam) + 1e-300))
                a[due] = np.log(np.clip(width / self.step, 1e-300, 1.0)) / log_c
                accepted[due] = 0
                reanneals += due.size
        return tr.result(self.name, chains=n, reanneals=reanneals)
