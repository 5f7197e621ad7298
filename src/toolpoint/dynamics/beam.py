"""Exact Timoshenko beam segment: transfer and dynamic stiffness matrices.

A uniform segment of length L (m) with Young's modulus E (Pa, complex
E(1 + iη) for structural damping η), shear modulus G = E / (2(1 + ν)), density
ρ (kg/m³), area A (m²), second moment I (m⁴) and Cowper shear coefficient κ.
With the state z = [w, ψ, Q, M] (deflection m, section rotation rad, shear
force N, bending moment N m), Q = κGA(w' − ψ), M = EIψ', harmonic motion at
ω (rad/s) obeys z' = A z with

    w' = ψ + Q/(κGA)      ψ' = M/(EI)
    Q' = −ρAω² w          M' = −Q − ρIω² ψ.

The transfer matrix is T = exp(A L), evaluated in closed form: the
eigenvalues s of A² solve s² + (am + bj) s + bm(aj − 1) = 0 with
a = 1/(κGA), b = 1/(EI), m = ρAω², j = ρIω², and with C(s) = cosh(L√s),
S(s) = sinh(L√s)/√s (entire functions of s) Sylvester's formula gives

    T = C(A²) + A·S(A²),   g(A²) = Δg · A² + (g(s1) − s1 Δg) · I,
    Δg = (g(s1) − g(s2)) / (s1 − s2).

Nodal loads are the external force/moment on the segment ends:
(F0, M0) = −(Q(0), M(0)), (F1, M1) = (Q(L), M(L)); eliminating the internal
forces from T gives the 4×4 dynamic stiffness D(ω) on [w0, ψ0, w1, ψ1]
(symmetric, and the exact static stiffness at ω = 0). ψ is the bending
rotation of the section, the work conjugate of the moment; it equals dy/dx
for a slender beam and shares its sign (one global x axis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


# Below this |s| L² the series are used: the closed-form divided differences
# lose ~ε/(|s1 − s2| L²) there, the series are exact to round-off.
SERIES_LIMIT = 0.25


def cowper_kappa(nu: float, id_over_od: float = 0.0) -> float:
    """Cowper's shear coefficient of a hollow circle, m = id/od.

    κ = 6(1+ν)(1+m²)² / ((7+6ν)(1+m²)² + (20+12ν)m²)
    """
    m2 = id_over_od**2
    return 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)


@dataclass(frozen=True)
class Section:
    """Cross-section and material of a uniform segment (SI units).

    Attributes
    ----------
    E, G : complex
        Young's and shear modulus, Pa, complex E(1 + iη) with structural damping.
    rho : float
        Density, kg/m³.
    A, Iz : float
        Area m² and second moment of area about the bending (z) axis, m⁴.
    kappa : float
        Shear coefficient (Cowper).
    """

    E: complex  # Pa, complex with structural damping
    G: complex  # Pa
    rho: float  # kg/m³
    A: float  # m²
    Iz: float  # m⁴
    kappa: float

    @classmethod
    def tube(cls, od_m: float, id_m: float, E: float, rho: float, nu: float, loss_factor: float = 0.0):
        """Hollow (or solid, id 0) circular section."""
        Ec = E * (1 + 1j * loss_factor)
        A = math.pi / 4 * (od_m**2 - id_m**2)
        Iz = math.pi / 64 * (od_m**4 - id_m**4)
        return cls(Ec, Ec / (2 * (1 + nu)), rho, A, Iz, cowper_kappa(nu, id_m / od_m))

    @property
    def mass_per_length(self) -> float:
        """ρA, kg/m."""
        return self.rho * self.A

    def wavenumber(self, omega) -> np.ndarray:
        """Euler–Bernoulli bending wavenumber β = (ρAω²/EI)^¼, 1/m (a size estimate)."""
        return (self.rho * self.A * np.asarray(omega, float) ** 2 / abs(self.E * self.Iz)) ** 0.25


def _series(x, odd: bool, terms: int = 10):
    """Σ x^k/(2k)! (odd=False) or Σ x^k/(2k+1)! (odd=True); 10 terms are exact to 1e-24 for |x| ≤ 0.25."""
    out = np.zeros_like(x)
    xp = np.ones_like(x)
    for k in range(terms):
        out = out + xp / math.factorial(2 * k + (1 if odd else 0))
        xp = xp * x
    return out


def _divided_series(s1, s2, L, odd: bool, terms: int = 11):
    """(g(s1) − g(s2))/(s1 − s2) by series, for g = C (odd=False) or S/L (odd=True)."""
    x1, x2 = L * L * s1, L * L * s2
    # (x1^k − x2^k)/(x1 − x2) = h_k, h_1 = 1, h_k = x1 h_{k−1} + x2^{k−1}
    out = np.zeros_like(s1)
    h = np.ones_like(s1)
    x2p = np.ones_like(s1)
    for k in range(1, terms):
        out = out + h / math.factorial(2 * k + (1 if odd else 0))
        x2p = x2p * x2
        h = x1 * h + x2p
    return out * L * L  # d/ds of x = L² s


def _coefficients(a, b, m, j, L):
    """Sylvester coefficients C0, S0, C1, S1 for element-wise arrays a, b, m, j, L (all (N,))."""
    p = a * m + b * j
    q = b * m * (a * j - 1)
    r = np.sqrt(p * p - 4 * q)
    r = np.where((np.conj(p) * r).real >= 0, r, -r)  # no cancellation in p + r
    s1 = -(p + r) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        s2 = np.where(s1 != 0, q / s1, 0)

    C0, S0, C1, S1 = (np.empty(a.size, complex) for _ in range(4))
    # Series where |s|L² is small (incl. ω = 0, where s1 = s2 = 0), closed form elsewhere.
    small = np.maximum(abs(s1), abs(s2)) * L * L < SERIES_LIMIT
    if np.any(small):
        t1, t2, Ls = s1[small], s2[small], L[small]
        dC = _divided_series(t1, t2, Ls, odd=False)
        dS = Ls * _divided_series(t1, t2, Ls, odd=True)
        C1[small], S1[small] = dC, dS
        C0[small] = _series(Ls * Ls * t1, odd=False) - t1 * dC
        S0[small] = Ls * _series(Ls * Ls * t1, odd=True) - t1 * dS
    big = ~small
    if np.any(big):
        t1, t2, Lb = s1[big], s2[big], L[big]
        r1, r2 = np.sqrt(t1), np.sqrt(t2)
        gC1, gC2 = np.cosh(Lb * r1), np.cosh(Lb * r2)
        gS1, gS2 = np.sinh(Lb * r1) / r1, np.sinh(Lb * r2) / r2
        dC = (gC1 - gC2) / (t1 - t2)
        dS = (gS1 - gS2) / (t1 - t2)
        C1[big], S1[big] = dC, dS
        C0[big] = gC1 - t1 * dC
        S0[big] = gS1 - t1 * dS
    return C0, S0, C1, S1


def transfer_matrices(pieces, omega) -> np.ndarray:
    """Transfer matrices (P, F, 4, 4) on [w, ψ, Q, M] of pieces [(Section, length m), …] at ω (F,) rad/s.

    T = C0 I + S0 A + C1 A² + S1 A³, written out entry by entry (A² and A³ in
    closed form), all pieces and frequencies in one vectorised pass.
    """
    w = np.asarray(omega, dtype=float).reshape(-1)
    P, F = len(pieces), w.size
    col = lambda v: np.repeat(np.asarray(v), F)  # noqa: E731 — per piece, repeated over frequency
    a = col([1.0 / (s.kappa * s.G * s.A) for s, _ in pieces])
    b = col([1.0 / (s.E * s.Iz) for s, _ in pieces])
    m = col([s.rho * s.A for s, _ in pieces]) * np.tile(w**2, P) + 0j
    j = col([s.rho * s.Iz for s, _ in pieces]) * np.tile(w**2, P) + 0j
    L = col([float(length) for _, length in pieces])
    C0, S0, C1, S1 = _coefficients(a, b, m, j, L)
    T = np.empty((P * F, 4, 4), complex)
    T[:, 0] = np.stack([C0 - a * m * C1, S0 - (a * m + b * j) * S1, a * S0 - (a * a * m + b) * S1, b * C1], -1)
    T[:, 1] = np.stack([b * m * S1, C0 - b * j * C1, -b * C1, b * S0 - b * b * j * S1], -1)
    T[:, 2] = np.stack([-m * S0 + a * m * m * S1, -m * C1, C0 - a * m * C1, -b * m * S1], -1)
    T[:, 3] = np.stack([m * C1, -j * S0 + (m + j * j * b) * S1, -S0 + (a * m + b * j) * S1, C0 - b * j * C1], -1)
    return T.reshape(P, F, 4, 4)


def transfer_matrix(sec: Section, L: float, omega) -> np.ndarray:
    """Transfer matrix T (F, 4, 4) of one uniform piece of length L (m); see :func:`transfer_matrices`."""
    return transfer_matrices([(sec, L)], omega)[0]


def mul2(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Product of two stacks of 2×2 matrices (F, 2, 2), written out entry by entry (faster than np.matmul)."""
    a00, a01, a10, a11 = A[:, 0, 0], A[:, 0, 1], A[:, 1, 0], A[:, 1, 1]
    b00, b01, b10, b11 = B[:, 0, 0], B[:, 0, 1], B[:, 1, 0], B[:, 1, 1]
    C = np.empty(np.broadcast_shapes(A.shape, B.shape), np.result_type(A, B))
    C[:, 0, 0] = a00 * b00 + a01 * b10
    C[:, 0, 1] = a00 * b01 + a01 * b11
    C[:, 1, 0] = a10 * b00 + a11 * b10
    C[:, 1, 1] = a10 * b01 + a11 * b11
    return C


def inv2(M: np.ndarray) -> np.ndarray:
    """Inverse of a stack of 2×2 matrices (..., 2, 2), closed form."""
    a, b, c, d = M[..., 0, 0], M[..., 0, 1], M[..., 1, 0], M[..., 1, 1]
    det = a * d - b * c
    out = np.empty_like(M)
    out[..., 0, 0] = d / det
    out[..., 0, 1] = -b / det
    out[..., 1, 0] = -c / det
    out[..., 1, 1] = a / det
    return out


def stiffness_from_transfer(T: np.ndarray) -> np.ndarray:
    """Exact dynamic stiffness D (F, 4, 4) on [w0, ψ0, w1, ψ1] from a transfer matrix.

    From T = [[T11, T12], [T21, T22]] (2×2 blocks, d = [w, ψ], f = [Q, M]) and
    nodal loads (F0, M0) = −f(0), (F1, M1) = f(L):
    D = [[T12⁻¹T11, −T12⁻¹], [T21 − T22T12⁻¹T11, T22T12⁻¹]].
    Singular only at the clamped–clamped natural frequencies of the piece;
    callers keep β L ≤ 2 so none lies in band.
    """
    T11, T12 = T[:, :2, :2], T[:, :2, 2:]
    T21, T22 = T[:, 2:, :2], T[:, 2:, 2:]
    T12i = inv2(T12)
    X = mul2(T12i, T11)
    D = np.empty_like(T)
    D[:, :2, :2] = X
    D[:, :2, 2:] = -T12i
    D[:, 2:, :2] = T21 - mul2(T22, X)
    D[:, 2:, 2:] = mul2(T22, T12i)
    # Symmetric in exact arithmetic; averaging removes round-off asymmetry.
    return 0.5 * (D + np.swapaxes(D, 1, 2))


def dynamic_stiffness(sec: Section, L: float, omega) -> np.ndarray:
    """Exact dynamic stiffness (F, 4, 4) of a uniform piece; see :func:`stiffness_from_transfer`."""
    return stiffness_from_transfer(transfer_matrix(sec, L, omega))
