"""Zero-order approximation (ZOA) of milling stability, straight from FRFs.

Altintas & Budak (1995), "Analytical prediction of stability lobes in
milling", CIRP Annals 44(1):357–362.

Replacing the periodic directional matrix H(t) of (1) in
:mod:`~toolpoint.stability.milling` by its tooth-pass average H₀ (N/m²) and
writing the tool-point receptance matrix Φ(iω) = [[Φ_xx, Φ_xy], [Φ_yx, Φ_yy]]
(m/N; the cross terms default to 0), a chatter vibration at ω_c is a
non-trivial solution of

    det[ I + a (1 − e^{−iω_c T}) H₀ Φ(iω_c) ] = 0.                      (2)

Let μ be an eigenvalue of the oriented FRF H₀Φ (1/m). It is found in closed
form at all frequency points at once,

    μ = tr/2 ± √(tr²/4 − det),  tr = trace(H₀Φ),  det = det(H₀) det(Φ).

(2) then needs a (1 − e^{−iε}) = −1/μ with a real and positive. That holds
only where Re μ < 0 — Altintas' Λ = −(N/4π) a K_t (1 − e^{−iωT}) = −1/λ with
λ = −4πμ/(N K_t) the eigenvalue of [α]Φ, so this is his Λ_R < 0 — and gives

    a_lim = −1 / (2 Re μ)                            (axial depth, m)
    ε     = π + 2 arg(−μ) ∈ (0, 2π)                   (phase between waves)
    T     = (ε + 2kπ) / ω_c,  n = 60 / (N T)          (rpm), lobe k = 0, 1, 2, …

a_lim depends on ω_c only; each k maps the same depth curve to another speed
range, which is why all lobes cost one eigenvalue evaluation. The limit at a
speed is the minimum over lobes and over both eigenvalue branches.

Near a sharp resonance Φ turns by up to ~0.25 rad between 1 Hz points, and one
such interval spans hundreds of rpm at low lobe numbers: with μ linear between
the FRF points the limit would be drawn as straight chords. So each FRF
interval is first split into ceil(δ / :data:`MAX_TURN`) equal parts (at most
:data:`MAX_PARTS`), δ = |Φ_{i+1} − Φ_i| / min(|Φ_i|, |Φ_{i+1}|) (≈ the phase
turn plus the relative change of |Φ|; the largest over Φ_xx, Φ_yy, Φ_xy, Φ_yx),
and Φ is interpolated at the new frequencies by cubic Hermite polynomials
(second-order finite-difference slopes; :func:`refine_frf_grid`); the FRF
points keep their values.
The split depends on the FRFs only — not on the speeds asked for or the
cutting conditions — and :func:`~toolpoint.stability.zoa_batch.zoa_limits`
refines the same way, so the two agree. Between neighbouring points of the
refined grid μ is interpolated linearly (complex), so Re μ
and 1/a_lim are linear in frequency there and ε follows from the interpolated
μ exactly. Where Re μ changes sign between two points the lobe is kept up to
the crossing, where a_lim → ∞ and ε → 0 or 2π: the lobe flank rises to its
vertical asymptote instead of being cut off at the last sampled point (which
would leave the speeds under the flank too optimistic). For a grid speed n on
a piece of lobe k, the parameter of the crossing solves
c(t) = n (k + ε(t)/2π), c = 60 f/N, by safeguarded Newton steps.

Single mode in x only: μ = h_xx Φ_xx, so a_lim = −1/(2 h_xx Re Φ_xx) and its
minimum is 2kζ(1+ζ)/h_xx (k = m ω_n² the modal stiffness), with
h_xx = N K_n/4 in slotting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..frf import FRF, check_freq_hz
from .cutting import CuttingConditions, check_cutting
from .milling import Lobe, LobeResult, average_directional_matrix, check_rpm

__all__ = ["zoa_lobes", "oriented_eigenvalues", "depth_and_phase", "DepthPhase", "MAX_LOBE_POINTS", "MAX_TURN",
           "MAX_PARTS", "interval_parts", "refine_frf_grid"]

# Work is streamed over blocks of at most this many (segment, lobe) pairs, so
# memory stays bounded however fine the FRF or low the minimum speed.
_BLOCK = 500_000
# The lobes kept in the result (for plots and --lobes-out) are thinned, every
# s-th FRF point, to at most this many points; the limit uses every point.
MAX_LOBE_POINTS = 1_000_000
MAX_TURN = 0.05
"""Largest change δ = |Φ_{i+1} − Φ_i| / min(|Φ_i|, |Φ_{i+1}|) (≈ the phase turn plus the relative change of |Φ|, rad) of
the FRFs between two points of the grid μ is interpolated linearly on: FRF intervals with more are split
(:func:`interval_parts`)."""
MAX_PARTS = 16
"""Most parts an FRF interval is split into."""


def interval_parts(freq_hz, values) -> np.ndarray:
    """Parts (1 … :data:`MAX_PARTS`) to split each FRF interval into: ceil(δ_i / t), t = :data:`MAX_TURN`, with
    δ_i = abs(Φ_(i+1) − Φ_i) / min(abs(Φ_i), abs(Φ_(i+1))); 1 from 0 Hz and where Φ is 0 or not finite.

    Parameters
    ----------
    freq_hz : numpy.ndarray
        (F,) increasing frequencies, Hz.
    values : numpy.ndarray
        (F,) or (n, F) complex FRF values on ``freq_hz``, one row per FRF.

    Returns
    -------
    numpy.ndarray
        int64 of shape (F − 1,) or (n, F − 1).
    """
    y = np.asarray(values)
    a = np.abs(y)
    turn = np.abs(y[..., 1:] - y[..., :-1])
    m = np.minimum(a[..., 1:], a[..., :-1])
    with np.errstate(invalid="ignore"):
        split = (turn > MAX_TURN * m) & (m > 0)  # most intervals turn less and stay whole
    split[..., np.asarray(freq_hz)[:-1] <= 0] = False  # no lobes from 0 Hz
    parts = np.ones(split.shape, np.int64)
    idx = np.nonzero(split)
    with np.errstate(invalid="ignore", over="ignore"):
        p = np.ceil(np.minimum(turn[idx] / m[idx], MAX_PARTS * MAX_TURN) / MAX_TURN)
    parts[idx] = np.where(np.isfinite(p) & (p > 1), p, 1).astype(np.int64)
    return parts


def refine_frf_grid(freq_hz, values, parts):
    """FRFs on their refined grids: interval i of row r split into ``parts[r, i]`` equal parts.

    Φ at the new points is the cubic Hermite polynomial between the interval's ends, with the slopes
    second-order finite differences (as ``numpy.gradient(…, edge_order=2)``); the FRF points keep their values.

    Parameters
    ----------
    freq_hz : numpy.ndarray
        (F,) increasing frequencies, Hz (at least 3).
    values : numpy.ndarray
        (n, F) complex FRF values.
    parts : numpy.ndarray
        (n, F − 1) or (F − 1,) (the same for every row) integers ≥ 1 (:func:`interval_parts`).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        (n, L) frequencies and values, L = the most points of a row; a shorter row is padded at its end with its
        last frequency and NaN.
    """
    f = np.asarray(freq_hz, float)
    y = np.asarray(values, complex)
    n, F = y.shape
    parts = np.broadcast_to(np.asarray(parts, np.int64), (n, F - 1))
    extra = parts - 1
    r, i = np.nonzero(extra)
    cnt = extra[r, i]
    per_row = np.bincount(r, weights=cnt, minlength=n).astype(np.int64)
    L = F + int(per_row.max(initial=0))
    # new points: after point i of row r, j = 1 … parts − 1; then each row padded to L points
    e = np.repeat(np.arange(r.size), cnt)
    j = 1 + np.arange(e.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    re, ie = r[e], i[e]
    t = j / parts[re, ie]
    h = f[ie + 1] - f[ie]
    h00, h10 = (1 + 2 * t) * (1 - t) ** 2, t * (1 - t) ** 2
    h01, h11 = t * t * (3 - 2 * t), t * t * (t - 1)
    d0, d1 = _slopes(f, y, r, i), _slopes(f, y, r, i + 1)
    y_new = h00 * y[re, ie] + h10 * h * d0[e] + h01 * y[re, ie + 1] + h11 * h * d1[e]
    pad = L - F - per_row
    rows_pad = np.repeat(np.arange(n), pad)
    at = np.r_[re * F + ie + 1, rows_pad * F + F]  # insertion points in the flattened (n, F) arrays
    order = np.argsort(at, kind="stable")
    at = at[order]
    ys = np.insert(y.reshape(-1), at, np.r_[y_new, np.full(rows_pad.size, np.nan + 0j)][order]).reshape(n, L)
    fs = np.insert(np.tile(f, n), at, np.r_[f[ie] + t * h, np.full(rows_pad.size, f[-1])][order]).reshape(n, L)
    return fs, ys


def _slopes(f, y, r, i):
    """dΦ/df of row r at point i: second-order finite differences (those of ``numpy.gradient(…, edge_order=2)``)."""
    F = f.size
    c = np.clip(i, 1, F - 2)  # the three points used: c − 1, c, c + 1
    h1, h2 = f[c] - f[c - 1], f[c + 1] - f[c]
    y0, y1, y2 = y[r, c - 1], y[r, c], y[r, c + 1]
    inner = (-h2 / (h1 * (h1 + h2))) * y0 + ((h2 - h1) / (h1 * h2)) * y1 + (h1 / (h2 * (h1 + h2))) * y2
    first = (-(2 * h1 + h2) / (h1 * (h1 + h2))) * y0 + ((h1 + h2) / (h1 * h2)) * y1 + (-h1 / (h2 * (h1 + h2))) * y2
    last = (h2 / (h1 * (h1 + h2))) * y0 + (-(h1 + h2) / (h1 * h2)) * y1 + ((2 * h2 + h1) / (h2 * (h1 + h2))) * y2
    return np.where(i == 0, first, np.where(i == F - 1, last, inner))


def oriented_eigenvalues(h0: np.ndarray, phi_xx: np.ndarray, phi_yy: np.ndarray, phi_xy=None,
                         phi_yx=None) -> np.ndarray:
    """Both eigenvalues μ of the oriented FRF H₀Φ at every frequency, 1/m.

    Parameters
    ----------
    h0 : numpy.ndarray
        (2, 2) average directional matrix, N/m².
    phi_xx, phi_yy : numpy.ndarray
        (n,) direct receptances, m/N.
    phi_xy, phi_yx : numpy.ndarray, optional
        (n,) cross receptances, m/N (default 0).

    Returns
    -------
    numpy.ndarray
        (2, n) complex. Closed-form 2×2 eigenvalues; the sign of the square
        root is chosen so the two branches are continuous in frequency: NumPy's
        principal root flips sign wherever the discriminant crosses the
        negative real axis; a flip is seen as the root turning by more than 90°
        between neighbours and undone with a cumulative parity.
    """
    zero = 0.0
    pxy = zero if phi_xy is None else phi_xy
    pyx = zero if phi_yx is None else phi_yx
    tr = h0[0, 0] * phi_xx + h0[0, 1] * pyx + h0[1, 0] * pxy + h0[1, 1] * phi_yy
    det = (h0[0, 0] * h0[1, 1] - h0[0, 1] * h0[1, 0]) * (phi_xx * phi_yy - pxy * pyx)
    s = np.sqrt(tr * tr / 4 - det)
    flip = np.zeros(s.shape, dtype=int)
    flip[1:] = (s[1:] * np.conj(s[:-1])).real < 0
    s = np.where(np.cumsum(flip) % 2 == 1, -s, s)
    return np.stack([tr / 2 + s, tr / 2 - s])


@dataclass(frozen=True)
class DepthPhase:
    """Zero-order depth limit, phase and validity at each eigenvalue μ (:func:`depth_and_phase`).

    Attributes
    ----------
    depth_m : numpy.ndarray
        a_lim = −1/(2 Re μ), m (inf where not valid).
    eps_rad : numpy.ndarray
        ε = π + 2 arg(−μ), rad: phase between the inner and outer waves.
    valid : numpy.ndarray
        Re μ < 0 beyond round-off (a > 0).
    """

    depth_m: np.ndarray
    eps_rad: np.ndarray
    valid: np.ndarray


def depth_and_phase(mu: np.ndarray) -> DepthPhase:
    """Depth limit, phase and validity from eigenvalues μ.

    Parameters
    ----------
    mu : numpy.ndarray
        Eigenvalues of H₀Φ, 1/m, shape (n,) or (branches, n).

    Returns
    -------
    DepthPhase
        Arrays of the shape of ``mu``.
    """
    valid = _negative(mu)
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(valid, -0.5 / mu.real, np.inf)
    return DepthPhase(depth, _phase(mu), valid)


def _negative(mu):
    # Re μ must be negative beyond round-off (a zero eigenvalue, e.g. a rigid
    # direction, comes out as ±1e-15 and would give absurd "lobes").
    scale = np.abs(mu).max(axis=0, keepdims=True) if mu.ndim > 1 else np.abs(mu)
    return np.isfinite(mu) & (mu.real < -1e-9 * scale)


def _phase(mu):
    """ε = π + 2 arg(−μ), rad; at Re μ = 0 the limit from the side Re μ < 0 (0 or 2π)."""
    return np.pi + 2 * np.arctan2(-mu.imag, -mu.real)


def _as_receptance(frf, name: str) -> FRF:
    if not isinstance(frf, FRF):
        raise InputError(f"expected an FRF, got {type(frf).__name__}", field=name)
    check_freq_hz(frf.freq_hz, field=name, min_points=3)
    if not np.all(np.isfinite(frf.values)):
        raise InputError(f"FRF values must be finite ({int((~np.isfinite(frf.values)).sum())} are not)", field=name)
    try:
        return frf.to_receptance()
    except ValueError as err:
        raise InputError(str(err), field=name) from None


def _common_grid(frf_x: FRF, others: dict) -> tuple[np.ndarray, dict]:
    """(f, {name: Φ on f}) on the x grid, restricted to the band every FRF covers.

    ``others`` maps "frf_y", "frf_xy", "frf_yx" to an FRF, ``None`` or
    ``"rigid"``; ``None`` means Φ_yy = Φ_xx (y) or 0 (cross terms).
    """
    given = {k: _as_receptance(v, k) for k, v in others.items() if isinstance(v, FRF)}
    for k, v in others.items():
        if v is not None and not isinstance(v, FRF) and not (k == "frf_y" and isinstance(v, str) and v == "rigid"):
            allowed = "an FRF, None or 'rigid'" if k == "frf_y" else "an FRF or None"
            raise InputError(f"expected {allowed}, got {v!r}", field=k)
    lo = max([frf_x.freq_hz[0]] + [g.freq_hz[0] for g in given.values()])
    hi = min([frf_x.freq_hz[-1]] + [g.freq_hz[-1] for g in given.values()])
    x = frf_x.band(lo, hi)
    if len(x) < 3:
        names = ", ".join(given)
        raise InputError(f"x FRF ({frf_x.freq_hz[0]:g}–{frf_x.freq_hz[-1]:g} Hz) and {names} share no "
                         "frequency band of 3 points", field=next(iter(given)))
    f = x.freq_hz
    out = {"xx": x.values}
    for k, name in (("frf_y", "yy"), ("frf_xy", "xy"), ("frf_yx", "yx")):
        v = others.get(k)
        if isinstance(v, FRF):
            g = given[k]
            same = len(g) == len(f) and np.allclose(g.freq_hz, f, rtol=1e-12, atol=0)
            out[name] = g.values if same else g.at(f).values
        elif name == "yy":
            out[name] = np.zeros_like(x.values) if isinstance(v, str) else x.values
        else:
            out[name] = None
    return f, out


def _check_not_zero(phi: dict, f) -> None:
    """An all-zero flexible FRF would read as 'no chatter'; refuse it instead."""
    if not np.any(phi["xx"][f > 0]):
        raise InputError("the x FRF is zero at every frequency (a rigid tool cannot be analysed: "
                         "no chatter is not a result here)", field="frf_x")


def zoa_lobes(
    frf_x: FRF,
    frf_y: FRF | str | None = None,
    cutting: CuttingConditions | None = None,
    *,
    rpm,
    frf_xy: FRF | None = None,
    frf_yx: FRF | None = None,
) -> LobeResult:
    """Stability lobes by the zero-order approximation, from tool-point receptances.

    Parameters
    ----------
    frf_x : FRF
        Receptance Φ_xx in the feed direction x, m/N (mobility/accelerance are converted).
    frf_y : FRF or "rigid" or None
        Receptance Φ_yy; ``None`` for a symmetric tool (Φ_yy = Φ_xx),
        ``"rigid"`` for Φ_yy = 0. Interpolated onto the x grid if it differs.
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r = K_n/K_t, a_e/D and down/up milling.
    rpm : array_like
        Increasing spindle speeds, rpm, on which the limit is returned.
    frf_xy, frf_yx : FRF, optional
        Cross receptances Φ_xy (x response to a y force) and Φ_yx, m/N; default 0.

    Returns
    -------
    LobeResult
        The limit (minimum over lobes k = 0, 1, … and both eigenvalue
        branches, m) and chatter frequency (Hz) on ``rpm``, every lobe's own
        points inside the range (thinned to :data:`MAX_LOBE_POINTS`), and the
        absolute minimum refined between frequency points (parabola through the
        three lowest-depth neighbours).

    Raises
    ------
    InputError
        Bad cutting conditions or speeds, non-finite FRF values, FRF bands that
        do not overlap, an x FRF that is zero everywhere.

    Examples
    --------
    One mode in x (922 Hz, ζ = 0.011, 0.03993 kg), rigid in y, slotting with
    two teeth: the minimum of the limit is 2kζ(1+ζ)/(N K_n/4) = 0.298 mm.

    >>> import numpy as np
    >>> from toolpoint.frf import FRF
    >>> from toolpoint.stability import CuttingConditions, zoa_lobes
    >>> f = np.arange(1.0, 3001.0)                     # Hz
    >>> w, wn, zeta, m = 2 * np.pi * f, 2 * np.pi * 922.0, 0.011, 0.03993
    >>> frf = FRF(f, 1 / (m * (wn**2 - w**2 + 2j * zeta * wn * w)))
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=1.0)
    >>> res = zoa_lobes(frf, "rigid", cut, rpm=np.linspace(5000, 25000, 200))
    >>> round(res.min_depth_m * 1e3, 3)                # mm
    0.298
    """
    cut = check_cutting(cutting)
    grid = check_rpm(rpm)
    frf_x = _as_receptance(frf_x, "frf_x")
    f, phi = _common_grid(frf_x, {"frf_y": frf_y, "frf_xy": frf_xy, "frf_yx": frf_yx})
    _check_not_zero(phi, f)
    phi_st, phi_ex = cut.immersion_angles
    h0 = average_directional_matrix(cut.teeth, cut.tangential_coeff, cut.radial_ratio, phi_st, phi_ex)

    mu = oriented_eigenvalues(h0, phi["xx"], phi["yy"], phi["xy"], phi["yx"])  # (2, nf)
    zero_order = depth_and_phase(mu)
    depth, eps, valid = zero_order.depth_m, zero_order.eps_rad, zero_order.valid
    valid &= f[None, :] > 0
    # Waves per tooth period at lobe k: f_c T = k + ε/2π; speed n = 60 f_c / (N (k + ε/2π)).
    c = 60.0 * f / cut.teeth  # rpm·(waves per tooth period)
    frac = eps / (2 * np.pi)

    # The limit on the grid refined where the FRFs turn fast (module docstring); the lobes' own points and the
    # absolute minimum's parabola stay at the FRF points (where Φ is known, not interpolated).
    fe, mue, valide = f, mu, valid
    names = [k for k in ("xx", "yy", "xy", "yx") if phi[k] is not None]
    stack = np.stack([phi[k] for k in names])
    parts = interval_parts(f, stack).max(axis=0)
    if np.any(parts > 1):
        fs, ys = refine_frf_grid(f, stack, parts)
        fe, dense = fs[0], dict(zip(names, ys))
        mue = oriented_eigenvalues(h0, dense["xx"], dense["yy"], dense.get("xy"), dense.get("yx"))
        valide = _negative(mue) & (fe[None, :] > 0)
    limit, chatter, knum = _envelope(grid, 60.0 / cut.teeth, fe, mue, valide)
    lobes, best = _lobe_points(grid, c, frac, depth, valid, f)
    min_d, min_r, min_f = _absolute_minimum(grid, limit, chatter, best, c, frac, depth, valid, f)
    params = dict(cut.as_dict(), cutting=cut, phi_st=phi_st, phi_ex=phi_ex, h0=h0,
                  freq_band_hz=(float(f[0]), float(f[-1])), cross=phi["xy"] is not None or phi["yx"] is not None)
    return LobeResult(grid, limit, chatter, lobes, "zoa", min_d, min_r, min_f, params, knum)


# ---------------------------------------------------------------- internals
def _k_range(c, frac, rmin, rmax):
    """Lobe numbers k with n = c/(k + frac) inside [rmin, rmax]: k ∈ [ceil(c/rmax − frac), floor(c/rmin − frac)]."""
    klo = np.maximum(np.ceil(c / rmax - frac), 0)
    khi = np.floor(c / rmin - frac)
    return klo, khi


def _blocks(counts, budget):
    """Slices of consecutive items whose counts sum to about ``budget`` at most (one item at least)."""
    cum = np.cumsum(counts)
    start = 0
    while start < counts.size:
        base = cum[start - 1] if start else 0
        stop = max(int(np.searchsorted(cum, base + budget, "right")), start + 1)
        yield slice(start, stop)
        start = stop


def _pairs(klo, khi):
    """Expand index ranges [klo_s, khi_s] into (s, k) pairs without a Python loop."""
    cnt = np.maximum(khi - klo + 1, 0).astype(np.int64)
    total = int(cnt.sum())
    s = np.repeat(np.arange(cnt.size), cnt)
    start = np.cumsum(cnt) - cnt
    k = klo.reshape(-1)[s] + (np.arange(total) - start[s])
    return s, k


def _pieces(mu, valid, f):
    """Pieces of lobe curve between neighbouring FRF points: (branch, i, t_a, t_b).

    μ is linear in t ∈ [0, 1] between points i and i + 1. A piece is where
    Re μ < 0: the whole interval when both ends are valid, else up to the
    crossing t* = Re μ_i / (Re μ_i − Re μ_{i+1}) of zero, where a_lim → ∞.
    """
    v0, v1 = valid[:, :-1], valid[:, 1:]
    usable = np.isfinite(mu[:, :-1]) & np.isfinite(mu[:, 1:]) & (f[None, :-1] > 0)
    b, i = np.nonzero((v0 | v1) & usable)
    m0, m1 = mu[b, i].real, mu[b, i + 1].real
    both = v0[b, i] & v1[b, i]
    with np.errstate(divide="ignore", invalid="ignore"):
        tstar = np.clip(np.where(both, 0.5, m0 / (m0 - m1)), 0.0, 1.0)
    left = v0[b, i] & ~both  # valid at i only: the piece ends at the crossing
    ta = np.where(both | left, 0.0, tstar)
    tb = np.where(both, 1.0, np.where(left, tstar, 1.0))
    keep = tb > ta
    return b[keep], i[keep], ta[keep], tb[keep]


def _at(mu, f, b, i, t):
    """(μ(t), f(t)) on the piece of branch b between points i, i + 1."""
    mt = mu[b, i] + t * (mu[b, i + 1] - mu[b, i])
    ft = f[i] + t * (f[i + 1] - f[i])
    return mt, ft


def _piece_ends(grid, teeth_c, f, mu, valid):
    """The pieces of :func:`_pieces` with, at both ends, c = 60 f/N and ε/2π, and the lobes k that meet the grid.

    Returns (b, i, t_a, t_b, c_a, c_b, ε_a/2π, ε_b/2π, k_lo, k_hi), one entry per piece.
    """
    rmin, rmax = grid[0], grid[-1]
    b, i, ta, tb = _pieces(mu, valid, f)
    mua, fa = _at(mu, f, b, i, ta)
    mub, fb = _at(mu, f, b, i, tb)
    # Ends at a crossing have Re μ = 0 exactly (round-off would put ε on the wrong side).
    mua = np.where(valid[b, i] | (ta == 0), mua, 1j * mua.imag)
    mub = np.where(valid[b, i + 1] | (tb == 1), mub, 1j * mub.imag)
    fra, frb = _phase(mua) / (2 * np.pi), _phase(mub) / (2 * np.pi)
    ca, cb = teeth_c * fa, teeth_c * fb
    klo_a, khi_a = _k_range(ca, fra, rmin, rmax)
    klo_b, khi_b = _k_range(cb, frb, rmin, rmax)
    return b, i, ta, tb, ca, cb, fra, frb, np.minimum(klo_a, klo_b), np.maximum(khi_a, khi_b)


def _envelope(grid, teeth_c, f, mu, valid):
    """Minimum over lobes of the lobe curves, sampled on ``grid``: (limit m, chatter Hz, lobe k).

    ``teeth_c`` is 60/N (rpm per Hz and wave per tooth period). Every piece
    (see :func:`_pieces`) of every lobe k whose speed span meets
    the grid contributes at the grid speeds it spans (a lobe may fold back in
    speed, so each piece is intersected with the grid on its own), streamed
    in blocks of at most ``_BLOCK`` (piece, k) pairs.
    """
    b, i, ta, tb, ca, cb, fra, frb, klo, khi = _piece_ends(grid, teeth_c, f, mu, valid)
    counts = np.maximum(khi - klo + 1, 0)

    limit = np.full(grid.size, np.inf)
    chatter = np.full(grid.size, np.nan)
    knum = np.full(grid.size, -1)
    for sl in _blocks(counts, _BLOCK):
        s, k = _pairs(klo[sl], khi[sl])
        s = s + sl.start
        with np.errstate(divide="ignore"):
            r0 = ca[s] / (k + fra[s])
            r1 = cb[s] / (k + frb[s])
        lo, hi = np.minimum(r0, r1), np.maximum(r0, r1)
        j0 = np.searchsorted(grid, lo, "left")
        j1 = np.searchsorted(grid, hi, "right")
        cnt = np.maximum(j1 - j0, 0)
        if not cnt.any():
            continue
        q = np.repeat(np.arange(cnt.size), cnt)
        start = np.cumsum(cnt) - cnt
        g = j0[q] + (np.arange(q.size) - start[q])
        p, kk, r = s[q], k[q], grid[g]
        t = _solve_speed(mu, f, teeth_c, b[p], i[p], ta[p], tb[p], fra[p], frb[p], kk, r)
        mt, ft = _at(mu, f, b[p], i[p], t)
        with np.errstate(divide="ignore"):
            d = np.where(mt.real < 0, -0.5 / mt.real, np.inf)
        order = np.lexsort((d, g))  # by grid index, then depth
        gs = g[order]
        sel = order[np.r_[True, gs[1:] != gs[:-1]]]
        better = d[sel] < limit[g[sel]]
        sel = sel[better]
        limit[g[sel]] = d[sel]
        chatter[g[sel]] = ft[sel]
        knum[g[sel]] = kk[sel]
    return limit, chatter, knum


def _solve_speed(mu, f, teeth_c, b, i, ta, tb, fra, frb, k, r, iters=40):
    """Parameter t ∈ [t_a, t_b] of each piece where lobe k passes speed r.

    Root of h(t) = c(t) − r (k + ε(t)/2π), c = 60 f/N: start from the exact
    root when ε is linear in t, then Newton steps (dε/dt = 2 Im(μ'/μ)) kept
    inside a bracket that bisection shrinks when a step leaves it.
    """
    dmu = mu[b, i + 1] - mu[b, i]
    df = f[i + 1] - f[i]

    def h(t):
        mt = mu[b, i] + t * dmu
        return teeth_c * (f[i] + t * df) - r * (k + _phase(mt) / (2 * np.pi)), mt

    lo, hi = ta.copy(), tb.copy()
    hlo = h(lo)[0]
    # Initial guess: ε linear between the piece ends (exact root of a linear-ε model).
    ca, cb = teeth_c * (f[i] + ta * df), teeth_c * (f[i] + tb * df)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = r * (frb - fra) - (cb - ca)
        u = np.where(den != 0, (ca - r * (k + fra)) / den, 0.5)
    t = ta + np.clip(np.nan_to_num(u, nan=0.5), 0.0, 1.0) * (tb - ta)
    for _ in range(iters):
        ht, mt = h(t)
        # Keep the bracket [lo, hi] with a sign change.
        same = np.sign(ht) == np.sign(hlo)
        lo, hlo = np.where(same, t, lo), np.where(same, ht, hlo)
        hi = np.where(same, hi, t)
        with np.errstate(divide="ignore", invalid="ignore"):
            deps = 2 * (np.conj(mt) * dmu).imag / np.abs(mt) ** 2
            dh = teeth_c * df - r * deps / (2 * np.pi)
            tn = t - ht / dh
        bad = ~np.isfinite(tn) | (tn <= lo) | (tn >= hi)
        tn = np.where(bad, 0.5 * (lo + hi), tn)
        if np.all(np.abs(tn - t) <= 1e-13):
            t = tn
            break
        t = tn
    return t


def _lobe_points(grid, c, frac, depth, valid, f):
    """Each lobe's own points with speed inside the grid range, grouped by (k, branch).

    Returns the lobes (thinned to at most ``MAX_LOBE_POINTS`` points) and the
    lowest-depth point (b, i, k) of all, found before thinning.
    """
    rmin, rmax = grid[0], grid[-1]
    b, i = np.nonzero(valid)
    klo, khi = _k_range(c[i], frac[b, i], rmin, rmax)
    counts = np.maximum(khi - klo + 1, 0)
    best = None
    has = counts > 0
    if has.any():
        p = int(np.argmin(np.where(has, depth[b, i], np.inf)))
        best = (int(b[p]), int(i[p]), int(klo[p]))
    stride = max(1, int(np.ceil(counts.sum() / MAX_LOBE_POINTS)))
    if stride > 1:
        keep = (i % stride) == 0
        b, i, klo, khi = b[keep], i[keep], klo[keep], khi[keep]
    s, k = _pairs(klo, khi)
    bb, ii = b[s], i[s]
    r = c[ii] / (k + frac[bb, ii])
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
    return lobes, best


def _absolute_minimum(grid, limit, chatter, best_point, c, frac, depth, valid, f):
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
    if best_point is None:
        return best
    b, i, kk = best_point
    r = c[i] / (kk + frac[b, i])
    if depth[b, i] < best[0]:
        best = (float(depth[b, i]), float(r), float(f[i]))
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
                rv = (c[i] / f[i]) * xv / (kk + fr)  # c/f = 60/N
                if 0 < yv <= best[0] and grid[0] <= rv <= grid[-1]:
                    best = (float(yv), float(rv), float(xv))
    return best
