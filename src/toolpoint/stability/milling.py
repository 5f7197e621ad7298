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

# Most spindle speeds one call evaluates: the envelope work grows with speeds ×
# lobes, and a chart never needs more points than a screen has pixels × 10.
MAX_RPM_POINTS = 100_000
# Fastest spindle speed accepted, rpm: the fastest micro-milling spindles turn at ~5e5 rpm; a larger
# number is a typo (and beyond it the tooth period falls below any FRF's resolution).
MAX_RPM = 1e6


# ----------------------------------------------------------------- validation
def check_rpm(rpm) -> np.ndarray:
    """Spindle speeds as a 1-D float array, rpm, checked.

    Parameters
    ----------
    rpm : array_like
        Speeds, rpm: finite, > 0, ≤ ``MAX_RPM``, strictly increasing, 1 … ``MAX_RPM_POINTS`` of them.

    Returns
    -------
    numpy.ndarray
        The speeds, rpm.

    Raises
    ------
    InputError
        Field ``rpm``.
    """
    try:
        r = np.asarray(rpm, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError("spindle speeds must be numbers", field="rpm") from None
    if r.size < 1:
        raise InputError("need at least one spindle speed", field="rpm")
    if r.size > MAX_RPM_POINTS:
        raise InputError(f"{r.size} spindle speeds, at most {MAX_RPM_POINTS} are evaluated in one call", field="rpm")
    if not np.all(np.isfinite(r)) or r[0] <= 0:
        raise InputError("spindle speeds must be finite and > 0 rpm", field="rpm")
    if r[-1] > MAX_RPM:
        raise InputError(f"spindle speeds above {MAX_RPM:g} rpm are not spindle speeds (got {r[-1]:g})", field="rpm")
    if np.any(np.diff(r) <= 0):
        raise InputError(f"spindle speeds must increase (got {r[0]:g} … {r[-1]:g} rpm)", field="rpm")
    return r


# ----------------------------------------------------------------- geometry
def _h_integral(phi, radial_ratio: float) -> np.ndarray:
    """Antiderivative ∫ H(φ) dφ / K_t of one tooth's directional matrix, shape (..., 2, 2).

    From ∫sc = −cos2φ/4, ∫s² = φ/2 − sin2φ/4, ∫c² = φ/2 + sin2φ/4.
    """
    kr = radial_ratio
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


def directional_coefficients(phi_st: float, phi_ex: float, radial_ratio: float) -> np.ndarray:
    """Altintas' directional coefficients [α] (module docstring), 2×2, dimensionless.

    Parameters
    ----------
    phi_st, phi_ex : float
        Entry and exit angles, rad.
    radial_ratio : float
        K_r = K_n/K_t, dimensionless.

    Examples
    --------
    >>> (directional_coefficients(0.0, np.pi, 0.0).round(6) + 0.0).tolist()  # slotting: [[0, −π], [π, 0]]
    [[0.0, -3.141593], [3.141593, 0.0]]
    """
    return -2.0 * (_h_integral(phi_ex, radial_ratio) - _h_integral(phi_st, radial_ratio))


def average_directional_matrix(teeth: int, tangential_coeff: float, radial_ratio: float, phi_st: float,
                               phi_ex: float) -> np.ndarray:
    """Tooth-pass average H₀ = −N K_t [α]/(4π) of H(t) in (1), N/m² (2×2).

    Parameters
    ----------
    teeth : int
        N.
    tangential_coeff : float
        K_t, N/m².
    radial_ratio : float
        K_r = K_n/K_t, dimensionless.
    phi_st, phi_ex : float
        Entry and exit angles, rad.
    """
    return -teeth * tangential_coeff * directional_coefficients(phi_st, phi_ex, radial_ratio) / (4 * np.pi)


def interval_directional_matrix(phi_edges, teeth: int, tangential_coeff: float, radial_ratio: float,
                                phi_st: float, phi_ex: float) -> np.ndarray:
    """Average of H(t) over each interval of tooth-0 angle.

    Interval i spans tooth-0 angles [φ_i, φ_{i+1}] (rad; φ increases linearly
    in time, so the angle average is the time average). Every tooth j
    contributes over its own angles φ + 2πj/N clipped to the cut
    [φ_st, φ_ex] — the screen function g — so jumps of H at entry/exit inside
    an interval are averaged exactly.

    Parameters
    ----------
    phi_edges : array_like
        Increasing interval edges of the tooth-0 angle, rad.
    teeth, tangential_coeff, radial_ratio, phi_st, phi_ex
        As in :func:`average_directional_matrix` (K_t in N/m², angles in rad).

    Returns
    -------
    numpy.ndarray
        Shape (len(phi_edges) − 1, 2, 2), N/m².
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
        total += (_h_integral(bb, radial_ratio) - _h_integral(aa, radial_ratio)).sum(axis=0)
    return tangential_coeff * total / (hi - lo)[:, None, None]


# ----------------------------------------------------------------- results
@dataclass(frozen=True)
class Lobe:
    """One lobe: the points of the stability boundary with k whole chatter waves per tooth period.

    Attributes
    ----------
    k : int
        Lobe number, k = floor(f_c T), T the tooth period.
    branch : int
        Eigenvalue branch (zero-order approximation: 0 or 1; semi-discretisation: 0).
    rpm : numpy.ndarray
        Spindle speeds of the points, rpm.
    depth_m : numpy.ndarray
        Axial depth limit at the points, m.
    chatter_hz : numpy.ndarray
        Chatter frequency at the points, Hz.
    """

    k: int
    branch: int
    rpm: np.ndarray
    depth_m: np.ndarray
    chatter_hz: np.ndarray


@dataclass(frozen=True)
class Pocket:
    """The best stable pocket of a stability limit (:meth:`LobeResult.pocket`).

    Attributes
    ----------
    rpm : float
        Spindle speed, rpm (nan when there is no pocket).
    depth_m : float
        Stability limit there, m (nan when there is no pocket).
    """

    rpm: float
    depth_m: float


@dataclass(frozen=True)
class LobeResult:
    """Stability lobes on a spindle-speed grid (SI: depth in m).

    Attributes
    ----------
    rpm : numpy.ndarray
        (n,) spindle speeds, rpm.
    depth_m : numpy.ndarray
        (n,) stability limit (axial depth, m), the minimum over lobes; ``inf``
        where no lobe (ZOA) or no instability up to the searched depth (SDM)
        was found.
    chatter_hz : numpy.ndarray
        (n,) chatter frequency of the limiting lobe, Hz (nan with inf depth).
    lobes : list of Lobe
        The individual lobes (each its own points, inside the speed range).
    method : str
        ``"zoa"`` or ``"sdm"``.
    min_depth_m, min_rpm, min_chatter_hz : float
        Absolute minimum of the limit in the range (m, rpm, Hz), refined
        between grid points where the method allows.
    params : dict
        The cutting conditions (``params["cutting"]``, a
        :class:`~toolpoint.stability.cutting.CuttingConditions`, and its
        fields) and solver settings used.
    limit_lobe : numpy.ndarray or None
        (n,) lobe number k of the limiting lobe at each speed, when the solver
        knows it (ZOA); see :attr:`lobe_number`.
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
    limit_lobe: np.ndarray | None = field(default=None, compare=False)

    @property
    def depth_mm(self) -> np.ndarray:
        """The stability limit in mm (``1e3 * depth_m``)."""
        return 1e3 * self.depth_m

    @property
    def lobe_number(self) -> np.ndarray:
        """Lobe number k of the limiting lobe per speed; −1 where no limit.

        ``limit_lobe`` when the solver gave it, else k = floor(f_c T), T = 60/(N n) s.
        """
        if self.limit_lobe is not None:
            return np.where(np.isfinite(self.depth_m), self.limit_lobe, -1).astype(int)
        teeth = self.params.get("teeth", 1)
        ok = np.isfinite(self.depth_m) & np.isfinite(self.chatter_hz)
        with np.errstate(invalid="ignore"):
            waves = self.chatter_hz * 60.0 / (teeth * self.rpm)
        # Points on a lobe's own boundary (f_c T an integer up to round-off) belong to the lower k.
        return np.where(ok, np.floor(np.where(ok, waves, 0.0) + 1e-9), -1).astype(int)

    def pocket(self) -> Pocket:
        """Best stable pocket: the highest local maximum of the limit strictly inside the speed range.

        A local maximum is a run of equal finite limits whose neighbours on
        both sides are lower, so a limit still rising at either end of the
        range is not a pocket (the best speed may lie outside it).

        Returns
        -------
        Pocket
            Speed (rpm) and limit (m); both nan when the limit has no such maximum.
        """
        d = np.asarray(self.depth_m, dtype=float)
        if d.size < 3:
            return Pocket(float("nan"), float("nan"))
        start = np.r_[0, np.flatnonzero(d[1:] != d[:-1]) + 1]  # runs of equal values
        stop = np.r_[start[1:], d.size]
        inner = (start > 0) & (stop < d.size)
        start, stop = start[inner], stop[inner]
        val = d[start]
        peak = np.isfinite(val) & (d[start - 1] < val) & (d[stop] < val)
        if not peak.any():
            return Pocket(float("nan"), float("nan"))
        j = int(np.argmax(np.where(peak, val, -np.inf)))
        mid = (start[j] + stop[j] - 1) // 2
        return Pocket(float(self.rpm[mid]), float(d[mid]))

    def plot(self, ax=None, **kw):
        """Stability chart, speed (rpm) against depth (mm).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
        **kw
            Passed to :func:`toolpoint.stability.plot.plot_lobes`.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from .plot import plot_lobes

        return plot_lobes(self, ax=ax, **kw)
