"""Speed and accuracy figures of the stability-lobe solvers (prints; not a test).

    .venv/bin/python benchmarks/bench_lobes.py [--quick]

Targets: zero-order lobes over 1000 speeds from a 3001-point FRF < 0.2 s;
semi-discretisation of one mode (100 speeds, bisection on depth; or a
100 × 50 speed × depth grid) < 5 s.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from toolpoint.stability import ModalModel, sdm_lobes, sdm_spectral_radius, zoa_lobes

# Insperger & Stépán (2004) benchmark: one mode in x, 2 teeth, Kt = 6e8, Kn = 2e8 N/m².
MODE = ModalModel([922.0], [0.011], [0.03993])
CUT = dict(teeth=2, kt=6e8, kr=1 / 3, milling="down")


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return out, min(times), float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats, skip the m = 160 reference")
    quick = ap.parse_args().quick
    rep = 3 if quick else 10

    f = np.linspace(0.0, 3000.0, 3001)
    frf = MODE.frf(f)
    rpm = np.linspace(2000.0, 25000.0, 1000)
    two = ModalModel([650.0, 922.0, 2214.0], [0.03, 0.011, 0.02], [0.4, 0.03993, 0.2]).frf(f)

    print("== zero-order approximation (3001-point FRF, 1000 speeds 2000–25000 rpm)")
    for name, fy, ri in (("x only, slotting", "rigid", 1.0), ("symmetric x = y, a/D = 0.5", None, 0.5),
                         ("x ≠ y (3 modes / 1 mode), a/D = 0.3", two, 0.3)):
        res, tmin, tmed = best_of(lambda: zoa_lobes(frf, fy, **CUT, radial_immersion=ri, rpm=rpm), rep)
        print(f"  {name:38s} best {1e3 * tmin:6.1f} ms  median {1e3 * tmed:6.1f} ms  "
              f"({len(res.lobes)} lobes, min {1e3 * res.min_depth_m:.4f} mm @ {res.min_rpm:.0f} rpm)  target < 200 ms")

    print("\n== closed form, one mode in x, slotting: a_min = 2kζ(1+ζ)/(N Kn/4)")
    k = MODE.stiffness[0]
    ref = 2 * k * 0.011 * 1.011 / (2 * 2e8 / 4)
    for df in (1.0, 0.1):
        fd = np.arange(0.0, 3000.0 + df / 2, df)
        res = zoa_lobes(MODE.frf(fd), "rigid", **CUT, radial_immersion=1.0, rpm=rpm)
        print(f"  FRF step {df:4.1f} Hz: ZOA {1e3 * res.min_depth_m:.6f} mm, closed form {1e3 * ref:.6f} mm, "
              f"relative error {res.min_depth_m / ref - 1:+.2e}")

    print("\n== semi-discretisation, one mode, 100 speeds 5000–25000 rpm (search + bisection, rtol 1e-3)")
    r100 = np.linspace(5000.0, 25000.0, 100)
    sdm = {}
    for ri in (1.0, 0.05):
        res, t, _ = best_of(lambda: sdm_lobes(MODE, None, **CUT, radial_immersion=ri, rpm=r100), 1 if quick else 2)
        sdm[ri] = res
        ms = res.params["m"]
        print(f"  a/D = {ri:4.2f}: {t:5.2f} s  (m = {ms.min()}–{ms.max()} steps over the cut; "
              f"min {1e3 * res.min_depth_m:.4f} mm @ {res.min_rpm:.0f} rpm, chatter {res.min_chatter_hz:.1f} Hz)  "
              "target < 5 s")
    depth = np.linspace(0.05e-3, 5e-3, 50)
    rho, t, _ = best_of(lambda: sdm_spectral_radius(MODE, None, **CUT, radial_immersion=0.05,
                                                    rpm=r100[None, :], depth=depth[:, None], m=20), 1)
    print(f"  a/D = 0.05, 100 × 50 speed × depth grid of ρ (m = 20): {t:5.2f} s, "
          f"{int((rho >= 1).sum())} of {rho.size} points unstable  target < 5 s")
    rho, t, _ = best_of(lambda: sdm_spectral_radius(MODE, None, **CUT, radial_immersion=1.0,
                                                    rpm=r100[None, :], depth=depth[:, None], m=40), 1)
    print(f"  a/D = 1.00, 100 × 50 speed × depth grid of ρ (m = 40): {t:5.2f} s")

    if not quick:
        three = ModalModel([650.0, 922.0, 2214.0], [0.03, 0.011, 0.02], [0.4, 0.03993, 0.2])
        res, t, _ = best_of(lambda: sdm_lobes(three, three, teeth=4, kt=6e8, kr=0.3, radial_immersion=0.5,
                                              rpm=r100), 1)
        ms = res.params["m"]
        print(f"  3 modes in x and in y, 4 teeth, a/D = 0.5: {t:5.2f} s  (m = {ms.min()}–{ms.max()}; "
              f"Floquet matrices up to {12 + 2 * (ms.max() + 1)}²)")

    zoa = zoa_lobes(frf, "rigid", **CUT, radial_immersion=1.0, rpm=r100)
    print(f"\n== slotting minima: ZOA {1e3 * zoa.min_depth_m:.4f} mm, SDM {1e3 * sdm[1.0].min_depth_m:.4f} mm "
          f"(SDM/ZOA − 1 = {sdm[1.0].min_depth_m / zoa.min_depth_m - 1:+.1%}; SDM on the 100-speed grid)")

    print("\n== SDM convergence with m (fixed steps over the cut), limit in mm")
    speeds = {1.0: [7424.0, 10051.0, 15909.0, 21000.0], 0.05: [7500.0, 10000.0, 15800.0, 18900.0]}
    ms = (10, 20, 40, 80) if quick else (10, 20, 40, 80, 160)
    for ri, sp in speeds.items():
        sp = np.array(sp)
        rows = [sdm_lobes(MODE, None, **CUT, radial_immersion=ri, rpm=sp, m=m, rtol=1e-6).depth_m for m in ms]
        print(f"  a/D = {ri:4.2f}   speeds {', '.join(f'{s:.0f}' for s in sp)} rpm")
        for i, m in enumerate(ms):
            change = "" if i == 0 else f"   max change vs m = {ms[i - 1]}: {np.max(np.abs(rows[i] / rows[i - 1] - 1)):.2%}"
            print(f"    m = {m:3d}: " + "  ".join(f"{1e3 * d:8.5f}" for d in rows[i]) + change)
        auto = sdm_lobes(MODE, None, **CUT, radial_immersion=ri, rpm=sp, rtol=1e-6)
        print(f"    default (20 steps/wave, m = {', '.join(str(x) for x in auto.params['m'])}): "
              + "  ".join(f"{1e3 * d:8.5f}" for d in auto.depth_m))


if __name__ == "__main__":
    main()
