"""Inverse RCSA (toolpoint.dynamics.inverse_rcsa): accuracy, conditioning and noise amplification.

Synthetic measurements on the numerical case (examples/numerical_case.toml):
a Ø16 mm steel blank rigidly clamped in the holder, its G11, G12, G22
computed by an independent path (the exact dense dynamic stiffness of spindle
+ holder-and-blank, spindle–holder joint, no RCSA), then inverted.

Prints
1. the noise-free recovery error of h, l, n, p (relative norm and worst point);
2. condition numbers vs frequency (3×3 system, and the relative condition
   number of h, l, p with respect to the data);
3. the noise study: complex Gaussian noise of std "level × peak |G|" on each
   FRF, median (over frequency) relative error of h, l, p — the first-order
   prediction, the raw inverse, Savitzky–Golay smoothed and modal-fit (smooth="modal") results;
4. the first-order amplification for other blank geometries and for
   measurement plans with two blanks.

Run: .venv/bin/python benchmarks/bench_inverse_rcsa.py  (≈ 10 s)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from toolpoint.dynamics.assembly import Component, Segment, load_assembly
from toolpoint.dynamics.components import assemble, mesh, receptance
from toolpoint.frf import FRF
from toolpoint.dynamics.inverse_rcsa import (
    ROOT, _split, blank_receptances, conditioning, noise_std, smooth_subassembly, subassembly_from_blank,
)
from toolpoint.dynamics.subassembly import Subassembly

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "numerical_case.toml"
MEDIAN_RAYLEIGH = np.sqrt(np.log(2))  # median |z| / rms |z| for circular complex Gaussian z


def blank_of(length_m: float, od_m: float, material) -> Component:
    return Component("blank", (Segment(length_m, od_m, 0.0, material),))


def measured(asm, blank: Component, x2_m: float, f) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """G11, G12, G22 of spindle + (holder + blank) by one dense exact stiffness solve."""
    cut = blank.length - x2_m
    hb = Component("holder+blank", asm.holder.segments + _split(blank, cut).segments)
    ms, mh = mesh(asm.spindle, f.max()), mesh(hb, f.max())
    D, off = assemble([ms, mh], [(0, ms.n_nodes - 1, 1, 0, *asm.spindle_holder.as_array())], 2 * np.pi * f)
    k2 = int(np.argmin(abs(mh.x - (asm.holder.length + cut))))
    X = receptance(D, [off[1] + 2 * (mh.n_nodes - 1), off[1] + 2 * k2])
    return X[:, 0, 0], X[:, 0, 1], X[:, 1, 1]


def entries(R):
    return np.stack([R[:, 0, 0], R[:, 0, 1], R[:, 1, 1]], -1)


def median_rel(sub: Subassembly, true: Subassembly) -> np.ndarray:
    """Median over frequency of |error| / |entry| for h, l, p."""
    return np.median(np.abs(entries(sub.R) - entries(true.R)) / np.abs(entries(true.R)), axis=0)


def norm_rel(sub: Subassembly, true: Subassembly) -> np.ndarray:
    """‖error‖ / ‖entry‖ over the band for h, l, p (dominated by the modes)."""
    return np.linalg.norm(entries(sub.R) - entries(true.R), axis=0) / np.linalg.norm(entries(true.R), axis=0)


def fmt(v) -> str:
    return " ".join(f"{x:9.3g}" for x in v)


def noise_free(asm, blank, x2, f, true):
    G = measured(asm, blank, x2, f)
    sub = subassembly_from_blank(blank, x2, *(FRF(f, g) for g in G))
    print(f"\n1. Noise-free recovery, blank Ø{blank.segments[0].od * 1e3:g} × {blank.length * 1e3:g} mm, "
          f"x2 = {x2 * 1e3:g} mm, {f[0]:g}–{f[-1]:g} Hz ({f.size} points)")
    for (i, j), name in zip(((0, 0), (0, 1), (1, 0), (1, 1)), "hlnp"):
        d = sub.R[:, i, j] - true.R[:, i, j]
        print(f"   {name}: ‖error‖/‖{name}‖ = {np.linalg.norm(d) / np.linalg.norm(true.R[:, i, j]):.2e}, "
              f"worst point {np.max(np.abs(d) / np.abs(true.R[:, i, j])):.2e}")


def condition_table(blank, x2, true, freqs=(20, 100, 500, 790, 1000, 1500, 2000, 2500, 3000)):
    c = conditioning(blank, x2, true)
    print(f"\n2. Conditioning, blank {blank.length * 1e3:g} mm, x2 = {x2 * 1e3:g} mm "
          "(system: cond of the column-scaled 3×3; κ: relative condition number of h, l, p)")
    print("   f [Hz]   system     κ_h       κ_l       κ_p")
    for fq in freqs:
        k = int(np.argmin(abs(c.freq_hz - fq)))
        print(f"   {c.freq_hz[k]:6.0f} {c.system[k]:8.3g} {fmt(c.relative[k])}")
    print(f"   median  {np.median(c.system):8.3g} {fmt(np.median(c.relative, 0))}")


def noise_study(asm, blank, x2, f, true, levels=(1e-4, 1e-3, 1e-2), windows=(10, 25, 50), seed=1):
    G = measured(asm, blank, x2, f)
    peaks = np.array([np.abs(g).max() for g in G])
    pred1 = MEDIAN_RAYLEIGH * np.median(noise_std(blank, x2, true, peaks) / np.abs(entries(true.R)), 0)
    rng = np.random.default_rng(seed)
    print(f"\n3. Noise study, blank {blank.length * 1e3:g} mm, x2 = {x2 * 1e3:g} mm: relative error of h, l, p "
          "(noise std = level × peak |G|); median over frequency | relative norm over the band")
    print(f"   first-order amplification (median error / level): {fmt(pred1)}")
    print(f"   level     method                {'h':>9} {'l':>9} {'p':>9}  | {'h':>9} {'l':>9} {'p':>9}")
    exact = subassembly_from_blank(blank, x2, *(FRF(f, g) for g in G))
    print(f"   {0:7.0e}   raw                  {fmt(median_rel(exact, true))}  | {fmt(norm_rel(exact, true))}")
    for w in windows:
        s = smooth_subassembly(exact, w)
        print(f"   {'':7}   smoothed {w:3g} Hz (bias)  {fmt(median_rel(s, true))}  | {fmt(norm_rel(s, true))}")
    for lvl in levels:
        noisy = [FRF(f, g + lvl * pk * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2))
                 for g, pk in zip(G, peaks)]
        raw = subassembly_from_blank(blank, x2, *noisy)
        print(f"   {lvl:7.0e}   first-order median   {fmt(pred1 * lvl)}  |")
        print(f"   {'':7}   raw                  {fmt(median_rel(raw, true))}  | {fmt(norm_rel(raw, true))}")
        for w in windows:
            s = smooth_subassembly(raw, w)
            print(f"   {'':7}   smoothed {w:3g} Hz         {fmt(median_rel(s, true))}  | {fmt(norm_rel(s, true))}")
        m = subassembly_from_blank(blank, x2, *noisy, smooth="modal")
        print(f"   {'':7}   modal fit of G       {fmt(median_rel(m, true))}  | {fmt(norm_rel(m, true))}")


def plan_amplification(true, plan, level=1.0):
    """First-order median relative error of h, l, p per unit noise level for a measurement plan.

    plan: [(blank, xa, xb)] — one translational FRF G_ab per entry, points xa, xb (m from the
    tip, 0 = tip). Linearised dG_ab = u·dSH·v (u = row 0 of R_a3 X, v = column 0 of X R_3b):
    rows [u0v0, u0v1 + u1v0, u1v1] on (h, l, p); least squares for more than three rows.
    """
    f = true.freq_hz
    rows, sig = [], []
    for blank, xa, xb in plan:
        xs = [x for x in (xa, xb) if x > 0]
        x2 = xs[0] if xs else blank.length / 2
        R = blank_receptances(blank, x2, f)
        idx = {0.0: 0, x2: 1}
        Xm = np.linalg.inv(R[:, ROOT, ROOT] + true.R)
        u = (R[:, idx[xa], ROOT] @ Xm)[:, 0, :]
        v = (Xm @ R[:, ROOT, idx[xb]])[:, :, 0]
        rows.append(np.stack([u[:, 0] * v[:, 0], u[:, 0] * v[:, 1] + u[:, 1] * v[:, 0], u[:, 1] * v[:, 1]], -1))
        Xa = Xm @ R[:, ROOT, idx[xb]]
        g = R[:, idx[xa], idx[xb], 0, 0] - (R[:, idx[xa], ROOT, 0:1, :] @ Xa[:, :, 0:1])[:, 0, 0]
        sig.append(level * np.abs(g).max())
    A = np.stack(rows, 1)  # (F, m, 3)
    J = np.linalg.pinv(A)  # (F, 3, m)
    std = np.sqrt(np.einsum("fem,m->fe", np.abs(J) ** 2, np.array(sig) ** 2))
    return MEDIAN_RAYLEIGH * np.median(std / np.abs(entries(true.R)), 0)


def geometry_table(true, steel):
    print("\n4. First-order amplification (median relative error of h, l, p per unit noise level)")
    print("   one blank Ø16, G11 G12 G22:")
    print("   L [mm]  x2 [mm]       h         l         p")
    for L in (0.04, 0.05, 0.08, 0.10):
        for gap in sorted({0.005, 0.010, 0.020, L / 2}):
            x2 = L - gap
            a = plan_amplification(true, [(blank_of(L, 0.016, steel), 0.0, 0.0), (blank_of(L, 0.016, steel), 0.0, x2),
                                          (blank_of(L, 0.016, steel), x2, x2)])
            print(f"   {L * 1e3:6.0f} {x2 * 1e3:8.0f} {fmt(a)}")
    b50, b80, b40 = blank_of(0.05, 0.016, steel), blank_of(0.08, 0.016, steel), blank_of(0.04, 0.016, steel)
    plans = {
        "80 mm: G11 G12 G22, x2 = 30 mm (one blank)": [(b80, 0, 0), (b80, 0, 0.03), (b80, 0.03, 0.03)],
        "two blanks 50 + 80 mm, tip G11 each + G12(50 mm, x2 = 40)": [(b50, 0, 0), (b80, 0, 0), (b50, 0, 0.04)],
        "two blanks 40 + 80 mm, tip G11 each + G12(40 mm, x2 = 30)": [(b40, 0, 0), (b80, 0, 0), (b40, 0, 0.03)],
        "two blanks 50 + 80 mm, all six (least squares, x2 = 40/70)": [
            (b50, 0, 0), (b50, 0, 0.04), (b50, 0.04, 0.04), (b80, 0, 0), (b80, 0, 0.07), (b80, 0.07, 0.07)],
        "one blank 50 mm, x2 = 40 mm": [(b50, 0, 0), (b50, 0, 0.04), (b50, 0.04, 0.04)],
    }
    print("   measurement plans:")
    for name, plan in plans.items():
        print(f"   {name:62s} {fmt(plan_amplification(true, plan))}")


def main():
    asm = load_assembly(EXAMPLE)
    steel = asm.holder.segments[0].material
    f_free = np.arange(2.0, 5001.0, 2.0)
    f = np.arange(20.0, 3001.0, 1.0)
    true_free = Subassembly.from_assembly(asm, f_free)
    true = Subassembly.from_assembly(asm, f)
    b80, b50 = blank_of(0.08, 0.016, steel), blank_of(0.05, 0.016, steel)
    noise_free(asm, b80, 0.03, f_free, true_free)
    condition_table(b80, 0.03, true)
    condition_table(b50, 0.04, true)
    noise_study(asm, b80, 0.03, f, true)
    noise_study(asm, b50, 0.04, f, true)
    geometry_table(true, steel)


if __name__ == "__main__":
    main()
