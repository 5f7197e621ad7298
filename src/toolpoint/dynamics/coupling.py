"""Receptance coupling substructure analysis (RCSA) through complex joints.

Eq. (1)/(3) of Čiča et al. (after Erturk et al.), one global x axis:

    C_ii = A_ii − A_ic (A_cc + B + K⁻¹)⁻¹ A_ci,   K = diag(kt + iωct, kr + iωcr),

where A is the receptance of the part being added (i its free end, c its
coupling end), B the receptance of the existing structure at the coupling
point, and K the joint's complex stiffness (kt N/m, ct N s/m, kr N m/rad,
cr N m s/rad). A rigid joint is K⁻¹ = 0.
"""

from __future__ import annotations

import numpy as np

from .beam import inv2

CHUNK = 16
"""Joint parameter sets per vectorised block of :class:`ToolPointCoupler` (cache-sized temporaries)."""


def joint_compliance(params, omega) -> np.ndarray:
    """K⁻¹ diagonal: (…, F, 2) with 1/(kt + iωct), 1/(kr + iωcr).

    ``params`` (…, 4) = [kt, ct, kr, cr]; an infinite stiffness gives 0 (rigid).
    """
    p = np.asarray(params, float)
    w = np.asarray(omega, float)
    kt, ct, kr, cr = (p[..., i, None] for i in range(4))
    with np.errstate(divide="ignore"):
        return np.stack([1.0 / (kt + 1j * w * ct), 1.0 / (kr + 1j * w * cr)], -1)


def couple(A: np.ndarray, B: np.ndarray, params, omega) -> np.ndarray:
    """Free-end receptance (F, 2, 2) of ``A`` joined to ``B`` by a joint.

    A (F, 4, 4) on [coupling end c, free end i]; B (F, 2, 2) at the coupling
    point of the existing structure; params = [kt, ct, kr, cr].
    """
    Acc, Aci = A[:, :2, :2], A[:, :2, 2:]
    Aic, Aii = A[:, 2:, :2], A[:, 2:, 2:]
    M = Acc + B
    kinv = joint_compliance(params, omega)
    M[:, 0, 0] += kinv[:, 0]
    M[:, 1, 1] += kinv[:, 1]
    return Aii - Aic @ inv2(M) @ Aci


def joint_coefficients(params) -> np.ndarray:
    """c(p) (N, 8) = [kt kr, ct cr, kt cr + ct kr, kt, ct, kr, cr, 1] for params (N, 4).

    With k̃t = kt + iωct and k̃r = kr + iωcr every term of the coupled
    tool-point expression is linear in these eight real numbers.
    """
    p = np.atleast_2d(np.asarray(params, float))
    kt, ct, kr, cr = p.T
    return np.stack([kt * kr, ct * cr, kt * cr + ct * kr, kt, ct, kr, cr, np.ones_like(kt)], -1)


def joint_coefficient_derivatives(params) -> np.ndarray:
    """∂c/∂p (N, 4, 8) for params (N, 4) = [kt, ct, kr, cr]."""
    p = np.atleast_2d(np.asarray(params, float))
    kt, ct, kr, cr = p.T
    z, o = np.zeros_like(kt), np.ones_like(kt)
    return np.stack(
        [
            np.stack([kr, z, cr, o, z, z, z, z], -1),
            np.stack([z, cr, kr, z, o, z, z, z], -1),
            np.stack([kt, z, ct, z, z, o, z, z], -1),
            np.stack([z, ct, kt, z, z, z, o, z], -1),
        ],
        1,
    )


class ToolPointCoupler:
    """Tool-point direct receptance h for many holder–tool joints at once.

    Only entry (0, 0) of Eq. (3) is needed. With P = T_cc + SH (2×2),
    u = row 0 of T_ic, v = column 0 of T_ci and k̃t = kt + iωct,
    k̃r = kr + iωcr, multiplying through by k̃t k̃r gives

        h = T_ii,00 − (C k̃t k̃r + α k̃t + β k̃r) / (Δ k̃t k̃r + P00 k̃t + P11 k̃r + 1)

    with α = u0v0, β = u1v1, Δ = det P and C = u·adj(P)·v per frequency.
    Expanding k̃t k̃r = kt kr − ω² ct cr + iω(kt cr + ct kr), numerator and
    denominator are ``c(p) @ B`` for the eight real joint coefficients c(p)
    (:func:`joint_coefficients`) and fixed complex bases B (8, F) — so a whole
    population is two real matrix products (BLAS) and one division. Rigid
    joint: h = T_ii,00 − C/Δ.
    """

    def __init__(self, T: np.ndarray, SH: np.ndarray, omega):
        self._setup(T[:, 2, 2].copy(), T[:, 2, :2], T[:, :2, 2], T[:, :2, :2] + SH, omega)

    @classmethod
    def from_parts(cls, t00, u, v, P, omega) -> "ToolPointCoupler":
        """The same rational form for any receptance h = t00 − u (P + K⁻¹)⁻¹ v.

        By the Woodbury identity, adding one 2-DOF spring element K = diag(k̃t, k̃r) (a joint between
        DOF pairs a and b, or a bearing from a to ground) to a structure of receptance G₀ gives, between
        any response DOF i and force DOF j,

            h_ij = G₀,ij − (G₀,ib − G₀,ia)(P + K⁻¹)⁻¹(G₀,bj − G₀,aj),  P = Dᵀ G₀ D,

        D = e_b − e_a (e_b for a bearing): this class with t00 = G₀,ij, u = G₀,ib − G₀,ia (F, 2),
        v = G₀,bj − G₀,aj (F, 2). ``params`` are then [k, c, kr, cr] of that element.

        Parameters
        ----------
        t00 : (F,) complex
            Receptance without the element, m/N (or 1/N, rad/N, rad/(N m) for other DOF pairs).
        u, v : (F, 2) complex
            Row and column couplings to the element's (w, ψ) DOFs.
        P : (F, 2, 2) complex
            Receptance across the element's DOFs without it.
        omega : (F,) float
            rad/s.

        Returns
        -------
        ToolPointCoupler

        Examples
        --------
        A mass-less spring to ground seen from its own DOF: h = 1/(k + iωc) once G₀ → ∞ is removed
        (here G₀ = P = 1 m/N, u = v = [1, 0]: h = 1 − 1/(1 + 1/k̃) = 1/(k̃ + 1)).

        >>> one = np.ones(1, complex)
        >>> P = np.eye(2, dtype=complex)[None]
        >>> c = ToolPointCoupler.from_parts(one, np.array([[1, 0]], complex), np.array([[1, 0]], complex), P, [1.0])
        >>> complex(c(np.array([3.0, 0.0, 1.0, 0.0]))[0])
        (0.25+0j)
        """
        self = cls.__new__(cls)
        self._setup(np.asarray(t00, complex).copy(), np.asarray(u, complex), np.asarray(v, complex),
                    np.asarray(P, complex), omega)
        return self

    def _setup(self, t00, u, v, P, omega) -> None:
        """Bases B_num, B_den (8, F) of the rational form (class docstring)."""
        w = np.asarray(omega, float)
        self.omega = w
        self.t00 = t00
        self._u, self._v, self._P = u, v, P  # kept so that couplers can be stacked (from_parts)
        alpha = u[:, 0] * v[:, 0]
        beta = u[:, 1] * v[:, 1]
        self.det = P[:, 0, 0] * P[:, 1, 1] - P[:, 0, 1] * P[:, 1, 0]
        self.C = u[:, 0] * (P[:, 1, 1] * v[:, 0] - P[:, 0, 1] * v[:, 1]) + u[:, 1] * (
            P[:, 0, 0] * v[:, 1] - P[:, 1, 0] * v[:, 0]
        )
        zero = np.zeros_like(self.C)
        iw = 1j * w
        self.B_num = np.stack([self.C, -(w**2) * self.C, iw * self.C, alpha, iw * alpha, beta, iw * beta, zero])
        self.B_den = np.stack(
            [self.det, -(w**2) * self.det, iw * self.det, P[:, 0, 0], iw * P[:, 0, 0], P[:, 1, 1], iw * P[:, 1, 1],
             np.ones_like(self.C)]
        )

    @staticmethod
    def _real_matmul(c: np.ndarray, B: np.ndarray) -> np.ndarray:
        """Real (…, 8) @ complex (8, F) as one real BLAS product on the interleaved (re, im) view."""
        out = c @ B.view(float)
        return out.view(complex)

    def num_den(self, params) -> tuple[np.ndarray, np.ndarray]:
        """Numerator and denominator (N, F) of the coupled expression."""
        c = joint_coefficients(params)
        return self._real_matmul(c, self.B_num), self._real_matmul(c, self.B_den)

    def __call__(self, params) -> np.ndarray:
        """h (N, F) complex, m/N, for params (N, 4) = [kt, ct, kr, cr] (or (4,) → (F,))."""
        single = np.ndim(params) == 1
        c = joint_coefficients(params)
        h = np.empty((c.shape[0], self.t00.size), complex)
        # Chunks of a few sets keep the (chunk, F) temporaries in cache (timings: docs/design/dynamics.md).
        for s in range(0, c.shape[0], CHUNK):
            x = c[s : s + CHUNK]
            q = self._real_matmul(x, self.B_num)
            q /= self._real_matmul(x, self.B_den)
            np.subtract(self.t00, q, out=h[s : s + CHUNK])
        return h[0] if single else h

    def jacobian(self, params) -> np.ndarray:
        """∂h/∂p (N, 4, F) for params (N, 4), exact (quotient rule on c(p) @ B)."""
        num, den = self.num_den(params)
        dc = joint_coefficient_derivatives(params)  # (N, 4, 8)
        dnum = self._real_matmul(dc, self.B_num)
        dden = self._real_matmul(dc, self.B_den)
        return -(dnum * den[:, None] - num[:, None] * dden) / (den**2)[:, None]

    def rigid(self) -> np.ndarray:
        """h (F,) for an infinitely stiff holder–tool joint."""
        return self.t00 - self.C / self.det
