"""The spindle–holder subassembly from measurements: inverse RCSA with a blank.

Only translational FRFs can be measured. After Park et al. (2003), a blank
(a plain cylinder of known geometry) is clamped in the holder and three
translational receptances of the assembly are measured at two points on it:

* point 1 — the blank tip,
* point 2 — a second point at distance ``x2_m`` from the tip (0 < x2 < L),
* point 3 — the blank root at the holder tip, where the blank leaves the holder
  (not measured).

G11 = y1/F1 (direct at the tip), G12 = y1/F2 = G21 (cross) and G22 = y2/F2
(direct at point 2), all m/N. The blank model is the part *outside* the
holder, a free–free Timoshenko beam with 2×2 receptance blocks R_ab(ω)
(a, b ∈ {1, 2, 3}, on [w, ψ] and [F, M]: h m/N, l 1/N, n rad/N, p rad/(N m));
the part inside the holder belongs to the subassembly, as do the spindle–holder
and the holder–blank joints: what is identified is Park's
"spindle–holder–blank-base" receptance SH = [[h, l], [n, p]] at the holder tip.
It serves tools with the blank's shank diameter and clamping.

Joining the blank rigidly to SH at 3 (Eq. 3 with K⁻¹ = 0) gives

    G_ab = R_ab − R_a3 X R_3b,     X = (R_33 + SH)⁻¹  (symmetric 2×2).

Each measured (translational, [0, 0]) entry is *linear* in the three unknowns
x = (X00, X01 = X10, X11): with r_a = row 0 of R_a3 and s_b = column 0 of R_3b,

    R_ab,00 − G_ab = r_a0 s_b0 X00 + (r_a0 s_b1 + r_a1 s_b0) X01 + r_a1 s_b1 X11,

so (1,1), (1,2), (2,2) give a 3×3 system M x = d per frequency, solved in one
batched LAPACK call, and then SH = X⁻¹ − R_33 (l = n by construction).

**Accuracy of the blank model.** At low frequency R_33 is dominated by the
rigid-body terms ~1/(mω²) and is far larger than SH, so SH = X⁻¹ − R_33 needs R
to a relative accuracy far better than the one asked of SH. The blank
receptances therefore come from the exact transfer chain cut at point 2
(:func:`blank_receptances`), which keeps every entry to round-off, wherever its
growth Σ βL ≤ ``CHAIN_LIMIT``, and from the dense exact stiffness matrix above
that (high frequency, where it is well conditioned).

**Noise.** The problem is ill conditioned: SH is a small part of the
measured response, and h, l, p are extrapolated from the two measuring points
to the holder tip. To first order dSH = J dG with (:func:`sensitivity`)

    J = S(P) M⁻¹,   P = R_33 + SH,   S(P) x = P X P in (00, 01, 11) coordinates,

and complex Gaussian measurement noise of standard deviation σ_k on G_k gives
standard deviations √(Σ_k |J_ek|² σ_k²) on h, l, p (:func:`noise_std`).
Measure the second point as close to the holder as possible.
:func:`smooth_subassembly` (Savitzky–Golay) and ``smooth="modal"`` (a common-pole
fit, :mod:`toolpoint.dynamics.modal`) reduce the noise. The measured error
amplification and the comparison of the smoothers are in
``docs/design/dynamics.md`` (``benchmarks/bench_inverse_rcsa.py`` prints them).

The subassembly can also come straight from a model
(:func:`subassembly_from_assembly`) or from four measured FRF files
(:func:`subassembly_from_files`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.signal import savgol_filter

from .assembly import Assembly, Component
from .beam import inv2, transfer_matrix
from .components import CHAIN_LIMIT, assemble, chain_growth, mesh, receptance
from ..errors import InputError
from ..frf import FRF, check_freq_hz
from ..io.frf_files import read_frf
from .modal import fit_modal
from .subassembly import Subassembly

__all__ = [
    "blank_receptances", "blank_frfs", "subassembly_from_blank", "subassembly_from_files", "subassembly_from_assembly",
    "smooth_subassembly", "modal_smooth_subassembly",
    "subassembly_replicates", "sensitivity", "noise_std", "Conditioning", "conditioning",
]

TIP, POINT2, ROOT = 0, 1, 2  # indices of points 1, 2, 3 in blank_receptances
_TOL = 1e-9  # m: a cut within this distance of a segment end is that end


# --------------------------------------------------------------------------- blank model
def _check_blank(blank: Component, x2_m: float) -> float:
    if blank.bearings:
        raise InputError("the blank is a free–free beam: it must have no bearings", field="blank")
    x2 = float(x2_m)
    L = blank.length
    if not (np.isfinite(x2) and _TOL < x2 < L - _TOL):
        raise InputError(
            f"the second point must lie on the blank, strictly between its tip (0) and the holder "
            f"tip ({L * 1e3:g} mm from the tip); got {x2 * 1e3:g} mm", field="x2_m")
    return x2


def _split(blank: Component, x_cut: float) -> Component:
    """The blank with a segment boundary at x_cut (m from its root), so the mesh has a node there."""
    segs, x = [], 0.0
    for s in blank.segments:
        if x + _TOL < x_cut < x + s.length - _TOL:
            segs += [replace(s, length=x_cut - x), replace(s, length=x + s.length - x_cut)]
        else:
            segs.append(s)
        x += s.length
    return replace(blank, segments=tuple(segs))


def blank_receptances(blank: Component, x2_m: float, freq_hz) -> np.ndarray:
    """Free–free receptances R (F, 3, 3, 2, 2) of the blank between its points 1, 2, 3.

    ``blank`` runs along the global x axis from its root at the holder tip (point 3,
    x = 0) to its tip (point 1, x = L); point 2 is ``x2_m`` (m) from the tip. Index
    0, 1, 2 = point 1, 2, 3 (``TIP``, ``POINT2``, ``ROOT``): ``R[:, a, b]`` is the
    2×2 block [[w/F, w/M], [ψ/F, ψ/M]] of the response at a to a load at b
    (m/N, 1/N, rad/N, rad/(N m)); R[:, a, b] = R[:, b, a]ᵀ.

    Transfer chain (state [w, ψ, Q, M], loads (F, M) at the points): with T_A over
    3 → 2, T_B over 2 → 1 and T = T_B T_A (2×2 blocks T11 … T22), the load jump
    Q(2⁺) = Q(2⁻) − P2 and free ends give

        R_3j = T21⁻¹ [T22, T_B,22, I]_j        (j = 3, 2, 1)
        R_2j = T_A,11 R_3j − T_A,12 δ_j3
        R_1j = T11 R_3j − T12 δ_j3 − T_B,12 δ_j2.
    """
    x2 = _check_blank(blank, x2_m)
    f = check_freq_hz(freq_hz, positive=True)  # the free–free blank is singular at 0 Hz
    cut = blank.length - x2
    m = mesh(_split(blank, cut), f.max())
    k2 = int(np.argmin(abs(m.x - cut)))
    w = 2 * np.pi * f
    R = np.empty((f.size, 3, 3, 2, 2), complex)
    low = chain_growth(m, w) <= CHAIN_LIMIT
    if np.any(low):
        R[low] = _chain3(m, k2, w[low])
    if not np.all(low):
        D, _ = assemble([m], [], w[~low])
        last = m.n_nodes - 1
        X = receptance(D, [2 * last, 2 * last + 1, 2 * k2, 2 * k2 + 1, 0, 1])
        R[~low] = X.reshape(-1, 3, 2, 3, 2).transpose(0, 1, 3, 2, 4)
    return R


def _chain3(m, k2: int, w: np.ndarray) -> np.ndarray:
    eye = np.broadcast_to(np.eye(4, dtype=complex), (w.size, 4, 4))
    TA, TB = eye.copy(), eye.copy()
    cache: dict = {}
    for sec, length, node in m.pieces:
        key = (id(sec), round(length, 15))
        if key not in cache:
            cache[key] = transfer_matrix(sec, length, w)
        if node < k2:
            TA = cache[key] @ TA
        else:
            TB = cache[key] @ TB
    T = TB @ TA
    T11, T12, T21, T22 = T[:, :2, :2], T[:, :2, 2:], T[:, 2:, :2], T[:, 2:, 2:]
    A11, A12 = TA[:, :2, :2], TA[:, :2, 2:]
    B12, B22 = TB[:, :2, 2:], TB[:, 2:, 2:]
    T21i = inv2(T21)
    R = np.empty((w.size, 3, 3, 2, 2), complex)
    R[:, ROOT, ROOT] = T21i @ T22
    R[:, ROOT, POINT2] = T21i @ B22
    R[:, ROOT, TIP] = T21i
    R[:, POINT2, ROOT] = A11 @ R[:, ROOT, ROOT] - A12
    R[:, POINT2, POINT2] = A11 @ R[:, ROOT, POINT2]
    R[:, POINT2, TIP] = A11 @ T21i
    R[:, TIP, ROOT] = T11 @ R[:, ROOT, ROOT] - T12
    R[:, TIP, POINT2] = T11 @ R[:, ROOT, POINT2] - B12
    R[:, TIP, TIP] = T11 @ T21i
    return R


# --------------------------------------------------------------------------- forward and inverse
_PAIRS = ((TIP, TIP), (TIP, POINT2), (POINT2, POINT2))  # G11, G12, G22


def _system(R: np.ndarray) -> np.ndarray:
    """M (F, 3, 3): rows (1,1), (1,2), (2,2); columns X00, X01, X11."""
    rows = []
    for a, b in _PAIRS:
        r = R[:, a, ROOT, 0, :]  # row 0 of R_a3
        s = R[:, ROOT, b, :, 0]  # column 0 of R_3b
        rows.append(np.stack([r[:, 0] * s[:, 0], r[:, 0] * s[:, 1] + r[:, 1] * s[:, 0], r[:, 1] * s[:, 1]], -1))
    return np.stack(rows, 1)


def _coupled(R: np.ndarray, SH: np.ndarray) -> np.ndarray:
    """G11, G12, G22 (F, 3) of the blank rigidly joined to SH at its root."""
    X = inv2(R[:, ROOT, ROOT] + SH)
    return np.stack([R[:, a, b, 0, 0] - (R[:, a, ROOT, 0:1, :] @ X @ R[:, ROOT, b, :, 0:1])[:, 0, 0]
                     for a, b in _PAIRS], -1)


def blank_frfs(blank: Component, x2_m: float, sub: Subassembly) -> tuple[FRF, FRF, FRF]:
    """Forward model: G11, G12, G22 (m/N) of the blank rigidly joined to ``sub`` at the holder tip.

    G_ab = R_ab − R_a3 (R_33 + SH)⁻¹ R_3b on ``sub.freq_hz`` — synthetic
    measurements, and the prediction to compare real measurements with.
    """
    R = blank_receptances(blank, x2_m, sub.freq_hz)
    G = _coupled(R, sub.R)
    return tuple(FRF(sub.freq_hz, G[:, k], "receptance", lab) for k, lab in enumerate(("G11", "G12", "G22")))


def _common_grid(frfs: dict[str, FRF], ref: str) -> np.ndarray:
    f = frfs[ref].freq_hz
    for name, g in frfs.items():
        if not isinstance(g, FRF):
            raise InputError(f"expected an FRF, got {type(g).__name__}", field=name)
        if not np.array_equal(g.freq_hz, f):
            lab = f" ({g.label})" if g.label else ""
            raise InputError(
                f"frequency grid{lab} ({g.freq_hz.size} points, {g.freq_hz[0]:g}–{g.freq_hz[-1]:g} Hz) differs "
                f"from {ref}'s ({f.size} points, {f[0]:g}–{f[-1]:g} Hz); bring all onto one grid first, "
                f"e.g. {name}.at({ref}.freq_hz) inside its band", field=name)
    return f


def subassembly_from_blank(blank: Component, x2_m: float, G11: FRF, G12: FRF, G22: FRF, *,
                           G21: FRF | None = None, smooth: float | None = None,
                           polyorder: int = 3, band=None) -> Subassembly:
    """Inverse RCSA: the holder-tip receptance SH = [[h, l], [n, p]] from three measured FRFs.

    Parameters
    ----------
    blank : Component — the blank outside the holder, root (holder tip) → tip, no bearings.
    x2_m : distance (m) of the second measuring point from the blank tip, 0 < x2 < L.
    G11, G12, G22 : FRF — tip direct, tip–point-2 cross and point-2 direct; any quantity
        (converted to receptance, m/N); all on one grid of frequencies > 0.
    G21 : optional second cross FRF (y2/F1); if given, G12 is replaced by the mean
        (G12 + G21)/2 (reciprocity), which halves that FRF's noise variance.
    smooth : None; ``"modal"`` — the three FRFs are first replaced by a common-pole
        modal fit (:func:`toolpoint.dynamics.modal.fit_modal`, weighted in the quantity
        G11 was measured in: ``meta["file_quantity"]``, else its ``quantity``), which removes
        the noise and keeps the peaks (recommended); or a Savitzky–Golay window in Hz
        applied to the result (:func:`smooth_subassembly`, ``polyorder``).
    band : None, (lo, hi) in Hz, or ``"auto"`` — use the measured FRFs in this band only
        (None: all of it); ``"auto"``: the intersection of their trusted bands
        (:func:`toolpoint.trust.trusted_band`: low-frequency noise ×1/ω², low
        coherence), named in the label when it cuts anything. A band with fewer
        than two points of the data is an InputError (field ``band``).

    Returns a :class:`Subassembly` on the FRFs' grid (inside ``band``): h m/N, l 1/N, n rad/N,
    p rad/(N m), with l = n. See the module docstring for the equations.
    Raises :class:`InputError` naming the FRF whose grid differs, or for a
    point outside the blank.
    """
    _check_blank(blank, x2_m)
    given = {"G11": G11, "G12": G12, "G22": G22}
    if G21 is not None:
        given["G21"] = G21
    _common_grid(given, "G11")
    given, cut = _blank_band(given, band)
    f = check_freq_hz(given["G11"].freq_hz, field="G11", positive=True)  # free–free blank: no 0 Hz
    g = {k: v.to_receptance().values for k, v in given.items()}
    g12 = 0.5 * (g["G12"] + g["G21"]) if G21 is not None else g["G12"]
    Gm = np.stack([g["G11"], g12, g["G22"]], -1)
    label = ""
    if _is_modal(smooth):
        fit = _modal_fit(f, Gm, G11.meta.get("file_quantity", G11.quantity))
        Gm = fit(f)
        label = f", modal fit ({fit.n_modes} modes)"
    R = blank_receptances(blank, x2_m, f)
    d = np.stack([R[:, a, b, 0, 0] for a, b in _PAIRS], -1) - Gm
    x = np.linalg.solve(_system(R), d[..., None])[..., 0]
    X = np.stack([x[:, :2], x[:, 1:]], 1)  # [[X00, X01], [X01, X11]]
    SH = inv2(X) - R[:, ROOT, ROOT]
    SH[:, 1, 0] = SH[:, 0, 1] = 0.5 * (SH[:, 0, 1] + SH[:, 1, 0])  # equal up to round-off
    sub = Subassembly(f, SH, f"spindle–holder (inverse RCSA, blank {blank.length * 1e3:g} mm, "
                             f"x2 {float(x2_m) * 1e3:g} mm{label}{cut})")
    return sub if smooth is None or _is_modal(smooth) else smooth_subassembly(sub, float(smooth), polyorder)


def subassembly_replicates(blank: Component, x2_m: float, G11: FRF, G12: FRF, G22: FRF, *, n: int,
                           rng: np.random.Generator, band=None) -> list[Subassembly]:
    """Wild-bootstrap replicates of the modal-smoothed inverse RCSA: the subassembly's own uncertainty.

    The three blank FRFs are fitted by common poles (as ``smooth="modal"``); each replicate adds the fit's
    residual back with a random phase per frequency, r_k(f) e^{iθ}, θ ~ U(0, 2π) — the measured noise with
    its size at every frequency (noise white in accelerance is large in receptance at low frequency), and
    any misfit, which makes it conservative — and repeats the fit and the inverse coupling. The spread of
    the replicates is the spread of the estimate under that noise (Wu 1986; Davison & Hinkley 1997,
    ch. 6).

    Parameters
    ----------
    blank, x2_m, G11, G12, G22, band :
        As :func:`subassembly_from_blank`.
    n : int
        Replicates.
    rng : numpy.random.Generator
        Source of the phases.

    Returns
    -------
    list of Subassembly
        On the same grid as ``subassembly_from_blank(..., smooth="modal", band=band)``.
    """
    _check_blank(blank, x2_m)
    given, _ = _blank_band({"G11": G11, "G12": G12, "G22": G22}, band)
    f = check_freq_hz(given["G11"].freq_hz, field="G11", positive=True)
    Gm = np.stack([given[k].to_receptance().values for k in ("G11", "G12", "G22")], -1)
    noise = G11.meta.get("file_quantity", G11.quantity)
    fitted = _modal_fit(f, Gm, noise)(f)
    resid = Gm - fitted
    out = []
    for _ in range(n):
        Gb = fitted + resid * np.exp(2j * np.pi * rng.random(resid.shape))
        b = {k: FRF(f, Gb[:, i], "receptance", meta={"file_quantity": noise})
             for i, k in enumerate(("G11", "G12", "G22"))}
        out.append(subassembly_from_blank(blank, x2_m, b["G11"], b["G12"], b["G22"], smooth="modal"))
    return out


def _blank_band(given: dict, band) -> tuple[dict, str]:
    """The measured FRFs cut to ``band`` (None, (lo, hi) Hz or "auto"), and a label part naming the cut."""
    from ..trust import trusted_band

    if band is None:
        return given, ""
    if isinstance(band, str):
        if band != "auto":
            raise InputError(f'band must be (lo, hi) in Hz or "auto", got {band!r}', field="band")
        tbs = {k: trusted_band(v, file=v.meta.get("source")) for k, v in given.items()}
        lo, hi = max(t.lo_hz for t in tbs.values()), min(t.hi_hz for t in tbs.values())
        why = "; ".join(f"{k}: {t.reason}" for k, t in tbs.items() if t.reason)
        if lo >= hi:
            raise InputError(f"the trusted bands of the measured FRFs do not overlap ({why})", field="band")
    else:
        tb = trusted_band(given["G11"], band=band, field="band")
        lo, hi, why = tb.lo_hz, tb.hi_hz, "given"
    f = given["G11"].freq_hz
    if (lo, hi) == (f[0], f[-1]):
        return given, ""
    return {k: v.band(lo, hi) for k, v in given.items()}, f", band {lo:g}–{hi:g} Hz: {why}"


def _modal_fit(f, Y, noise: str = "receptance"):
    """Common-pole fit of the receptance columns of ``Y`` (noise white in ``noise``)."""
    try:
        return fit_modal(f, Y, quantity="receptance", noise=noise)
    except InputError as e:  # too few points, an all-zero FRF: say it is the modal fit that failed
        raise InputError(f"modal fit impossible: {e.message}", field="smooth") from None


def _is_modal(smooth) -> bool:
    if isinstance(smooth, str):
        if smooth != "modal":
            raise InputError(f"smooth must be \"modal\" or a window in Hz, got {smooth!r}", field="smooth")
        return True
    return False


# --------------------------------------------------------------------------- other sources
def subassembly_from_assembly(assembly: Assembly, freq_hz) -> Subassembly:
    """The model's subassembly: spindle + holder + spindle–holder joint (Eq. 1).

    The same as :meth:`Subassembly.from_assembly` (frequencies > 0 Hz).
    """
    return Subassembly.from_assembly(assembly, freq_hz)


def subassembly_from_files(h_path, l_path, n_path, p_path, *, smooth: float | str | None = None,
                           polyorder: int = 3) -> Subassembly:
    """The subassembly from four FRF files (any format :func:`~toolpoint.io.frf_files.read_frf` reads).

    Each file holds one entry of SH = [[h, l], [n, p]] at the holder tip, written
    as a "receptance" FRF whose numbers are in that entry's own unit: h = y/F m/N,
    l = y/M m/(N m) = 1/N, n = θ/F rad/N, p = θ/M rad/(N m) — the file's
    nominal m/N label is not checked against them (a mobility or accelerance file
    is converted by iω or −ω² as usual). All four must be on the same grid of
    frequencies > 0; otherwise :class:`InputError` names the file. l and n are
    kept as given (reciprocity l = n is not enforced). ``smooth``: None, ``"modal"``
    (:func:`modal_smooth_subassembly`) or a Savitzky–Golay window in Hz.
    """
    paths = {"h": h_path, "l": l_path, "n": n_path, "p": p_path}
    frfs = {k: read_frf(v) for k, v in paths.items()}
    f = frfs["h"].freq_hz
    for k, g in frfs.items():
        if not np.array_equal(g.freq_hz, f):
            raise InputError(f"frequency grid ({g.freq_hz.size} points, {g.freq_hz[0]:g}–{g.freq_hz[-1]:g} Hz) "
                             f"differs from that of h ({paths['h']}: {f.size} points, {f[0]:g}–{f[-1]:g} Hz)",
                             file=paths[k], field="freq_hz")
        check_freq_hz(g.freq_hz, file=paths[k], positive=True)  # the subassembly has no 0 Hz point
    R = np.stack([np.stack([frfs["h"].values, frfs["l"].values], -1),
                  np.stack([frfs["n"].values, frfs["p"].values], -1)], 1)
    sub = Subassembly(f, R, f"spindle–holder (files {Path(str(h_path)).name}, …)")
    if smooth is None:
        return sub
    return modal_smooth_subassembly(sub) if _is_modal(smooth) else smooth_subassembly(sub, float(smooth), polyorder)


# --------------------------------------------------------------------------- smoothing
def modal_smooth_subassembly(sub: Subassembly) -> Subassembly:
    """h, l, n, p replaced by one common-pole modal fit (:mod:`toolpoint.dynamics.modal`).

    For a subassembly that is already noisy (e.g. four measured files). With a
    blank, ``subassembly_from_blank(..., smooth="modal")`` fits the measured
    FRFs instead, before the noise is amplified, which is better.
    """
    Y = sub.R.reshape(-1, 4)
    fit = _modal_fit(sub.freq_hz, Y)
    return Subassembly(sub.freq_hz, fit(sub.freq_hz).reshape(-1, 2, 2),
                       f"{sub.label}, modal fit ({fit.n_modes} modes)")


def smooth_subassembly(sub: Subassembly, window_hz: float, polyorder: int = 3, entries: str = "hlnp") -> Subassembly:
    """Savitzky–Golay smoothing of the ``entries`` (real and imaginary parts) over frequency.

    The window is ``window_hz`` wide (rounded to an odd number of points ≥
    polyorder + 2) on a uniform grid. It averages out measurement noise
    (white noise falls by ≈ √(window points / 2.25) for a cubic) but flattens
    any mode whose half-power bandwidth is comparable to the window: keep the
    window below the bandwidth of the sharpest mode that matters, or smooth
    only the noisier rotational entries (``entries="lnp"``).
    """
    f = sub.freq_hz
    if f.size < 2:
        raise ValueError("smoothing needs at least two frequencies")
    step = np.diff(f)
    if np.ptp(step) > 1e-6 * step.mean():
        raise ValueError("Savitzky–Golay smoothing needs a uniform frequency grid")
    n = int(round(float(window_hz) / step.mean()))
    n = max(n + (1 - n % 2), polyorder + 2 + (polyorder % 2))  # odd, > polyorder
    if n > f.size:
        raise ValueError(f"smoothing window {window_hz:g} Hz ({n} points) is longer than the data ({f.size} points)")
    bad = set(entries) - set("hlnp")
    if bad or not entries:
        raise ValueError(f"entries must be letters of 'hlnp', got {entries!r}")
    R = sub.R.copy()
    for name in set(entries):
        i, j = divmod("hlnp".index(name), 2)
        R[:, i, j] = (savgol_filter(sub.R[:, i, j].real, n, polyorder)
                      + 1j * savgol_filter(sub.R[:, i, j].imag, n, polyorder))
    return Subassembly(f, R, f"{sub.label}, smoothed {window_hz:g} Hz ({entries})")


# --------------------------------------------------------------------------- conditioning
def sensitivity(blank: Component, x2_m: float, sub: Subassembly) -> np.ndarray:
    """J (F, 3, 3): d[h, l, p] = J d[G11, G12, G22], the inverse linearised at ``sub``.

    dx = −M⁻¹ dG and dSH = −P dX P with P = R_33 + SH give J = S(P) M⁻¹, where
    S(P) = [[P00², 2P00P01, P01²], [P00P01, P00P11 + P01², P01P11], [P01², 2P01P11, P11²]].
    Units: rows h, l, p in m/N, 1/N, rad/(N m) per m/N of G.
    """
    R = blank_receptances(blank, x2_m, sub.freq_hz)
    P = R[:, ROOT, ROOT] + sub.R
    a, b, c = P[:, 0, 0], 0.5 * (P[:, 0, 1] + P[:, 1, 0]), P[:, 1, 1]
    S = np.stack([np.stack([a * a, 2 * a * b, b * b], -1),
                  np.stack([a * b, a * c + b * b, b * c], -1),
                  np.stack([b * b, 2 * b * c, c * c], -1)], 1)
    return S @ np.linalg.inv(_system(R))


def noise_std(blank: Component, x2_m: float, sub: Subassembly, sigma) -> np.ndarray:
    """Standard deviation (F, 3) of the recovered h, l, p for complex Gaussian noise on G11, G12, G22.

    ``sigma`` (3,) or (F, 3): standard deviation of each measured FRF (m/N),
    E|noise|² = σ². First order: σ_e = √(Σ_k |J_ek|² σ_k²). |error| is then
    Rayleigh-distributed, median ≈ 0.833 σ_e.
    """
    J = sensitivity(blank, x2_m, sub)
    s = np.broadcast_to(np.asarray(sigma, float), (J.shape[0], 3))
    return np.sqrt(np.einsum("fek,fk->fe", np.abs(J) ** 2, s**2))


@dataclass(frozen=True)
class Conditioning:
    """Condition numbers of the inverse vs frequency.

    system : (F,) 2-norm condition number of the 3×3 system M with unit-norm
        columns (unit-independent; how well the three measurements separate X).
    relative : (F, 3) relative condition number of h, l, p with respect to the
        measurements, ‖J_e‖₂ ‖(G11, G12, G22)‖₂ / |e|: relative error of the entry
        per relative error of the data (includes the step X → SH).
    """

    freq_hz: np.ndarray
    system: np.ndarray
    relative: np.ndarray


def conditioning(blank: Component, x2_m: float, sub: Subassembly) -> Conditioning:
    """:class:`Conditioning` of the one-blank inverse, linearised at ``sub``."""
    R = blank_receptances(blank, x2_m, sub.freq_hz)
    M = _system(R)
    Mn = M / np.linalg.norm(M, axis=1, keepdims=True)
    J = sensitivity(blank, x2_m, sub)
    G = _coupled(R, sub.R)
    e = np.stack([sub.R[:, 0, 0], sub.R[:, 0, 1], sub.R[:, 1, 1]], -1)
    rel = np.linalg.norm(J, axis=2) * np.linalg.norm(G, axis=1)[:, None] / np.abs(e)
    return Conditioning(sub.freq_hz, np.linalg.cond(Mn), rel)
