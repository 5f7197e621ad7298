r"""Zero-order stability limits of many FRFs of one symmetric tool at once.

The recommendation samples a few hundred joints per tool; calling
:func:`~toolpoint.stability.zoa.zoa_lobes` per sample (lobes, chatter
frequencies, refined minimum) costs ~0.1 s each. Here only the limit on a
speed grid is computed, for all samples together.

For a symmetric tool (Φ_yy = Φ_xx = Φ, no cross terms) the oriented FRF is
H₀Φ, so its eigenvalues are μ_b(ω) = λ_b Φ(ω) with λ_b (b = 0, 1) the two
eigenvalues of the average directional matrix H₀ (N/m²): no branch tracking
over frequency is needed. As in :mod:`~toolpoint.stability.zoa`,

    1/a_lim = −2 Re μ  (1/m),   ε = π + 2 arg(−μ),
    tooth period T = (k + ε/2π) / f,  n = 60 / (N T)  (rpm),  k = 0, 1, …

Each FRF interval is first split where the sample's Φ turns fast, exactly as in ``zoa_lobes``
(:func:`~toolpoint.stability.zoa.interval_parts`, :func:`~toolpoint.stability.zoa.refine_frf_grid`:
⌈|Φ_{i+1} − Φ_i| / min(|Φ_i|, |Φ_{i+1}|) / 0.05⌉ parts, cubic Hermite Φ at the new points) — per sample,
depending on its FRF only; the samples' refined grids are padded to one length with invalid points. μ is
interpolated linearly between the points of that grid, so 1/a_lim is linear there;
where Re μ changes sign the piece runs to the crossing (1/a_lim = 0, ε = 0 or
2π), so a lobe flank rises to its asymptote instead of being cut. Unlike
``zoa_lobes``, which solves for the exact point of each grid speed on a piece
(Newton), 1/a_lim is interpolated linearly in the tooth period between the
piece's ends; the limit at a speed is 1 / max over (piece, lobe, branch) of
the interpolated 1/a_lim. The difference to ``zoa_lobes`` is measured in
``tests/recommend/test_library.py`` and ``docs/design/recommend.md``.
"""

from __future__ import annotations

import numpy as np

from .cutting import CuttingConditions
from .milling import average_directional_matrix, check_rpm
from .zoa import interval_parts, refine_frf_grid

__all__ = ["zoa_limits", "directional_eigenvalues"]

# (sample, piece, lobe, speed) entries handled per block: bounds memory (~100 B each).
_BLOCK_ENTRIES = 2_000_000


def zoa_limits(freq_hz, receptance, cutting: CuttingConditions, rpm, *, cap_m: float = np.inf,
               subdivide: int = 4, directional=None) -> np.ndarray:
    """Zero-order stability limits (axial depth, m) of a symmetric tool for many receptances.

    Parameters
    ----------
    freq_hz : array_like, shape (F,)
        Increasing frequencies, Hz (> 0).
    receptance : array_like, shape (N, F) or (F,)
        Tool-point receptances Φ_xx = Φ_yy, m/N (cross terms 0).
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r, immersion, milling.
    rpm : array_like, shape (G,)
        Increasing spindle speeds, rpm.
    cap_m : float, default inf
        Depths above this (m) are not resolved: pieces of lobe entirely above
        it are skipped and the result is clipped to it (faster; the limit is
        then "≥ cap_m" where it equals cap_m).
    subdivide : int, default 4
        Each piece between FRF points is split in this many parts, each
        interpolated linearly in the tooth period (error ∝ 1/subdivide²).
    directional : array_like, shape (N, 2), optional
        Per receptance, the two eigenvalues of the average directional matrix (N/m², with K_t;
        :func:`directional_eigenvalues`) — each sample its own cutting coefficients; default: those of
        ``cutting`` for all.

    Returns
    -------
    ndarray, shape (N, G) or (G,)
        Stability limit, m: the minimum over lobes and both eigenvalue
        branches; inf (or ``cap_m``) where no lobe reaches the speed.

    Examples
    --------
    One mode in x and y (922 Hz, ζ = 0.011, 0.03993 kg), slotting, two teeth:
    the minimum of the limit is 2kζ(1+ζ)/(N K_t (1 + K_r²)^½ ... ) — here
    compared with :func:`~toolpoint.stability.zoa_lobes` itself:

    >>> import numpy as np
    >>> from toolpoint.frf import FRF
    >>> from toolpoint.stability import CuttingConditions, zoa_lobes
    >>> f = np.arange(1.0, 3001.0)
    >>> w, wn, zeta, m = 2 * np.pi * f, 2 * np.pi * 922.0, 0.011, 0.03993
    >>> h = 1 / (m * (wn**2 - w**2 + 2j * zeta * wn * w))
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=1.0)
    >>> rpm = np.linspace(5000, 25000, 300)
    >>> fast = zoa_limits(f, h, cut, rpm)
    >>> ref = zoa_lobes(FRF(f, h), None, cut, rpm=rpm).depth_m
    >>> bool(np.max(np.abs(fast / ref - 1)) < 1e-3)
    True
    """
    f = np.asarray(freq_hz, float)
    H = np.asarray(receptance)
    single = H.ndim == 1
    H = np.atleast_2d(H)
    grid = check_rpm(rpm)
    if directional is None:
        lam = np.broadcast_to(directional_eigenvalues(cutting), (H.shape[0], 2))
    else:
        lam = np.asarray(directional, complex)
        if lam.shape != (H.shape[0], 2):
            raise ValueError(f"directional must have shape ({H.shape[0]}, 2), got {lam.shape}")
    period = 1.0 / grid[::-1]  # ascending, 1/rpm
    G = grid.size
    qmax = np.zeros((H.shape[0], G))  # 1/a_lim, 1/m; 0 = no lobe
    q_cap = 0.0 if not np.isfinite(cap_m) else 1.0 / cap_m
    rmin, rmax = grid[0], grid[-1]
    step = (rmax - rmin) / (G - 1) if G > 1 else 0.0
    step = step if G > 2 and np.allclose(np.diff(grid), step, rtol=1e-9, atol=0) else None
    chunk = max(1, int(_BLOCK_ENTRIES // max(1, 4 * G)))
    for s0 in range(0, H.shape[0], chunk):
        fs, Hs = _refined(f, H[s0:s0 + chunk])  # (n, F') each: the samples' own refined grids, padded
        mu = lam[s0:s0 + chunk, :, None] * Hs[:, None, :]  # (n, 2, F')
        _accumulate(qmax[s0:s0 + chunk], mu, fs, 60.0 / cutting.teeth, period, rmin, rmax, q_cap, subdivide, step)
    with np.errstate(divide="ignore"):
        limit = np.where(qmax > 0, 1.0 / np.where(qmax > 0, qmax, 1.0), np.inf)[:, ::-1]
    limit = np.minimum(limit, cap_m)
    return limit[0] if single else limit


def directional_eigenvalues(cutting: CuttingConditions, kt_factor=None, radial_ratio=None) -> np.ndarray:
    """The two eigenvalues of the average directional matrix (N/m²), for one cut or per sample.

    Parameters
    ----------
    cutting : CuttingConditions
        Teeth, K_t, K_r, immersion, milling.
    kt_factor, radial_ratio : array_like, shape (N,), optional
        Per sample: K_t as a multiple of ``cutting``'s, and K_r (default ``cutting``'s).

    Returns
    -------
    ndarray, shape (2,) or (N, 2)
        Complex eigenvalues λ of A₀ = N K_t/(2π) [α]; the zero-order eigenvalues are λ Φ(ω).

    Examples
    --------
    >>> from toolpoint.stability import CuttingConditions
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=1.0)
    >>> lam = directional_eigenvalues(cut, [1.0, 2.0], [0.3, 0.3])
    >>> bool(np.allclose(lam[1], 2 * lam[0])) and bool(np.allclose(lam[0], directional_eigenvalues(cut)))
    True
    """
    phi_st, phi_ex = cutting.immersion_angles
    n = None if kt_factor is None and radial_ratio is None else np.size(
        kt_factor if kt_factor is not None else radial_ratio)
    ktf = np.ones(1 if n is None else n) if kt_factor is None else np.asarray(kt_factor, float).reshape(-1)
    kr = (np.full(ktf.size, cutting.radial_ratio) if radial_ratio is None else
          np.asarray(radial_ratio, float).reshape(-1))
    # H₀ is linear in K_r (and ∝ K_t): H₀(K_r) = A + K_r B, so every sample's 2×2 at once, no loop over samples
    a = average_directional_matrix(cutting.teeth, cutting.tangential_coeff, 0.0, phi_st, phi_ex)
    b = average_directional_matrix(cutting.teeth, cutting.tangential_coeff, 1.0, phi_st, phi_ex) - a
    h0 = ktf[:, None, None] * (a[None] + kr[:, None, None] * b[None])
    tr = h0[:, 0, 0] + h0[:, 1, 1]
    det = h0[:, 0, 0] * h0[:, 1, 1] - h0[:, 0, 1] * h0[:, 1, 0]
    root = np.sqrt((tr * tr / 4 - det).astype(complex))
    out = np.stack([tr / 2 + root, tr / 2 - root], axis=-1)
    return out[0] if n is None else out


def _refined(f, H):
    """(frequencies, receptances), each (n, F'): every row on its own refined grid (as ``zoa_lobes`` refines it),
    padded at the end with its last frequency and NaN (invalid: no piece there)."""
    parts = interval_parts(f, H)  # (n, F − 1)
    if not np.any(parts > 1):
        return np.broadcast_to(f, H.shape), H
    return refine_frf_grid(f, H, parts)


def _accumulate(qmax, mu, f, teeth_c, period, rmin, rmax, q_cap, subdivide, step):
    """qmax[s, g] = max(qmax, 1/a_lim of every lobe piece of sample s at reversed-grid speed g).

    Two passes: (piece, lobe) pairs whose period range (a conservative bound over the piece's
    ``subdivide + 1`` points) holds no grid speed are dropped first — most of them on a grid of a
    few hundred speeds — and only the rest are split into their ``subdivide`` parts.
    """
    scale = np.abs(mu).max(axis=1, keepdims=True)
    valid = np.isfinite(mu) & (mu.real < -1e-9 * scale) & (f[:, None, :] > 0)
    v0, v1 = valid[..., :-1], valid[..., 1:]
    q = np.where(valid, -2.0 * mu.real, 0.0)
    keep = (v0 | v1) & (np.maximum(q[..., :-1], q[..., 1:]) > q_cap)
    s, b, i = np.nonzero(keep)
    if s.size == 0:
        return
    m0, m1 = mu[s, b, i], mu[s, b, i + 1]
    both = v0[s, b, i] & v1[s, b, i]
    left = v0[s, b, i] & ~both
    with np.errstate(divide="ignore", invalid="ignore"):
        tstar = np.clip(np.where(both, 0.5, m0.real / (m0.real - m1.real)), 0.0, 1.0)
    ta = np.where(both | left, 0.0, tstar)
    tb = np.where(both, 1.0, np.where(left, tstar, 1.0))
    ok = tb > ta
    s, i, m0, m1, ta, tb = s[ok], i[ok], m0[ok], m1[ok], ta[ok], tb[ok]
    # the piece's subdivide + 1 points (each piece in `subdivide` parts: the speed n(t) is not linear in t
    # where ε turns fast, at sharp peaks)
    t = ta[:, None] + (tb - ta)[:, None] * (np.arange(subdivide + 1) / subdivide)[None, :]  # (P, S+1)
    mt = m0[:, None] + t * (m1 - m0)[:, None]
    mt[:, 0] = np.where(ta > 0, 1j * mt[:, 0].imag, mt[:, 0])  # exactly Re μ = 0 at a crossing
    mt[:, -1] = np.where(tb < 1, 1j * mt[:, -1].imag, mt[:, -1])
    fa, fb = f[s, i], f[s, i + 1]
    c = teeth_c * (fa[:, None] + t * (fb - fa)[:, None])  # 60 f / N, increasing along the piece
    frac = (np.pi + 2 * np.arctan2(-mt.imag, -mt.real)) / (2 * np.pi)  # in [0, 1]
    qt = np.maximum(-2.0 * mt.real, 0.0)
    # pass 1: lobe k of the whole piece has its tooth period (1/rpm) within [(k + fr_lo)/c_hi, (k + fr_hi)/c_lo]
    fr_lo, fr_hi, c_lo, c_hi = frac.min(axis=1), frac.max(axis=1), c[:, 0], c[:, -1]
    klo = np.maximum(np.ceil(c_lo / rmax - fr_hi), 0)
    khi = np.floor(c_hi / rmin - fr_lo)
    cnt = np.maximum(khi - klo + 1, 0).astype(np.int64)
    p = np.repeat(np.arange(cnt.size), cnt)
    k = klo[p] + (np.arange(p.size) - np.repeat(np.cumsum(cnt) - cnt, cnt))
    if step is None:
        hit = (np.searchsorted(period, (k + fr_hi[p]) / c_lo[p], "right")
               > np.searchsorted(period, (k + fr_lo[p]) / c_hi[p], "left"))
    else:  # evenly spaced speeds: grid index m = (rpm − rmin)/step, widened by 1e-6 step (pass 2 is exact)
        with np.errstate(divide="ignore"):
            m_hi = np.minimum((c_hi[p] / (k + fr_lo[p]) - rmin) / step + 1e-6, period.size - 1)
        m_lo = np.maximum((c_lo[p] / (k + fr_hi[p]) - rmin) / step - 1e-6, 0.0)
        hit = np.floor(m_hi) >= np.ceil(m_lo)
    p, k = p[hit], k[hit]
    # pass 2: the parts j of the pieces and lobes that hold a grid speed
    j = np.tile(np.arange(subdivide), p.size)
    p, k = np.repeat(p, subdivide), np.repeat(k, subdivide)
    pa = (k + frac[p, j]) / c[p, j]  # 1/n = (k + frac)/c, 1/rpm
    pb = (k + frac[p, j + 1]) / c[p, j + 1]
    lo = np.searchsorted(period, np.minimum(pa, pb), "left")
    hi = np.searchsorted(period, np.maximum(pa, pb), "right")
    n_g = np.maximum(hi - lo, 0)
    e = np.repeat(np.arange(p.size), n_g)
    g = lo[e] + (np.arange(e.size) - np.repeat(np.cumsum(n_g) - n_g, n_g))
    if e.size == 0:
        return
    pe, je = p[e], j[e]
    qa_e, qb_e, pa_e, pb_e = qt[pe, je], qt[pe, je + 1], pa[e], pb[e]
    span = pb_e - pa_e
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(span != 0, (period[g] - pa_e) / span, 0.0)
    qg = np.where(span != 0, qa_e + np.clip(w, 0, 1) * (qb_e - qa_e), np.maximum(qa_e, qb_e))
    G = period.size
    flat = qmax.reshape(-1)
    np.maximum.at(flat, s[pe] * G + g, qg)
    qmax[...] = flat.reshape(qmax.shape)
