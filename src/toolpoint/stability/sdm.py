"""First-order semi-discretisation (SDM) of milling stability for modal models.

Insperger & Stépán (2002) "Semi-discretization method for delayed systems",
IJNME 55:503–518; (2004) "Updated semi-discretization method for periodic
delay-differential equations with discrete delay", IJNME 61:117–141.

Model. Modes r (mass m_r, stiffness k_r, damping c_r) in x and/or y, modal
coordinates q, x = Σ_{r∈x} q_r, y = Σ_{r∈y} q_r (u = S q). With (1) of
:mod:`~toolpoint.stability.milling`,

    M q̈ + C q̇ + K q = −a Sᵀ H(t) S [q(t) − q(t − T)],     T = 60/(N n).

In state form ẏ = A(t) y + B(t) u(t − T), y = (q, q̇):

    A(t) = [[0, I], [−M⁻¹(K + a SᵀH(t)S), −M⁻¹C]],  B(t) = [[0], [a M⁻¹SᵀH(t)]].

Discretisation. Time is measured from a tooth's entry. H(t) is non-zero only
on the cut [0, t_c], t_c = min(T, (φ_ex − φ_st)/Ω), and vanishes in free
flight [t_c, T]. The cut is split into ``m`` steps Δt = t_c/m with nodes t_i;
on each, H is replaced by its exact average H_i (see
:func:`~toolpoint.stability.milling.interval_directional_matrix`) and the
delayed term by the straight line between the nodes one period earlier
(first-order SDM: u(t−T) ≈ u_{i−m*} + (t − t_i)/Δt · (u_{i−m*+1} − u_{i−m*}),
where "m*" denotes the same node of the previous period). Then exactly

    y_{i+1} = P_i y_i + (Γ0_i − Γ1_i) u'_i + Γ1_i u'_{i+1},
    P_i = e^{A_iΔt},  Γ0_i = ∫₀^Δt e^{A_i(Δt−s)} ds B_i,  Γ1_i = ∫₀^Δt e^{A_i(Δt−s)} (s/Δt) ds B_i,

all three from one exponential of the block matrix
[[A_iΔt, B_iΔt, 0], [0, 0, I], [0, 0, 0]] (Van Loan). Free flight is solved
exactly, y(T) = e^{A₀(T − t_c)} y_m: with H = 0 there is no delayed term, so
this equals the classic uniform-step SDM there, at no cost. Because the delay
is one tooth period, the nodes of the previous period are the delayed nodes,
so the state z = (y_0, u'_0, …, u'_m) of size 2n + (m+1)d (d flexible
directions) maps linearly over one period: z' = Φ z. The cut is stable iff the
spectral radius ρ(Φ) < 1 (Floquet).

Discretisation number m. ``m`` counts steps over the *cut*, not over the
whole tooth period as in Insperger & Stépán; the two coincide whenever a
tooth still cuts when the next one enters (slotting with ≥ 2 teeth, for
instance); at a/D = 0.05 (2 teeth, down-milling: cut ≈ 14 % of the
period) m = 20 over the cut has the resolution of ≈ 140 uniform steps. The
error is O(Δt²) and grows with the number of chatter waves per cut (high
lobe numbers, low speeds), so by default m is set per speed to 20 steps per
wave of 1.1 × the highest natural frequency, at least 20 and at most 200
(``params["m"]`` of the result). Convergence on the benchmark of Insperger &
Stépán 2004 (2 teeth, K_t = 6e8 N/m², K_n = 2e8 N/m², f_n = 922 Hz,
ζ = 0.011, modal mass 0.03993 kg, x only, down-milling; limit in mm at 7424,
10051, 15909, 21000 rpm for slotting, at 7500, 10000, 15800, 18900 rpm for
a/D = 0.05; benchmarks/bench_lobes.py):

    slotting  m =  20: 0.36475 0.34356 0.32702 2.29568
              m =  40: 0.32736 0.32445 0.31985 2.26602   (max change 10 %)
              m =  80: 0.31891 0.31992 0.31809 2.25860   (2.6 %)
              m = 160: 0.31685 0.31880 0.31765 2.25674   (0.65 %)
              default, m = 96, 68, 40, 32: 0.31807 0.32050 0.31985 2.27159
    a/D=0.05  m =  20: 2.62511 4.09208 5.99221 4.14411   (default; 0.28 % from m = 10)
              m =  40: 2.62326 4.09106 5.99254 4.14583   (0.07 %)

The default changes by < 1 % when m is doubled (tests/test_stability_sdm.py).
Near cusps, where two lobes meet, the limit is steep in speed and the
relative change at one fixed speed can be larger.

Stability limit. For each speed the depth is raised geometrically (ratio
``step``) from a small value until ρ ≥ 1 — only the still-stable speeds are
evaluated at each level, all at once — then bisected (geometric mean) to a
relative width ``rtol`` (default 1e-3, well below the discretisation error). An unstable band thinner than ``step`` in depth
(the tip of a flip-lobe island) can be stepped over.

Cost: eigenvalues of the (2n + (m+1)d)² Floquet matrices dominate; BLAS is
held to one thread meanwhile (threads only contend on stacks of small
matrices). One mode, 100 speeds: ≈ 2 s in slotting (m up to 136), ≈ 0.3 s at
a/D = 0.05 (m = 20) on the 2-core development machine.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .milling import (
    Lobe,
    LobeResult,
    check_cutting,
    check_rpm,
    immersion_angles,
    interval_directional_matrix,
    single_thread_blas,
)
from .modalfit import ModalModel

__all__ = ["sdm_lobes", "sdm_spectral_radius", "expm_batch", "STEPS_PER_WAVE"]

STEPS_PER_WAVE = 20  # default resolution: steps of the cut per chatter wave
M_MIN, M_MAX = 20, 200  # bounds of the step count over the cut
# Soft cap on floats held by one batch (expm blocks and Floquet matrices).
_CHUNK_FLOATS = 4_000_000


# ------------------------------------------------------------------ batched expm
def expm_batch(X: np.ndarray) -> np.ndarray:
    """exp(X) for a stack (..., k, k): Taylor degree 12 with per-matrix scaling and squaring.

    With ‖X/2^s‖₁ ≤ 1/2 the truncation error is < 0.5¹³/13! ≈ 2e-14. Stacked
    small matmuls in NumPy are ~10× faster here than scipy.linalg.expm's
    per-matrix Padé for the 4×4 … 16×16 blocks of the SDM.
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


# ------------------------------------------------------------------ model setup
def _m_ladder(m_max: int) -> np.ndarray:
    """Allowed step counts 20, 24, 28, 32, 40, 48, … (≈ 2^(1/4) apart, multiples of 4)."""
    j = np.arange(64)
    ladder = np.unique(4 * np.ceil(M_MIN * 2.0 ** (j / 4) / 4).astype(int))
    return np.r_[ladder[ladder < m_max], m_max]


class _System:
    """Modal matrices and cut geometry for one cutting condition; discretisations cached per m."""

    def __init__(self, modes_x, modes_y, teeth, kt, kr, radial_immersion, milling):
        if modes_x is None and modes_y is None:
            raise InputError("need modes in x, y or both", field="modes")
        groups = [(d, mm) for d, mm in ((0, modes_x), (1, modes_y)) if mm is not None]
        for d, mm in groups:
            if not isinstance(mm, ModalModel):
                raise InputError(f"expected a ModalModel, got {type(mm).__name__}", field="modes_" + "xy"[d])
            if np.any(mm.mass_kg <= 0):
                raise InputError(
                    "modal masses must be > 0 for the semi-discretisation (negative: not a driving-point FRF?)",
                    field="modes_" + "xy"[d],
                )
        self.teeth, self.kt, self.kr, self.ri, self.milling = check_cutting(teeth, kt, kr, radial_immersion, milling)
        self.phi_st, self.phi_ex = immersion_angles(self.ri, self.milling)
        self.modes = groups
        self.dirs = [d for d, _ in groups]
        self.wn = np.concatenate([mm.omega_n for _, mm in groups])
        self.ze = np.concatenate([mm.zeta for _, mm in groups])
        self.mass = np.concatenate([mm.mass_kg for _, mm in groups])
        n = self.n = self.wn.size
        self.d = len(groups)
        S = np.zeros((self.d, n))
        start = 0
        for j, (_, mm) in enumerate(groups):
            S[j, start : start + mm.n_modes] = 1.0
            start += mm.n_modes
        self.S = S  # u = S q: displacement of each flexible direction
        self.A0 = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(self.wn**2), -np.diag(2 * self.ze * self.wn)]])
        # Cut span of one tooth within a tooth period (several teeth may cut at once).
        self.cut_angle = min(self.phi_ex - self.phi_st, 2 * np.pi / self.teeth)
        self._EF = {}

    def directional(self, m: int):
        """(E_i, F_i) = (M⁻¹SᵀH_iS, M⁻¹SᵀH_i) for the m steps of the cut, shapes (m, n, n), (m, n, d)."""
        if m not in self._EF:
            edges = self.phi_st + self.cut_angle * np.arange(m + 1) / m
            H = interval_directional_matrix(edges, self.teeth, self.kt, self.kr, self.phi_st, self.phi_ex)
            Hd = H[:, self.dirs][:, :, self.dirs]  # (m, d, d): rigid directions drop out
            Minv = (1.0 / self.mass)[None, :, None]
            E = Minv * np.einsum("dn,idk,kp->inp", self.S, Hd, self.S)
            F = Minv * np.einsum("dn,idk->ink", self.S, Hd)
            self._EF[m] = (E, F)
        return self._EF[m]

    def cut_time(self, rpm):
        """(cut time t_c, free-flight time T − t_c), s."""
        omega = 2 * np.pi * np.asarray(rpm, float) / 60.0
        t_cut = self.cut_angle / omega
        return t_cut, np.maximum(2 * np.pi / (self.teeth * omega) - t_cut, 0.0)

    def steps(self, rpm, m=None, steps_per_wave=STEPS_PER_WAVE, m_max=M_MAX):
        """Steps over the cut per speed: ``m`` if given, else enough for ``steps_per_wave`` per wave.

        A wave is a period of the highest natural frequency +10 % (chatter sits
        just above a mode), so m = steps_per_wave · 1.1 f_max · t_c, rounded up
        to a ladder of values (few distinct m keep the batches large) and kept
        within [20, m_max].
        """
        rpm = np.asarray(rpm, float)
        if m is not None:
            if int(m) != m or m < 2:
                raise InputError(f"must be an integer ≥ 2, got {m!r}", field="m")
            return np.full(rpm.shape, int(m))
        waves = 1.1 * self.wn.max() / (2 * np.pi) * self.cut_time(rpm)[0]
        need = np.ceil(steps_per_wave * waves)
        ladder = _m_ladder(m_max)
        return ladder[np.minimum(np.searchsorted(ladder, need), ladder.size - 1)]

    def monodromy(self, rpm, depth, m: int, cut_end: bool = False):
        """Floquet transition matrices Φ, shape (B, D, D), for paired 1-D arrays rpm, depth.

        ``cut_end=True`` also returns the map z ↦ y(t_c) to the end of the cut (B, 2n, D).
        """
        n, d = self.n, self.d
        E, F = self.directional(m)
        B = rpm.size
        t_cut, t_free = self.cut_time(rpm)
        dt = t_cut / m
        na = 2 * n + 2 * d
        X = np.zeros((B, m, na, na))
        X[:, :, : 2 * n, : 2 * n] = self.A0
        X[:, :, n : 2 * n, :n] -= depth[:, None, None, None] * E
        X[:, :, n : 2 * n, 2 * n : 2 * n + d] = depth[:, None, None, None] * F
        X[:, :, : 2 * n] *= dt[:, None, None, None]
        X[:, :, 2 * n : 2 * n + d, 2 * n + d :] = np.eye(d)
        Ex = expm_batch(X)
        P = Ex[:, :, : 2 * n, : 2 * n]
        G0 = Ex[:, :, : 2 * n, 2 * n : 2 * n + d]
        G1 = Ex[:, :, : 2 * n, 2 * n + d :]
        Pfree = expm_batch(self.A0[None] * t_free[:, None, None])

        D = 2 * n + (m + 1) * d
        Y = np.zeros((B, 2 * n, D))
        Y[:, :, : 2 * n] = np.eye(2 * n)
        Phi = np.empty((B, D, D))
        Phi[:, 2 * n : 2 * n + d] = np.einsum("dn,bnk->bdk", self.S, Y[:, :n])
        for i in range(m):  # loop over time steps of the cut (not over speeds or depths)
            c0 = 2 * n + i * d
            Y = P[:, i] @ Y
            Y[:, :, c0 : c0 + d] += G0[:, i] - G1[:, i]
            Y[:, :, c0 + d : c0 + 2 * d] += G1[:, i]
            Phi[:, c0 + d : c0 + 2 * d] = np.einsum("dn,bnk->bdk", self.S, Y[:, :n])
        Phi[:, : 2 * n] = Pfree @ Y
        return (Phi, Y) if cut_end else Phi

    def multipliers(self, rpm, depth, m):
        """(spectral radius, critical multiplier) for paired rpm, depth, steps arrays.

        Points are grouped by their step count and processed in memory-bounded chunks.
        """
        rpm = np.asarray(rpm, float).reshape(-1)
        depth = np.asarray(depth, float).reshape(-1)
        m = np.broadcast_to(np.asarray(m, int), rpm.shape)
        crit = np.empty(rpm.size, complex)
        na = 2 * self.n + 2 * self.d
        with single_thread_blas():
            self._multipliers(rpm, depth, m, crit, na)
        return np.abs(crit), crit

    def _multipliers(self, rpm, depth, m, crit, na):
        for mm in np.unique(m):
            idx = np.flatnonzero(m == mm)
            D = 2 * self.n + (mm + 1) * self.d
            chunk = max(1, _CHUNK_FLOATS // max(mm * na * na, D * D))
            for s in range(0, idx.size, chunk):
                j = idx[s : s + chunk]
                ev = np.linalg.eigvals(self.monodromy(rpm[j], depth[j], int(mm)))
                crit[j] = ev[np.arange(ev.shape[0]), np.argmax(np.abs(ev), axis=1)]

    def critical(self, rpm, depth, m, samples_free: int = 64):
        """Critical multiplier μ and chatter frequency (Hz) at paired rpm, depth, steps.

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
        n, d = self.n, self.d
        mu = np.empty(rpm.size, complex)
        fc = np.empty(rpm.size)
        with single_thread_blas():
            for mm in np.unique(m):
                idx = np.flatnonzero(m == mm)
                Phi, Ycut = self.monodromy(rpm[idx], depth[idx], int(mm), cut_end=True)
                ev, vec = np.linalg.eig(Phi)
                j = np.argmax(np.abs(ev), axis=1)
                b = np.arange(idx.size)
                mu[idx] = ev[b, j]
                v = vec[b, :, j]  # (B, D)
                # The cut: this period's node values are μ × the stored previous ones.
                u_cut = mu[idx, None, None] * v[:, 2 * n :].reshape(idx.size, mm + 1, d)
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
                        uf[:, k] = y[:, :n] @ self.S.T
                    t.append(t_cut[:, None] + ds[:, None] * np.arange(1, samples_free + 1)[None, :])
                    u.append(uf)
                t, u = np.concatenate(t, axis=1), np.concatenate(u, axis=1)
                period = 60.0 / (self.teeth * rpm[idx])
                f0 = np.angle(mu[idx]) / (2 * np.pi * period)
                jmax = int(np.ceil(2.0 * self.wn.max() / (2 * np.pi) * period.max())) + 1
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


# ------------------------------------------------------------------ public API
def sdm_spectral_radius(
    modes_x: ModalModel | None,
    modes_y: ModalModel | None,
    *,
    teeth: int,
    kt: float,
    kr: float,
    radial_immersion: float,
    milling: str = "down",
    rpm,
    depth,
    m: int | None = None,
    steps_per_wave: float = STEPS_PER_WAVE,
) -> np.ndarray:
    """Spectral radius ρ of the Floquet transition matrix at (rpm, depth m), broadcast.

    ρ < 1 stable, ρ > 1 chatter. A speed × depth grid is
    ``sdm_spectral_radius(..., rpm=r[None, :], depth=a[:, None])``; its
    ρ = 1 contour is the stability boundary. ``m``: steps over the cut
    (default: ``steps_per_wave`` per chatter wave, see :func:`sdm_lobes`).
    """
    sysm = _System(modes_x, modes_y, teeth, kt, kr, radial_immersion, milling)
    r, a = np.broadcast_arrays(np.asarray(rpm, float), np.asarray(depth, float))
    if np.any(~np.isfinite(r) | (r <= 0)) or np.any(~np.isfinite(a) | (a < 0)):
        raise InputError("speeds must be > 0 rpm and depths finite and ≥ 0 m", field="rpm/depth")
    rho, _ = sysm.multipliers(r.reshape(-1), a.reshape(-1), sysm.steps(r.reshape(-1), m, steps_per_wave))
    return rho.reshape(r.shape)


def _default_depth_scale(sysm: _System) -> float:
    """A depth scale (m) for the search: the zero-order absolute minimum of the same modes.

    That minimum, min over ω of −1/(2 Re μ(ω)), holds for every speed range
    (each lobe reaches it), so it is taken straight from the eigenvalues.
    """
    from .milling import average_directional_matrix
    from .zoa import depth_and_phase, oriented_eigenvalues

    f = np.linspace(0.0, 2.0 * sysm.wn.max() / (2 * np.pi), 20001)[1:]
    byd = dict(sysm.modes)
    phi = [byd[d].frf(f, residuals=False).values if d in byd else np.zeros(f.size, complex) for d in (0, 1)]
    h0 = average_directional_matrix(sysm.teeth, sysm.kt, sysm.kr, sysm.phi_st, sysm.phi_ex)
    depth, _, valid = depth_and_phase(oriented_eigenvalues(h0, *phi))
    if valid.any():
        return float(depth[valid].min())
    # No zero-order lobe at all: the depth at which the cutting stiffness a·|H| matches the softest mode.
    hmax = np.abs(sysm.directional(M_MIN)[1]).max() * sysm.mass.max()
    return float((sysm.mass * sysm.wn**2).min() / max(hmax, 1e-30))


def sdm_lobes(
    modes_x: ModalModel | None,
    modes_y: ModalModel | None,
    *,
    teeth: int,
    kt: float,
    kr: float,
    radial_immersion: float,
    milling: str = "down",
    rpm,
    m: int | None = None,
    steps_per_wave: float = STEPS_PER_WAVE,
    m_max: int = M_MAX,
    depth_min: float | None = None,
    depth_max: float | None = None,
    step: float = 1.25,
    rtol: float = 1e-3,
) -> LobeResult:
    """Stability limit by first-order semi-discretisation, per spindle speed.

    Parameters
    ----------
    modes_x, modes_y : modes in x (feed) and y; ``None`` for a rigid direction.
    teeth, kt (N/m²), kr (K_n/K_t), radial_immersion (a_e/D), milling : as in
        :func:`~toolpoint.stability.zoa.zoa_lobes`.
    rpm : increasing spindle speeds, rpm.
    m : steps over the cut, the same at every speed; default ``None`` chooses
        per speed ``steps_per_wave`` (20) steps per wave of 1.1 × the highest
        natural frequency, within [20, ``m_max``] (see module docstring).
    depth_min, depth_max : search range for the axial depth (m); default
        1/4 and 100 times the zero-order minimum of the same modes. Speeds
        still stable at ``depth_max`` get ``inf``.
    step : ratio between successive depths of the upward search; an unstable
        band thinner than this ratio can be missed.
    rtol : relative width of the final bracket.

    Returns
    -------
    LobeResult (method ``"sdm"``): limit = the lowest unstable depth (upper
    end of the final bracket), chatter frequency from the critical Floquet
    multiplier and its eigenvector, lobes = runs of equal k = floor(f_c T);
    ``params["m"]`` holds the steps used at each speed.
    """
    sysm = _System(modes_x, modes_y, teeth, kt, kr, radial_immersion, milling)
    grid = check_rpm(rpm)
    msteps = sysm.steps(grid, m, steps_per_wave, m_max)
    if depth_min is None or depth_max is None:
        scale = _default_depth_scale(sysm)
        depth_min = scale / 4 if depth_min is None else depth_min
        depth_max = 100 * scale if depth_max is None else depth_max
    if not (0 < depth_min < depth_max and np.isfinite(depth_max)):
        raise InputError(f"need 0 < depth_min < depth_max, got {depth_min:g}, {depth_max:g} m", field="depth")
    if not step > 1 or not (0 < rtol < 0.1):
        raise InputError("need step > 1 and 0 < rtol < 0.1", field="step/rtol")

    n = grid.size
    lo = np.zeros(n)  # largest depth known stable
    hi = np.full(n, np.inf)  # smallest depth known unstable
    # Upward search, all still-stable speeds together at each depth level.
    a = depth_min
    todo = np.arange(n)
    while todo.size:
        rho, _ = sysm.multipliers(grid[todo], np.full(todo.size, a), msteps[todo])
        unstable = rho >= 1.0
        hi[todo[unstable]] = a
        lo[todo[~unstable]] = a
        todo = todo[~unstable]
        if a >= depth_max:
            break
        a = min(a * step, depth_max)
    _refine(sysm, grid, msteps, lo, hi, rtol)

    limit = hi
    chatter = np.full(n, np.nan)
    fin = np.isfinite(limit)
    if fin.any():
        chatter[fin] = sysm.critical(grid[fin], limit[fin], msteps[fin])[1]
    lobes = _split_lobes(grid, limit, chatter, sysm.teeth)
    params = dict(
        teeth=sysm.teeth, kt=sysm.kt, kr=sysm.kr, radial_immersion=sysm.ri, milling=sysm.milling,
        phi_st=sysm.phi_st, phi_ex=sysm.phi_ex, m=msteps, depth_min=depth_min, depth_max=depth_max,
        step=step, rtol=rtol,
    )
    if not fin.any():
        return LobeResult(grid, limit, chatter, lobes, "sdm", params=params)
    j = int(np.argmin(limit))
    return LobeResult(grid, limit, chatter, lobes, "sdm", float(limit[j]), float(grid[j]), float(chatter[j]), params)


def _refine(sysm, grid, msteps, lo, hi, rtol, max_iter=200):
    """Bisect every finite bracket [lo, hi] (ρ(lo) < 1 ≤ ρ(hi)) to hi − lo ≤ rtol·hi, in place.

    Geometric mean while lo > 0, halving while lo = 0 (unstable already at the
    smallest depth searched). False position on ln ρ was tried and needed as
    many steps: the critical multiplier below the limit is often not the one
    that crosses, so ln ρ(ln a) has a kink inside the bracket.
    """
    br = np.flatnonzero(np.isfinite(hi) & (hi - lo > rtol * hi))
    for _ in range(max_iter):  # ends long before unless ρ ≥ 1 down to depth 0 (undamped)
        if not br.size:
            break
        mid = np.where(lo[br] > 0, np.sqrt(lo[br] * hi[br]), 0.5 * hi[br])
        rho, _ = sysm.multipliers(grid[br], mid, msteps[br])
        uns = rho >= 1.0
        hi[br[uns]] = mid[uns]
        lo[br[~uns]] = mid[~uns]
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
