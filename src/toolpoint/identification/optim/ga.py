"""Genetic algorithm, structured like MATLAB's ``ga`` (see :class:`GA`).

Why it departs from MATLAB (elite-covariance mutation, relative stall test) and
the evidence behind the defaults: ``docs/design/identification.md``.
"""

from __future__ import annotations

import numpy as np

from .base import Optimizer, Tracker, from_unit, horizon, start_unit

__all__ = ["GA"]


class GA(Optimizer):
    r"""Genetic algorithm on the unit cube of x = log10 [kt, ct, kr, cr].

    Each generation the population (``popsize`` members, ranked by objective) is replaced by

    * **elite** — the best ``elite_fraction``·P members, unchanged and not re-evaluated (MATLAB EliteCount;
      the paper's "reproduction" 0.1);
    * **crossover children** — ``crossover_fraction`` of the rest, from two parents a, b:
      ``"intermediate"`` c = a + r ⊙ (b − a), r_i ~ U(0, ``crossover_ratio``) per gene; or ``"heuristic"``
      c = w + R (b* − w) from the worse parent w past the better one b*, R = ``heuristic_ratio``;
    * **mutation children** — the remaining members, a parent x plus a Gaussian step:
      ``"elite_covariance"`` y = x + s Σ_j z_j (e_j − ē)/√(E − 1), z_j ~ N(0, 1), over the E elite members
      e_j (y ~ N(x, s² C_elite), s = ``mutation_scale``); or ``"gaussian"`` y = x + σ_g z, z ~ N(0, I),
      σ_g = s·max(0, 1 − ``mutation_shrink``·g/G) at breeding step g = 0, 1, … of a run that lasts
      G iterations (G = ``maxiter``, or fewer when ``maxfev`` allows fewer, see
      :func:`~toolpoint.identification.optim.base.horizon`);
    * **uniform mutation** — each gene of each child is re-drawn uniformly with probability
      ``mutation_probability``; children are then clipped to the bounds.

    Parents come from stochastic universal sampling on rank-scaled fitness (∝ 1/√rank) or from tournaments.
    The population is evaluated in one vectorised call per generation; with ``maxfev`` the last generation
    evaluates only the children that fit, so the budget is never exceeded.

    Parameters
    ----------
    popsize : int, default 420
        Members of the population (the paper's value). Unlike scipy's DE, a number of members, not a
        multiplier.
    maxiter : int or None, default 2430
        Iteration (generation) limit; the initial population is iteration 1.
    maxfev : int or None, default None
        Evaluation budget (model evaluations); never exceeded.
    stall_iter : int or None, default 50
        Stall window, generations; None disables the stall test.
    tol : float, default 5e-5
        Converged when the best objective improved by at most ``tol`` (relative) over the last
        ``stall_iter`` generations (5e-5 = MATLAB's FunctionTolerance 1e-6 per generation × 50).
    f_target : float or None, default None
        Converged when the best objective is ≤ this value, m/N.
    elite_fraction : float, default 0.1
    crossover_fraction : float, default 0.65
        Fraction of the non-elite members made by crossover.
    mutation_probability : float, default 0.015
        Per-gene probability of a uniform re-draw.
    crossover : {"intermediate", "heuristic"}, default "intermediate"
    crossover_ratio : float, default 1.0
    heuristic_ratio : float, default 1.2
    mutation : {"elite_covariance", "gaussian"}, default "elite_covariance"
    mutation_scale : float or None, default None
        s; None means 1.5 for ``"elite_covariance"`` and MATLAB's 1 for ``"gaussian"``.
    mutation_shrink : float, default 1.0
        Shrink of the ``"gaussian"`` step over the run.
    selection : {"stochastic_uniform", "tournament"}, default "stochastic_uniform"
    tournament_size : int, default 4

    Notes
    -----
    Deprecated option names (one release): ``population_size`` → ``popsize``, ``generations`` → ``maxiter``,
    ``stall_generations`` → ``stall_iter``, ``function_tolerance`` (average change per generation) →
    ``tol`` = function_tolerance × stall_iter (total change over the window).

    The result carries ``popsize`` (members actually used) and ``mutation_step`` (the last
    max(0, 1 − shrink·g/G) factor of the ``"gaussian"`` schedule; None for ``"elite_covariance"``).
    """

    name = "ga"
    _OPTIONS = ("popsize", "maxiter", "maxfev", "stall_iter", "tol", "f_target", "elite_fraction",
                "crossover_fraction", "mutation_probability", "crossover", "crossover_ratio", "heuristic_ratio",
                "mutation", "mutation_scale", "mutation_shrink", "selection", "tournament_size")

    def __init__(
        self,
        *,
        popsize: int = 420,
        maxiter: int | None = 2430,
        maxfev: int | None = None,
        stall_iter: int | None = 50,
        tol: float = 5e-5,
        f_target: float | None = None,
        elite_fraction: float = 0.1,
        crossover_fraction: float = 0.65,
        mutation_probability: float = 0.015,
        crossover: str = "intermediate",
        crossover_ratio: float = 1.0,
        heuristic_ratio: float = 1.2,
        mutation: str = "elite_covariance",
        mutation_scale: float | None = None,
        mutation_shrink: float = 1.0,
        selection: str = "stochastic_uniform",
        tournament_size: int = 4,
    ):
        if crossover not in ("intermediate", "heuristic"):
            raise ValueError(f"crossover must be 'intermediate' or 'heuristic', got {crossover!r}")
        if mutation not in ("elite_covariance", "gaussian"):
            raise ValueError(f"mutation must be 'elite_covariance' or 'gaussian', got {mutation!r}")
        if selection not in ("stochastic_uniform", "tournament"):
            raise ValueError(f"selection must be 'stochastic_uniform' or 'tournament', got {selection!r}")
        self.popsize = popsize
        self.maxiter = maxiter
        self.maxfev = maxfev
        self.stall_iter = stall_iter
        self.tol = tol
        self.f_target = f_target
        self.elite_fraction = elite_fraction
        self.crossover_fraction = crossover_fraction
        self.mutation_probability = mutation_probability
        self.crossover = crossover
        self.crossover_ratio = crossover_ratio
        self.heuristic_ratio = heuristic_ratio
        self.mutation = mutation
        self.mutation_scale = mutation_scale
        self.mutation_shrink = mutation_shrink
        self.selection = selection
        self.tournament_size = tournament_size

    @property
    def scale(self) -> float:
        """The mutation scale s in use (1.5 for the elite covariance, 1 for ``"gaussian"`` unless set)."""
        if self.mutation_scale is not None:
            return self.mutation_scale
        return 1.5 if self.mutation == "elite_covariance" else 1.0

    def step_factor(self, g: int, G: int | None) -> float:
        """The ``"gaussian"`` step factor max(0, 1 − shrink·g/G) at breeding step g of a G-iteration run."""
        return 1.0 if G is None else max(0.0, 1.0 - self.mutation_shrink * g / G)

    def _parents(self, rng, P: int, n: int) -> np.ndarray:
        """n parent indices into a population sorted best first."""
        if self.selection == "tournament":  # the smallest index of each tournament wins
            return rng.integers(0, P, (n, self.tournament_size)).min(axis=1)
        fitness = 1.0 / np.sqrt(np.arange(1, P + 1))  # rank scaling
        edges = np.cumsum(fitness / fitness.sum())
        pointers = (rng.random() + np.arange(n)) / n  # stochastic universal sampling
        idx = np.minimum(np.searchsorted(edges, pointers), P - 1)
        rng.shuffle(idx)
        return idx

    def _minimize(self, problem, rng: np.random.Generator, callback=None):
        term = self.termination()
        tr = Tracker(problem, term, callback)
        d = problem.n_var
        P = self.popsize
        if term.maxfev is not None:
            P = max(2, min(P, term.maxfev))
        n_elite = min(max(1, int(round(self.elite_fraction * P))), P - 1)
        n_cross = int(round(self.crossover_fraction * (P - n_elite)))
        n_mut = P - n_elite - n_cross
        G = horizon(term, P, P - n_elite)  # the schedule follows the run's real length
        scale = self.scale

        def evaluate(U):
            X = np.clip(from_unit(problem, U), problem.xl, problem.xu)
            F = problem.evaluate(X)
            tr.offer(X, F)
            return F

        U = rng.random((P, d))
        if (s0 := start_unit(problem)) is not None:
            U[0] = s0  # one member at the problem's start
        F = evaluate(U)
        gen = 0
        last_step = None
        while not tr.next_iteration():
            order = np.argsort(F, kind="stable")
            U, F = U[order], F[order]
            pidx = self._parents(rng, P, 2 * n_cross + n_mut)
            ia, ib, im = pidx[:n_cross], pidx[n_cross : 2 * n_cross], pidx[2 * n_cross :]
            a, b = U[ia], U[ib]
            if self.crossover == "heuristic":
                a_better = (ia <= ib)[:, None]  # sorted: smaller index = better objective
                best, worst = np.where(a_better, a, b), np.where(a_better, b, a)
                cross = worst + self.heuristic_ratio * (best - worst)
            else:
                cross = a + rng.uniform(0.0, self.crossover_ratio, (n_cross, d)) * (b - a)
            if self.mutation == "elite_covariance":
                elite = U[:n_elite]
                dev = (elite - elite.mean(axis=0)) / np.sqrt(max(n_elite - 1, 1))
                step = rng.standard_normal((n_mut, n_elite)) @ dev
            else:
                last_step = self.step_factor(gen, G)
                step = last_step * rng.standard_normal((n_mut, d))
            mut = U[im] + scale * step
            children = np.vstack([cross, mut])
            flip = rng.random(children.shape) < self.mutation_probability
            children[flip] = rng.random(int(flip.sum()))
            children = np.clip(children, 0.0, 1.0)
            if term.maxfev is not None:  # never exceed the evaluation budget
                children = children[: max(term.maxfev - tr.nfev, 0)]
            Fc = evaluate(children)
            U = np.vstack([U[:n_elite], children])
            F = np.concatenate([F[:n_elite], Fc])
            gen += 1
        return tr.result(self.name, popsize=P, mutation_step=last_step)
