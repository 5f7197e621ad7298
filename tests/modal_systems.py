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

    def modal_constants(self) -> tuple[np.ndarray, np.ndarray]:
        """Exact poles λ_r (rad/s, Im > 0, by frequency) and modal constants A_er (m/(N s)), (n,) and (n, m).

        From the state-space form x' = A x + B u, y = C x: H(s) = Σ_r (C v_r)(w_r B) / (s − λ_r)
        with right eigenvectors v_r and W = V⁻¹, so A_er = (C v_r)_e (w_r B).
        """
        n = self.M.shape[0]
        A = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-np.linalg.solve(self.M, self.K), -np.linalg.solve(self.M, self.C)]])
        B = np.zeros(2 * n)
        B[n:] = np.linalg.solve(self.M, np.eye(n)[self.input])
        lam, V = eig(A)
        W = np.linalg.inv(V)
        C = np.zeros((len(self.outputs), 2 * n))
        C[np.arange(len(self.outputs)), list(self.outputs)] = 1.0
        res = (C @ V) * (W @ B)[None]  # (m, 2n)
        keep = np.flatnonzero(lam.imag > 0)
        keep = keep[np.argsort(np.abs(lam[keep]))]
        return lam[keep], res[:, keep].T

    def crlb(self, f, noise: str, level: float) -> tuple[np.ndarray, np.ndarray]:
        """Cramér–Rao lower bound of the natural frequencies and damping ratios, as relative 1σ, (n,) each.

        Data: the FRFs at ``f`` (Hz) in ``noise`` (the quantity the noise is white in) with complex
        Gaussian noise ``level`` × peak |y_e| (as :func:`add_noise`; the peak over ``f``). Model:
        the complex-mode sum with free complex modal constants per FRF and the residual terms
        U_e + iω V_e − L_e/ω² (all nuisance parameters). Analytic Jacobian, Fisher information
        JᵀJ / σ² of the real and imaginary parts, parameters (ln σ_r, ln ω_dr, Re A_er, Im A_er, U, V, L).
        """
        k = {"receptance": 0, "mobility": 1, "accelerance": 2}[noise]
        w = 2 * np.pi * np.asarray(f, float)
        s = 1j * w[:, None]
        lam, A = self.modal_constants()
        n, m = A.shape
        sig = level * np.abs(self.frf(f, noise)).max(0) / np.sqrt(2)  # per real component
        u, v = 1.0 / (s - lam), 1.0 / (s - np.conj(lam))
        fac = (1j * w) ** k
        blocks = []  # per FRF e: (F, P) complex derivative of its model
        P = 2 * n + m * (2 * n + 3)
        for e in range(m):
            D = np.zeros((w.size, P), complex)
            for j, g in enumerate((lam.real, 1j * lam.imag)):  # dλ/d ln σ = −σ = Re λ, dλ/d ln ω_d = iω_d
                D[:, j * n:(j + 1) * n] = A[:, e] * g * u**2 + np.conj(A[:, e] * g) * v**2
            o = 2 * n + e * (2 * n + 3)
            D[:, o:o + n], D[:, o + n:o + 2 * n] = u + v, 1j * (u - v)
            D[:, o + 2 * n], D[:, o + 2 * n + 1], D[:, o + 2 * n + 2] = 1.0, 1j * w, -1.0 / w**2
            blocks.append(D * (fac / sig[e])[:, None])
        J = np.concatenate([np.concatenate([b.real, b.imag]) for b in blocks])
        cov = np.linalg.inv(J.T @ J)
        a = lam.real**2 / np.abs(lam) ** 2  # ln ω_n = a ln σ + (1 − a) ln ω_d; ln ζ = (1 − a)(ln σ − ln ω_d)
        i, j = np.arange(n), np.arange(n) + n
        var_w = a**2 * cov[i, i] + (1 - a) ** 2 * cov[j, j] + 2 * a * (1 - a) * cov[i, j]
        var_z = (1 - a) ** 2 * (cov[i, i] + cov[j, j] - 2 * cov[i, j])
        return np.sqrt(var_w), np.sqrt(var_z)


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
