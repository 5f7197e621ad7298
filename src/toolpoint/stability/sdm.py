"""Semi-/full discretisation of milling stability for state-space tool-point models.

Insperger & Stépán (2002) "Semi-discretization method for delayed systems",
IJNME 55:503–518; (2004) "Updated semi-discretization method for periodic
delay-differential equations with discrete delay", IJNME 61:117–141.

Model. The tool point is ż = A z + B F, r = C z
(:class:`~toolpoint.stability.statespace.StateSpaceModel`: n states, forces
F = (F_x, F_y) in N, displacements r = (x, y) in m). With the directional
matrix H(t) (N/m² per m of chip, :mod:`~toolpoint.stability.milling`) the
regenerative force at axial depth a (m) is F = −a H(t) [r(t) − r(t − T)],
T = 60/(N n) s the tooth period, so

    ż = (A − a B H(t) C) z + a B H(t) r(t − T).

Only the d directions that move (non-zero rows of C) and the force
directions that excite the model (non-zero columns of B) are kept.

Discretisation (full discretisation: Ding, Zhu, Zhang & Ding, "A full-discretization
method for prediction of milling stability", IJMTM 50 (2010) 502–509). Time
runs from a tooth's entry. H(t) is non-zero only on the cut [0, t_c],
t_c = min(T, (φ_ex − φ_st)/Ω) s, Ω the spindle speed in rad/s. The cut is
split into m steps Δt = t_c/m; on each, H is replaced by its exact average
H_i (:func:`~toolpoint.stability.milling.interval_directional_matrix`) and
the regenerative displacement g = r(t − T) − C z(t) by the straight line
between its values at the step's ends, so that, with P = e^{AΔt},

    z_{i+1} = P z_i + a (Γ0 − Γ1) H_i g_i + a Γ1 H_i g_{i+1},
    Γ0 = ∫₀^Δt e^{A(Δt−s)} ds B,   Γ1 = ∫₀^Δt e^{A(Δt−s)} (s/Δt) ds B.

P, Γ0 and Γ1 do not depend on the depth: one exponential of the Van Loan
block [[AΔt, BΔt, 0], [0, 0, I], [0, 0, 0]] per speed serves every depth
(the first-order SDM of Insperger & Stépán puts a B H_i C into the
exponential, one per step and depth). The term in z_{i+1} is solved exactly
by the Woodbury identity (a d × d inverse). The error in the limit is
O(Δt²), as for the first-order SDM, and both converge to the same limit
(``docs/design/stability.md``). Free flight [t_c, T] has no delayed term and
is solved exactly, z(T) = e^{A(T − t_c)} z(t_c). A model whose poles are all
complex is first put in real modal coordinates (:func:`_modal_basis`).

Delayed-displacement nodes. The delayed displacement is carried at every
s-th step only (q + 1 = m/s + 1 nodes over the cut) and interpolated to the
m + 1 step ends by local Lagrange polynomials of degree 9 (``s = 1``:
every node). Because the delay is one tooth period, the state
ζ = (z_0, r_0, …, r_q) of size n + (q + 1)d maps linearly over one period,
ζ' = Φ ζ; the cut is stable iff the spectral radius ρ(Φ) < 1 (Floquet). The
multiplier of largest modulus comes from a Krylov subspace of Φ where Φ is
large, all its eigenvalues where that fails or Φ is small
(:func:`critical_multipliers`).

Default resolution. A chatter wave is a period of f_w = 1.1 × the highest
frequency that can chatter within the searched depths, Hz: the highest
zero-order chatter frequency of the speed range, or the highest frequency
(at most the highest natural frequency) whose zero-order limit lies within
the search range, whichever is higher (1.1 × the highest natural frequency
with ``seed=False`` and in :func:`sdm_spectral_radius`). The speed range's
chatter frequencies alone are not enough: a mode the zero-order lobes pass
over at these speeds but the delay's interpolation does not resolve turns
spuriously unstable (the example tool of :mod:`toolpoint.shop` at 9000 rpm
alone: its 2213 Hz mode at 0.56 mm, against 1.07 mm on the 776 Hz mode
with the mode resolved). Per speed,
m = accuracy · max(24 · f_w t_c, 20) on a ladder 20, 24, 28, 32, 40, …
(≈ 2^(1/4) apart) within [20, m_max] (default 200 × max(accuracy, 1)), and
s is the largest divisor of m (≤ 16) leaving at least 5 · max(accuracy, 1)
nodes per wave and 8 node intervals over the cut.
``m`` counts steps over the cut, not over the tooth period. Measured
accuracy and cost are in ``docs/design/stability.md``.

Stability limit. Per speed the depth starts at 0.85 × the zero-order limit
(or at ``depth_min`` where no zero-order lobe covers the speed, or where
the start is already unstable) and rises by at most the ratio ``step`` per
evaluation (less where the secant of ln ρ against ln a puts ρ = 1 nearer)
until ρ ≥ 1; the bracket is then shrunk by Illinois false position on ln ρ
against ln a, with bisection steps, to a relative width ``rtol``. An
unstable band thinner than ``step`` in depth can be stepped over. Speeds are
searched in blocks of 50, all still-open speeds of a block at once; BLAS is
held to one thread meanwhile.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.linalg import matrix_balance

from ..blas import single_thread_blas
from ..errors import InputError
from .cutting import CuttingConditions, check_cutting
from .milling import Lobe, LobeResult, check_rpm, interval_directional_matrix
from .statespace import StateSpaceModel

__all__ = ["sdm_lobes", "sdm_limit_near", "sdm_limit_near_many", "sdm_spectral_radius", "as_state_space",
           "expm_batch", "STEPS_PER_WAVE", "NODES_PER_WAVE"]

STEPS_PER_WAVE = 24
"""Default steps of the cut per chatter wave at ``accuracy=1`` (module docstring)."""
NODES_PER_WAVE = 5
"""Default delayed-displacement nodes per chatter wave at ``accuracy=1``."""
INTERP_DEGREE = 9  # local Lagrange interpolation of the delayed displacement between nodes
MIN_NODES = 8  # fewest node intervals over the cut
WAVE_MARGIN = 1.1  # resolution frequency / highest zero-order chatter frequency
M_MIN, M_MAX = 20, 200  # bounds of the step count over the cut
SEED_FRACTION = 0.85  # the seeded search starts at this fraction of the zero-order limit
_BLOCK_SPEEDS = 50  # speeds searched together (progress is reported per block)
_ZOA_POINTS = 200_000  # most frequency points of the zero-order seed
# Soft cap on floats held by one batch (expm blocks and Floquet matrices).
_CHUNK_FLOATS = 4_000_000


# ------------------------------------------------------------------ batched expm
def expm_batch(X: np.ndarray) -> np.ndarray:
    """Matrix exponentials of a stack of small square matrices.

    Taylor polynomial of degree 12 (Horner) of X/2^s with a per-matrix s such
    that ‖X/2^s‖₁ ≤ 1/2 (truncation error < 0.5¹³/13! ≈ 2e-14 relative), then
    s squarings. Stacked matrix products keep the work in NumPy, without a
    Python loop over the matrices.

    Parameters
    ----------
    X : numpy.ndarray
        (..., k, k) real or complex matrices (dimensionless: time already multiplied in).

    Returns
    -------
    numpy.ndarray
        e^X, same shape.

    Examples
    --------
    >>> E = expm_batch(np.array([[[0.0, 1.0], [-1.0, 0.0]]]))  # a rotation by 1 rad
    >>> bool(np.allclose(E[0], [[np.cos(1), np.sin(1)], [-np.sin(1), np.cos(1)]]))
    True
    """
    shape = X.shape
    X = X.reshape(-1, shape[-2], shape[-1])
    norm = np.abs(X).sum(axis=-2).max(axis=-1)
    s = np.maximum(0, np.ceil(np.log2(np.maximum(norm, 1e-300) / 0.5))).astype(int)
    X = X / (2.0 ** s)[:, None, None]
    eye = np.eye(shape[-1])
    E = eye + X / 12.0
    for k in range(11, 0, -1):  # Horner: I + X(I + X/2(I + … ))
        E = eye + (X @ E) / k
    for j in range(int(s.max(initial=0))):
        sel = s > j
        E[sel] = E[sel] @ E[sel]
    return E.reshape(shape)


# ------------------------------------------------------------------ the critical multiplier
KRYLOV_MIN_D = 40
"""Floquet matrices of at least this size get their critical multiplier from a Krylov subspace
(:func:`critical_multipliers`), smaller ones from all their eigenvalues. At D = 46 and 54 the Krylov steps took
0.87 and 0.67 of the eigenvalues' CPU (an EM16-50 update, 2026-12-03); smaller sizes were not tried."""
KRYLOV_DIM = 24
"""Arnoldi steps of :func:`critical_multipliers`."""
KRYLOV_TOL = 1e-10
"""Largest accepted residual of the dominant Ritz pair, relative to its modulus (else all eigenvalues)."""


@functools.lru_cache(maxsize=64)
def _start_vector(D: int) -> np.ndarray:
    """A fixed generic start vector of length D: every point's search is its own, whatever its batch."""
    v = np.random.default_rng(20261203).standard_normal(D)
    v /= np.linalg.norm(v)
    v.setflags(write=False)  # shared by every call through the cache
    return v


def critical_multipliers(Phi: np.ndarray) -> np.ndarray:
    """The eigenvalue of largest modulus of each Floquet matrix, (B,) complex, from Φ (B, D, D).

    The SDM's Φ has a few multipliers of the modes near the unit circle and a long tail towards 0 (the delay's
    discretisation): of 214 at 3000 rpm on EM16-50 about 140 exceed 1e-3 in modulus, yet the outermost is the
    first the Krylov space K_k(Φ, v) = span{v, Φv, …, Φ^{k−1}v} resolves. For D ≥ :data:`KRYLOV_MIN_D`, k =
    :data:`KRYLOV_DIM` Arnoldi steps (classical Gram–Schmidt twice, all matrices at once) give the Hessenberg
    H_k = Q_kᵀ Φ Q_k, and the Ritz value θ of largest modulus of H_k is taken where its residual
    ‖Φ Q_k y − θ Q_k y‖ = h_{k+1,k} |e_kᵀ y| ≤ :data:`KRYLOV_TOL` |θ| (θ is then an exact eigenvalue of Φ + E,
    ‖E‖ no larger, so its error is that times the multiplier's condition number); elsewhere (below that size,
    and for a complex Φ) ``numpy.linalg.eigvals`` of the whole matrix. Measured (2026-12-03): on 310 prior
    samples of the campaign tools EM12-60, EM16-50 and EM28-80 at their grids' speeds and depths 0.01–5 mm
    (D ≥ 60) |ρ_Krylov / ρ_eigvals − 1| ≤ 1.6e-10; on all 20,398 Floquet matrices of the EM16-50 updates after 0
    and after 6 cuts of one truth (D = 44–214) ≤ 1.2e-7 (a non-normal Φ at D = 62; the depth searches stop at a
    relative width of 1e-3), 356 of them (1.7 %) redone by ``eigvals``; 0.83 against 7.4 ms per matrix at
    D = 214, 0.23 against 1.0 ms at D = 82 (``tests/stability/test_stability_sdm.py``;
    ``benchmarks/bench_lobes.py --sdm-only`` prints the table). The start vector is fixed, so a point's multiplier
    does not depend on the batch it is computed in.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> Q = np.linalg.qr(rng.standard_normal((80, 80)))[0]
    >>> Phi = (Q * np.r_[1.02, 0.5 ** np.arange(1, 80)]) @ Q.T  # one outer multiplier, a tail towards 0
    >>> mu = critical_multipliers(Phi[None])
    >>> round(float(abs(mu[0])), 12)
    1.02
    """
    Phi = np.asarray(Phi)
    B, D = Phi.shape[0], Phi.shape[-1]
    # the SDM's Φ is real; a complex one (the steps below do not conjugate) gets all its eigenvalues
    if D < KRYLOV_MIN_D or B == 0 or np.iscomplexobj(Phi):
        return _outermost(np.linalg.eigvals(Phi))
    k = KRYLOV_DIM
    Q = np.zeros((B, k + 1, D))
    H = np.zeros((B, k + 1, k))
    Q[:, 0] = _start_vector(D)
    for j in range(k):
        w = (Phi @ Q[:, j, :, None])[..., 0]
        scale = np.linalg.norm(w, axis=1)
        for _ in range(2):  # classical Gram–Schmidt, twice: orthogonal to rounding
            h = (Q[:, : j + 1] @ w[..., None])[..., 0]
            w -= (h[:, None, :] @ Q[:, : j + 1])[:, 0]
            H[:, : j + 1, j] += h
        nrm = np.linalg.norm(w, axis=1)
        # an invariant subspace (e.g. depth 0: Φ has rank n): its Ritz values are exact, the rest of Q stays 0
        live = nrm > 1e-13 * np.maximum(scale, 1e-300)
        H[:, j + 1, j] = np.where(live, nrm, 0.0)
        Q[live, j + 1] = w[live] / nrm[live, None]
    ev, Y = np.linalg.eig(H[:, :k])
    b = np.arange(B)
    i = np.argmax(np.abs(ev), axis=1)
    mu = ev[b, i]
    resid = H[:, k, k - 1] * np.abs(Y[b, k - 1, i])
    redo = ~(resid <= KRYLOV_TOL * np.abs(mu))
    if redo.any():
        mu[redo] = _outermost(np.linalg.eigvals(Phi[redo]))
    return mu


def _outermost(ev: np.ndarray) -> np.ndarray:
    """The eigenvalue of largest modulus in each row of ``ev`` (B, D): (B,)."""
    return ev[np.arange(ev.shape[0]), np.argmax(np.abs(ev), axis=1)]


# ------------------------------------------------------------------ model setup
def _m_ladder(m_max: int) -> np.ndarray:
    """Allowed step counts 20, 24, 28, 32, 40, 48, … (≈ 2^(1/4) apart, multiples of 4)."""
    j = np.arange(64)
    ladder = np.unique(4 * np.ceil(M_MIN * 2.0 ** (j / 4) / 4).astype(int))
    return np.r_[ladder[ladder < m_max], m_max]


@functools.lru_cache(maxsize=64)
def _interp_matrix(m: int, s: int, degree: int = None) -> np.ndarray:
    """(m + 1, q + 1) weights of local Lagrange interpolation from q + 1 = m/s + 1 nodes to m + 1 nodes.

    Fine node i sits at coarse coordinate t = i/s; it is interpolated from the
    ``degree`` + 1 coarse nodes around it (the stencil shifted inwards at the
    ends), so the interpolation error is O(h^(degree+1)), h the coarse spacing.
    ``s = 1``: identity.
    """
    if s == 1:
        L = np.eye(m + 1)
        L.setflags(write=False)
        return L
    degree = INTERP_DEGREE if degree is None else degree
    q = m // s
    t = np.arange(m + 1) / s
    p = min(degree, q)
    j0 = np.clip(np.floor(t).astype(int) - (p - 1) // 2, 0, q - p)
    L = np.zeros((m + 1, q + 1))
    rows = np.arange(m + 1)
    for k in range(p + 1):  # Lagrange basis polynomials of the stencil
        w = np.ones(m + 1)
        for j in range(p + 1):
            if j != k:
                w *= (t - (j0 + j)) / (k - j)
        L[rows, j0 + k] += w
    L.setflags(write=False)  # cached and shared between systems
    return L


def _modal_basis(A: np.ndarray):
    """Real modal basis of A: (T, λ), T⁻¹AT = [[Σ, Ω], [−Ω, Σ]], Σ = diag Re λ, Ω = diag Im λ; or None.

    λ: the poles with Im λ > 0, sorted. Columns of T: Re v_k for every pole, then
    Im v_k (v_k of unit norm, with the phase making Re v_k ⟂ Im v_k), so the
    exponential of the transformed A is four diagonal blocks. None when A has a
    real eigenvalue (overdamped or first-order states) or nearly dependent
    eigenvectors (cond T > 1e8): the dense path is used then.
    """
    lam, V = np.linalg.eig(A)
    up = lam.imag > 0
    if 2 * up.sum() != lam.size:
        return None
    order = np.argsort(lam[up], kind="stable")
    lam, V = lam[up][order], V[:, up][:, order]
    V = V / np.linalg.norm(V, axis=0)
    V = V * np.exp(-0.5j * np.angle(np.einsum("ik,ik->k", V, V)))  # Re v ⟂ Im v
    T = np.hstack([V.real, V.imag])
    if not np.linalg.cond(T) < 1e8:
        return None
    return T, lam


class _System:
    """State-space matrices and cut geometry for one cutting condition; discretisations cached per m."""

    def __init__(self, model: StateSpaceModel, cut: CuttingConditions):
        self.model = model
        self.cut = cut
        self.teeth, self.tangential_coeff, self.radial_ratio = cut.teeth, cut.tangential_coeff, cut.radial_ratio
        self.phi_st, self.phi_ex = cut.immersion_angles
        self.out, self.inp = model.outputs, model.inputs
        self.n = model.n_states
        self.d = self.out.size
        self.f_max = model.max_frequency_hz
        basis = _modal_basis(model.A)
        self.blocks = basis is not None  # real modal coordinates (A in four diagonal blocks)
        if self.blocks:
            # z = T z̃: A becomes blocks [[σ, ω], [−ω, σ]] per pole σ + iω (exact up to the eigen-solver's rounding).
            T, lam = basis
            self.A0 = np.block([[np.diag(lam.real), np.diag(lam.imag)], [-np.diag(lam.imag), np.diag(lam.real)]])
            self.C = model.C[self.out] @ T
            self.Bin = np.linalg.solve(T, model.B[:, self.inp])
        else:
            # Balance A by a diagonal similarity of powers of 2 (exact): second-order modal blocks
            # [[0, 1], [−ω², ·]] have norm ω², [[0, ω], [−ω, ·]] only ω, which spares the exponentials squarings.
            self.A0, (scale, _) = matrix_balance(model.A, permute=False, separate=True)
            self.C = model.C[self.out] * scale[None, :]  # (d, n): displacement of each moving direction
            self.Bin = model.B[:, self.inp] / scale[:, None]  # (n, p): forces that excite the model
        # Cut span of one tooth within a tooth period (several teeth may cut at once).
        self.cut_angle = min(self.phi_ex - self.phi_st, 2 * np.pi / self.teeth)
        self._H = {}
        self._L = {}

    def directional(self, m: int) -> np.ndarray:
        """Exact averages H_i (N/m² per m of chip) over the m steps of the cut: (m, p, d), exciting × moving."""
        if m not in self._H:
            edges = self.phi_st + self.cut_angle * np.arange(m + 1) / m
            H = interval_directional_matrix(edges, self.teeth, self.tangential_coeff, self.radial_ratio,
                                            self.phi_st, self.phi_ex)
            self._H[m] = H[:, self.inp][:, :, self.out]  # rigid directions drop out
        return self._H[m]

    def interp(self, m: int, s: int) -> np.ndarray:
        if (m, s) not in self._L:
            self._L[m, s] = _interp_matrix(m, s)
        return self._L[m, s]

    def stencils(self, m: int, s: int):
        """Per step i: the first node ``lo[i]`` of a window of w nodes holding the weights of its delayed
        displacements at both ends, and the window weights ``Lw`` (m, 2, w) (rows: ends i, i + 1)."""
        if (m, s, "w") not in self._L:
            L = self.interp(m, s)
            nz = (L[:-1] != 0) | (L[1:] != 0)
            first = np.argmax(nz, axis=1)
            last = L.shape[1] - np.argmax(nz[:, ::-1], axis=1)
            w = int((last - first).max())
            lo = np.minimum(first, L.shape[1] - w)
            cols = lo[:, None] + np.arange(w)
            rows = np.arange(m)[:, None]
            self._L[m, s, "w"] = lo, np.stack([L[rows, cols], L[rows + 1, cols]], axis=1)
        return self._L[m, s, "w"]

    def cut_time(self, rpm):
        """(cut time t_c, free-flight time T − t_c), s."""
        omega = 2 * np.pi * np.asarray(rpm, float) / 60.0
        t_cut = self.cut_angle / omega
        return t_cut, np.maximum(2 * np.pi / (self.teeth * omega) - t_cut, 0.0)

    def step_maps(self, rpm, m: int):
        """Depth-independent step matrices for speeds ``rpm``: P = e^{AΔt} (B, n, n), Γ0, Γ1 (B, n, p), e^{A(T − t_c)}.

        Γ0 = ∫₀^Δt e^{A(Δt−s)} ds B, Γ1 = ∫₀^Δt e^{A(Δt−s)} (s/Δt) ds B, Δt = t_c/m, from one
        exponential of the Van Loan block [[AΔt, BΔt, 0], [0, 0, I], [0, 0, 0]] per speed.
        """
        n, p = self.n, self.Bin.shape[-1]
        t_cut, t_free = self.cut_time(rpm)
        dt = t_cut / m
        X = np.zeros((rpm.size, n + 2 * p, n + 2 * p))
        X[:, :n, :n] = self.A0 * dt[:, None, None]  # A0 (n, n), or (B, n, n) for a stack of models
        # Input columns scaled to the norm of the state block (exact, undone below): the exponential's
        # cost grows with the log of the block's norm.
        c = np.maximum(np.abs(self.Bin).sum(axis=-2).max(axis=-1)
                       / np.maximum(np.abs(self.A0).sum(axis=-2).max(axis=-1), 1e-300), 1e-300)[..., None, None]
        X[:, :n, n: n + p] = (self.Bin / c) * dt[:, None, None]
        X[:, n: n + p, n + p:] = np.eye(p)
        Ex = expm_batch(X)
        G1 = Ex[:, :n, n + p:] * c
        return Ex[:, :n, :n], Ex[:, :n, n: n + p] * c - G1, G1, expm_batch(self.A0 * t_free[:, None, None])

    def monodromy(self, rpm, depth, m: int, s: int = 1, cut_end: bool = False, maps=None):
        """Floquet transition matrices Φ, shape (B, D, D), for paired 1-D arrays rpm, depth.

        ``m`` steps over the cut; the delayed displacement is carried at every
        ``s``-th node (m/s + 1 nodes, local Lagrange interpolation of degree
        ``INTERP_DEGREE`` in between; s = 1: every node).
        ``cut_end=True`` also returns the map z ↦ z(t_c) to the end of the cut (B, n, D).
        ``maps``: :meth:`step_maps` of these speeds, if already computed.

        Per step (module docstring) g = r(t − T) − C z is linear between the step's
        ends, so z_{i+1} = P z_i + a(Γ0 − Γ1)H_i g_i + aΓ1 H_i g_{i+1}; the term in
        z_{i+1} is solved by the Woodbury identity,
        (I + U C)⁻¹ = I − U K C, U = aΓ1H_i, K = (I + C U)⁻¹ (d × d).
        The steps run compiled, one point at a time (:func:`toolpoint.stability._sdm_steps.floquet`: in NumPy the
        small stacked products cost their calls, not their arithmetic; ``docs/design/stability.md``).
        """
        from ._sdm_steps import floquet  # compiled on first use (numba), cached on disk

        n, d = self.n, self.d
        H = self.directional(m)
        q1 = self.interp(m, s).shape[1]
        B = rpm.size
        P, G0, G1, Pfree = self.step_maps(rpm, m) if maps is None else maps
        D = n + q1 * d
        lo_c, Lw = self.stencils(m, s)
        Phi = np.empty((B, D, D))
        Y = np.empty((B, n, D))
        if any(np.iscomplexobj(x) for x in (P, G0, G1, Pfree, H, self.C)):
            raise TypeError("the SDM's step maps are real (a real state-space model)")
        # one compiled signature: C-contiguous float64, a leading point axis (H and C: one model's, or each point's)
        args = [np.require(x, np.float64, "C") for x in (
            np.broadcast_to(P, (B, n, n)), np.broadcast_to(G0, (B,) + G0.shape[-2:]),
            np.broadcast_to(G1, (B,) + G1.shape[-2:]), np.broadcast_to(Pfree, (B, n, n)),
            H if H.ndim == 4 else H[None], self.C if self.C.ndim == 3 else self.C[None], np.broadcast_to(depth, (B,)))]
        floquet(*args, np.require(lo_c, np.int64, "C"), np.require(Lw, np.float64, "C"), int(s), Phi, Y)
        return (Phi, Y) if cut_end else Phi

    def multipliers(self, rpm, depth, m, s):
        """(spectral radius, critical multiplier) for paired rpm, depth, steps, spacing arrays.

        Points are grouped by (m, s) and processed in memory-bounded chunks.
        """
        rpm = np.asarray(rpm, float).reshape(-1)
        depth = np.asarray(depth, float).reshape(-1)
        m = np.broadcast_to(np.asarray(m, int), rpm.shape)
        s = np.broadcast_to(np.asarray(s, int), rpm.shape)
        crit = np.empty(rpm.size, complex)
        with single_thread_blas():
            key = m * 1000 + s
            for kk in np.unique(key):
                mm, ss = divmod(int(kk), 1000)
                idx = np.flatnonzero(key == kk)
                D = self.n + (mm // ss + 1) * self.d
                # Φ and Y of each point (the compiled loop stores no step maps), its P, e^{A(T − t_c)}, Γ0, Γ1; and
                # the critical multiplier's Krylov basis (KRYLOV_DIM + 1 vectors of D)
                per_point = D * D + self.n * D + 2 * self.n * (self.n + self.d) + (KRYLOV_DIM + 1) * D
                chunk = max(1, _CHUNK_FLOATS // per_point)
                for c in range(0, idx.size, chunk):
                    j = idx[c: c + chunk]
                    crit[j] = critical_multipliers(self.monodromy(rpm[j], depth[j], mm, ss))
        return np.abs(crit), crit

    def critical(self, rpm, depth, m, s, samples_free: int = 64):
        """Critical multiplier μ and chatter frequency (Hz) at paired rpm, depth, steps, spacing.

        μ = e^{iω₀T} fixes the chatter frequency only modulo the tooth-passing
        frequency f_T = 1/T: the critical Floquet solution is
        u(t) = e^{iω₀t} p(t), p T-periodic, i.e. a comb of lines
        f_j = ω₀/2π + j f_T. The chatter frequency reported is the strongest
        line: the largest Fourier coefficient |∫₀^T u(t) e^{−i2πf_j t} dt| of
        the eigen-solution over one period, sampled at the nodes of the cut
        and ``samples_free`` points of the (exact) free flight, trapezoid
        rule. This also settles flip (μ < 0: f_T/2 + j f_T) lobes, whose
        eigenvector is real.
        """
        rpm = np.asarray(rpm, float).reshape(-1)
        depth = np.asarray(depth, float).reshape(-1)
        m = np.broadcast_to(np.asarray(m, int), rpm.shape)
        s = np.broadcast_to(np.asarray(s, int), rpm.shape)
        n, d = self.n, self.d
        mu = np.empty(rpm.size, complex)
        fc = np.empty(rpm.size)
        key = m * 1000 + s
        with single_thread_blas():
            for kk in np.unique(key):
                mm, ss = divmod(int(kk), 1000)
                idx = np.flatnonzero(key == kk)
                Phi, Ycut = self.monodromy(rpm[idx], depth[idx], mm, ss, cut_end=True)
                ev, vec = np.linalg.eig(Phi)
                j = np.argmax(np.abs(ev), axis=1)
                b = np.arange(idx.size)
                mu[idx] = ev[b, j]
                v = vec[b, :, j]  # (B, D)
                # The cut: this period's node values are μ × the stored previous ones (fine nodes by interpolation).
                coarse = v[:, n:].reshape(idx.size, -1, d)
                u_cut = mu[idx, None, None] * np.einsum("ij,bjd->bid", self.interp(mm, ss), coarse)
                t_cut, t_free = self.cut_time(rpm[idx])
                t = [np.arange(mm + 1)[None, :] * (t_cut / mm)[:, None]]
                u = [u_cut]
                # Free flight: y(t_c + s) = e^{A₀s} y(t_c), exact.
                if np.any(t_free > 0):
                    ds = t_free / samples_free
                    step = expm_batch(self.A0[None] * ds[:, None, None])
                    y = np.einsum("bij,bj->bi", Ycut, v)
                    uf = np.empty((idx.size, samples_free, d), complex)
                    for k in range(samples_free):  # loop over time samples
                        y = np.einsum("bij,bj->bi", step, y)
                        uf[:, k] = y @ self.C.T
                    t.append(t_cut[:, None] + ds[:, None] * np.arange(1, samples_free + 1)[None, :])
                    u.append(uf)
                t, u = np.concatenate(t, axis=1), np.concatenate(u, axis=1)
                period = 60.0 / (self.teeth * rpm[idx])
                f0 = np.angle(mu[idx]) / (2 * np.pi * period)
                jmax = int(np.ceil(2.0 * self.f_max * period.max())) + 1
                lines = f0[:, None] + np.arange(-jmax, jmax + 1)[None, :] / period[:, None]  # (B, J)
                phase = np.exp(-2j * np.pi * lines[:, :, None] * t[:, None, :])  # (B, J, S)
                w = np.diff(t, axis=1)
                wt = np.zeros_like(t)
                wt[:, :-1] += w / 2
                wt[:, 1:] += w / 2
                coef = np.einsum("bjs,bsd->bjd", phase * wt[:, None, :], u)
                power = (np.abs(coef) ** 2).sum(axis=-1)
                fc[idx] = np.abs(lines[b, np.argmax(power, axis=1)])
        return mu, fc

    def resolution(self, rpm, m=None, accuracy=1.0, m_max=M_MAX, f_wave=None):
        """(steps m over the cut, node spacing s) per speed.

        A wave is a period of ``f_wave`` (Hz; default the highest natural
        frequency +10 %, chatter sitting just above a mode):
        m = accuracy · max(STEPS_PER_WAVE · f_wave · t_c, M_MIN), on a ladder of values
        within [20, m_max]; the delayed displacement is carried at every s-th
        step, s the largest divisor of m leaving NODES_PER_WAVE · max(accuracy, 1)
        nodes per wave and at least MIN_NODES intervals. A given ``m`` is used as it
        is, with s = 1.
        """
        rpm = np.asarray(rpm, float)
        if m is not None:
            if int(m) != m or m < 2:
                raise InputError(f"must be an integer ≥ 2, got {m!r}", field="m")
            return np.full(rpm.shape, int(m)), np.ones(rpm.shape, int)
        waves = (1.1 * self.f_max if f_wave is None else f_wave) * self.cut_time(rpm)[0]
        # The floor M_MIN resolves H(t) over the cut whatever the waves: it scales with the accuracy too.
        need = np.ceil(accuracy * np.maximum(STEPS_PER_WAVE * waves, M_MIN))
        ladder = _m_ladder(m_max)
        mm = ladder[np.minimum(np.searchsorted(ladder, need), ladder.size - 1)]
        # Largest divisor s of m with at least NODES_PER_WAVE nodes per wave and MIN_NODES + 1 nodes.
        # Below accuracy 1 only the steps thin out: fewer than NODES_PER_WAVE nodes per wave do not interpolate.
        limit = np.minimum(mm / np.maximum(max(accuracy, 1.0) * NODES_PER_WAVE * waves, 1e-300), mm / MIN_NODES)
        s = np.ones(mm.shape, int)
        for c in range(2, 17):  # candidate spacings, a handful
            s = np.where((mm % c == 0) & (c <= limit), c, s)
        return mm, s


class _Stack:
    """Many models of one structure (the same n, d, forces, teeth and cut span; e.g. a prior's samples), whose
    spectral radii are computed for points of different models together: the step loop of
    :meth:`_System.monodromy` then runs once per chunk of points, not once per model."""

    def __init__(self, systems):
        self.systems = list(systems)
        first = self.systems[0]
        self.n, self.d, self.p = first.n, first.d, first.Bin.shape[1]
        for sy in self.systems:
            if (sy.n, sy.d, sy.Bin.shape[1], sy.teeth) != (self.n, self.d, self.p, first.teeth) or not np.isclose(
                    sy.cut_angle, first.cut_angle, rtol=1e-12, atol=0.0):
                raise ValueError("_Stack: models of different structure or cut geometry")
        self.A0 = np.stack([sy.A0 for sy in self.systems])
        self.C = np.stack([sy.C for sy in self.systems])
        self.Bin = np.stack([sy.Bin for sy in self.systems])
        self.f_max = np.array([sy.f_max for sy in self.systems])
        self._H = {}

    def directional(self, m: int) -> np.ndarray:
        """(K, m, p, d): each model's H_i (:meth:`_System.directional`)."""
        if m not in self._H:
            self._H[m] = np.stack([sy.directional(m) for sy in self.systems])
        return self._H[m]

    def view(self, k, m: int) -> "_System":
        """A :class:`_System` of the points' models ``k`` (B,) for ``m`` steps: A0, C, B and H with a leading
        axis B (the discretisation's interpolation weights shared: they depend on m and s only)."""
        first = self.systems[0]
        v = object.__new__(_System)
        v.__dict__.update(teeth=first.teeth, cut_angle=first.cut_angle, n=self.n, d=self.d, _L=first._L,
                          A0=self.A0[k], C=self.C[k], Bin=self.Bin[k], _H={m: self.directional(m)[k]})
        return v

    def multipliers(self, k, rpm, depth, m, s):
        """As :meth:`_System.multipliers`, point j on model ``k[j]``."""
        k = np.asarray(k, int).reshape(-1)
        rpm = np.asarray(rpm, float).reshape(-1)
        depth = np.asarray(depth, float).reshape(-1)
        m = np.broadcast_to(np.asarray(m, int), rpm.shape)
        s = np.broadcast_to(np.asarray(s, int), rpm.shape)
        crit = np.empty(rpm.size, complex)
        n, d = self.n, self.d
        with single_thread_blas():
            key = m * 1000 + s
            for kk in np.unique(key):
                mm, ss = divmod(int(kk), 1000)
                idx = np.flatnonzero(key == kk)
                D = n + (mm // ss + 1) * d
                # as _System.multipliers, plus each point's own H
                per_point = D * D + n * D + 2 * n * (n + d) + (KRYLOV_DIM + 1) * D + mm * self.p * d
                chunk = max(1, _CHUNK_FLOATS // per_point)
                for c in range(0, idx.size, chunk):
                    j = idx[c: c + chunk]
                    v = self.view(k[j], mm)
                    crit[j] = critical_multipliers(v.monodromy(rpm[j], depth[j], mm, ss))
        return np.abs(crit), crit


# ------------------------------------------------------------------ public API
def as_state_space(modes_x, modes_y=None) -> StateSpaceModel:
    """The tool-point model the SDM works on, from what the caller gave.

    Parameters
    ----------
    modes_x : StateSpaceModel or ModalModel or None
        A complete 2-input 2-output model (then ``modes_y`` must be ``None``),
        or the real modes in x (``None``: rigid in x).
    modes_y : ModalModel or None
        Real modes in y (``None``: rigid in y).

    Returns
    -------
    StateSpaceModel
    """
    if isinstance(modes_x, StateSpaceModel):
        if modes_y is not None:
            raise InputError("give a StateSpaceModel alone (it holds both directions)", field="modes_y")
        return modes_x
    return StateSpaceModel.from_modes(modes_x, modes_y)


def _check_accuracy(accuracy) -> float:
    try:
        acc = float(accuracy)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {accuracy!r}", field="accuracy") from None
    if not 0.25 <= acc <= 16:
        raise InputError(f"must be from 0.25 to 16, got {acc:g}", field="accuracy")
    return acc


def sdm_spectral_radius(
    modes_x,
    modes_y=None,
    cutting: CuttingConditions | None = None,
    *,
    rpm,
    depth,
    m: int | None = None,
    accuracy: float = 1.0,
    multiplier: bool = False,
) -> np.ndarray:
    """Spectral radius ρ of the Floquet transition matrix at (rpm, depth), broadcast.

    ρ < 1 stable, ρ > 1 chatter. A speed × depth grid is
    ``sdm_spectral_radius(..., rpm=r[None, :], depth=a[:, None])``; its
    ρ = 1 contour is the stability boundary.

    Parameters
    ----------
    modes_x, modes_y : StateSpaceModel, ModalModel or None
        The tool-point model (see :func:`as_state_space`).
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r, a_e/D, down/up milling.
    rpm : array_like
        Spindle speeds, rpm (> 0).
    depth : array_like
        Axial depths, m (≥ 0), broadcast against ``rpm``.
    m : int, optional
        Steps over the cut, every node carried; default: see :func:`sdm_lobes`.
    accuracy : float
        Resolution factor of the default discretisation (see :func:`sdm_lobes`).
    multiplier : bool, default False
        Return the critical Floquet multiplier μ itself (complex, |μ| = ρ): its angle says the chatter
        frequency modulo the tooth-passing frequency f_T = 1/T, f ≡ ±arg(μ) f_T / 2π (mod f_T) — which mode
        grows, where several could.

    Returns
    -------
    numpy.ndarray
        ρ, dimensionless (μ, complex, with ``multiplier``), shape of the broadcast of ``rpm`` and ``depth``.

    Examples
    --------
    At zero depth only free vibration is left: ρ = e^{−ζω_n T}.

    >>> from toolpoint.stability import CuttingConditions, ModalModel, sdm_spectral_radius
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=0.05)
    >>> rho = sdm_spectral_radius(ModalModel([922.0], [0.011], [0.03993]), None, cut, rpm=10000.0, depth=0.0)
    >>> bool(np.isclose(rho, np.exp(-0.011 * 2 * np.pi * 922.0 * 60 / (2 * 10000.0))))
    True
    """
    cut = check_cutting(cutting)
    sysm = _System(as_state_space(modes_x, modes_y), cut)
    acc = _check_accuracy(accuracy)
    r, a = np.broadcast_arrays(np.asarray(rpm, float), np.asarray(depth, float))
    if np.any(~np.isfinite(r) | (r <= 0)) or np.any(~np.isfinite(a) | (a < 0)):
        raise InputError("speeds must be > 0 rpm and depths finite and ≥ 0 m", field="rpm/depth")
    mm, ss = sysm.resolution(r.reshape(-1), m, acc, int(round(M_MAX * max(acc, 1.0))))
    rho, mu = sysm.multipliers(r.reshape(-1), a.reshape(-1), mm, ss)
    return (mu if multiplier else rho).reshape(r.shape)


def sdm_limit_near(
    modes_x, modes_y=None, cutting: CuttingConditions | None = None, *, rpm, depth_m, chatter_hz=None, **search
) -> tuple[np.ndarray, np.ndarray]:
    """The SDM limit near a guess at each speed: a bracket stepped out from the guess, then bisected.

    From the guess a₀ the depth steps by e^{±h} (h = ``log_step``) towards ρ = 1 until the verdict changes
    (at most ``max_steps`` steps), then the bracket is bisected ``bisections`` times in ln a and the limit
    interpolated linearly in ρ between its ends. ρ is no distance to the limit (below it, the slowest
    free vibration sets ρ and it hardly moves with depth; unstable islands occur above and below the limit),
    so only its verdict is trusted. Cost: 1 + steps + bisections spectral radii per speed, vectorised over
    speeds — for many models at few speeds each (the shop update's particles), where :func:`sdm_lobes`
    searches upwards from half the zero-order limit. An unstable band thinner than e^h can be stepped over,
    as in :func:`sdm_lobes`.

    Parameters
    ----------
    modes_x, modes_y, cutting
        As :func:`sdm_spectral_radius`.
    rpm : array_like, shape (U,)
        Spindle speeds, rpm.
    depth_m : array_like, shape (U,)
        The guesses, m (> 0, finite).
    chatter_hz : array_like, optional
        Zero-order chatter frequencies at the speeds, Hz (scalar or (U,)): the discretisation resolves
        ``1.1 ×`` the highest of them and of the natural frequencies, as :func:`sdm_lobes` does over its grid
        (default: computed by the zero-order method at these speeds).
    **search
        ``log_step`` (float, default 0.2): h, the step in ln a while bracketing.
        ``max_steps`` (int, default 5): largest number of steps; a limit farther than e^{±h·max_steps} from
        the guess is reported at that bound, unbracketed.
        ``bisections`` (int, default 4): halvings of the bracket; its final width is h / 2^bisections in ln a
        (0.0125 by default).
        ``accuracy`` (float, default 1): resolution factor of the discretisation (:func:`sdm_lobes`).

    Returns
    -------
    limit_m : ndarray, shape (U,)
        Estimated limits, m.
    bracketed : ndarray of bool, shape (U,)
        ``False`` where no verdict change was found within the steps.

    Examples
    --------
    Insperger & Stépán's benchmark again (:func:`sdm_lobes` gives 4.09 mm at 10000 rpm), from a guess of 3 mm:

    >>> from toolpoint.stability import CuttingConditions, ModalModel
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=0.05)
    >>> lim, ok = sdm_limit_near(ModalModel([922.0], [0.011], [0.03993]), None, cut, rpm=[10000.0],
    ...                          depth_m=[3e-3])
    >>> round(float(lim[0]) * 1e3, 2), bool(ok[0])
    (4.09, True)
    """
    r = np.asarray(rpm, float).reshape(-1)
    a0 = np.asarray(depth_m, float).reshape(-1)
    if r.shape != a0.shape or np.any(~np.isfinite(r) | (r <= 0)) or np.any(~np.isfinite(a0) | (a0 <= 0)):
        raise InputError("need as many finite guesses > 0 m as speeds > 0 rpm", field="rpm/depth_m")
    fc = None if chatter_hz is None else _per_point(chatter_hz, r.shape)[None]
    lim, ok = sdm_limit_near_many([(modes_x, modes_y, cutting)], rpm=r, depth_m=a0[None], chatter_hz=fc, **search)
    return lim[0], ok[0]


def _per_point(chatter_hz, shape) -> np.ndarray:
    """``chatter_hz`` (Hz) broadcast to the points' shape, or refused naming the field."""
    try:
        return np.broadcast_to(np.asarray(chatter_hz, float), shape)
    except ValueError:
        raise InputError(f"needs one frequency per point {shape} (or one for all), got shape "
                         f"{np.shape(chatter_hz)}", field="chatter_hz") from None


def _near_options(log_step: float = 0.2, max_steps: int = 5, bisections: int = 4, accuracy: float = 1.0):
    """The search options of :func:`sdm_limit_near` (their defaults' one home), checked."""
    if not 0 < log_step <= 1 or int(max_steps) != max_steps or max_steps < 1 or not 0 <= bisections <= 20:
        raise InputError("need 0 < log_step ≤ 1, max_steps ≥ 1 and 0 ≤ bisections ≤ 20",
                         field="log_step/max_steps/bisections")
    return float(log_step), int(max_steps), int(bisections), _check_accuracy(accuracy)


def _near(rho, a0, log_step, max_steps, bisections):
    """:func:`sdm_limit_near`'s search from guesses ``a0`` (m), ``rho(idx, ln a)`` the spectral radii of points idx."""
    all_ = np.arange(a0.size)
    lo_x = np.log(a0)
    lo_r = rho(all_, lo_x)
    hi_x, hi_r = lo_x.copy(), lo_r.copy()
    up = lo_r < 1  # stable at the guess: the limit is above
    direction = np.where(up, 1.0, -1.0)
    open_ = all_.copy()
    for _ in range(int(max_steps)):  # step out until the verdict changes
        if open_.size == 0:
            break
        x = hi_x[open_] + direction[open_] * log_step
        rr = rho(open_, x)
        lo_x[open_], lo_r[open_] = hi_x[open_], hi_r[open_]
        hi_x[open_], hi_r[open_] = x, rr
        open_ = open_[(rr < 1) == up[open_]]
    bracketed = np.ones(a0.size, bool)
    bracketed[open_] = False
    # order each bracket (s: stable end, c: chatter end)
    s_x, s_r = np.where(up, lo_x, hi_x), np.where(up, lo_r, hi_r)
    c_x, c_r = np.where(up, hi_x, lo_x), np.where(up, hi_r, lo_r)
    idx = np.flatnonzero(bracketed)
    for _ in range(int(bisections)):
        if idx.size == 0:
            break
        x = 0.5 * (s_x[idx] + c_x[idx])
        rr = rho(idx, x)
        st = rr < 1
        s_x[idx[st]], s_r[idx[st]] = x[st], rr[st]
        c_x[idx[~st]], c_r[idx[~st]] = x[~st], rr[~st]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip((1 - s_r) / (c_r - s_r), 0.0, 1.0)
    est = np.where(bracketed, s_x + np.where(np.isfinite(t), t, 0.5) * (c_x - s_x), hi_x)
    with np.errstate(divide="ignore", invalid="ignore"):  # d ln ρ / d ln a across the last bracket
        slope = np.where(bracketed & (s_r > 0) & (c_r > 0), (np.log(c_r) - np.log(s_r)) / (c_x - s_x), np.nan)
    return np.exp(est), bracketed, slope


def sdm_limit_near_many(tools, *, rpm, depth_m, chatter_hz=None, rho_at=None, extras: bool = False,
                        **search) -> tuple:
    """:func:`sdm_limit_near` for many models at once (e.g. samples of a prior), each at its own guesses.

    Each model's search is that of :func:`sdm_limit_near` over its valid points (its own discretisation, from
    its highest natural and chatter frequency); models of one structure (the same number of states, moving
    directions and forces, teeth and cut span) are evaluated together, so that the discretisation's step loop
    runs once per chunk of points of many models rather than once per model (on 120 three-mode models at three
    speeds each, 1.3 s CPU against 2.0 s for the loop of one search per model it replaced, the same limits to the
    bit; 2026-11-30).

    Parameters
    ----------
    tools : sequence of (modes_x, modes_y, cutting)
        K models, each as :func:`sdm_spectral_radius` takes them.
    rpm : array_like, shape (U,) or (K, U)
        Spindle speeds, rpm (> 0).
    depth_m : array_like, shape (K, U)
        The guesses, m; points whose guess is not finite and > 0 are skipped.
    chatter_hz : array_like, shape (K, U), optional
        Zero-order chatter frequencies, Hz (default: each model's zero-order method at its speeds).
    rho_at : array_like, shape (K, U, J), optional
        Depths, m, at which each point's spectral radius per tooth period is also wanted (NaN: none); with
        ``extras``.
    extras : bool, default False
        Also return a dict: ``"growth_per_s"`` (K, U), how fast chatter grows just past each limit, κ = d ln ρ /
        d ln a / T (1/s, T the tooth period; the slope across the search's last bracket, NaN where unbracketed),
        and ``"rho_at"`` (K, U, J), ρ at ``rho_at``'s depths (None without them).
    **search
        ``log_step``, ``max_steps``, ``bisections``, ``accuracy``: as :func:`sdm_limit_near`.

    Returns
    -------
    limit_m : ndarray, shape (K, U)
        Estimated limits, m (NaN at skipped points).
    bracketed : ndarray of bool, shape (K, U)
        ``False`` where no verdict change was found within the steps, and at skipped points.
    extras : dict
        With ``extras=True`` only (above).

    Examples
    --------
    Insperger & Stépán's benchmark and the same tool with twice the modal mass at the same frequency and
    damping ratio — twice the stiffness, so twice the limit:

    >>> from toolpoint.stability import CuttingConditions, ModalModel
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=0.05)
    >>> tools = [(ModalModel([922.0], [0.011], [0.03993]), None, cut),
    ...          (ModalModel([922.0], [0.011], [2 * 0.03993]), None, cut)]
    >>> lim, ok = sdm_limit_near_many(tools, rpm=[10000.0], depth_m=[[3e-3], [6e-3]])
    >>> np.round(lim[:, 0] * 1e3, 2).tolist(), ok[:, 0].tolist()
    ([4.09, 8.18], [True, True])
    """
    log_step, max_steps, bisections, acc = _near_options(**search)
    systems = [_System(as_state_space(mx, my), check_cutting(c)) for mx, my, c in tools]
    K = len(systems)
    a0 = np.asarray(depth_m, float)
    if K == 0 or a0.ndim != 2 or a0.shape[0] != K:
        raise InputError(f"need one row of guesses per model ({K}), got shape {a0.shape}", field="depth_m")
    r = np.broadcast_to(np.asarray(rpm, float), a0.shape)
    if np.any(~np.isfinite(r) | (r <= 0)):
        raise InputError("speeds must be finite and > 0 rpm", field="rpm")
    ok = np.isfinite(a0) & (a0 > 0)
    if chatter_hz is None:
        fc = np.full(a0.shape, np.nan)
        for i, sy in enumerate(systems):  # the zero-order seed of each model (callers usually have it)
            if ok[i].any():
                u, inv = np.unique(r[i, ok[i]], return_inverse=True)
                fc[i, ok[i]] = _zoa_seed(sy, u, *_zoa_grid(sy)).chatter_hz[inv]
    else:
        fc = _per_point(chatter_hz, a0.shape)
    limit, bracketed = np.full(a0.shape, np.nan), np.zeros(a0.shape, bool)
    slope = np.full(a0.shape, np.nan)
    at = None if rho_at is None else np.asarray(rho_at, float)
    if at is not None and not extras:  # its radii would be computed and dropped
        raise InputError("rho_at needs extras=True (the radii are returned in the extras)", field="rho_at")
    if at is not None and (at.ndim != 3 or at.shape[:2] != a0.shape):
        raise InputError(f"need shape ({a0.shape[0]}, {a0.shape[1]}, J), got {at.shape}", field="rho_at")
    rho_at = None if at is None else np.full(at.shape, np.nan)
    mmax = int(round(M_MAX * max(acc, 1.0)))
    groups = {}
    for i, sy in enumerate(systems):  # models the discretisation can stack
        if ok[i].any():
            groups.setdefault((sy.n, sy.d, sy.Bin.shape[1], sy.teeth, float(sy.cut_angle)), []).append(i)
    for members in groups.values():
        st = _Stack([systems[i] for i in members])
        kk, jj = np.nonzero(ok[members])  # points: model (in the stack), speed
        rows = np.asarray(members)[kk]
        fcm = np.where(ok[members], fc[members], np.nan)
        with np.errstate(invalid="ignore"):
            f_fc = np.nanmax(np.where(np.isfinite(fcm), fcm, -np.inf), axis=1)
        f_wave = WAVE_MARGIN * np.maximum(st.f_max, f_fc)  # per model, as sdm_limit_near over its points
        mm = np.empty(kk.size, int)
        ss = np.empty(kk.size, int)
        for q, i in enumerate(members):
            sel = kk == q
            mm[sel], ss[sel] = systems[i].resolution(r[i, jj[sel]], None, acc, mmax, float(f_wave[q]))
        rp = r[rows, jj]

        def rho(idx, x, st=st, kk=kk, rp=rp, mm=mm, ss=ss):  # ρ at points idx, depths e^x
            return st.multipliers(kk[idx], rp[idx], np.exp(x), mm[idx], ss[idx])[0]

        limit[rows, jj], bracketed[rows, jj], slope[rows, jj] = _near(rho, a0[rows, jj], log_step, max_steps,
                                                                      bisections)
        if at is not None:  # ρ at the asked depths of each point, all of them in one call
            jj_at = np.nonzero(np.isfinite(at[rows, jj]) & (at[rows, jj] > 0))
            if jj_at[0].size:
                p, q = jj_at
                rho_at[rows[p], jj[p], q] = rho(p, np.log(at[rows[p], jj[p], q]))
    if not extras:
        return limit, bracketed
    with np.errstate(divide="ignore", invalid="ignore"):
        growth = slope * np.array([sy.teeth for sy in systems], float)[:, None] * r / 60.0  # per tooth period → /s
    return limit, bracketed, {"growth_per_s": growth, "rho_at": rho_at}


def _zoa_depths(sysm: _System, phi: np.ndarray):
    """Zero-order depth limits (m, ``inf`` where no lobe) per frequency of the grid, all eigenvalue branches
    (:func:`~toolpoint.stability.zoa.depth_and_phase`)."""
    from .milling import average_directional_matrix
    from .zoa import depth_and_phase, oriented_eigenvalues

    h0 = average_directional_matrix(sysm.teeth, sysm.tangential_coeff, sysm.radial_ratio, sysm.phi_st, sysm.phi_ex)
    return depth_and_phase(oriented_eigenvalues(h0, phi[:, 0, 0], phi[:, 1, 1], phi[:, 0, 1], phi[:, 1, 0]))


def _chatter_reach(sysm: _System, freq_hz: np.ndarray, phi: np.ndarray, depth_max: float) -> float:
    """The highest frequency (Hz, at most the highest natural frequency) at which the zero-order limit is at most
    ``depth_max`` (m): a mode there can chatter within the search, at some speed. 0 when none."""
    zero_order = _zoa_depths(sysm, phi)
    ok = zero_order.valid & (zero_order.depth_m <= depth_max)
    ok = ok.any(axis=0) if ok.ndim > 1 else ok
    return float(min(freq_hz[ok].max(), sysm.f_max)) if ok.any() else 0.0


def _zoa_minimum(sysm: _System, freq_hz: np.ndarray, phi: np.ndarray) -> float:
    """The zero-order absolute minimum, m: min over ω of −1/(2 Re μ(ω)), μ the eigenvalues of H₀Φ(iω).

    It holds for every speed range (each lobe reaches it). Without any zero-order
    lobe: 1/(max |B H_i| / max |B| · max |Φ(f_0)|), a depth at which the cutting
    stiffness is of the order of the structure's stiffness at the lowest grid frequency f_0.
    """
    zero_order = _zoa_depths(sysm, phi)
    if zero_order.valid.any():
        return float(zero_order.depth_m[zero_order.valid].min())
    hmax = np.abs(sysm.directional(M_MIN)).max()
    return float(1.0 / max(hmax * np.abs(phi[0]).max(), 1e-300))


def _zoa_grid(sysm: _System) -> tuple[np.ndarray, np.ndarray]:
    """A frequency grid (Hz) resolving every pole (≥ 8 points per half-power band) and Φ on it (F, 2, 2)."""
    lam = sysm.model.poles
    fn = np.abs(lam) / (2 * np.pi)
    bw = np.maximum(-lam.real / (2 * np.pi), 1e-6 * fn)  # half-power half-width, Hz
    df = max(bw.min() / 8, 1.5 * fn.max() / _ZOA_POINTS)
    f = np.arange(df, 1.5 * fn.max() + df, df)
    return f, sysm.model.frf(f)


def _zoa_seed(sysm: _System, grid, f, phi):
    """Zero-order lobes (LobeResult) on ``grid``: limit inf where no lobe covers a speed (all inf if x is rigid)."""
    from ..frf import FRF
    from .zoa import zoa_lobes

    if not np.any(phi[:, 0, 0]):
        return LobeResult(grid, np.full(grid.size, np.inf), np.full(grid.size, np.nan))
    fx = FRF(f, phi[:, 0, 0])
    fy = FRF(f, phi[:, 1, 1]) if np.any(phi[:, 1, 1]) else "rigid"
    cross = {k: FRF(f, phi[:, i, j]) for k, (i, j) in (("frf_xy", (0, 1)), ("frf_yx", (1, 0))) if np.any(phi[:, i, j])}
    return zoa_lobes(fx, fy, sysm.cut, rpm=grid, **cross)


class _Progress:
    """Speeds finished, reported to a callable(done, total), a tqdm bar (``True``) or nobody."""

    def __init__(self, progress, total):
        self.bar = None
        self.fn = None
        if progress is True:
            from tqdm import tqdm

            self.bar = tqdm(total=total, unit="speed", desc="semi-discretisation", leave=False)
        elif callable(progress):
            self.fn = progress
        self.total, self.done = total, 0

    def add(self, k):
        self.done += k
        if self.bar is not None:
            self.bar.update(k)
        elif self.fn is not None:
            self.fn(self.done, self.total)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def sdm_lobes(
    modes_x,
    modes_y=None,
    cutting: CuttingConditions | None = None,
    *,
    rpm,
    m: int | None = None,
    accuracy: float = 1.0,
    m_max: int | None = None,
    depth_min: float | None = None,
    depth_max: float | None = None,
    step: float = 1.25,
    rtol: float = 1e-3,
    seed: bool = True,
    progress=None,
    widen: int = 2,
    chatter: bool = True,
) -> LobeResult:
    """Stability limit by semi-discretisation, per spindle speed.

    Parameters
    ----------
    modes_x, modes_y : StateSpaceModel, ModalModel or None
        The tool-point model: a :class:`~toolpoint.stability.statespace.StateSpaceModel`
        (any complex modes, cross terms) alone, or real modes in x and y
        (``None`` for a rigid direction).
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r = K_n/K_t, a_e/D, down/up milling.
    rpm : array_like
        Increasing spindle speeds, rpm.
    m : int, optional
        Steps over the cut, the same at every speed, every node carried;
        default ``None``: chosen per speed from
        ``accuracy`` (module docstring).
    accuracy : float
        Resolution factor (0.25 … 16) of the default discretisation: steps per
        chatter wave scale with it (up to ``m_max`` steps), delayed-displacement
        nodes per wave with max(accuracy, 1), and so does the time (measured
        error and cost: ``docs/design/stability.md``).
    m_max : int, optional
        Largest default ``m``; default 200 × max(accuracy, 1).
    depth_min, depth_max : float, optional
        Search range for the axial depth, m; default 1/4 and 100 times the
        zero-order minimum of the same model, and speeds still stable at 100 ×
        are searched again with the range × 10, at most ``widen`` times (the
        pocket of a lightly damped mode at low radial immersion can lie deeper:
        a campaign tool's 654 Hz mode of ζ 0.45 % at 25 % immersion has one at
        100–150 × its minimum). Speeds still stable at ``depth_max`` (given, or
        the widened default: ``params["depth_max"]``) get ``inf``.
    step : float
        Ratio between successive depths of the upward search; an unstable band
        thinner than this ratio can be missed.
    rtol : float
        Relative width of the final bracket.
    seed : bool
        Start the upward search at half the zero-order limit of each speed
        (module docstring); ``False``: from ``depth_min`` at every speed.
    progress : bool or callable, optional
        ``True``: a tqdm bar on stderr; a callable is called as
        ``progress(speeds_done, speeds_total)`` after each block of 50 speeds.
    widen : int, default 2
        Widenings of the default ``depth_max`` (0: none; ignored when
        ``depth_max`` is given).
    chatter : bool, default True
        ``False``: the limits only — no chatter frequencies (``nan``) and no
        lobes, which spares one eigen-decomposition with eigenvectors per
        speed (a sixth to a third of the time on the shop's priors:
        ``docs/design/stability.md``).

    Returns
    -------
    LobeResult
        Method ``"sdm"``: limit = the lowest unstable depth found (upper end
        of the final bracket, m), chatter frequency (Hz) from the critical
        Floquet multiplier and its eigenvector, lobes = runs of equal
        k = floor(f_c T); ``params["m"]`` and ``params["node_spacing"]`` hold
        the steps and the node spacing used at each speed,
        ``params["evaluations"]`` the Floquet matrices computed.

    Raises
    ------
    InputError
        Bad model, cutting conditions, speeds or settings.

    Examples
    --------
    Insperger & Stépán's benchmark (one mode in x, 2 teeth, a/D = 0.05, down-milling):

    >>> from toolpoint.stability import CuttingConditions, ModalModel, sdm_lobes
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=0.05)
    >>> res = sdm_lobes(ModalModel([922.0], [0.011], [0.03993]), None, cut, rpm=[10000.0])
    >>> round(float(res.depth_mm[0]), 2)
    4.09
    """
    cut = check_cutting(cutting)
    sysm = _System(as_state_space(modes_x, modes_y), cut)
    acc = _check_accuracy(accuracy)
    grid = check_rpm(rpm)
    for name, flag in (("seed", seed), ("chatter", chatter)):  # a string "False" would be true
        if not isinstance(flag, (bool, np.bool_)):
            raise InputError(f"must be True or False, got {flag!r}", field=name)
    if not step > 1 or not (0 < rtol < 0.1):
        raise InputError("need step > 1 and 0 < rtol < 0.1", field="step/rtol")
    f, phi = _zoa_grid(sysm)
    widen = _check_widen(widen) if depth_max is None else 0
    depth_min, depth_max = _depth_range(sysm, f, phi, depth_min, depth_max)
    start, f_wave = _starts(sysm, grid, f, phi, seed, depth_min, depth_max)
    if f_wave is not None:  # resolve every mode that can chatter within the searched depths, not only this range's
        reach = _chatter_reach(sysm, f, phi, depth_max * 10.0 ** widen)
        f_wave = max(f_wave, WAVE_MARGIN * reach)
    if m_max is None:
        m_max = int(round(M_MAX * max(acc, 1.0)))
    msteps, spacing = sysm.resolution(grid, m, acc, m_max, f_wave)
    limit, evaluations = _limits(sysm, grid, msteps, spacing, start, depth_min, depth_max, step, rtol, progress)
    for _ in range(widen):  # speeds known stable at depth_max: upward again from there, the range × 10
        todo = np.flatnonzero(~np.isfinite(limit))
        if not todo.size:
            break
        again, more = _limits(sysm, grid[todo], msteps[todo], spacing[todo], np.full(todo.size, depth_max),
                              depth_min, 10.0 * depth_max, step, rtol, None)
        limit[todo], evaluations, depth_max = again, evaluations + more, 10.0 * depth_max
    params = dict(cut.as_dict(), cutting=cut, phi_st=sysm.phi_st, phi_ex=sysm.phi_ex, m=msteps,
                  node_spacing=spacing, accuracy=acc, depth_min=depth_min, depth_max=depth_max, step=step,
                  rtol=rtol, seed=seed, evaluations=evaluations, model=sysm.model)
    return _sdm_result(sysm, grid, limit, msteps, spacing, params, chatter)


def _check_widen(widen) -> int:
    if isinstance(widen, bool) or not isinstance(widen, (int, np.integer)) or not 0 <= widen <= 4:
        raise InputError(f"must be an integer in 0…4, got {widen!r}", field="widen")
    return int(widen)


def _depth_range(sysm: _System, f, phi, depth_min, depth_max) -> tuple[float, float]:
    """The depth search range, m: the given ends, else 1/4 and 100 × the zero-order minimum; checked."""
    if depth_min is None or depth_max is None:
        scale = _zoa_minimum(sysm, f, phi)
        depth_min = scale / 4 if depth_min is None else depth_min
        depth_max = 100 * scale if depth_max is None else depth_max
    if not (0 < depth_min < depth_max and np.isfinite(depth_max)):
        raise InputError(f"need 0 < depth_min < depth_max, got {depth_min:g}, {depth_max:g} m", field="depth")
    return depth_min, depth_max


def _starts(sysm: _System, grid, f, phi, seed, depth_min, depth_max):
    """(first depth of the upward search per speed m, highest chatter frequency to resolve Hz or None).

    Seeded: a fraction of the zero-order limit of each speed, within the range;
    else ``depth_min`` everywhere (and no chatter frequency known).
    """
    start = np.full(grid.size, float(depth_min))
    f_wave = None
    if seed:
        zoa = _zoa_seed(sysm, grid, f, phi)
        start = np.clip(np.where(np.isfinite(zoa.depth_m), SEED_FRACTION * zoa.depth_m, depth_min),
                        depth_min, depth_max)
        if np.any(np.isfinite(zoa.chatter_hz)):
            # Chatter waves, not the highest mode, set the resolution: the exponentials integrate any mode exactly.
            f_wave = WAVE_MARGIN * float(np.nanmax(zoa.chatter_hz))
    return start, f_wave


def _limits(sysm: _System, grid, msteps, spacing, start, depth_min, depth_max, step, rtol, progress):
    """(limit per speed m: the smallest depth found unstable, Floquet matrices computed), block by block."""
    n = grid.size
    lo = np.zeros(n)  # largest depth known stable
    hi = np.full(n, np.inf)  # smallest depth known unstable
    rlo, rhi = np.zeros(n), np.full(n, np.inf)  # ρ there
    count = [0]
    bar = _Progress(progress, n)
    try:
        for blk in np.array_split(np.arange(n), max(1, int(np.ceil(n / _BLOCK_SPEEDS)))):
            ev = _Evaluator(sysm, grid, msteps, spacing, count)
            _search(ev, blk, start, depth_min, depth_max, step, lo, hi, rlo, rhi)
            _refine(ev, blk, lo, hi, rlo, rhi, rtol)
            bar.add(blk.size)
    finally:
        bar.close()
    return hi, count[0]


def _sdm_result(sysm: _System, grid, limit, msteps, spacing, params, with_chatter=True) -> LobeResult:
    """The LobeResult: chatter frequencies at the limit (unless ``with_chatter`` is false), lobes, and the lowest
    limit."""
    n = grid.size
    chatter = np.full(n, np.nan)
    fin = np.isfinite(limit)
    if fin.any() and with_chatter:
        chatter[fin] = sysm.critical(grid[fin], limit[fin], msteps[fin], spacing[fin])[1]
    lobes = _split_lobes(grid, limit, chatter, sysm.teeth)
    if not fin.any():
        return LobeResult(grid, limit, chatter, lobes, "sdm", params=params)
    j = int(np.argmin(limit))
    return LobeResult(grid, limit, chatter, lobes, "sdm", float(limit[j]), float(grid[j]), float(chatter[j]), params)


class _Evaluator:
    """ρ at (speed index, depth) pairs, counting the Floquet matrices computed."""

    def __init__(self, sysm, grid, msteps, spacing, count):
        self.sysm, self.grid, self.m, self.s, self.count = sysm, grid, msteps, spacing, count

    def __call__(self, idx, depth):
        self.count[0] += idx.size
        return self.sysm.multipliers(self.grid[idx], depth, self.m[idx], self.s[idx])[0]


def _search(ev, idx, start, depth_min, depth_max, step, lo, hi, rlo, rhi):
    """Bracket the limit of speeds ``idx``: ρ(lo) < 1 ≤ ρ(hi), in place.

    Upward search from ``start``: each step multiplies the depth by at most
    ``step``; from the second stable point on, by less when the secant of
    ln ρ against ln a through the last two points puts ρ = 1 closer
    (aiming 0.5 % beyond it, so the bracket closes tight). A speed already
    unstable at a seeded start above ``depth_min`` is searched again from
    ``depth_min`` (the SDM limit can lie far below the zero-order one there).
    """
    a = start[idx].copy()
    todo = idx.copy()
    restarted = np.zeros(lo.size, bool)
    prev_a = np.zeros(lo.size)  # last stable depth of the current upward run (0: none yet)
    prev_g = np.zeros(lo.size)
    while todo.size:
        rho = ev(todo, a)
        uns = rho >= 1.0
        again = uns & (a > depth_min * (1 + 1e-12)) & (lo[todo] == 0) & ~restarted[todo]
        if again.any():  # unstable at its first (seeded) depth: restart from the bottom
            restarted[todo[again]] = True
            a[again] = depth_min
            uns &= ~again
        hi[todo[uns]], rhi[todo[uns]] = a[uns], rho[uns]
        st = ~uns & ~again
        lo[todo[st]], rlo[todo[st]] = a[st], rho[st]
        g = np.log(np.maximum(rho, 1e-300))
        ratio = np.full(todo.size, step)
        pa, pg = prev_a[todo], prev_g[todo]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            slope = (g - pg) / np.log(a / pa)
            guess = np.exp(-g / slope) * 1.005
        ok = st & (pa > 0) & (slope > 0) & np.isfinite(guess)
        ratio[ok] = np.clip(guess[ok], 1.002, step)
        prev_a[todo[st]], prev_g[todo[st]] = a[st], g[st]
        keep = ~uns & ~(st & (a >= depth_max))
        todo, a = todo[keep], np.where(again, a, np.minimum(a * ratio, depth_max))[keep]


def _refine(ev, idx, lo, hi, rlo, rhi, rtol, max_iter=200):
    """Shrink every finite bracket [lo, hi] (ρ(lo) < 1 ≤ ρ(hi)) to hi − lo ≤ rtol·hi, in place.

    Illinois (modified false position) on ln ρ against ln a; the estimate is
    moved 0.4·rtol towards the far end of the bracket, so an accurate
    estimate closes the bracket at the next evaluation. A bisection step
    (geometric mean; halving while lo = 0) follows whenever the last step did
    not halve the bracket: the critical multiplier below the limit is often
    not the one that crosses, so ln ρ(ln a) can have a kink inside the
    bracket, where plain false position stalls.
    """
    br = idx[np.isfinite(hi[idx]) & (hi[idx] - lo[idx] > rtol * hi[idx])]
    glo = np.log(np.maximum(rlo, 1e-300))
    ghi = np.log(np.maximum(rhi, 1e-300))
    bisect = np.zeros(lo.size, bool)
    last = np.zeros(lo.size, int)
    for _ in range(max_iter):  # ends long before unless ρ ≥ 1 down to depth 0 (undamped)
        if not br.size:
            break
        l, h = lo[br], hi[br]  # noqa: E741
        width = np.log(h) - np.log(np.where(l > 0, l, h / 2))
        with np.errstate(divide="ignore", invalid="ignore"):
            xl, xh = np.log(l), np.log(h)
            x = xl - glo[br] * (xh - xl) / (ghi[br] - glo[br])
            # Overshoot towards the farther end, and stay at least a quarter of the tolerance inside.
            x = x + np.where(x - xl > xh - x, -0.4, 0.4) * rtol
            eps = 0.25 * rtol
            x = np.clip(x, xl + eps, xh - eps)
        geo = np.where(l > 0, np.sqrt(l * h), 0.5 * h)
        mid = np.where(bisect[br] | (l <= 0) | ~np.isfinite(x), geo, np.exp(x))
        rho = ev(br, mid)
        g = np.log(np.maximum(rho, 1e-300))
        uns = rho >= 1.0
        b_u, b_s = br[uns], br[~uns]
        hi[b_u], ghi[b_u] = mid[uns], g[uns]
        lo[b_s], glo[b_s] = mid[~uns], g[~uns]
        # Illinois: the end kept twice in a row has its ln ρ halved.
        side = np.where(uns, 1, -1)
        twice = side == last[br]
        glo[b_u[twice[uns]]] *= 0.5
        ghi[b_s[twice[~uns]]] *= 0.5
        last[br] = side
        new_width = np.log(hi[br]) - np.log(np.where(lo[br] > 0, lo[br], hi[br] / 2))
        bisect[br] = new_width > 0.5 * width
        br = br[hi[br] - lo[br] > rtol * hi[br]]


def _split_lobes(rpm, depth, chatter, teeth):
    """Group the limit into lobes: runs of equal k = floor(f_c T), T = 60/(N n)."""
    fin = np.isfinite(depth) & np.isfinite(chatter)
    k = np.where(fin, np.floor(chatter * 60.0 / (teeth * rpm) + 1e-9), -1).astype(int)
    cuts = np.flatnonzero(np.diff(k) != 0) + 1
    out = []
    for idx in np.split(np.arange(rpm.size), cuts):
        if idx.size and k[idx[0]] >= 0:
            out.append(Lobe(int(k[idx[0]]), 0, rpm[idx], depth[idx], chatter[idx]))
    return out
