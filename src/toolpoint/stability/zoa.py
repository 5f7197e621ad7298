"""Zero-order approximation (ZOA) of milling stability, straight from FRFs.

Altintas & Budak (1995), "Analytical prediction of stability lobes in
milling", CIRP Annals 44(1):357–362.

Replacing the periodic directional matrix H(t) of (1) in
:mod:`~toolpoint.stability.milling` by its tooth-pass average H₀ (N/m²) and
writing the tool-point receptance matrix Φ(iω) = diag(Φ_xx, Φ_yy) (m/N; the
cross receptances Φ_xy, Φ_yx are neglected, as usual for a tool point), a
chatter vibration at ω_c is a non-trivial solution of

    det[ I + a (1 − e^{−iω_c T}) H₀ Φ(iω_c) ] = 0.                      (2)

Let μ be an eigenvalue of the oriented FRF H₀Φ (1/m). It is found in closed
form at all frequency points at once,

    μ = tr/2 ± √(tr²/4 − det),  tr = h_xx Φ_xx + h_yy Φ_yy,
                                det = (h_xx h_yy − h_xy h_yx) Φ_xx Φ_yy.

(2) then needs a (1 − e^{−iε}) = −1/μ with a real and positive. That holds
only where Re μ < 0 — Altintas' Λ = −(N/4π) a K_t (1 − e^{−iωT}) = −1/λ with
λ = −4πμ/(N K_t) the eigenvalue of [α]Φ, so this is his Λ_R < 0 — and gives

    a_lim = −1 / (2 Re μ)                            (axial depth, m)
    ε     = π + 2 arg(−μ) ∈ (0, 2π)                   (phase between waves)
    T     = (ε + 2kπ) / ω_c,  n = 60 / (N T)          (rpm), lobe k = 0, 1, 2, …

Altintas writes the same as a_lim = −2πΛ_R(1 + κ²)/(N K_t), κ = Λ_I/Λ_R,
ψ = arctan κ, ε = π − 2ψ. a_lim depends on ω_c only; each k maps the same
depth curve to another speed range, which is why all lobes cost one
eigenvalue evaluation. The limit at a speed is the minimum over lobes (and
over both eigenvalue branches).

Between neighbouring FRF points f, ε and a_lim are interpolated linearly, so
a lobe is only as fine as the FRF: near a sharp mode the k = 0 lobe can move
by a thousand rpm per 1 Hz step, and there a finer FRF grid is the remedy.

Single mode in x only: μ = h_xx Φ_xx, so a_lim = −1/(2 h_xx Re Φ_xx) and its
minimum is 2kζ(1+ζ)/h_xx (k = m ω_n² the modal stiffness), with
h_xx = N K_n/4 in slotting.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..frf import FRF
from .milling import (
    Lobe,
    LobeResult,
    average_directional_matrix,
    check_cutting,
    check_rpm,
    immersion_angles,
)

__all__ = ["zoa_lobes", "oriented_eigenvalues", "depth_and_phase"]

# Largest number of (lobe, segment) pairs handled at once; guards memory when a
# wide FRF band meets a very low minimum speed (thousands of lobes).
_MAX_PAIRS = 4_000_000


def oriented_eigenvalues(h0: np.ndarray, phi_xx: np.ndarray, phi_yy: np.ndarray) -> np.ndarray:
    """Both eigenvalues μ of H₀·diag(Φ_xx, Φ_yy) at every frequency, shape (2, n), 1/m.

    Closed-form 2×2 eigenvalues. The sign of the square root is chosen so the
    two branches are continuous in frequency: NumPy's principal root flips sign
    wherever the discriminant crosses the negative real axis; a flip is seen as
    the root turning by more than 90° between neighbours and undone with a
    cumulative parity, without a loop over frequencies.
    """
    tr = h0[0, 0] * phi_xx + h0[1, 1] * phi_yy
    det = (h0[0, 0] * h0[1, 1] - h0[0, 1] * h0[1, 0]) * phi_xx * phi_yy
    s = np.sqrt(tr * tr / 4 - det)
    flip = np.zeros(s.shape, dtype=int)
    flip[1:] = (s[1:] * np.conj(s[:-1])).real < 0
    s = np.where(np.cumsum(flip) % 2 == 1, -s, s)
    return np.stack([tr / 2 + s, tr / 2 - s])


def depth_and_phase(mu: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a_lim m, ε rad, valid) from eigenvalues μ; valid where Re μ < 0 (a > 0)."""
    # Re μ must be negative beyond round-off (a zero eigenvalue, e.g. a rigid
    # direction, comes out as ±1e-15 and would give absurd "lobes").
    scale = np.abs(mu).max(axis=0, keepdims=True) if mu.ndim > 1 else np.abs(mu)
    valid = np.isfinite(mu) & (mu.real < -1e-9 * scale)
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(valid, -0.5 / mu.real, np.inf)
        eps = np.pi + 2 * np.arctan(mu.imag / mu.real)  # arg(−μ) = arctan(μ_I/μ_R) when μ_R < 0
    return depth, eps, valid


def _as_receptance(frf, name: str) -> FRF:
    if not isinstance(frf, FRF):
        raise InputError(f"expected an FRF, got {type(frf).__name__}", field=name)
    try:
        frf = frf.to_receptance()
    except ValueError as err:
        raise InputError(str(err), field=name) from None
    if len(frf) < 3:
        raise InputError("FRF needs at least 3 frequency points", field=name)
    if np.any(np.diff(frf.freq_hz) <= 0) or not np.all(np.isfinite(frf.values)):
        raise InputError("FRF frequencies must increase and values be finite", field=name)
    return frf


def _common_grid(frf_x: FRF, frf_y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(f, Φ_xx, Φ_yy) on the x grid (restricted to the band both FRFs cover)."""
    if frf_y is None:
        return frf_x.freq_hz, frf_x.values, frf_x.values
    if isinstance(frf_y, str) and frf_y == "rigid":
        return frf_x.freq_hz, frf_x.values, np.zeros_like(frf_x.values)
    frf_y = _as_receptance(frf_y, "frf_y")
    if len(frf_y) == len(frf_x) and np.allclose(frf_y.freq_hz, frf_x.freq_hz, rtol=1e-12, atol=0):
        return frf_x.freq_hz, frf_x.values, frf_y.values
    x = frf_x.band(frf_y.freq_hz[0], frf_y.freq_hz[-1])
    if len(x) < 3:
        raise InputError(
            f"x FRF ({frf_x.freq_hz[0]:g}–{frf_x.freq_hz[-1]:g} Hz) and y FRF "
            f"({frf_y.freq_hz[0]:g}–{frf_y.freq_hz[-1]:g} Hz) share no frequency band",
            field="frf_y",
        )
    return x.freq_hz, x.values, frf_y.at(x.freq_hz).values


def zoa_lobes(
    frf_x: FRF,
    frf_y: FRF | str | None = None,
    *,
    teeth: int,
    kt: float,
    kr: float,
    radial_immersion: float,
    milling: str = "down",
    rpm,
) -> LobeResult:
    """Stability lobes by the zero-order approximation, from tool-point receptances.

    Parameters
    ----------
    frf_x : receptance in the feed direction x (m/N; mobility/accelerance are converted).
    frf_y : receptance in y; ``None`` for a symmetric tool (Φ_yy = Φ_xx),
        ``"rigid"`` for Φ_yy = 0. Interpolated onto the x grid if it differs.
    teeth : number of teeth N.
    kt : tangential cutting coefficient K_t, N/m².
    kr : K_n/K_t.
    radial_immersion : a_e/D ∈ (0, 1].
    milling : ``"down"`` or ``"up"``.
    rpm : increasing spindle speeds (rpm) on which the limit is returned.

    Returns
    -------
    LobeResult with the limit (minimum over lobes k = 0, 1, … and both
    eigenvalue branches) and chatter frequency on ``rpm``, every lobe's own
    points inside the range, and the absolute minimum refined between
    frequency points (parabola through the three lowest-depth neighbours).
    """
    teeth, kt, kr, ri, milling = check_cutting(teeth, kt, kr, radial_immersion, milling)
    grid = check_rpm(rpm)
    frf_x = _as_receptance(frf_x, "frf_x")
    f, pxx, pyy = _common_grid(frf_x, frf_y)
    phi_st, phi_ex = immersion_angles(ri, milling)
    h0 = average_directional_matrix(teeth, kt, kr, phi_st, phi_ex)

    mu = oriented_eigenvalues(h0, pxx, pyy)  # (2, nf)
    depth, eps, valid = depth_and_phase(mu)
    valid &= f[None, :] > 0
    # Waves per tooth period at lobe k: f_c T = k + ε/2π; speed n = 60 f_c / (N (k + ε/2π)).
    c = 60.0 * f[None, :] / teeth  # (1, nf): rpm·(waves per tooth period)
    frac = eps / (2 * np.pi)

    limit, chatter = _envelope(grid, c, frac, depth, valid, f)
    lobes, pts = _lobe_points(grid, c, frac, depth, valid, f)
    min_d, min_r, min_f = _absolute_minimum(grid, limit, chatter, pts, c, frac, depth, valid, f)
    params = dict(
        teeth=teeth, kt=kt, kr=kr, radial_immersion=ri, milling=milling,
        phi_st=phi_st, phi_ex=phi_ex, h0=h0, freq_band_hz=(float(f[0]), float(f[-1])),
    )
    return LobeResult(grid, limit, chatter, lobes, "zoa", min_d, min_r, min_f, params)


# ---------------------------------------------------------------- internals
def _k_range(c, frac, rmin, rmax):
    """Lobe numbers k with n = c/(k + frac) inside [rmin, rmax]: k ∈ [ceil(c/rmax − frac), floor(c/rmin − frac)]."""
    klo = np.maximum(np.ceil(c / rmax - frac), 0)
    khi = np.floor(c / rmin - frac)
    return klo, khi


def _pairs(klo, khi):
    """Expand index ranges [klo_s, khi_s] into (s, k) pairs without a Python loop."""
    cnt = np.maximum(khi - klo + 1, 0).astype(np.int64)
    total = int(cnt.sum())
    if total > _MAX_PAIRS:
        raise InputError(
            f"{total} lobe segments in this speed range (FRF band too wide for so low a minimum "
            "speed): raise the minimum rpm or limit the FRF band",
            field="rpm",
        )
    s = np.repeat(np.arange(cnt.size), cnt)
    start = np.cumsum(cnt) - cnt
    k = klo.reshape(-1)[s] + (np.arange(total) - start[s])
    return s, k


def _envelope(grid, c, frac, depth, valid, f):
    """Minimum over lobes of the lobe curves, sampled on ``grid``.

    Every pair of neighbouring valid frequency points is a segment of lobe k
    (f, ε and a_lim interpolated linearly between them); a lobe may fold back
    in speed, so each segment is intersected with the grid on its own
    (searchsorted over its speed range, which n(t) spans monotonically) and
    the minimum per grid speed taken over all segments that cover it.
    """
    rmin, rmax = grid[0], grid[-1]
    seg = valid[:, :-1] & valid[:, 1:] & (np.abs(np.diff(frac, axis=1)) < 0.5)
    b, i = np.nonzero(seg)
    cc0, cc1 = c[0, i], c[0, i + 1]
    fr0, fr1 = frac[b, i], frac[b, i + 1]
    klo0, khi0 = _k_range(cc0, fr0, rmin, rmax)
    klo1, khi1 = _k_range(cc1, fr1, rmin, rmax)
    # A segment matters for k unless both ends lie on the same side of the range.
    s, k = _pairs(np.minimum(klo0, klo1), np.maximum(khi0, khi1))
    r0 = cc0[s] / (k + fr0[s])
    r1 = cc1[s] / (k + fr1[s])
    lo, hi = np.minimum(r0, r1), np.maximum(r0, r1)
    j0 = np.searchsorted(grid, lo, "left")
    j1 = np.searchsorted(grid, hi, "right")
    cnt = np.maximum(j1 - j0, 0)
    q = np.repeat(np.arange(cnt.size), cnt)
    start = np.cumsum(cnt) - cnt
    g = j0[q] + (np.arange(q.size) - start[q])
    # Along a segment f, ε and a_lim vary linearly in t ∈ [0, 1]; the speed
    # n(t) = c(t)/(k + ε(t)/2π) is then a ratio of linear functions, inverted
    # exactly. (Straight lines in the (rpm, depth) plane would cut corners
    # where one frequency step spans a wide speed range: low k, sharp modes.)
    sq = s[q]
    r = grid[g]
    kk = k[q]
    with np.errstate(divide="ignore", invalid="ignore"):
        den = r * (fr1 - fr0)[sq] - (cc1 - cc0)[sq]
        t = np.where(den != 0, (cc0[sq] - r * (kk + fr0[sq])) / den, 0.0)
    t = np.clip(t, 0.0, 1.0)
    a0, a1 = depth[b[sq], i[sq]], depth[b[sq], i[sq] + 1]
    d = a0 + t * (a1 - a0)
    fc = f[i[sq]] + t * (f[i[sq] + 1] - f[i[sq]])
    limit = np.full(grid.size, np.inf)
    chatter = np.full(grid.size, np.nan)
    if g.size:
        order = np.lexsort((d, g))  # by grid index, then depth
        g_sorted = g[order]
        first = np.r_[True, g_sorted[1:] != g_sorted[:-1]]
        sel = order[first]
        limit[g[sel]] = d[sel]
        chatter[g[sel]] = fc[sel]
    return limit, chatter


def _lobe_points(grid, c, frac, depth, valid, f):
    """Each lobe's own points with speed inside the grid range, grouped by (k, branch)."""
    rmin, rmax = grid[0], grid[-1]
    b, i = np.nonzero(valid)
    klo, khi = _k_range(c[0, i], frac[b, i], rmin, rmax)
    s, k = _pairs(klo, khi)
    bb, ii = b[s], i[s]
    r = c[0, ii] / (k + frac[bb, ii])
    keep = (r >= rmin) & (r <= rmax)  # guards rounding at the range ends
    bb, ii, k, r = bb[keep], ii[keep], k[keep], r[keep]
    order = np.lexsort((ii, bb, k))
    bb, ii, k, r = bb[order], ii[order], k[order].astype(int), r[order]
    d, fc = depth[bb, ii], f[ii]
    cuts = np.flatnonzero((np.diff(k) != 0) | (np.diff(bb) != 0)) + 1
    lobes = [
        Lobe(int(kk[0]), int(bq[0]), rr, dd, ff)
        for kk, bq, rr, dd, ff in zip(*(np.split(x, cuts) for x in (k, bb, r, d, fc)))
        if kk.size
    ]
    return lobes, (bb, ii, k, r, d)


def _absolute_minimum(grid, limit, chatter, pts, c, frac, depth, valid, f):
    """Lowest limit in the range: the lowest lobe point, refined by a parabola in frequency.

    Lobe depth depends on the chatter frequency only, so near its lowest
    sampled point a(f) is refined by the vertex of the parabola through three
    neighbours; the speed follows from ε interpolated at the vertex. The grid
    limit (which covers lobe pieces crossing the range ends) is the fallback.
    """
    best = (np.inf, np.nan, np.nan)
    finite = np.isfinite(limit)
    if finite.any():
        j = int(np.argmin(np.where(finite, limit, np.inf)))
        best = (float(limit[j]), float(grid[j]), float(chatter[j]))
    bb, ii, k, r, d = pts
    if d.size == 0:
        return best
    p = int(np.argmin(d))
    if d[p] < best[0]:
        best = (float(d[p]), float(r[p]), float(f[ii[p]]))
    b, i, kk = bb[p], ii[p], k[p]
    if 0 < i < f.size - 1 and valid[b, i - 1] and valid[b, i + 1]:
        x = f[i - 1 : i + 2]
        y = depth[b, i - 1 : i + 2]
        # Vertex of the parabola through (x, y), on a possibly uneven grid.
        d1, d2 = (y[1] - y[0]) / (x[1] - x[0]), (y[2] - y[1]) / (x[2] - x[1])
        curv = (d2 - d1) / (x[2] - x[0])
        if curv > 0:
            xv = 0.5 * (x[0] + x[1]) - d1 / (2 * curv)
            if x[0] < xv < x[2]:
                yv = y[1] + d1 * (xv - x[1]) + curv * (xv - x[0]) * (xv - x[1])
                fr = np.interp(xv, x, frac[b, i - 1 : i + 2])
                rv = (c[0, i] / f[i]) * xv / (kk + fr)  # c/f = 60/N
                if 0 < yv <= best[0] and grid[0] <= rv <= grid[-1]:
                    best = (float(yv), float(rv), float(xv))
    return best
