"""Regenerative milling in the time domain, vectorised over many (speed, depth) points.

Model (Tlusty's surface-history simulation; Schmitz & Smith, *Machining
Dynamics*, 2nd ed. 2019, ch. 4), in the conventions of
:mod:`toolpoint.stability.milling` so that it can be compared with the SDM
and the zero-order lobes: tooth j of N at φ_j(t) = Ω t + θ_j, measured
clockwise from +y, axial slice l lagging by ψ_l (helix, :class:`Tool`).
A slice of thickness a/L of a tooth inside the immersion
(φ_st ≤ φ mod 2π ≤ φ_ex) removes the chip

    h = f_j sin φ + s_prev − (x sin φ + y cos φ − ρ_j),                     (1)

f_j the feed per tooth (scaled by the tooth's pitch), ρ_j its runout and
s_prev the surface the previous tooth left at the same angle and slice, one
pitch τ_j earlier. Where h ≤ 0 the tooth has left the cut: no force, and the
surface it leaves is the previous one moved by the feed (s_prev + f_j sin φ);
otherwise the surface it leaves is x sin φ + y cos φ − ρ_j. The slice's force
(linear + edge model) is

    F_t = (a/L)(K_t h + K_te),  F_n = (a/L)(K_n h + K_ne),
    F_x = F_t cos φ + F_n sin φ,  F_y = −F_t sin φ + F_n cos φ.             (2)

Time stepping. One revolution is M = N·S steps of Δt = 60/(n M) s (S steps
per tooth: the delays τ_j are whole numbers of steps). The structure is
stepped exactly for a force held over each step (zero-order hold per complex
mode, :mod:`~toolpoint.simulation.structure`). The force of step i is taken
at the step's midpoint: the angles at t_i + Δt/2, the screen function
replaced by the fraction of the step the tooth spends in the immersion (as
the SDM averages H over a step), and the displacement predicted at
t_i + Δt/2 by the same exact map over half a step with the previous step's
force. That makes the scheme second order in Δt, where sampling the force at
t_i would lag it by Δt/2 (a phase error of π f Δt at a chatter frequency f).

Start. By default ("steady") the tool starts on the periodic forced response
of the rigid-tool force (exact when the pitch is equal and there is no
runout: then every chip is f sin φ and the surfaces repeat), plus a seed of
relative size ``seed_level``: a stable cut decays back, an unstable one grows
from the seed, and what is measured is the linear growth the SDM predicts.
"rest" starts from rest on fresh material (a real entry transient, which can
kick a cut below the linear limit into finite-amplitude chatter).

Force noise. A real cutting force fluctuates about the model's (2) by a few % (chip formation, the material,
friction); ``force_noise`` multiplies each step's force by 1 + ξ, ξ white. It makes what a sensor hears of a stable
cut near the limit: the tool's modes driven between the harmonics, more as the closed loop's damping falls. The
verdict is then taken from a noise-free twin of each point run in the same batch (see :func:`simulate_milling`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..blas import single_thread_blas
from ..errors import InputError
from ..stability.cutting import CuttingConditions, check_cutting
from .structure import ModalDynamics, as_modal_dynamics
from .tool import Tool

__all__ = ["SimulationResult", "simulate_milling", "steps_per_tooth_needed", "DEFAULT_STEPS_PER_TOOTH",
           "STEPS_PER_MODE_PERIOD", "MIN_STEPS_PER_MODE_PERIOD"]

DEFAULT_STEPS_PER_TOOTH = 64
"""Steps per tooth period before substeps are added for the modes."""
STEPS_PER_MODE_PERIOD = 20
"""Automatic substeps give at least this many steps per period of the highest mode."""
MIN_STEPS_PER_MODE_PERIOD = 8
"""Fewest steps per period of the highest mode accepted when the user fixes the step."""
SATURATED = 1e-3
"""Deviation from the periodic cut (RMS over a revolution / displacement scale) above which a cut chatters."""
FLOOR = 1e-11
"""Deviation (relative) below which growth is round-off, not chatter."""
NOISE_BAND_HZ = 5000.0
"""Band B over which ``force_noise`` is the relative standard deviation of the cutting force, Hz."""
_TABLE_BYTES = 96e6  # angle tables per revolution are precomputed below this size, else for as many steps as fit


@dataclass(frozen=True)
class SimulationResult:
    """Time-domain milling simulation of P (speed, depth) points (SI units).

    Attributes
    ----------
    rpm, depth_m : numpy.ndarray
        (P,) spindle speed, rpm, and axial depth, m.
    feed_m : float
        Mean feed per tooth f_z, m.
    dt_s : numpy.ndarray
        (P,) time step, s.
    steps_per_rev : int
        M, steps per revolution (all points).
    revolutions : int
        Revolutions simulated.
    record_start : int
        Index of the first recorded step (time ``record_start * dt_s``).
    force_n : numpy.ndarray
        (P, R, 2) cutting force on the tool (F_x, F_y) held over each recorded step, N.
    displacement_m : numpy.ndarray
        (P, R, 2) tool displacement (x, y) at the start of each recorded step, m.
    once_per_rev_m : numpy.ndarray
        (P, revolutions + 1, 2) displacement sampled once per revolution (t = k·60/n), m.
    deviation_m : numpy.ndarray
        (P, revolutions) RMS over each revolution of r(t) − r(t − T), m, T the period of the forced cut: the
        tooth period 60/(n N) when the teeth are alike (equal pitch, no runout), else the revolution 60/n. Zero
        for a stable cut; against the revolution, a period-doubling (flip) chatter of an even-toothed cutter
        (f_c = (j + ½) f_t, a spindle harmonic) repeats every revolution and would look stable.
    metric : numpy.ndarray
        (P,) Honeycutt & Schmitz (2016) metric: mean |r_k − r_{k−1}| of the once-per-revolution samples over
        the last revolutions over the peak-to-peak displacement of the last revolution (dimensionless).
    growth_per_rev : numpy.ndarray
        (P,) growth rate of the deviation, 1/revolution (ln of the ratio of its RMS over the last quarter of the
        revolutions and the quarter before, per revolution): > 0 where the cut is unstable.
    stable : numpy.ndarray
        (P,) bool: the deviation decays and stays below ``SATURATED`` × the displacement scale (with
        ``force_noise``, of the noise-free twin run; so are ``growth_per_rev`` and ``chatter_hz``).
    chatter_hz : numpy.ndarray
        (P,) peak of the spectrum of the displacement less its part periodic with T (recorded part), Hz; nan
        where stable.
    sle_m : numpy.ndarray
        (P,) surface location error, m: the tooth tip's deviation from the commanded wall at the surface
        generation angle (exit φ_ex in down-milling, entry φ_st in up-milling), along the wall normal; > 0 is
        an undercut (material left). Mean over teeth and slices of the last revolution.
    surface_m : numpy.ndarray
        (P, passes) wall location (SLE) left by each tooth pass of the recorded revolutions (slice mean), m.
    surface_pv_m : numpy.ndarray
        (P,) peak-to-valley of the wall locations of the last revolution over teeth and slices, m
        (the geometric feed-mark cusp f_z²/(8R) is not included).
    mean_force_n : numpy.ndarray
        (P, 2) mean force over the recorded whole revolutions, N.
    params : dict
        Conditions and settings used.
    """

    rpm: np.ndarray
    depth_m: np.ndarray
    feed_m: float
    dt_s: np.ndarray
    steps_per_rev: int
    revolutions: int
    record_start: int
    force_n: np.ndarray
    displacement_m: np.ndarray
    once_per_rev_m: np.ndarray
    deviation_m: np.ndarray
    metric: np.ndarray
    growth_per_rev: np.ndarray
    stable: np.ndarray
    chatter_hz: np.ndarray
    sle_m: np.ndarray
    surface_m: np.ndarray
    surface_pv_m: np.ndarray
    mean_force_n: np.ndarray
    params: dict = field(default_factory=dict, compare=False)

    @property
    def time_s(self) -> np.ndarray:
        """(P, R) time of each recorded step, s."""
        n = self.force_n.shape[1]
        return (self.record_start + np.arange(n))[None, :] * self.dt_s[:, None]


# ----------------------------------------------------------------- checks
def _points(rpm, depth_m):
    try:
        r, a = np.broadcast_arrays(np.asarray(rpm, float), np.asarray(depth_m, float))
    except (TypeError, ValueError):
        raise InputError("speeds and depths must be numbers of broadcastable shapes", field="rpm/depth_m") from None
    r, a = r.reshape(-1).copy(), a.reshape(-1).copy()
    if r.size < 1:
        raise InputError("need at least one point", field="rpm")
    if np.any(~np.isfinite(r) | (r <= 0)) or np.any(r > 1e6):
        raise InputError("spindle speeds must be finite, > 0 and ≤ 1e6 rpm", field="rpm")
    if np.any(~np.isfinite(a) | (a < 0)):
        raise InputError(f"axial depths must be finite and ≥ 0 m, got {a[~np.isfinite(a) | (a < 0)][0]:g}",
                         field="depth_m")
    return r, a


def _positive_int(value, field, low=1, high=10**7) -> int:
    try:
        v = int(value)
        ok = v == value and low <= v <= high and not isinstance(value, bool)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise InputError(f"must be an integer from {low} to {high}, got {value!r}", field=field)
    return v


def steps_per_tooth_needed(f_max_hz: float, rpm, teeth: int, steps_per_tooth=None, substeps=None):
    """Steps per tooth period S at each speed: ``steps_per_tooth`` × substeps.

    Parameters
    ----------
    f_max_hz : float
        Highest natural frequency of the model, Hz.
    rpm : array_like
        Spindle speeds, rpm.
    teeth : int
        N.
    steps_per_tooth : int, optional
        Steps per tooth period before substeps (default ``DEFAULT_STEPS_PER_TOOTH``).
    substeps : int, optional
        Fixed substeps; default: the fewest giving ``STEPS_PER_MODE_PERIOD`` steps per period of the highest mode.

    Returns
    -------
    numpy.ndarray
        (P,) int S.

    Raises
    ------
    InputError
        A fixed step giving fewer than ``MIN_STEPS_PER_MODE_PERIOD`` steps per period of the highest mode.
    """
    base = DEFAULT_STEPS_PER_TOOTH if steps_per_tooth is None else _positive_int(steps_per_tooth,
                                                                                 "steps_per_tooth", 4, 100_000)
    periods = f_max_hz * 60.0 / (teeth * np.asarray(rpm, float))  # periods of the highest mode per tooth period
    if substeps is None:
        sub = np.maximum(1, np.ceil(STEPS_PER_MODE_PERIOD * periods / base)).astype(int)
    else:
        sub = np.full(periods.shape, _positive_int(substeps, "substeps", 1, 10_000))
        worst = float(np.min(base * sub / periods))
        if worst < MIN_STEPS_PER_MODE_PERIOD:
            raise InputError(f"steps_per_tooth × substeps = {base * int(sub.flat[0])} gives {worst:.3g} steps per "
                             f"period of the highest mode ({f_max_hz:.4g} Hz); need ≥ {MIN_STEPS_PER_MODE_PERIOD}",
                             field="substeps" if substeps is not None else "steps_per_tooth")
    return base * sub


# ----------------------------------------------------------------- the core
class _Cut:
    """Per-point geometry and force tables of one batch (points on the last axis)."""

    def __init__(self, cut: CuttingConditions, tool: Tool, depth, feed, S: int):
        N = cut.teeth
        M = N * S
        self.M = M
        theta = tool.angles(N)
        k = np.round(theta * M / (2 * np.pi)).astype(int) % M
        if np.unique(k).size != N:
            raise InputError("two teeth fall on the same angular step: refine steps_per_tooth",
                             field="tooth_angles_deg")
        order = np.argsort(k)
        if np.any(order != np.arange(N)):
            raise InputError("tooth angles must increase", field="tooth_angles_deg")
        self.delay = (np.roll(k, -1) - k) % M  # tooth j+1 passed the same angle d_j steps earlier
        self.delay[self.delay == 0] = M  # one tooth: its own previous pass
        self.nxt = (np.arange(N) + 1) % N
        self.R = int(self.delay.max()) + 1  # ring buffer of surfaces
        self.theta = 2 * np.pi * k / M  # rounded to the step grid
        self.feed = feed * N * self.delay / M  # feed per tooth ∝ its pitch
        self.rho = tool.runout(N)
        # period of the forced (stable) cut, steps: a tooth period when the teeth are alike (equal pitch, no
        # runout), else a revolution. The verdict compares the motion with itself one period earlier: against
        # a revolution, a period-doubling (flip) chatter of an even-toothed cutter repeats and looks stable.
        alike = M % N == 0 and np.all(self.delay == M // N) and not np.any(self.rho)
        self.period = M // N if alike else M
        psi, L = tool.lag(depth)
        self.L = L
        phase = self.theta[:, None, None] - psi[None, :, :]  # (N, L, P) or (N, 1, P)
        if tool.helix_deg == 0:
            phase = phase[:, :, :1]  # the same for every point
        self.phase = phase
        self.slice_depth = depth / L  # (P,)
        self.phi_st, self.phi_ex = cut.immersion_angles
        self.kt, self.kn = cut.tangential_coeff, cut.normal_coeff
        self.kte, self.kne = tool.edge_tangential, tool.edge_normal
        self.edge = self.kte > 0 or self.kne > 0
        P = depth.size
        nbytes = 8 * M * phase.size * (7 if self.edge else 5) * (P if phase.shape[2] == 1 else 1)
        self._tables = None  # the whole revolution's tables, contiguous (the compiled step loop's input)
        self._nbytes = nbytes
        if nbytes <= _TABLE_BYTES:
            self._tables = self.tables(0, M)
        # where each tooth reads the surface ring (R, N, L, P) at step i: row (i − delay) mod R of the next tooth, as
        # flat indices into its first two axes, by i mod R
        rows = (np.arange(self.R)[:, None] - self.delay[None, :]) % self.R
        self._read = np.require(rows * N + self.nxt[None, :], np.int64, "CW")
        self._rho_flat = np.require(self.rho, float, "CW")

    def _angles(self, i):
        """s, c, in-cut mask, force factors at step(s) i (midpoint angles, in-cut fraction of the step)."""
        dphi = 2 * np.pi / self.M
        start = dphi * i + self.phase
        mid = start + dphi / 2
        s, c = np.sin(mid), np.cos(mid)
        width = self.phi_ex - self.phi_st
        ph = np.mod(start - self.phi_st, 2 * np.pi)
        over = np.clip(np.minimum(ph + dphi, width) - ph, 0, None) + np.clip(np.minimum(ph + dphi - 2 * np.pi,
                                                                                       width), 0, None)
        g = over / dphi * self.slice_depth  # m of depth in the cut, averaged over the step
        shape = np.broadcast_shapes(s.shape, g.shape)
        s, c = np.broadcast_to(s, shape), np.broadcast_to(c, shape)
        out = [s, c, g > 0, self.feed[:, None, None] * s, g * (self.kt * c + self.kn * s),
               g * (-self.kt * s + self.kn * c)]
        if self.edge:
            out += [g * (self.kte * c + self.kne * s), g * (-self.kte * s + self.kne * c)]
        return out

    def tables(self, a: int, b: int) -> list:
        """The tables of steps a ≤ i < b (within one revolution), (b − a, N, L, P) contiguous each, the edge forces'
        zero when the tool has none (the compiled loop's input)."""
        P = self.slice_depth.size
        shape = (b - a,) + self.phase.shape[:2] + (P,)
        # writable C arrays, as every array the loop takes: one compiled signature (numba types read-only apart)
        out = [np.require(np.broadcast_to(t, shape), None, "CW") for t in
               self._angles(np.arange(a, b)[:, None, None, None])]
        if not self.edge:
            out += [np.zeros((1, 1, 1, 1))] * 2
        return out

    def chunks(self, i_from: int, i_to: int):
        """(a, b, t0, tables) over steps i_from ≤ i < i_to: pieces within one revolution whose tables (row i − t0)
        fit in ``_TABLE_BYTES`` — the revolution's own when they were precomputed."""
        M = self.M
        span = M if self._tables is not None else max(1, int(M * _TABLE_BYTES // max(self._nbytes, 1)))
        i = i_from
        while i < i_to:
            r0 = (i // M) * M
            b = min(i_to, i + span, r0 + M)
            if self._tables is not None:
                yield i, b, r0, self._tables
            else:
                yield i, b, i, self.tables(i - r0, b - r0)
            i = b

    def at(self, i: int):
        """The tables of step i (i any integer; they repeat every revolution)."""
        if self._tables is not None:
            return [t[i % self.M] for t in self._tables[:8 if self.edge else 6]]
        return self._angles(i % self.M)


def _run(dyn: ModalDynamics, cut: CuttingConditions, tool: Tool, rpm, depth, feed, revolutions: int, S: int,
         start: str, seed: int, seed_level: float, record: int, force_noise: float = 0.0,
         noise_band_hz: float = NOISE_BAND_HZ) -> dict:
    """Simulate one batch with a common S; returns the raw arrays (points last).

    With ``force_noise`` > 0 the batch runs twice side by side (2 P columns, the same kick): the first P columns
    with the force noise, the last P without it (the twin that judges the linear stability; :func:`_split`)."""
    P0 = rpm.size
    twin = force_noise > 0
    if twin:
        rpm, depth = np.tile(rpm, 2), np.tile(depth, 2)
    P = rpm.size
    geo = _Cut(cut, tool, depth, feed, S)
    M, R, Pf = geo.M, geo.R, geo.period
    dt = 60.0 / (rpm * M)
    E, G = dyn.step_maps(dt)
    Eh, Gh = dyn.step_maps(dt / 2)
    W, Cout = dyn.inputs, dyn.outputs
    m = dyn.poles.size
    L = geo.L

    from ._steps import modal_pass, rigid_steps, run_steps  # compiled on first use (numba), cached on disk

    # writable C arrays of fixed dtypes, as the compiled loops take them (one signature each)
    W0, W1, Cc = (np.require(z, complex, "CW") for z in (W[:, 0], W[:, 1], Cout))
    E, G, Eh, Gh = (np.require(np.broadcast_to(z, (m, P)), complex, "CW") for z in (E, G, Eh, Gh))
    read, rho = geo._read, geo._rho_flat

    # rigid tool, two revolutions from fresh material: the periodic rigid-tool force and surfaces
    buf = np.zeros((R, cut.teeth, L, P))
    Frig = np.zeros((M, 2, P))
    for a, b, t0, tab in geo.chunks(-2 * M, 0):
        rigid_steps(a, b, t0, M, R, *tab, geo.edge, read, rho, buf, Frig)
    # periodic forced response of the discrete system: η_0 = Σ E^{M−1−i} G u_i / (1 − E^M)
    acc = np.zeros((m, P), complex)
    r_pre = np.zeros((M, 2, P))  # displacement at the step starts of the revolution before t = 0
    mid_pre = np.zeros((M, 2, P))  # and at the midpoints (what the chip saw)
    modal_pass(E, G, Eh, Gh, W0, W1, Cc, Frig, Frig[M - 1].copy(), acc, False, r_pre, mid_pre)
    eta0 = acc / (1 - E**M)
    eta = eta0.copy()
    modal_pass(E, G, Eh, Gh, W0, W1, Cc, Frig, Frig[M - 1].copy(), eta, True, r_pre, mid_pre)
    f_prev = Frig[M - 1].copy()  # the force held over the step before t = 0
    scale = np.maximum(np.abs(r_pre).max(axis=(0, 1)), 1e-15)  # displacement scale, m
    if start == "steady":
        # surfaces of the displaced periodic cut: the rigid ones moved by the displacement's projection
        for i in range(-R, 0):
            s, c = geo.at(i)[:2]
            x, y = mid_pre[i % M]
            buf[i % R] += s * x + c * y
        eta = eta0.copy()
        ring = r_pre[M - Pf:].copy()  # the period before t = 0
    else:
        buf[:] = 0.0
        eta = np.zeros((m, P), complex)
        ring = np.zeros((Pf, 2, P))
        f_prev = np.zeros((2, P))
    rng = np.random.default_rng(seed)
    kick = rng.standard_normal((m, P0)) + 1j * rng.standard_normal((m, P0))
    kick = np.tile(kick, (1, P // P0))  # the twin gets the same kick
    eta = eta + seed_level * scale * kick / (np.abs(Cout).max(axis=0)[:, None] * np.sqrt(2) * max(m, 1))
    if twin:
        # white relative fluctuation of the cutting force, one-sided PSD force_noise² / noise_band_hz (1/Hz):
        # per-step samples of std force_noise / sqrt(2 Δt B) have that PSD up to the step's Nyquist frequency
        nrng = np.random.default_rng([int(seed), 0x5EED])
        amp = np.zeros(P)
        amp[:P0] = force_noise / np.sqrt(2.0 * dt[:P0] * noise_band_hz)
        block = np.zeros((M, P))

    i0 = (revolutions - record) * M
    rec_r = np.zeros((record * M + 1, 2, P))
    rec_f = np.zeros((record * M, 2, P))
    opr = np.zeros((revolutions + 1, 2, P))
    dev = np.zeros((revolutions, P))
    r = np.require((Cout @ eta).real, float, "CW")
    mid = np.require((Cout @ (Eh * eta + Gh * (W0[:, None] * f_prev[0] + W1[:, None] * f_prev[1]))).real, float, "CW")
    eta, ring = np.require(eta, complex, "CW"), np.require(ring, float, "CW")
    if not twin:
        amp, block = np.zeros(P), np.zeros((M, P))
    for rev in range(revolutions):
        if twin:
            block[:, :P0] = nrng.standard_normal((M, P0))
        for a, b, t0, tab in geo.chunks(rev * M, (rev + 1) * M):
            run_steps(a, b, t0, M, R, Pf, i0, *tab, geo.edge, read, rho, buf, E, G, Eh, Gh, W0, W1, Cc, eta, mid, r,
                      ring, dev, opr, rec_r, rec_f, amp, block)
    opr[-1] = r
    rec_r[-1] = r
    out = dict(dt=dt, M=M, geo=geo, rec_r=rec_r, rec_f=rec_f, opr=opr, dev=np.sqrt(dev / M), scale=scale, i0=i0,
               period=Pf)
    return _split(out, P0) if twin else out


def _split(out: dict, P0: int) -> dict:
    """The noisy columns of a twin batch, with the noise-free twin's raw arrays under ``"quiet"``."""
    import copy

    def cols(d, sl):
        r = {k: (v[..., sl] if isinstance(v, np.ndarray) else v) for k, v in d.items()}
        geo = copy.copy(d["geo"])
        if geo.phase.shape[2] > 1:
            geo.phase = geo.phase[..., sl]
        r["geo"] = geo
        return r

    noisy = cols(out, slice(0, P0))
    noisy["quiet"] = cols(out, slice(P0, None))
    return noisy


# ----------------------------------------------------------------- metrics
def _verdict(dev, opr, rec_r, M, scale):
    """Honeycutt & Schmitz metric, growth rate and stability verdict (see SimulationResult)."""
    revs = dev.shape[0]
    q = max(revs // 4, 1)
    late = np.mean(dev[-q:] ** 2, axis=0)
    early = np.mean(dev[-2 * q:-q] ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        growth = np.where(early > 0, 0.5 * np.log(np.maximum(late, 1e-300) / np.maximum(early, 1e-300)) / q, 0.0)
    last = rec_r[-M - 1:]
    ptp = np.maximum(np.ptp(last, axis=0).max(axis=0), 1e-300)
    w = min(10, revs)
    jumps = np.linalg.norm(np.diff(opr[-w - 1:], axis=0), axis=1)  # (w, P)
    metric = jumps.mean(axis=0) / ptp
    rel = np.sqrt(late) / scale
    stable = ~((rel > SATURATED) | ((growth > 0) & (rel > FLOOR)))
    return metric, growth, stable


def _chatter(rec_r, period, dt, stable):
    """Peak frequency of the recorded displacement less its part periodic with the forced cut's ``period``
    (steps), Hz (nan where stable)."""
    n_rev = (rec_r.shape[0] - 1) // period
    P = rec_r.shape[2]
    out = np.full(P, np.nan)
    if n_rev < 2 or np.all(stable):
        return out
    x = rec_r[: n_rev * period]
    sync = x.reshape(n_rev, period, 2, P).mean(axis=0)
    res = x - np.tile(sync, (n_rev, 1, 1))
    res = res - res.mean(axis=0)
    pick = np.argmax((res**2).sum(axis=0), axis=0)  # the direction that moves most, per point
    sig = np.take_along_axis(res, pick[None, None, :], axis=1)[:, 0, :]
    nfft = 4 * sig.shape[0]
    spec = np.abs(np.fft.rfft(sig * np.hanning(sig.shape[0])[:, None], n=nfft, axis=0))
    spec[0] = 0
    k = np.clip(np.argmax(spec, axis=0), 1, spec.shape[0] - 2)
    cols = np.arange(P)
    a, b, c = np.log(spec[k - 1, cols] + 1e-300), np.log(spec[k, cols] + 1e-300), np.log(spec[k + 1, cols] + 1e-300)
    den = a - 2 * b + c
    off = np.where(den < 0, 0.5 * (a - c) / np.where(den < 0, den, -1), 0.0)
    out = (k + off) / (nfft * dt)
    return np.where(stable, np.nan, out)


def _surface(rec_r, geo: _Cut, milling: str, i0: int, record: int):
    """Wall location at the surface generation angle for every tooth pass and slice of the recording."""
    M = geo.M
    phi_g = geo.phi_ex if milling == "down" else geo.phi_st
    n_g = np.array([np.sin(phi_g), np.cos(phi_g)])
    P = rec_r.shape[2]
    phase = np.broadcast_to(geo.phase, (geo.phase.shape[0], geo.phase.shape[1], P))
    # step (fractional) at which tooth j, slice l is at φ_g within a revolution, from the revolution start
    pos = np.mod(phi_g - phase, 2 * np.pi) * M / (2 * np.pi)  # (N, L, P)
    walls = []
    for k in range(record):
        t = k * M + pos
        lo = np.clip(np.floor(t).astype(int), 0, rec_r.shape[0] - 2)
        fr = t - lo
        cols = np.arange(P)[None, None, :]
        proj = rec_r[lo, 0, cols] * n_g[0] + rec_r[lo, 1, cols] * n_g[1]
        proj1 = rec_r[lo + 1, 0, cols] * n_g[0] + rec_r[lo + 1, 1, cols] * n_g[1]
        walls.append((1 - fr) * proj + fr * proj1 - geo.rho[:, None, None])
    walls = np.stack(walls)  # (record, N, L, P)
    order = np.argsort(pos.mean(axis=1), axis=0)  # teeth in the order they pass
    per_pass = np.take_along_axis(walls.mean(axis=2), np.broadcast_to(order[None], walls.shape[:2] + (P,)), axis=1)
    surface = per_pass.reshape(-1, P).T  # (P, passes)
    last = walls[-1]
    return last.mean(axis=(0, 1)), surface, last.max(axis=(0, 1)) - last.min(axis=(0, 1))


# ----------------------------------------------------------------- public API
def simulate_milling(modes_x, modes_y=None, cutting: CuttingConditions | None = None, *, rpm, depth_m,
                     feed_m: float = 1e-4, tool: Tool | None = None, revolutions: int = 40,
                     steps_per_tooth: int | None = None, substeps: int | None = None, start: str = "steady",
                     seed: int = 0, seed_level: float = 1e-6, record_revolutions: int | None = None,
                     chunk: int = 1000, force_noise: float = 0.0) -> SimulationResult:
    """Time-domain simulation of regenerative milling at many (speed, depth) points at once.

    Parameters
    ----------
    modes_x, modes_y : StateSpaceModel, ModalFit, ModalModel, list of (f_n Hz, k N/m, ζ) or None
        The tool point (see :func:`~toolpoint.simulation.structure.as_modal_dynamics`): real modes per
        direction, or a full model with cross terms (``StateSpaceModel``, ``ModalFit``).
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r = K_n/K_t, a_e/D, down/up milling.
    rpm, depth_m : array_like
        Spindle speeds (rpm) and axial depths (m, ≥ 0), broadcast to P points.
    feed_m : float
        Mean feed per tooth f_z, m (> 0).
    tool : Tool, optional
        Helix, slices, tooth angles, runout, edge coefficients (default: straight, equal pitch, no edge force).
    revolutions : int
        Revolutions simulated (≥ 8).
    steps_per_tooth : int, optional
        Steps per tooth period (default 64) before substeps.
    substeps : int, optional
        Substeps per step; default: enough for 20 steps per period of the highest mode. A fixed value
        giving fewer than 8 is refused.
    start : {"steady", "rest"}
        Start on the periodic rigid-force response plus a seed (default), or at rest on fresh material.
    seed : int
        Seed of the random initial perturbation.
    seed_level : float
        Size of the perturbation relative to the displacement scale (≥ 0).
    record_revolutions : int, optional
        Last revolutions whose force and displacement are kept (default all; ≥ 1).
    chunk : int
        Most points simulated together (memory).
    force_noise : float
        Relative standard deviation s of the cutting force's random fluctuation over a band of
        ``NOISE_BAND_HZ`` (5 kHz), ≥ 0 and ≤ 0.3 (default 0: no noise). The force of each step is multiplied by
        1 + ξ_i, ξ white with one-sided PSD s²/B up to the step's Nyquist frequency: chip formation, the
        material's inhomogeneity and friction make a force whose standard deviation is 4–9 % of its mean, Gaussian
        and modelled as multiplicative noise (Fodor, Sykora & Bachrathy, Int J Adv Manuf Technol 111 (2020)
        213–226, doi:10.1007/s00170-020-05877-8; measured in turning). It drives the tool's modes in a stable cut
        (a real cut's vibration between the harmonics; the closed loop's least damped mode swells as the limit
        nears) and seeds chatter. The points then run twice, with and without the noise (one batch, the same
        kick): ``stable``, ``growth_per_rev`` and ``chatter_hz`` come from the noise-free run (the linear
        stability; the noisy deviation never decays), every recorded signal and ``metric`` from the noisy one.
        The band's value (5 kHz) and white shape are assumptions: a dynamometer resolves the force to a few kHz.

    Returns
    -------
    SimulationResult

    Raises
    ------
    InputError
        Naming the field: no mode, zero teeth, negative depth, a step that cannot resolve the highest mode, …

    Examples
    --------
    One mode in x (922 Hz, k = 1.34e6 N/m, ζ = 0.011), slotting with two teeth at 10 000 rpm:
    0.2 mm is stable, 0.5 mm chatters (the SDM limit there is 0.32 mm).

    >>> from toolpoint.stability import CuttingConditions
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=1.0)
    >>> res = simulate_milling([(922.0, 1.34e6, 0.011)], None, cut, rpm=10000.0, depth_m=[2e-4, 5e-4],
    ...                        revolutions=16, steps_per_tooth=32)
    >>> res.stable.tolist()
    [True, False]
    """
    cut = check_cutting(cutting)
    dyn = as_modal_dynamics(modes_x, modes_y)
    tool = Tool() if tool is None else tool
    if not isinstance(tool, Tool):
        raise InputError(f"expected a Tool, got {type(tool).__name__}", field="tool")
    tool.angles(cut.teeth), tool.runout(cut.teeth)
    rpm, depth = _points(rpm, depth_m)
    try:
        feed = float(feed_m)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {feed_m!r}", field="feed_m") from None
    if not (np.isfinite(feed) and 0 < feed < 0.1):
        raise InputError(f"must be finite, > 0 and < 0.1 m, got {feed_m!r}", field="feed_m")
    revolutions = _positive_int(revolutions, "revolutions", 8, 100_000)
    record = revolutions if record_revolutions is None else _positive_int(record_revolutions, "record_revolutions",
                                                                           1, revolutions)
    if start not in ("steady", "rest"):
        raise InputError(f"must be 'steady' or 'rest', got {start!r}", field="start")
    level = float(seed_level)
    if not (np.isfinite(level) and 0 <= level <= 1e-2):
        raise InputError(f"must be in [0, 0.01], got {seed_level!r}", field="seed_level")
    chunk = _positive_int(chunk, "chunk", 1, 10**6)
    try:
        noise = float(force_noise)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {force_noise!r}", field="force_noise") from None
    if not (np.isfinite(noise) and 0 <= noise <= 0.3):
        raise InputError(f"must be in [0, 0.3], got {force_noise!r}", field="force_noise")
    S = int(steps_per_tooth_needed(dyn.max_frequency_hz, rpm, cut.teeth, steps_per_tooth, substeps).max())
    parts = []
    with single_thread_blas():
        for a in range(0, rpm.size, chunk):
            sl = slice(a, a + chunk)
            parts.append(_run(dyn, cut, tool, rpm[sl], depth[sl], feed, revolutions, S, start, seed + a, level,
                              record, noise))
    res = _assemble(parts, cut, tool, rpm, depth, feed, revolutions, record, S, start, dyn)
    res.params["force_noise"] = noise
    return res


def _assemble(parts, cut, tool, rpm, depth, feed, revolutions, record, S, start, dyn) -> SimulationResult:
    cols = {k: [] for k in ("metric", "growth", "stable", "chatter", "sle", "surface", "pv")}
    for p in parts:
        metric = _verdict(p["dev"], p["opr"], p["rec_r"], p["M"], p["scale"])[0]
        q = p.get("quiet", p)  # with force noise, the noise-free twin says whether the cut is stable
        _, growth, stable = _verdict(q["dev"], q["opr"], q["rec_r"], q["M"], q["scale"])
        sle, surface, pv = _surface(p["rec_r"], p["geo"], cut.milling, p["i0"], record)
        for k, v in zip(cols, (metric, growth, stable, _chatter(q["rec_r"], q["period"], q["dt"], stable), sle,
                               surface, pv)):
            cols[k].append(v)
    cat = np.concatenate
    M = parts[0]["M"]
    rec_f = cat([p["rec_f"] for p in parts], axis=2)
    rec_r = cat([p["rec_r"][:-1] for p in parts], axis=2)
    mean_force = rec_f[: (rec_f.shape[0] // M) * M].mean(axis=0).T
    return SimulationResult(
        rpm=rpm, depth_m=depth, feed_m=feed, dt_s=cat([p["dt"] for p in parts]), steps_per_rev=M,
        revolutions=revolutions, record_start=parts[0]["i0"], force_n=rec_f.transpose(2, 0, 1),
        displacement_m=rec_r.transpose(2, 0, 1),
        once_per_rev_m=cat([p["opr"] for p in parts], axis=2).transpose(2, 0, 1),
        deviation_m=cat([p["dev"] for p in parts], axis=1).T, metric=cat(cols["metric"]),
        growth_per_rev=cat(cols["growth"]), stable=cat(cols["stable"]), chatter_hz=cat(cols["chatter"]),
        sle_m=cat(cols["sle"]), surface_m=cat(cols["surface"], axis=0), surface_pv_m=cat(cols["pv"]),
        mean_force_n=mean_force,
        params=dict(cutting=cut, **cut.as_dict(), tool=tool, steps_per_tooth=S, start=start,
                    max_frequency_hz=dyn.max_frequency_hz),
    )
