"""Speed and accuracy figures of the time-domain milling simulation (prints; not a test).

    .venv/bin/python benchmarks/bench_simulation.py [--quick]

Targets (issue 24): ≤ 20 ms CPU per (speed, depth) point on the 1-DOF benchmark (922 Hz, ζ 0.011, 2 teeth,
slotting, 40 revolutions, 4 axial slices), vectorised over points; a 100 × 50 stability + SLE map in ≤ 2 min
on 2 cores; the stability boundary by bisection within 2 % of the SDM off the steep flanks.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time

import numpy as np

from toolpoint.simulation import Tool, simulate_map, simulate_milling, sle_frequency_domain, stability_boundary
from toolpoint.stability import CuttingConditions, ModalModel, sdm_lobes

MODE = ModalModel([922.0], [0.011], [0.03993])
SLOT = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1 / 3, radial_immersion=1.0)


def timed(fn):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c0, time.perf_counter() - w0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller map and fewer speeds for the boundary")
    ap.add_argument("--cut-only", action="store_true", help="only the simulated shop's one cut (a step loop's cost)")
    a = ap.parse_args()
    q = a.quick
    print(f"machine: {platform.platform()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} CPUs; python {platform.python_version()}, numpy {np.__version__}")
    print(f"date: {datetime.datetime.now().isoformat(timespec='seconds')}")

    # 0. one cut of the simulated shop (toolpoint.shop.campaign.simulated_shop): few points, many steps, the case the
    # compiled step loop is for (a NumPy loop paid ~1 µs per call whatever the points; the virtual campaigns and the
    # slow tests make hundreds of such cuts). The first call of the process loads (or compiles) the kernels: not timed
    from toolpoint.shop.campaign import simulated_shop
    from toolpoint.shop.model import cornelius_2024, sdm_limits

    pr = cornelius_2024(0.1)
    th = pr.theta(np.zeros((1, pr.sigma.size)))[0]
    a_lim = sdm_limits(pr, th, [20276.0])[0][0]
    shop = simulated_shop(pr, force_noise=0.05)
    shop(th, 20276.0, 0.5 * a_lim, np.random.default_rng(1))  # loads the compiled kernels
    cpus = [timed(lambda: shop(th, 20276.0, 0.85 * a_lim, np.random.default_rng(0)))[1] for _ in range(3)]
    print(f"\none shop cut (Cornelius 2024 median tool, 20276 rpm, 0.85 × its SDM limit, 5 % force noise: the twin "
          f"batch of 2 points, then `cut` on its microphone record): {min(cpus):.2f} s CPU (best of 3)")
    if a.cut_only:
        return

    # 1. per-point cost, 4 slices (30° helix, 12 mm tool), 40 revolutions, batches of increasing size
    tool = Tool(diameter_m=0.012, helix_deg=30, slices=4)
    print("\nper-point CPU, 1-DOF benchmark, 40 rev, 4 slices (helix 30°), 64 steps/tooth (+ substeps)")
    for n in (10, 100, 500) if not q else (10, 100):
        rpm = np.linspace(8000, 25000, n)
        depth = np.full(n, 0.3e-3)
        res, cpu, wall = timed(lambda: simulate_milling(MODE, None, SLOT, rpm=rpm, depth_m=depth, tool=tool,
                                                        revolutions=40, record_revolutions=2))
        print(f"  {n:4d} points: {1e3 * cpu / n:7.2f} ms CPU/point, {1e3 * wall / n:7.2f} ms wall/point "
              f"(steps/rev {res.steps_per_rev})")

    # 2. map
    ns, nd = (100, 50) if not q else (40, 20)
    rpm = np.linspace(5000, 25000, ns)
    depth = np.linspace(0.05e-3, 4e-3, nd)
    mp, cpu, wall = timed(lambda: simulate_map(MODE, None, SLOT, rpm=rpm, depth_m=depth, revolutions=40))
    print(f"\n{ns} × {nd} stability + SLE map (40 rev, straight flutes): {cpu:.1f} s CPU, {wall:.1f} s wall, "
          f"{1e3 * cpu / (ns * nd):.2f} ms CPU/point")
    sdm = sdm_lobes(MODE, None, SLOT, rpm=rpm).depth_m
    grid_lim = mp.limit_m
    step = depth[1] - depth[0]
    agree = np.mean(np.abs(grid_lim - np.minimum(sdm, depth[-1])) <= step + 1e-12)
    print(f"  map limit within one depth step ({1e3 * step:.3f} mm) of the SDM at {100 * agree:.0f} % of speeds")

    # 3. boundary by bisection vs SDM
    sp = np.linspace(4000, 25000, 43 if not q else 12)
    ref = sdm_lobes(MODE, None, SLOT, rpm=sp, rtol=1e-4).depth_m
    b, cpu, wall = timed(lambda: stability_boundary(MODE, None, SLOT, rpm=sp, depth_lo=0.8 * ref,
                                                    depth_hi=1.25 * ref, rtol=2e-3, revolutions=40))
    err = 100 * (b / ref - 1)
    print(f"\nboundary by bisection, {sp.size} speeds: {cpu:.1f} s CPU; deviation from SDM: median "
          f"{np.median(np.abs(err)):.2f} %, max {np.max(np.abs(err)):.2f} % (all speeds, flanks included)")

    # 4. SLE time domain vs frequency domain
    MX = [(900.0, 2e6, 0.03), (2100.0, 8e6, 0.02)]
    MY = [(850.0, 1.8e6, 0.03), (2300.0, 9e6, 0.02)]
    cut = CuttingConditions(teeth=3, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=0.25)
    r = np.linspace(5000, 20000, 16)
    a = np.full(r.size, 0.2e-3)
    td = simulate_milling(MX, MY, cut, rpm=r, depth_m=a, revolutions=16, record_revolutions=2)
    fd = sle_frequency_domain(MX, MY, cut, rpm=r, depth_m=a)
    print(f"\nSLE, 2 modes/direction, 25 % down-milling, {r.size} stable speeds: |time − frequency| max "
          f"{1e6 * np.max(np.abs(td.sle_m - fd)):.3f} µm (SLE range {1e6 * fd.min():.2f} … {1e6 * fd.max():.2f} µm)")


if __name__ == "__main__":
    main()
