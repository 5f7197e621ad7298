"""Milling geometry shared by the stability solvers: immersion angles,
directional coefficients, and the :class:`LobeResult` both solvers return.

Conventions (Altintas & Budak 1995; Insperger & Stépán 2004)
------------------------------------------------------------
The tool turns clockwise seen from the spindle, x is the feed direction and y
the normal one. The angular position φ of a tooth is measured clockwise from
the +y axis; tooth j of N sits at φ_j(t) = Ω t + 2πj/N (Ω in rad/s). A tooth
cuts while φ_st ≤ φ_j mod 2π ≤ φ_ex (screen function g(φ_j) = 1, else 0):

* up-milling:   φ_st = 0,                 φ_ex = arccos(1 − 2 a_e/D)
* down-milling: φ_st = arccos(2 a_e/D − 1), φ_ex = π

with a_e/D the radial immersion. The dynamic chip of a tooth is
h = (Δx sin φ + Δy cos φ) g(φ), Δ = r(t) − r(t−T) the regenerative
displacement over the tooth period T = 2π/(NΩ). With tangential and normal
forces F_t = K_t a h, F_n = K_n a h (K_n = K_r K_t, a the axial depth) the
force on the tool is

    F(t) = −a H(t) [r(t) − r(t − T)],                                  (1)

    H(t) = Σ_j g(φ_j) [[ s(K_t c + K_n s),  c(K_t c + K_n s)],
                       [ s(−K_t s + K_n c), c(−K_t s + K_n c)]],

s = sin φ_j, c = cos φ_j; H is in N/m² (per metre of depth and metre of chip).
Its tooth-pass average is H₀ = (N/2π) ∫_{φ_st}^{φ_ex} H dφ = −N K_t [α]/(4π),
[α] being Altintas' directional coefficients

    α_xx = ½[ cos2φ − 2K_rφ + K_r sin2φ ],   α_xy = ½[−sin2φ − 2φ + K_r cos2φ],
    α_yx = ½[−sin2φ + 2φ + K_r cos2φ ],      α_yy = ½[−cos2φ − 2K_rφ − K_r sin2φ],

each evaluated between φ_st and φ_ex. Example: slotting gives
α_xx = −π K_r, so h₀,xx = N K_n / 4.

Units are SI everywhere inside: depth in m, K_t in N/m², speed in rpm only as
the user-facing axis of the lobes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError

MILLING = ("down", "up")


def single_thread_blas():
    """Context: BLAS/LAPACK on one thread.

    The solvers call LAPACK on stacks of small matrices (or tall-thin least
    squares); there OpenBLAS threads only contend — measured 6–20× slower on
    the 2-core development machine.
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(1, user_api="blas")


# ----------------------------------------------------------------- validation
def check_cutting(teeth, kt, kr, radial_immersion, milling) -> tuple[int, float, float, float, str]:
    """Validate the cutting parameters shared by both solvers (raises InputError)."""
    try:
        n = int(teeth)
    except (TypeError, ValueError):
        raise InputError(f"must be a positive integer, got {teeth!r}", field="teeth") from None
    if n != teeth or n < 1:
        raise InputError(f"must be a positive integer, got {teeth!r}", field="teeth")
    kt = float(kt)
    if not np.isfinite(kt) or kt <= 0:
        raise InputError(f"tangential cutting coefficient must be > 0 N/m², got {kt:g}", field="kt")
    kr = float(kr)
    if not np.isfinite(kr) or kr < 0:
        raise InputError(f"radial ratio Kn/Kt must be finite and ≥ 0, got {kr:g}", field="kr")
    ri = float(radial_immersion)
    if not (0.0 < ri <= 1.0):
        raise InputError(f"radial immersion a_e/D must be in (0, 1], got {ri:g}", field="radial_immersion")
    if milling not in MILLING:
        raise InputError(f"must be 'down' or 'up', got {milling!r}", field="milling")
    return n, kt, kr, ri, milling


def check_rpm(rpm) -> np.ndarray:
    """Spindle speeds (rpm): finite, > 0, strictly increasing, at least one."""
    r = np.asarray(rpm, dtype=float).reshape(-1)
    if r.size < 1:
        raise InputError("need at least one spindle speed", field="rpm")
    if not np.all(np.isfinite(r)) or r[0] <= 0:
        raise InputError("spindle speeds must be finite and > 0 rpm", field="rpm")
    if np.any(np.diff(r) <= 0):
        raise InputError(f"spindle speeds must increase (got {r[0]:g} … {r[-1]:g} rpm)", field="rpm")
    return r


# ----------------------------------------------------------------- geometry
def immersion_angles(radial_immersion: float, milling: str = "down") -> tuple[float, float]:
    """Entry and exit angles (φ_st, φ_ex) in rad for radial immersion a_e/D ∈ (0, 1]."""
    ri = float(radial_immersion)
    if milling == "up":
        return 0.0, float(np.arccos(1.0 - 2.0 * ri))
    if milling == "down":
        return float(np.arccos(2.0 * ri - 1.0)), float(np.pi)
    raise InputError(f"must be 'down' or 'up', got {milling!r}", field="milling")


def _h_integral(phi, kr: float) -> np.ndarray:
    """Antiderivative ∫ H(φ) dφ / K_t of one tooth's directional matrix, shape (..., 2, 2).

    From ∫sc = −cos2φ/4, ∫s² = φ/2 − sin2φ/4, ∫c² = φ/2 + sin2φ/4.
    """
    phi = np.asarray(phi, dtype=float)
    c2, s2 = np.cos(2 * phi), np.sin(2 * phi)
    isc = -c2 / 4
    iss = phi / 2 - s2 / 4
    icc = phi / 2 + s2 / 4
    out = np.empty(phi.shape + (2, 2))
    out[..., 0, 0] = isc + kr * iss
    out[..., 0, 1] = icc + kr * isc
    out[..., 1, 0] = -iss + kr * isc
    out[..., 1, 1] = -isc + kr * icc
    return out


def directional_coefficients(phi_st: float, phi_ex: float, kr: float) -> np.ndarray:
    """Altintas' directional coefficients [α] (2×2, dimensionless), see module docstring."""
    return -2.0 * (_h_integral(phi_ex, kr) - _h_integral(phi_st, kr))


def average_directional_matrix(teeth: int, kt: float, kr: float, phi_st: float, phi_ex: float) -> np.ndarray:
    """Tooth-pass average H₀ = −N K_t [α]/(4π) of H(t) in (1), N/m² (2×2)."""
    return -teeth * kt * directional_coefficients(phi_st, phi_ex, kr) / (4 * np.pi)


def interval_directional_matrix(phi_edges, teeth: int, kt: float, kr: float, phi_st: float, phi_ex: float) -> np.ndarray:
    """Average of H(t) over each interval of tooth-0 angle, shape (len(phi_edges) − 1, 2, 2), N/m².

    Interval i spans tooth-0 angles [φ_i, φ_{i+1}] (φ increases linearly in
    time, so the angle average is the time average). Every tooth j contributes
    over its own angles φ + 2πj/N clipped to the cut [φ_st, φ_ex] — the screen
    function g — so jumps of H at entry/exit inside an interval are averaged
    exactly.
    """
    e = np.asarray(phi_edges, dtype=float)
    lo, hi = e[:-1], e[1:]
    shift = 2 * np.pi * np.arange(teeth)[:, None] / teeth
    # A tooth's angle is taken mod 2π into [φ_st, φ_st + 2π): all of [φ_st, φ_ex] lies there.
    a = lo[None, :] + shift
    b = hi[None, :] + shift
    total = np.zeros((lo.size, 2, 2))
    for wrap in (0.0, -2 * np.pi):  # intervals straddling φ_st + 2π fold back one turn
        aa = np.clip(a + wrap, phi_st, phi_ex)
        bb = np.clip(b + wrap, phi_st, phi_ex)
        total += (_h_integral(bb, kr) - _h_integral(aa, kr)).sum(axis=0)
    return kt * total / (hi - lo)[:, None, None]


# ----------------------------------------------------------------- results
@dataclass(frozen=True)
class Lobe:
    """One lobe: the points of the stability boundary with k whole chatter waves per tooth period.

    k = floor(f_c T), T the tooth period; ``branch`` tells the eigenvalue branch
    (zero-order approximation: 0 or 1; semi-discretisation: 0).
    """

    k: int
    branch: int
    rpm: np.ndarray
    depth_m: np.ndarray
    chatter_hz: np.ndarray


@dataclass(frozen=True)
class LobeResult:
    """Stability lobes on a spindle-speed grid (SI: depth in m).

    Attributes
    ----------
    rpm : (n,) spindle speeds, rpm.
    depth_m : (n,) stability limit (axial depth, m), the minimum over lobes;
        ``inf`` where no lobe (ZOA) or no instability up to the searched depth
        (SDM) was found.
    chatter_hz : (n,) chatter frequency of the limiting lobe, Hz (nan with inf depth).
    lobes : the individual lobes (each its own points, inside the speed range).
    method : ``"zoa"`` or ``"sdm"``.
    min_depth_m, min_rpm, min_chatter_hz : absolute minimum of the limit in the
        range, refined between grid points where the method allows.
    params : the cutting parameters and solver settings used.
    """

    rpm: np.ndarray
    depth_m: np.ndarray
    chatter_hz: np.ndarray
    lobes: list = field(default_factory=list)
    method: str = ""
    min_depth_m: float = float("nan")
    min_rpm: float = float("nan")
    min_chatter_hz: float = float("nan")
    params: dict = field(default_factory=dict, compare=False)

    @property
    def depth_mm(self) -> np.ndarray:
        return 1e3 * self.depth_m

    def pocket(self) -> tuple[float, float]:
        """Best stable pocket: (rpm, depth m) of the maximum limit on the grid (inf if unbounded)."""
        d = self.depth_m
        if np.all(np.isnan(d)):
            return float("nan"), float("nan")
        i = int(np.nanargmax(d))
        return float(self.rpm[i]), float(d[i])

    def plot(self, ax=None, **kw):
        """Stability chart (see :func:`toolpoint.stability.plot.plot_lobes`); returns the axes."""
        from .plot import plot_lobes

        return plot_lobes(self, ax=ax, **kw)
