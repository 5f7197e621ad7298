"""Genetic algorithm, structured like MATLAB's ``ga``.

Each generation (population P, scores ranked):

* **elite** — the best ``elite_fraction``·P members pass unchanged
  (the paper's "reproduction" 0.1);
* **crossover children** — ``crossover_fraction`` of the rest (paper 0.65):
  intermediate crossover, child = a + r ⊙ (b − a), r ~ U(0, ratio) per gene
  (MATLAB ``crossoverintermediate``; a scattered-gene crossover is poor on
  continuous variables);
* **mutation children** — the remaining members: a parent plus Gaussian noise
  whose scale shrinks linearly to 0 over the generations (MATLAB
  ``mutationgaussian``, Scale 1, Shrink 1, relative to the bound range);
* **uniform mutation** — every gene of every child is re-drawn uniformly within
  its bounds with probability ``mutation_probability`` (paper 0.015, MATLAB
  ``mutationuniform``).

Parents are chosen by stochastic universal sampling on rank-scaled fitness
(MATLAB ``fitscalingrank``: fitness ∝ 1/√rank; ``selectionstochunif``). All in
the unit cube of the log10 parameters; the whole population is evaluated in one
vectorised call.
"""

from __future__ import annotations

import numpy as np

from .base import Termination, Tracker, from_unit


class GA:
    name = "ga"

    def __init__(
        self,
        population_size: int = 420,
        generations: int = 2430,
        elite_fraction: float = 0.1,
        crossover_fraction: float = 0.65,
        mutation_probability: float = 0.015,
        crossover_ratio: float = 1.0,
        mutation_scale: float = 1.0,
        mutation_shrink: float = 1.0,
        stall_generations: int | None = 50,
        crossover: str = "intermediate",
        mutation: str = "adaptive",
        selection: str = "stochastic_uniform",
        tournament_size: int = 4,
        heuristic_ratio: float = 1.2,
        blx_alpha: float = 0.5,
        function_tolerance: float = 1e-6,
    ):
        self.population_size = population_size
        self.generations = generations
        self.elite_fraction = elite_fraction
        self.crossover_fraction = crossover_fraction
        self.mutation_probability = mutation_probability
        self.crossover_ratio = crossover_ratio
        self.mutation_scale = mutation_scale
        self.mutation_shrink = mutation_shrink
        self.stall_generations = stall_generations
        self.crossover = crossover
        self.mutation = mutation
        self.selection = selection
        self.tournament_size = tournament_size
        self.heuristic_ratio = heuristic_ratio
        self.blx_alpha = blx_alpha
        self.function_tolerance = function_tolerance

    def termination(self) -> Termination:
        return Termination(max_iter=self.generations, stall_iter=self.stall_generations, ftol=self.function_tolerance)

    @staticmethod
    def _select(rng, fitness: np.ndarray, n: int) -> np.ndarray:
        """Stochastic universal sampling: n parent indices, one random offset."""
        edges = np.cumsum(fitness / fitness.sum())
        pointers = (rng.random() + np.arange(n)) / n
        return np.minimum(np.searchsorted(edges, pointers), fitness.size - 1)

    def minimize(self, problem, rng: np.random.Generator, termination: Termination | None = None, callback=None):
        term = termination or self.termination()
        tr = Tracker(problem, term, callback)
        P, d = self.population_size, problem.n_var
        n_elite = max(1, int(round(self.elite_fraction * P)))
        n_cross = int(round(self.crossover_fraction * (P - n_elite)))
        n_mut = P - n_elite - n_cross
        G = term.max_iter or self.generations
        U = rng.random((P, d))
        F = problem.evaluate(from_unit(problem, U))
        tr.offer(from_unit(problem, U), F)
        gen = 0
        step = self.mutation_scale * 0.1
        while not tr.next_iteration():
            order = np.argsort(F)
            U, F = U[order], F[order]
            fitness = 1.0 / np.sqrt(np.arange(1, P + 1))
            n_par = 2 * n_cross + n_mut
            if self.selection == "tournament":  # population is sorted: the smallest index wins
                pidx = rng.integers(0, P, (n_par, self.tournament_size)).min(axis=1)
            else:
                pidx = self._select(rng, fitness, n_par)
            rng.shuffle(pidx)
            parents = U[pidx]
            problem_scores = F
            a, b = parents[:n_cross], parents[n_cross : 2 * n_cross]
            if self.crossover == "heuristic":
                fa, fb = problem_scores[pidx[:n_cross]], problem_scores[pidx[n_cross : 2 * n_cross]]
                better = np.where((fa <= fb)[:, None], a, b)
                worse = np.where((fa <= fb)[:, None], b, a)
                cross = worse + self.heuristic_ratio * (better - worse)
            elif self.crossover == "blx":
                cross = a + rng.uniform(-self.blx_alpha, 1 + self.blx_alpha, (n_cross, d)) * (b - a)
            else:
                cross = a + rng.uniform(0, self.crossover_ratio, (n_cross, d)) * (b - a)
            if self.mutation == "elite_spread":
                # step per gene = the spread of the elite: large while the good members
                # disagree, small once they agree — follows long, thin valleys
                sigma = self.mutation_scale * U[:n_elite].std(axis=0)
            elif self.mutation == "adaptive":
                # MATLAB's default for bounded problems (mutationadaptfeasible): the step
                # grows after a generation that improved the best, shrinks otherwise
                sigma = step
            else:  # mutationgaussian: scale shrinking linearly over the generations
                sigma = self.mutation_scale * max(0.0, 1 - self.mutation_shrink * gen / G)
            mut = parents[2 * n_cross :] + sigma * rng.standard_normal((n_mut, d))
            children = np.vstack([cross, mut])
            flip = rng.random(children.shape) < self.mutation_probability
            children[flip] = rng.random(int(flip.sum()))
            children = np.clip(children, 0.0, 1.0)
            Fc = problem.evaluate(from_unit(problem, children))
            U = np.vstack([U[:n_elite], children])
            F = np.concatenate([F[:n_elite], Fc])
            best_before = tr.best_f
            tr.offer(from_unit(problem, children), Fc)
            step = min(step * 2.0, 0.5) if tr.best_f < best_before else max(step / 2.0, 1e-6)
            gen += 1
        return tr.result(self.name, population_size=P)
