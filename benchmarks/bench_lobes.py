"""Speed and accuracy figures of the stability-lobe solvers (prints; not a test).

    .venv/bin/python benchmarks/bench_lobes.py [--quick] [--sdm-only]

First the semi-discretisation tables (machine and date printed): default accuracy
against a converged plain-SDM reference for the one-mode Insperger & Stépán cases
and a 2-DOF case, CPU time per boundary, and the 4-modes-per-direction case
(1000 speeds; 100 with --quick, ≈ 1 min). --quick --sdm-only takes ≈ 1 min.

Targets: zero-order lobes over 1000 speeds from a 3001-point FRF < 0.2 s;
semi-discretisation of one mode (100 speeds, bisection on depth; or a
100 × 50 speed × depth grid) < 5 s; 4 complex modes per direction (fitted by
``dynamics.modal.fit_frfs``), 1000 speeds ≤ 20 s CPU, within 1 % of a converged
reference off the steep flanks; the ``accuracy`` cost table.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time

import numpy as np

from toolpoint.stability import CuttingConditions, ModalModel, sdm_lobes, sdm_spectral_radius, zoa_lobes

# Insperger & Stépán (2004) benchmark: one mode in x, 2 teeth, Kt = 6e8, Kn = 2e8 N/m².
MODE = ModalModel([922.0], [0.011], [0.03993])


def cut(ri, teeth=2, kr=1 / 3):
    return CuttingConditions(teeth=teeth, tangential_coeff=6e8, radial_ratio=kr, radial_immersion=ri)


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return out, min(times), float(np.median(times))


def _exact_one_mode(rpm, h, nk=10):
    """Exact zero-order limit (m) of MODE (x only, h > 0) per speed, by bisection in ω."""
    wn = MODE.omega_n[0]
    T = 60.0 / (2 * rpm)

    def phi(w):
        return 1 / (MODE.mass_kg[0] * (wn**2 - w**2 + 2j * MODE.zeta[0] * wn * w))

    out = np.full(T.size, np.inf)
    for dk in range(nk):
        k = np.maximum(np.ceil(wn * T / (2 * np.pi) - 1 - 1e-12), 0) + dk
        lo, hi = np.full(T.size, wn * (1 + 1e-15)), np.full(T.size, 2 * np.pi * 3000.0)

        def g(w):
            mu = h * phi(w)
            return w * T - (np.pi + 2 * np.arctan2(-mu.imag, -mu.real)) - 2 * np.pi * k

        ok = (g(lo) < 0) & (g(hi) > 0)
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            neg = g(mid) < 0
            lo, hi = np.where(neg, mid, lo), np.where(neg, hi, mid)
        out = np.where(ok, np.minimum(out, -0.5 / (h * phi(0.5 * (lo + hi)).real)), out)
    return out


def _cpu(fn):
    """(result, CPU s, wall s) of one call."""
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c, time.perf_counter() - w


def _reference(model_x, model_y, c, sp, ms):
    """Converged discretisation (every node, fixed m): Richardson extrapolation of the two finest m (error O(Δt²))."""
    a, b = (sdm_lobes(model_x, model_y, c, rpm=sp, m=m, rtol=1e-6).depth_m for m in ms)
    return b + (b - a) / 3


def sdm_accuracy_table(quick: bool) -> None:
    """Default SDM against a converged reference: one-mode Insperger cases, the 2-DOF case; time per boundary."""
    print(f"\n== SDM default (accuracy 1) against the converged discretisation — {platform.node()}, "
          f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"{datetime.datetime.now().isoformat(timespec='minutes')}")
    ms = (80, 160) if quick else (160, 320)
    print(f"   reference: every node carried, m = {ms[0]} and {ms[1]} steps over the cut, Richardson-extrapolated")
    # 2-DOF case: x 456.78/1448.89 Hz, y 516.52/1408.45 Hz; our choice: every mode k = 2e7 N/m, ζ = 0.02.
    k2, z2 = 2e7, 0.02

    def modes(fn):
        fn = np.array(fn)
        return ModalModel(fn, [z2] * fn.size, k2 / (2 * np.pi * fn) ** 2)

    two_x, two_y = modes([456.78, 1448.89]), modes([516.52, 1408.45])
    cases = [
        ("1 mode, slotting, down", MODE, None, cut(1.0), [7424.0, 10051.0, 15909.0, 21000.0]),
        ("1 mode, a/D 0.05, down", MODE, None, cut(0.05), [7500.0, 10000.0, 15800.0, 18900.0]),
        ("1 mode, a/D 0.05, up", MODE, None,
         CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1 / 3, radial_immersion=0.05, milling="up"),
         [7500.0, 10000.0, 15800.0, 18900.0]),
        ("2-DOF x/y, a/D 0.5, down", two_x, two_y,
         CuttingConditions(teeth=2, tangential_coeff=1319.4e6, radial_ratio=788.8 / 1319.4, radial_immersion=0.5),
         [4000.0, 6000.0, 8000.0, 10000.0, 12000.0]),
    ]
    print(f"   {'case':28s} {'speeds':>6s} {'max |err|':>9s} {'median':>8s} {'m':>9s} "
          f"{'CPU s/boundary (100 speeds)':>28s}")
    for name, mx, my, c, sp in cases:
        sp = np.array(sp)
        ref = _reference(mx, my, c, sp, ms)
        res = sdm_lobes(mx, my, c, rpm=sp, rtol=1e-5)
        err = np.abs(res.depth_m / ref - 1)
        r100 = np.linspace(sp.min(), sp.max(), 100)
        _, cpu, wall = _cpu(lambda: sdm_lobes(mx, my, c, rpm=r100))
        print(f"   {name:28s} {sp.size:6d} {err.max():9.2%} {np.median(err):8.2%} "
              f"{res.params['m'].min():4d}–{res.params['m'].max():<4d} {cpu:10.2f} (wall {wall:.2f})")
    print(f"   2-DOF modal parameters chosen: k = {k2:.0e} N/m and ζ = {z2} for every mode, "
          f"K_r = 788.8/1319.4 = {788.8 / 1319.4:.4f}")


def _four_mode_model():
    """4 complex modes per direction (x = y) fitted to the README example assembly by ``dynamics.modal.fit_frfs``."""
    from pathlib import Path

    from toolpoint.dynamics.modal import fit_frfs
    from toolpoint.dynamics.model import frf_from_toml
    from toolpoint.stability import from_modal_fit

    frf = frf_from_toml(Path(__file__).resolve().parents[1] / "examples" / "numerical_case.toml").to_receptance()
    fit = fit_frfs([frf], n_modes=4)
    return fit, from_modal_fit(fit)


def sdm_four_modes(quick: bool) -> None:
    """CPU time of the SDM with 4 fitted complex modes per direction, 1000 speeds; error and cost per accuracy."""
    fit, model = _four_mode_model()
    n = 100 if quick else 1000
    c = cut(0.5, teeth=4, kr=0.3)
    res, cpu, wall = _cpu(lambda: sdm_lobes(model, None, c, rpm=np.linspace(5000.0, 30000.0, n)))
    note = f" (×10 ≈ {10 * cpu:.0f} s for 1000)" if quick else ""
    print(f"\n== SDM, 4 fitted complex modes per direction (f_n {', '.join(f'{f:.0f}' for f in fit.fn_hz)} Hz, "
          f"{model.n_states} states), 4 teeth, a/D 0.5, {n} speeds 5000–30000 rpm: CPU {cpu:.1f} s{note}, "
          f"wall {wall:.1f} s, {res.params['evaluations']} Floquet matrices ({res.params['evaluations'] / n:.1f} "
          f"per speed), m = {res.params['m'].min()}–{res.params['m'].max()}  target ≤ 20 s CPU for 1000")

    # Accuracy against a converged reference (accuracy 4, steps up to 800), off the steep flanks.
    sp = np.linspace(5000.0, 30000.0, 21 if quick else 41)
    ref = sdm_lobes(model, None, c, rpm=sp, accuracy=4.0, m_max=800, rtol=1e-5).depth_m
    print(f"   error against the converged limit (accuracy 4, up to 800 steps over the cut) at {sp.size} speeds; "
          "steep flank: |d ln a/d ln n| > 10 (1 % in depth = 0.1 % in speed), from the default limit at n(1 ± 0.5 %)")
    print(f"   {'accuracy':>8s} {'max |err| off flanks':>21s} {'median':>8s} {'max on flanks':>14s} "
          f"{'CPU s, 1000 speeds':>19s}")
    n_cost = 100  # the cost of accuracy ≠ 1 is measured on 100 speeds and scaled to 1000
    for acc in (0.5, 1.0, 2.0, 4.0):
        got = sdm_lobes(model, None, c, rpm=sp, accuracy=acc).depth_m
        if acc == 1.0:
            up = sdm_lobes(model, None, c, rpm=sp * 1.005).depth_m
            dn = sdm_lobes(model, None, c, rpm=sp / 1.005).depth_m
            flank = np.abs(np.log(up / dn) / np.log(1.005**2)) > 10
        err = np.abs(got / ref - 1)
        if acc == 1.0:
            cost = cpu * n_cost / n  # the 1000-speed run above
        else:
            cost = _cpu(lambda: sdm_lobes(model, None, c, rpm=np.linspace(5000.0, 30000.0, n_cost), accuracy=acc))[1]
        scale = "" if acc == 1.0 else f" (100 speeds ×{1000 // n_cost})"
        on = f"{err[flank].max():14.2%}" if (acc >= 1.0 and flank.any()) else f"{'—':>14s}"
        print(f"   {acc:8.2g} {err[~flank].max() if acc >= 1.0 else err.max():21.2%} "
              f"{np.median(err[~flank] if acc >= 1.0 else err):8.2%} {on} {cost * 1000 / n_cost:15.1f}{scale}")
    print(f"   ({int(flank.sum())} of {sp.size} speeds on steep flanks; at accuracy 0.5 all speeds are counted)")


def sdm_krylov(quick: bool) -> None:
    """The critical multiplier from Arnoldi steps against all eigenvalues: CPU per Floquet matrix and agreement.

    Three symmetric modes (748, 1890, 2176 Hz, like the campaign tool EM16-50), slotting with 3 teeth: the cut is
    the whole tooth period, so a low speed carries many delayed-displacement nodes (D = 46–214 states).
    """
    from toolpoint.stability import sdm as sdm_mod

    modes = ModalModel([748.0, 1890.0, 2176.0], [0.03, 0.025, 0.02], [0.35, 0.06, 0.08])
    c = CuttingConditions(teeth=3, tangential_coeff=8e8, radial_ratio=0.2, radial_immersion=1.0)
    sy = sdm_mod._System(sdm_mod.as_state_space(modes, modes), c)
    n = 40 if quick else 200
    print(f"\n== critical multiplier: {sdm_mod.KRYLOV_DIM} Arnoldi steps (from D = {sdm_mod.KRYLOV_MIN_D}) against "
          f"numpy.linalg.eigvals, {n} Floquet matrices per speed at 0.8–1.2 × the limit; 3 modes, slotting, 3 teeth")
    print(f"   {'rpm':>6s} {'D':>4s} {'eigvals ms':>10s} {'Krylov ms':>9s} {'redone':>6s} {'max |Δρ|/ρ':>11s} "
          f"{'max |Δμ|':>9s}")
    rpm = np.array([3000.0, 6000.0, 9000.0, 12000.0, 15000.0])
    lim = sdm_lobes(modes, modes, c, rpm=rpm).depth_m
    m, s = sy.resolution(rpm, None, 1.0, sdm_mod.M_MAX, 1.1 * sy.f_max)
    for r, a, mm, ss in zip(rpm, lim, m, s):
        Phi = sy.monodromy(np.full(n, r), a * np.linspace(0.8, 1.2, n), int(mm), int(ss))
        t = time.process_time()
        ev = np.linalg.eigvals(Phi)
        t_full = time.process_time() - t
        want = ev[np.arange(n), np.argmax(np.abs(ev), axis=1)]
        calls = []
        full = np.linalg.eigvals
        np.linalg.eigvals = lambda x, full=full: (calls.append(x.shape[0]), full(x))[1]
        try:
            t = time.process_time()
            got = sdm_mod.critical_multipliers(Phi)
            t_kr = time.process_time() - t
        finally:
            np.linalg.eigvals = full
        redone = "all" if Phi.shape[1] < sdm_mod.KRYLOV_MIN_D else str(sum(calls))
        print(f"   {r:6.0f} {Phi.shape[1]:4d} {1e3 * t_full / n:10.3f} {1e3 * t_kr / n:9.3f} {redone:>6s} "
              f"{np.max(np.abs(np.abs(got) / np.abs(want) - 1)):11.1e} {np.max(np.abs(got - want)):9.1e}")


def _numpy_monodromy(sy, rpm, depth, m, s):
    """Φ of the NumPy step loop the compiled one replaced (``toolpoint/stability/sdm.py`` of ``0859c25``): stacked
    products over the points, each step's maps stored, the delayed terms of every step formed at once."""
    n, d = sy.n, sy.d
    H, L = sy.directional(m), sy.interp(m, s)
    q1, B = L.shape[1], rpm.size
    P, G0, G1, Pfree = sy.step_maps(rpm, m)
    a = depth[:, None, None, None]
    sub = "bnp,ipd->bind" if H.ndim == 3 else "bnp,bipd->bind"
    U0, U1 = a * np.einsum(sub, G0, H), a * np.einsum(sub, G1, H)
    C = sy.C if sy.C.ndim == 2 else sy.C[:, None]
    CU0, CU1 = C @ U0, C @ U1
    W = U1 @ np.linalg.inv(np.eye(d) + CU1)
    right = np.concatenate([np.broadcast_to(C, CU0.shape[:2] + sy.C.shape[-2:]),
                            (sy.C @ P)[:, None] - CU0 @ C], axis=2)
    M = P[:, None] - np.concatenate([U0, W], axis=3) @ right
    E0, E1 = U0 - W @ CU0, W
    D = n + q1 * d
    Y = np.zeros((B, n, D))
    Y[:, :, :n] = np.eye(n)
    Phi = np.empty((B, D, D))
    Phi[:, n: n + d] = 0.0
    Phi[:, n: n + d, :n] = sy.C
    lo_c, Lw = sy.stencils(m, s)
    w = Lw.shape[-1]
    X = np.stack([E0, E1], axis=4).transpose(1, 0, 2, 3, 4).reshape(m, B * n * d, 2)
    G = (X @ Lw).reshape(m, B, n, d, w).transpose(0, 1, 2, 4, 3).reshape(m, B, n, w * d)
    act = n
    for i in range(m):
        c0 = n + lo_c[i] * d
        Y[:, :, :act] = M[:, i] @ Y[:, :, :act]
        Y[:, :, c0: c0 + w * d] += G[i]
        act = max(act, c0 + w * d)
        if (i + 1) % s == 0:
            j = (i + 1) // s
            Phi[:, n + j * d: n + (j + 1) * d] = sy.C @ Y
    Phi[:, :n] = Pfree @ Y
    return Phi


def sdm_steps(quick: bool) -> None:
    """The compiled step loop of the Floquet matrices against the NumPy loop it replaced: CPU per matrix, agreement.

    Three symmetric modes like the campaign tool EM16-50 (as :func:`sdm_krylov`), 4 teeth at a/D 0.5 and slotting with
    3 teeth, batches of 8 and 80 points at 0.8–1.2 × the limit: the sizes of a shop update's searches.
    """
    from toolpoint.stability import sdm as sdm_mod

    modes = ModalModel([748.0, 1890.0, 2176.0], [0.03, 0.025, 0.02], [0.35, 0.06, 0.08])
    reps = 3 if quick else 7
    print("\n== Floquet matrices: the compiled step loop (numba) against the NumPy loop it replaced; "
          f"3 modes x = y, best of {reps}, ms per matrix")
    print(f"   {'cut':>22s} {'rpm':>6s} {'m':>4s} {'s':>2s} {'D':>4s} {'batch':>5s} {'NumPy':>7s} {'compiled':>8s} "
          f"{'max |ΔΦ|/max|Φ|':>16s} {'max |Δρ|/ρ':>11s}")
    for name, c in (("4 teeth, a/D 0.5", CuttingConditions(teeth=4, tangential_coeff=8e8, radial_ratio=0.3,
                                                            radial_immersion=0.5)),
                    ("3 teeth, slotting", CuttingConditions(teeth=3, tangential_coeff=8e8, radial_ratio=0.2,
                                                             radial_immersion=1.0))):
        sy = sdm_mod._System(sdm_mod.as_state_space(modes, modes), c)
        rpm = np.array([6000.0, 15000.0])
        lim = sdm_lobes(modes, modes, c, rpm=rpm).depth_m
        m, s = sy.resolution(rpm, None, 1.0, sdm_mod.M_MAX, 1.1 * sy.f_max)
        for r, a, mm, ss in zip(rpm, lim, m, s):
            for b in (8, 80):
                rr, aa = np.full(b, r), a * np.linspace(0.8, 1.2, b)
                t_np, t_nb = [], []
                for _ in range(reps):  # alternating, so the VM's drift falls on both
                    t = time.process_time()
                    ref = _numpy_monodromy(sy, rr, aa, int(mm), int(ss))
                    t_np.append(time.process_time() - t)
                    t = time.process_time()
                    got = sy.monodromy(rr, aa, int(mm), int(ss))
                    t_nb.append(time.process_time() - t)
                dphi = np.max(np.abs(got - ref) / np.abs(ref).max(axis=(1, 2))[:, None, None])
                rho0, rho1 = (np.abs(np.linalg.eigvals(x)).max(axis=1) for x in (ref, got))
                print(f"   {name:>22s} {r:6.0f} {mm:4d} {ss:2d} {ref.shape[1]:4d} {b:5d} {1e3 * min(t_np) / b:7.3f} "
                      f"{1e3 * min(t_nb) / b:8.3f} {dphi:16.1e} {np.max(np.abs(rho1 / rho0 - 1)):11.1e}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="fewer repeats, coarser references, 100 instead of 1000 speeds for the 4-mode case")
    ap.add_argument("--sdm-only", action="store_true", help="only the semi-discretisation accuracy and cost tables")
    args = ap.parse_args()
    quick = args.quick
    sdm_accuracy_table(quick)
    sdm_four_modes(quick)
    sdm_krylov(quick)
    sdm_steps(quick)
    if args.sdm_only:
        return
    rep = 3 if quick else 10

    f = np.linspace(0.0, 3000.0, 3001)
    frf = MODE.frf(f)
    rpm = np.linspace(2000.0, 25000.0, 1000)
    two = ModalModel([650.0, 922.0, 2214.0], [0.03, 0.011, 0.02], [0.4, 0.03993, 0.2]).frf(f)

    print("== zero-order approximation (3001-point FRF, 1000 speeds 2000–25000 rpm)")
    for name, fy, ri in (("x only, slotting", "rigid", 1.0), ("symmetric x = y, a/D = 0.5", None, 0.5),
                         ("x ≠ y (3 modes / 1 mode), a/D = 0.3", two, 0.3)):
        res, tmin, tmed = best_of(lambda: zoa_lobes(frf, fy, cut(ri), rpm=rpm), rep)
        print(f"  {name:38s} best {1e3 * tmin:6.1f} ms  median {1e3 * tmed:6.1f} ms  "
              f"({len(res.lobes)} lobes, min {1e3 * res.min_depth_m:.4f} mm @ {res.min_rpm:.0f} rpm)  target < 200 ms")

    print("\n== closed form, one mode in x, slotting: a_min = 2kζ(1+ζ)/(N Kn/4)")
    k = MODE.stiffness[0]
    ref = 2 * k * 0.011 * 1.011 / (2 * 2e8 / 4)
    for df in (1.0, 0.1):
        fd = np.arange(0.0, 3000.0 + df / 2, df)
        res = zoa_lobes(MODE.frf(fd), "rigid", cut(1.0), rpm=rpm)
        print(f"  FRF step {df:4.1f} Hz: ZOA {1e3 * res.min_depth_m:.6f} mm, closed form {1e3 * ref:.6f} mm, "
              f"relative error {res.min_depth_m / ref - 1:+.2e}")

    print("\n== streamed: one mode, 0.01 Hz steps over 0–3000 Hz (300001 points), 1000 speeds 2000–25000 rpm")
    fine = np.arange(0.0, 3000.005, 0.01)
    res, t, _ = best_of(lambda: zoa_lobes(MODE.frf(fine), "rigid", cut(1.0), rpm=rpm), 1 if quick else 3)
    print(f"  {t:5.2f} s  ({len(res.lobes)} lobes, {sum(lobe.rpm.size for lobe in res.lobes)} lobe points kept)")

    print("\n== exact zero-order limit (per-speed root of ωT − ε(ω) = 2πk on the closed-form FRF), 1 Hz FRF")
    h = 2 * 2e8 / 4
    ref = _exact_one_mode(rpm, h)
    for df in (1.0, 0.5, 0.1):
        fd = np.arange(0.0, 3000.0 + df / 2, df)
        res = zoa_lobes(MODE.frf(fd), "rigid", cut(1.0), rpm=rpm)
        q = res.depth_m / ref - 1
        print(f"  FRF step {df:4.1f} Hz: max limit/exact − 1 = {q.max():+.2e} (at {rpm[np.argmax(q)]:.0f} rpm), "
              f"min {q.min():+.2e}")

    print("\n== semi-discretisation, one mode, 100 speeds 5000–25000 rpm (search + bisection, rtol 1e-3)")
    r100 = np.linspace(5000.0, 25000.0, 100)
    sdm = {}
    for ri in (1.0, 0.05):
        res, t, _ = best_of(lambda: sdm_lobes(MODE, None, cut(ri), rpm=r100), 1 if quick else 2)
        sdm[ri] = res
        ms = res.params["m"]
        print(f"  a/D = {ri:4.2f}: {t:5.2f} s  (m = {ms.min()}–{ms.max()} steps over the cut; "
              f"min {1e3 * res.min_depth_m:.4f} mm @ {res.min_rpm:.0f} rpm, chatter {res.min_chatter_hz:.1f} Hz)  "
              "target < 5 s")
    depth = np.linspace(0.05e-3, 5e-3, 50)
    rho, t, _ = best_of(lambda: sdm_spectral_radius(MODE, None, cut(0.05),
                                                    rpm=r100[None, :], depth=depth[:, None], m=20), 1)
    print(f"  a/D = 0.05, 100 × 50 speed × depth grid of ρ (m = 20): {t:5.2f} s, "
          f"{int((rho >= 1).sum())} of {rho.size} points unstable  target < 5 s")
    rho, t, _ = best_of(lambda: sdm_spectral_radius(MODE, None, cut(1.0),
                                                    rpm=r100[None, :], depth=depth[:, None], m=40), 1)
    print(f"  a/D = 1.00, 100 × 50 speed × depth grid of ρ (m = 40): {t:5.2f} s")

    if not quick:
        three = ModalModel([650.0, 922.0, 2214.0], [0.03, 0.011, 0.02], [0.4, 0.03993, 0.2])
        res, t, _ = best_of(lambda: sdm_lobes(three, three, cut(0.5, teeth=4, kr=0.3), rpm=r100), 1)
        ms = res.params["m"]
        print(f"  3 modes in x and in y, 4 teeth, a/D = 0.5: {t:5.2f} s  (m = {ms.min()}–{ms.max()}; "
              f"Floquet matrices up to {12 + 2 * (ms.max() + 1)}²)")

    zoa = zoa_lobes(frf, "rigid", cut(1.0), rpm=r100)
    print(f"\n== slotting minima: ZOA {1e3 * zoa.min_depth_m:.4f} mm, SDM {1e3 * sdm[1.0].min_depth_m:.4f} mm "
          f"(SDM/ZOA − 1 = {sdm[1.0].min_depth_m / zoa.min_depth_m - 1:+.1%}; SDM on the 100-speed grid)")

    print("\n== SDM convergence with m (fixed steps over the cut), limit in mm")
    speeds = {1.0: [7424.0, 10051.0, 15909.0, 21000.0], 0.05: [7500.0, 10000.0, 15800.0, 18900.0]}
    ms = (10, 20, 40, 80) if quick else (10, 20, 40, 80, 160)
    for ri, sp in speeds.items():
        sp = np.array(sp)
        rows = [sdm_lobes(MODE, None, cut(ri), rpm=sp, m=m, rtol=1e-6).depth_m for m in ms]
        print(f"  a/D = {ri:4.2f}   speeds {', '.join(f'{s:.0f}' for s in sp)} rpm")
        for i, m in enumerate(ms):
            rel = np.max(np.abs(rows[i] / rows[i - 1] - 1)) if i else 0.0
            change = "" if i == 0 else f"   max change vs m = {ms[i - 1]}: {rel:.2%}"
            print(f"    m = {m:3d}: " + "  ".join(f"{1e3 * d:8.5f}" for d in rows[i]) + change)
        auto = sdm_lobes(MODE, None, cut(ri), rpm=sp, rtol=1e-6)
        print(f"    default (20 steps/wave, m = {', '.join(str(x) for x in auto.params['m'])}): "
              + "  ".join(f"{1e3 * d:8.5f}" for d in auto.depth_m))


if __name__ == "__main__":
    main()
