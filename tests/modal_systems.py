"""Synthetic non-proportionally damped systems for the modal-fit tests and benchmark.

Built from M, C, K with a damping matrix that is not a combination of M and K;
the exact FRFs come from a direct solve of (K − ω²M + iωC) x = F per frequency
and the exact poles from the eigenvalues of the state-space matrix — both
independent of the fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import eig
from scipy.stats import ortho_group


@dataclass(frozen=True)
class System:
    """M (kg), C (N s/m), K (N/m) and the input / output DOFs of the FRFs."""

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    outputs: tuple
    input: int = 0

    def receptance(self, f) -> np.ndarray:
        """(F, m) exact receptances x_out / F_in, m/N, at ``f`` (Hz)."""
        w = 2 * np.pi * np.asarray(f, float)[:, None, None]
        rhs = np.zeros((self.M.shape[0], 1))
        rhs[self.input] = 1.0
        x = np.linalg.solve(self.K[None] - w**2 * self.M[None] + 1j * w * self.C[None], rhs[None])[..., 0]
        return x[:, list(self.outputs)]

    def frf(self, f, quantity: str) -> np.ndarray:
        """(F, m) exact FRFs in ``quantity`` (receptance, mobility or accelerance)."""
        k = {"receptance": 0, "mobility": 1, "accelerance": 2}[quantity]
        return self.receptance(f) * ((2j * np.pi * np.asarray(f, float)) ** k)[:, None]

    def poles(self) -> tuple[np.ndarray, np.ndarray]:
        """Exact natural frequencies (Hz) and damping ratios, from the state-space eigenvalues."""
        n = self.M.shape[0]
        A = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-np.linalg.solve(self.M, self.K), -np.linalg.solve(self.M, self.C)]])
        lam = eig(A)[0]
        lam = lam[lam.imag > 0]
        lam = lam[np.argsort(np.abs(lam))]
        return np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam)


def make_system(fn_hz, zeta: float, seed: int, outputs=(0, 1, 2)) -> System:
    """A system whose undamped natural frequencies are ``fn_hz`` (Hz), non-proportionally damped.

    M = diag(masses); K = M^½ Φ diag(ω²) Φᵀ M^½ with a random orthogonal Φ; C has a
    proportional part giving about ``zeta`` plus a localised damper between DOFs 0
    and 1, which couples the modes (complex modes).
    """
    rng = np.random.default_rng(seed)
    n = len(fn_hz)
    m = rng.uniform(0.2, 1.0, n)
    Ms = np.diag(np.sqrt(m))
    Phi = ortho_group.rvs(n, random_state=rng)
    wn = 2 * np.pi * np.asarray(fn_hz, float)
    K = Ms @ Phi @ np.diag(wn**2) @ Phi.T @ Ms
    K = 0.5 * (K + K.T)
    C = Ms @ Phi @ np.diag(2 * zeta * wn) @ Phi.T @ Ms
    c_loc = 2 * zeta * np.sqrt(K[0, 0] * m[0])  # a damper as strong as the proportional part
    C[np.ix_([0, 1], [0, 1])] += c_loc * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return System(np.diag(m), 0.5 * (C + C.T), K, tuple(outputs))


FOUR = make_system([420.0, 1130.0, 1870.0, 2560.0], 0.015, seed=1)
FIVE = make_system([610.0, 1482.0, 1622.0, 2240.0, 2790.0], 0.012, seed=2)


def add_noise(Y, level: float, seed: int) -> np.ndarray:
    """Complex Gaussian noise, standard deviation ``level`` × peak |y_e| of each column."""
    rng = np.random.default_rng(seed)
    s = level * np.abs(Y).max(0)
    return Y + s * (rng.standard_normal(Y.shape) + 1j * rng.standard_normal(Y.shape)) / np.sqrt(2)
